//! Datasets 151 (header) and 164 (units).
//!
//! 151: model file name, description, program, then creation and save dates (free text lines,
//! kept as read). 164 (I10,20A1,I10 / 3D25.17 / D25.17): units code, description, temperature
//! mode (1 absolute, 2 relative); the factors that convert the file's length, force and
//! temperature units to SI (value_SI = value_file × factor), and the temperature offset.
//! A quantity with unit exponents (l, f, t) — records 8–11 of dataset 58 — converts to SI by
//! L^l · F^f · T^t.

use crate::d58::e25;
use crate::error::{UffError, syntax};
use crate::fields::{cols, int_field, numbers, record};
use crate::scan::RawDataset;
use serde::Serialize;
use std::fmt::Write as _;

/// Dataset 151: free-text header lines.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Header151 {
    /// The record lines as read (model name, description, program, dates).
    pub lines: Vec<String>,
}

/// The program that lamdyn names in record 6 of its 151 headers ("program which created the
/// universal file"), followed by its version: how [`written_by_lamdyn`] knows lamdyn's files.
pub const PROGRAM: &str = "lamdyn";

impl Header151 {
    /// lamdyn's header: model name and description `description`, lamdyn (and its version)
    /// as the program of the database and of the file (records 3 and 6), dates "NONE" so that
    /// equal inputs write equal files.
    pub fn lamdyn(description: &str) -> Self {
        let program = format!("{PROGRAM} {}", env!("CARGO_PKG_VERSION"));
        let no_date = format!("{:<10}{:<10}", "NONE", "NONE");
        Self {
            lines: vec![
                description.to_string(),
                description.to_string(),
                program.clone(),
                format!("{no_date}{:>10}{:>10}{:>10}", 0, 0, 0),
                no_date.clone(),
                program,
                no_date,
            ],
        }
    }
}

/// Whether `head`, the first bytes of a file, opens with lamdyn's 151 header (record 6 names
/// [`PROGRAM`]): lamdyn replaces only universal files it wrote. Reads at most the header's
/// eight lines.
pub fn written_by_lamdyn(head: &[u8]) -> bool {
    let text = String::from_utf8_lossy(head);
    let mut lines = text.lines().skip_while(|l| l.trim().is_empty());
    let opens = lines.next().map(str::trim) == Some("-1")
        && lines.next().and_then(|l| l.split_whitespace().next()) == Some("151");
    let program = lines.nth(5).unwrap_or("");
    opens
        && program
            .strip_prefix(PROGRAM)
            .is_some_and(|rest| rest.is_empty() || rest.starts_with(' '))
}

/// Dataset 164: the file's units.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Units164 {
    /// Units code (1 SI, 2 BG, 3 MG, 4 BA, 5 MM, 6 CM, 7 IN, 8 GM, 9 US, 10 MN; 0 user).
    pub code: i64,
    /// Description.
    pub description: String,
    /// Temperature mode: 1 absolute, 2 relative.
    pub temperature_mode: i64,
    /// Length factor to metres.
    pub length: f64,
    /// Force factor to newtons.
    pub force: f64,
    /// Temperature factor to kelvin.
    pub temperature: f64,
    /// Temperature offset.
    pub temperature_offset: f64,
}

impl Units164 {
    /// SI: every factor 1.
    pub fn si() -> Self {
        Self {
            code: 1,
            description: "SI".into(),
            temperature_mode: 2,
            length: 1.0,
            force: 1.0,
            temperature: 1.0,
            temperature_offset: 0.0,
        }
    }

    /// The factor L^l F^f T^t that converts a quantity with these unit exponents to SI.
    pub fn factor(&self, length_exp: i64, force_exp: i64, temperature_exp: i64) -> f64 {
        let p = |b: f64, e: i64| b.powi(e.clamp(-64, 64) as i32);
        p(self.length, length_exp) * p(self.force, force_exp) * p(self.temperature, temperature_exp)
    }
}

