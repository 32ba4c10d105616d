//! Splitting a UFF stream into datasets.
//!
//! A dataset is framed by delimiter lines `    -1` (format I6): the first line after the opening
//! delimiter holds the dataset number (I6), the following lines its records, and the next
//! delimiter closes it. A binary dataset 58 announces itself as `58b` with the header
//! (I6,1A1,I6,I6,I12,I12,I6,I6,I12,I12): byte order (1 little endian, 2 big endian), floating
//! point format (2 = IEEE 754), the number of ASCII lines that follow (11, records 1–11) and the
//! number of bytes of binary data after them. The byte count is checked: the closing delimiter
//! must follow the data directly.
//!
//! Lines may end in LF or CRLF; text is read as Latin-1 so that any byte sequence is accepted
//! (vendor files carry non-ASCII labels).

use crate::error::{UffError, syntax};
use std::io::{BufRead, Read};

/// The header of a binary dataset 58b.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BinaryHeader {
    /// True for little endian (code 1), false for big endian (code 2).
    pub little_endian: bool,
    /// Floating point format code (2 = IEEE 754; others are rejected when decoding).
    pub float_format: i64,
    /// ASCII lines between the header and the data.
    pub ascii_lines: usize,
    /// Bytes of binary data.
    pub bytes: usize,
}

/// One dataset as found in the stream: its number, where it starts, its ASCII lines (with their
/// line numbers) and, for 58b, its binary data.
#[derive(Debug, Clone)]
pub struct RawDataset {
    /// Dataset number (58, 2411, ...).
    pub number: u32,
    /// The dataset-number line as read.
    pub header: String,
    /// Line of the dataset number (1-based).
    pub line: usize,
    /// Byte offset of the opening delimiter in the stream.
    pub offset: u64,
    /// The 58b header, for binary datasets.
    pub binary: Option<BinaryHeader>,
    /// Record lines (number, text without the line end); all of them, or the first
    /// `keep_lines` when listing.
    pub lines: Vec<(usize, String)>,
    /// Total number of record lines (ASCII), also when not all were kept.
    pub n_lines: usize,
    /// Binary data (empty when listing or for ASCII datasets).
    pub payload: Vec<u8>,
    /// A remark about a tolerated defect (lenient reading).
    pub notice: Option<String>,
}

/// Reads datasets one at a time from a buffered stream.
pub struct Scanner<R: BufRead> {
    input: R,
    line: usize,
    offset: u64,
    buf: Vec<u8>,
    keep_lines: usize,
    keep_payload: bool,
    lenient: bool,
}

fn latin1(bytes: &[u8]) -> String {
    bytes.iter().map(|&b| b as char).collect()
}

/// Newline bytes in `b`, counted in u8 lanes over chunks of 255 (vectorizes well).
fn count_newlines(b: &[u8]) -> usize {
    b.chunks(255)
        .map(|c| {
            usize::from(
                c.iter()
                    .map(|&x| u8::from(x == b'\n'))
                    .fold(0u8, u8::wrapping_add),
            )
        })
        .sum()
}

/// `    -1` (possibly with trailing blanks): a delimiter. A longer field holding -1 (a data value
/// in I10) is not.
fn is_delimiter(line: &[u8]) -> bool {
    let end = line
        .iter()
        .rposition(|b| !b.is_ascii_whitespace())
        .map_or(0, |p| p + 1);
    let t = &line[..end];
    t.len() <= 6
        && t.len() >= 2
        && t.ends_with(b"-1")
        && t[..t.len() - 2].iter().all(|b| *b == b' ')
}

impl<R: BufRead> Scanner<R> {
    /// A scanner that keeps every line and the binary data.
    pub fn new(input: R) -> Self {
        Self {
            input,
            line: 0,
            offset: 0,
            buf: Vec::new(),
            keep_lines: usize::MAX,
            keep_payload: true,
            lenient: false,
        }
    }

    /// Lenient framing: a 58b whose header byte count differs from the size its records 6–7
    /// give (points × bytes per point) is read with the latter, and a notice says so. pyuff
    /// 2.5.8 writes points × 8 for complex double data, half the true size.
    pub fn lenient(mut self, lenient: bool) -> Self {
        self.lenient = lenient;
        self
    }

    /// A scanner for listing: keeps only the first `keep_lines` lines of each dataset and skips
    /// binary data.
    pub fn listing(input: R, keep_lines: usize) -> Self {
        Self {
            keep_lines,
            keep_payload: false,
            ..Self::new(input)
        }
    }

