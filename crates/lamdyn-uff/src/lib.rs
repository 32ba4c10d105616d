//! # lamdyn-uff
//!
//! Reader and writer for the Universal File Format (UFF/UNV), the interchange format every EMA
//! system exports (Simcenter Testlab, BK Connect, ARTeMIS, Oros, ME'scope).
//!
//! | dataset | what | module | read | write |
//! |---|---|---|---|---|
//! | 58, 58b | function at a DOF: time data, spectra, FRFs, coherence; all eight record-12 layouts, ASCII and binary in either byte order | [`d58`] | yes | yes |
//! | 55 | data at nodes: real and complex mode shapes | [`d55`] | yes | yes |
//! | 151 | header | [`meta`] | yes | yes |
//! | 164 | units, with factors to SI | [`meta`] | yes | yes |
//! | 15, 2411 | nodes | [`geometry`] | yes | yes |
//! | 2412 | elements | [`geometry`] | yes | — |
//! | 82 | trace lines | [`geometry`] | yes | — |
//! | 18, 2420 | coordinate systems (origin and axes in the global frame) | [`geometry`] | yes | — |
//! | others | skipped with a notice | | | |
//!
//! [`read`] loads a whole file; [`list`] streams one and reports what it holds (dataset, line,
//! byte offset, a one-line summary) without keeping data; [`frf`] turns the FRFs of a file into
//! the project's [`lamdyn_frf::FrfSet`] with units converted to SI; [`reencode`] converts
//! between ASCII and binary 58b keeping every other dataset verbatim; [`vtu`] writes mode shapes
//! with their mesh for ParaView. Errors name the line
//! ([`UffError`]); no input makes the reader panic (fuzzed: see docs/uff.md).
//!
//! Format reference: the I-DEAS/Simcenter universal file dataset descriptions (formats quoted
//! in each module), cross-checked against the conformance files of UFFFiles.jl and pyuff.

#![deny(missing_docs)]

pub mod d55;
pub mod d58;
mod error;
mod fields;
pub mod frf;
pub mod geometry;
pub mod meta;
mod record7;
pub mod scan;
pub mod time;
pub mod vtu;

pub use error::UffError;

use scan::{RawDataset, Scanner};
use serde::Serialize;
use std::io::BufRead;

/// One dataset of a file.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Dataset {
    /// 58 or 58b.
    Function(Box<d58::Function58>),
    /// 55.
    NodalData(Box<d55::Modal55>),
    /// 151.
    Header(meta::Header151),
    /// 164.
    Units(meta::Units164),
    /// 15 or 2411.
    Nodes(geometry::Nodes),
    /// 2412.
    Elements(Vec<geometry::Element>),
    /// 82.
    TraceLine(geometry::TraceLine),
    /// 18 or 2420.
    CoordinateSystems(Vec<geometry::CoordinateSystem>),
}

/// A dataset with where it was found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Located {
    /// Line of the dataset number (1-based).
    pub line: usize,
    /// Whether it was binary (58b).
    pub binary: bool,
    /// The dataset.
    pub dataset: Dataset,
}

/// A file's datasets, in order, with the notices about skipped ones.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct UffFile {
    /// Datasets read.
    pub datasets: Vec<Located>,
    /// One line per dataset skipped (unknown number).
    pub notices: Vec<String>,
}

impl UffFile {
    /// The functions (dataset 58) of the file.
    pub fn functions(&self) -> impl Iterator<Item = &d58::Function58> {
        self.datasets.iter().filter_map(|d| match &d.dataset {
            Dataset::Function(f) => Some(f.as_ref()),
            _ => None,
        })
    }

    /// The last units dataset (164) of the file, if any.
    pub fn units(&self) -> Option<&meta::Units164> {
        self.datasets.iter().rev().find_map(|d| match &d.dataset {
            Dataset::Units(u) => Some(u),
            _ => None,
        })
    }
}

/// Numbers of the datasets this crate reads.
pub const SUPPORTED: [u32; 10] = [15, 18, 55, 58, 82, 151, 164, 2411, 2412, 2420];

/// Reader options.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// Accept an ASCII dataset 58 whose record 12 holds fewer points than record 7 announces
    /// (files cut short by hand, e.g. pyuff's `dataset_milestone_in_header.uff`), keeping the
    /// points found, and a 58b whose header byte count disagrees with its records 6–7 (as
    /// pyuff 2.5.8 writes complex data), reading the size the records give; each with a
    /// notice. Off by default: both are errors.
    pub lenient_counts: bool,
}