/// Parses a dataset 151.
pub fn parse_151(ds: &RawDataset) -> Header151 {
    Header151 {
        lines: ds
            .lines
            .iter()
            .map(|(_, l)| l.trim_end().to_string())
            .collect(),
    }
}

/// Parses a dataset 164.
///
/// # Errors
/// [`UffError::Syntax`] naming the line: bad integers, fewer than four factors, factors that
/// are not positive.
pub fn parse_164(ds: &RawDataset) -> Result<Units164, UffError> {
    let (a1, r1) = record(&ds.lines, 0, ds.line, "record 1 (units code)")?;
    let code = int_field(r1, 0, 10, 0, a1, "record 1 units code")?;
    let description = cols(r1, 10, 30).trim().to_string();
    let temperature_mode = int_field(r1, 30, 40, 2, a1, "record 1 temperature mode")?;
    let mut v = Vec::new();
    numbers(&ds.lines[1.min(ds.lines.len())..], &mut v)?;
    if v.len() < 4 {
        return Err(syntax(
            ds.lines.last().map_or(ds.line, |l| l.0),
            format!(
                "dataset 164: {} unit factors, expected 4 (length, force, temperature, offset)",
                v.len()
            ),
        ));
    }
    for (k, name) in ["length", "force", "temperature"].iter().enumerate() {
        if v[k] <= 0.0 {
            return Err(syntax(
                ds.line + 2,
                format!("dataset 164: {name} factor {} must be positive", v[k]),
            ));
        }
    }
    Ok(Units164 {
        code,
        description,
        temperature_mode,
        length: v[0],
        force: v[1],
        temperature: v[2],
        temperature_offset: v[3],
    })
}

/// Writes a dataset 151.
pub fn write_151(h: &Header151, out: &mut String) {
    out.push_str("    -1\n   151\n");
    for l in &h.lines {
        let _ = writeln!(out, "{l}");
    }
    out.push_str("    -1\n");
}

/// Writes a dataset 164.
///
/// # Errors
/// [`UffError::Write`] for a description over 20 characters or a non-finite factor.
pub fn write_164(u: &Units164, out: &mut String) -> Result<(), UffError> {
    if u.description.chars().count() > 20 {
        return Err(UffError::Write(format!(
            "units description '{}' is longer than 20 characters",
            u.description
        )));
    }
    if ![u.length, u.force, u.temperature, u.temperature_offset]
        .iter()
        .all(|v| v.is_finite())
    {
        return Err(UffError::Write(
            "dataset 164 with a non-finite factor".into(),
        ));
    }
    let _ = writeln!(
        out,
        "    -1\n   164\n{:>10}{:<20}{:>10}",
        u.code, u.description, u.temperature_mode
    );
    let _ = writeln!(
        out,
        "{}{}{}\n{}\n    -1",
        e25(u.length),
        e25(u.force),
        e25(u.temperature),
        e25(u.temperature_offset)
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// lamdyn's own header is recognised in either encoding's file; another program's 151, a
    /// file that opens with another dataset and a program name that only starts like lamdyn's
    /// are not.
    #[test]
    fn lamdyn_knows_its_own_header() {
        let mut own = String::new();
        write_151(&Header151::lamdyn("FRFs"), &mut own);
        assert!(written_by_lamdyn(own.as_bytes()));
        assert!(written_by_lamdyn(
            format!("\n{own}    -1\n    58b ...").as_bytes()
        ));
        let ours = format!("{PROGRAM} ");
        let foreign = own.replace(&ours, "pyuff ");
        assert!(!written_by_lamdyn(foreign.as_bytes()));
        let lookalike = own.replace(&ours, "lamdyn-clone ");
        assert!(!written_by_lamdyn(lookalike.as_bytes()));
        assert!(!written_by_lamdyn(b"    -1\n  2411\n"));
        assert!(!written_by_lamdyn(b""));
        assert!(!written_by_lamdyn(&[0xff, 0xfe, 0x00]));
    }
}