    /// The next line without its line end, or `None` at the end of the stream.
    fn next_line(&mut self) -> Result<Option<usize>, UffError> {
        self.buf.clear();
        let n = self
            .input
            .read_until(b'\n', &mut self.buf)
            .map_err(|e| syntax(self.line + 1, format!("read error: {e}")))?;
        if n == 0 {
            return Ok(None);
        }
        self.offset += n as u64;
        self.line += 1;
        while matches!(self.buf.last(), Some(b'\n' | b'\r')) {
            self.buf.pop();
        }
        Ok(Some(self.line))
    }

    /// The next dataset, or `None` after the last one.
    ///
    /// # Errors
    /// [`UffError::Syntax`] naming the line: a dataset without a closing delimiter (truncated
    /// file), a bad dataset number, a 58b header that does not parse, binary data shorter or
    /// longer than its byte count.
    pub fn next_dataset(&mut self) -> Result<Option<RawDataset>, UffError> {
        // Find an opening delimiter; blank lines between datasets are allowed.
        let mut start = self.offset;
        loop {
            match self.next_line()? {
                None => return Ok(None),
                Some(_) if is_delimiter(&self.buf) => break,
                Some(l) if self.buf.iter().all(u8::is_ascii_whitespace) => {
                    let _ = l;
                    start = self.offset;
                }
                Some(l) => {
                    let what = if l == 1 {
                        "not a universal file: it must start with a dataset delimiter '    -1'"
                    } else {
                        "expected a dataset delimiter '    -1'"
                    };
                    return Err(syntax(l, format!("{what}, found '{}'", excerpt(&self.buf))));
                }
            }
        }
        // The dataset number; a repeated delimiter is skipped.
        let number_line = loop {
            match self.next_line()? {
                None => return Ok(None),
                Some(_) if is_delimiter(&self.buf) => continue,
                Some(l) => break l,
            }
        };
        let head = latin1(&self.buf);
        let mut tokens = head.split_whitespace();
        let first = tokens.next().unwrap_or("");
        let (digits, binary) = match first.strip_suffix(['b', 'B']) {
            Some(d) => (d, true),
            None => (first, false),
        };
        let number: u32 = digits.parse().map_err(|_| {
            syntax(
                number_line,
                format!("'{}' is not a dataset number", head.trim()),
            )
        })?;
        let binary = if binary {
            let v: Vec<i64> = tokens
                .map(|t| t.parse::<i64>())
                .collect::<Result<_, _>>()
                .map_err(|_| {
                    syntax(
                        number_line,
                        format!("58b header '{}' does not parse", head.trim()),
                    )
                })?;
            if v.len() < 4 || v[2] < 0 || v[3] < 0 {
                return Err(syntax(
                    number_line,
                    format!(
                        "58b header '{}': expected byte order, float format, ASCII line count and \
                         byte count",
                        head.trim()
                    ),
                ));
            }
            let little_endian = match v[0] {
                1 => true,
                2 => false,
                o => {
                    return Err(syntax(
                        number_line,
                        format!("58b byte order {o}: must be 1 (little endian) or 2 (big endian)"),
                    ));
                }
            };
            Some(BinaryHeader {
                little_endian,
                float_format: v[1],
                ascii_lines: v[2] as usize,
                bytes: v[3] as usize,
            })
        } else {
            None
        };
        let mut ds = RawDataset {
            number,
            header: head.trim_end().to_string(),
            line: number_line,
            offset: start,
            binary,
            lines: Vec::new(),
            n_lines: 0,
            payload: Vec::new(),
            notice: None,
        };
        match binary {
            Some(h) => self.read_binary(&mut ds, h)?,
            None => self.read_ascii(&mut ds)?,
        }
        Ok(Some(ds))
    }

    fn keep(&mut self, ds: &mut RawDataset, line: usize) {
        ds.n_lines += 1;
        if ds.lines.len() < self.keep_lines {
            ds.lines.push((line, latin1(&self.buf)));
        }
    }

    fn read_ascii(&mut self, ds: &mut RawDataset) -> Result<(), UffError> {
        loop {
            match self.next_line()? {
                None => {
                    return Err(syntax(
                        self.line,
                        format!(
                            "dataset {} starting at line {} ends without its closing '    -1' \
                             (truncated file?)",
                            ds.number, ds.line
                        ),
                    ));
                }
                Some(_) if is_delimiter(&self.buf) => return Ok(()),
                Some(l) => self.keep(ds, l),
            }
        }
    }