fn decode(
    ds: &RawDataset,
    options: ReadOptions,
    notices: &mut Vec<String>,
) -> Result<Option<Dataset>, UffError> {
    Ok(Some(match ds.number {
        58 => {
            let (f, notice) = d58::parse(ds, options.lenient_counts)?;
            notices.extend(notice);
            Dataset::Function(Box::new(f))
        }
        55 => Dataset::NodalData(Box::new(d55::parse(ds)?)),
        151 => Dataset::Header(meta::parse_151(ds)),
        164 => Dataset::Units(meta::parse_164(ds)?),
        15 => Dataset::Nodes(geometry::parse_15(ds)?),
        2411 => Dataset::Nodes(geometry::parse_2411(ds)?),
        2412 => Dataset::Elements(geometry::parse_2412(ds)?),
        82 => Dataset::TraceLine(geometry::parse_82(ds)?),
        18 => Dataset::CoordinateSystems(geometry::parse_18(ds)?),
        2420 => Dataset::CoordinateSystems(geometry::parse_2420(ds)?),
        _ => return Ok(None),
    }))
}

/// Reads every dataset of a UFF stream (default options).
///
/// # Errors
/// The first [`UffError`] of the stream, naming its line.
pub fn read<R: BufRead>(input: R) -> Result<UffFile, UffError> {
    read_with(input, ReadOptions::default())
}

/// Reads every dataset of a UFF stream with `options`.
///
/// The stream is scanned in order; the datasets scanned are decoded in batches of about
/// [`BATCH_BYTES`], the datasets of a batch in parallel, so that a file of many long records
/// is not decoded on one core while at most a batch's raw bytes wait in memory. Errors come in
/// the stream's order: a dataset's decoding error before a later one's framing error.
///
/// # Errors
/// The first [`UffError`] of the stream, naming its line.
pub fn read_with<R: BufRead>(input: R, options: ReadOptions) -> Result<UffFile, UffError> {
    let mut scanner = Scanner::new(input).lenient(options.lenient_counts);
    let mut file = UffFile::default();
    let (mut batch, mut bytes) = (Vec::new(), 0);
    loop {
        // Some(the end or the framing error) once the stream has no more datasets to give.
        let end = match scanner.next_dataset() {
            Ok(Some(ds)) => {
                bytes += ds.payload.len() + ds.lines.iter().map(|(_, l)| l.len()).sum::<usize>();
                batch.push(ds);
                None
            }
            Ok(None) => Some(Ok(())),
            Err(e) => Some(Err(e)),
        };
        if end.is_some() || bytes >= BATCH_BYTES {
            decode_batch(std::mem::take(&mut batch), options, &mut file)?;
            bytes = 0;
        }
        if let Some(end) = end {
            return end.map(|()| file);
        }
    }
}

/// Raw bytes (binary payloads and record lines) scanned before [`read_with`] decodes them.
pub const BATCH_BYTES: usize = 32 << 20;

/// Decodes `batch` (datasets in the stream's order) in parallel into `file`, with their notices
/// in that order.
///
/// # Errors
/// The first dataset's error, in the batch's order.
fn decode_batch(
    batch: Vec<RawDataset>,
    options: ReadOptions,
    file: &mut UffFile,
) -> Result<(), UffError> {
    use rayon::prelude::*;
    let decoded: Vec<_> = batch
        .par_iter()
        .map(|ds| {
            let mut notices = Vec::new();
            decode(ds, options, &mut notices).map(|d| (d, notices))
        })
        .collect();
    for (ds, result) in batch.iter().zip(decoded) {
        file.notices.extend(ds.notice.clone());
        let (dataset, notices) = result?;
        file.notices.extend(notices);
        match dataset {
            Some(dataset) => file.datasets.push(Located {
                line: ds.line,
                binary: ds.binary.is_some(),
                dataset,
            }),
            None => file.notices.push(format!(
                "line {}: dataset {} skipped (not supported)",
                ds.line, ds.number
            )),
        }
    }
    Ok(())
}

/// Reads a UFF file from disk; errors name the file.
///
/// # Errors
/// [`UffError::Open`] for a file that cannot be opened, [`UffError::InFile`] (`'path' line N:
/// ...`) for malformed content.
pub fn read_path(path: &std::path::Path, options: ReadOptions) -> Result<UffFile, UffError> {
    let path_text = || path.display().to_string();
    let f = std::fs::File::open(path).map_err(|e| UffError::Open {
        path: path_text(),
        reason: e.to_string(),
    })?;
    read_with(std::io::BufReader::with_capacity(1 << 16, f), options).map_err(|e| {
        UffError::InFile {
            path: path_text(),
            source: Box::new(e),
        }
    })
}

/// One dataset of a listing.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Entry {
    /// Dataset number.
    pub number: u32,
    /// Line of the dataset number.
    pub line: usize,
    /// Byte offset of its opening delimiter.
    pub offset: u64,
    /// Binary (58b).
    pub binary: bool,
    /// Whether this crate reads it.
    pub supported: bool,
    /// One line: for 58 the function, DOFs and axis; for others the record count.
    pub summary: String,
}