    fn read_binary(&mut self, ds: &mut RawDataset, h: BinaryHeader) -> Result<(), UffError> {
        for _ in 0..h.ascii_lines {
            match self.next_line()? {
                None => {
                    return Err(syntax(
                        self.line,
                        format!(
                            "dataset 58b at line {} ends inside its {} ASCII records",
                            ds.line, h.ascii_lines
                        ),
                    ));
                }
                Some(l) => self.keep(ds, l),
            }
        }
        let data_line = self.line + 1;
        let mut bytes = h.bytes;
        if self.lenient {
            if let Some(layout) = crate::record7::layout_bytes(&ds.lines) {
                if layout != h.bytes {
                    ds.notice = Some(format!(
                        "line {}: dataset 58b header gives {} bytes, its records 6-7 {layout}: \
                         read {layout}",
                        ds.line, h.bytes
                    ));
                    bytes = layout;
                }
            }
        }
        let short = |_: std::io::Error| {
            syntax(
                data_line,
                format!(
                    "dataset 58b at line {}: the header gives {} bytes of data but the file ends \
                     before",
                    ds.line, bytes
                ),
            )
        };
        let eof = || std::io::Error::from(std::io::ErrorKind::UnexpectedEof);
        let payload = if self.keep_payload {
            // Grown as it is read, so that a header claiming a huge size cannot allocate it.
            let mut p = Vec::with_capacity(bytes.min(1 << 26));
            let got = (&mut self.input)
                .take(bytes as u64)
                .read_to_end(&mut p)
                .map_err(short)?;
            if got != bytes {
                return Err(short(eof()));
            }
            p
        } else {
            let skipped = std::io::copy(
                &mut (&mut self.input).take(bytes as u64),
                &mut std::io::sink(),
            )
            .map_err(short)?;
            if skipped != bytes as u64 {
                return Err(short(eof()));
            }
            Vec::new()
        };
        self.offset += bytes as u64;
        // Line numbers after binary data count the newline bytes inside it.
        if self.keep_payload {
            self.line += count_newlines(&payload);
        }
        ds.payload = payload;
        // The data is followed by an optional line end, then the delimiter.
        match self.next_line()? {
            Some(_) if self.buf.is_empty() || is_delimiter(&self.buf) => {}
            _ => {
                return Err(syntax(
                    data_line,
                    format!(
                        "dataset 58b at line {}: binary data longer than the {} bytes its header \
                         gives (wrong byte count)",
                        ds.line, h.bytes
                    ),
                ));
            }
        }
        if !is_delimiter(&self.buf) {
            match self.next_line()? {
                Some(_) if is_delimiter(&self.buf) => {}
                _ => {
                    return Err(syntax(
                        data_line,
                        format!(
                            "dataset 58b at line {}: no closing '    -1' after its {} bytes of \
                             data (wrong byte count?)",
                            ds.line, h.bytes
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// The start of a line for a message: at most 40 characters, control and non-ASCII bytes
/// escaped (a binary file must not reach the terminal raw).
fn excerpt(line: &[u8]) -> String {
    let text: String = line
        .iter()
        .take(40)
        .flat_map(|b| std::ascii::escape_default(*b))
        .map(char::from)
        .collect();
    let text = text.trim_end().to_string();
    if line.len() > 40 { text + "..." } else { text }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newline_count() {
        let b: Vec<u8> = (0..10_000u32)
            .map(|i| {
                if i % 7 == 0 {
                    b'\n'
                } else {
                    (i % 251) as u8 | 1
                }
            })
            .collect();
        assert_eq!(
            count_newlines(&b),
            b.iter().filter(|x| **x == b'\n').count()
        );
    }

    #[test]
    fn delimiters() {
        assert!(is_delimiter(b"    -1"));
        assert!(is_delimiter(b"    -1   "));
        assert!(is_delimiter(b"-1"));
        assert!(!is_delimiter(b"        -1"));
        assert!(!is_delimiter(b"    -1    -1"));
        assert!(!is_delimiter(b"   1-1"));
    }

    #[test]
    fn splits_datasets_and_reports_truncation() {
        let text = "    -1\n    15\n a\n    -1\n\n    -1\n   164\n b\n c\n    -1\n";
        let mut s = Scanner::new(text.as_bytes());
        let a = s.next_dataset().unwrap().unwrap();
        assert_eq!((a.number, a.line, a.lines.len()), (15, 2, 1));
        let b = s.next_dataset().unwrap().unwrap();
        assert_eq!((b.number, b.line, b.lines[1].0), (164, 7, 9));
        assert!(s.next_dataset().unwrap().is_none());
        let err = Scanner::new("    -1\n    15\n a\n".as_bytes())
            .next_dataset()
            .unwrap_err();
        assert!(err.to_string().contains("truncated"), "{err}");
    }
}