/// Lists the datasets of a stream without keeping their data: for each one its number, line,
/// offset and a summary from its header records.
///
/// # Errors
/// The first framing error ([`scan::Scanner::next_dataset`]) or a bad 58 header.
pub fn list<R: BufRead>(input: R) -> Result<Vec<Entry>, UffError> {
    let mut scanner = Scanner::listing(input, 11);
    let mut out = Vec::new();
    while let Some(ds) = scanner.next_dataset()? {
        let summary = match ds.number {
            58 => {
                let (f, n) = d58::parse_header(&ds)?;
                let x = match f.abscissa {
                    d58::Abscissa::Even { start, step } => format!(
                        "{} to {} step {}",
                        start,
                        start + step * n.saturating_sub(1) as f64,
                        step
                    ),
                    d58::Abscissa::Uneven(_) => "uneven abscissa".into(),
                };
                format!(
                    "function type {} '{}': {}:{}{:+} / {}:{}{:+}, {n} {:?} points, {x} {}, \
                     ordinate {} / {}",
                    f.function_type,
                    f.id_lines[0].trim(),
                    f.response.entity,
                    f.response.node,
                    f.response.direction,
                    f.reference.entity,
                    f.reference.node,
                    f.reference.direction,
                    f.ordinate_type,
                    f.axes[0].units,
                    f.axes[1].units,
                    f.axes[2].units
                )
            }
            _ => format!("{} record lines", ds.n_lines),
        };
        out.push(Entry {
            number: ds.number,
            line: ds.line,
            offset: ds.offset,
            binary: ds.binary.is_some(),
            supported: SUPPORTED.contains(&ds.number),
            summary,
        });
    }
    Ok(out)
}

/// Re-encodes a UFF stream: datasets 58 are rewritten in `encoding` (ASCII, or binary 58b in
/// the given byte order); every other dataset, known or not, is copied line for line. Returns
/// the new file and the notices of lenient reading.
///
/// # Errors
/// The first framing or dataset-58 error of the input ([`UffError::Syntax`], naming the line)
/// or a 58 that cannot be written.
pub fn reencode<R: BufRead>(
    input: R,
    encoding: Encoding,
    options: ReadOptions,
) -> Result<(Vec<u8>, Vec<String>), UffError> {
    let mut scanner = Scanner::new(input).lenient(options.lenient_counts);
    let (mut out, mut notices) = (Vec::new(), Vec::new());
    while let Some(ds) = scanner.next_dataset()? {
        notices.extend(ds.notice.clone());
        if ds.number == 58 {
            let (f, notice) = d58::parse(&ds, options.lenient_counts)?;
            notices.extend(notice);
            out.extend(write(&[Dataset::Function(Box::new(f))], encoding)?);
        } else {
            out.extend_from_slice(b"    -1\n");
            out.extend(ds.header.chars().map(|c| c as u32 as u8));
            out.push(b'\n');
            for (_, l) in &ds.lines {
                out.extend(l.chars().map(|c| c as u32 as u8));
                out.push(b'\n');
            }
            out.extend_from_slice(b"    -1\n");
        }
    }
    Ok((out, notices))
}

/// How a file is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// Every dataset in ASCII.
    Ascii,
    /// Datasets 58 as binary 58b in this byte order (true: little endian), the rest ASCII.
    Binary {
        /// Little endian.
        little_endian: bool,
    },
}

/// Writes datasets (58, 55, 151, 164, 15, 2411; others are refused).
///
/// # Errors
/// [`UffError::Write`] for a dataset that cannot be written (see each writer) or a kind without
/// a writer.
pub fn write(datasets: &[Dataset], encoding: Encoding) -> Result<Vec<u8>, UffError> {
    let mut out = Vec::new();
    for d in datasets {
        let mut s = String::new();
        match d {
            Dataset::Function(f) => match encoding {
                Encoding::Ascii => d58::write_ascii(f, &mut s)?,
                Encoding::Binary { little_endian } => {
                    d58::write_binary(f, little_endian, &mut out)?;
                    continue;
                }
            },
            Dataset::NodalData(m) => d55::write(m, &mut s)?,
            Dataset::Header(h) => meta::write_151(h, &mut s),
            Dataset::Units(u) => meta::write_164(u, &mut s)?,
            Dataset::Nodes(n) if n.dataset == 15 => geometry::write_15(&n.nodes, &mut s)?,
            Dataset::Nodes(n) => geometry::write_2411(&n.nodes, &mut s)?,
            other => {
                return Err(UffError::Write(format!(
                    "no writer for {}",
                    match other {
                        Dataset::Elements(_) => "dataset 2412",
                        Dataset::TraceLine(_) => "dataset 82",
                        _ => "coordinate systems (18, 2420)",
                    }
                )));
            }
        }
        out.extend_from_slice(s.as_bytes());
    }
    Ok(out)
}
