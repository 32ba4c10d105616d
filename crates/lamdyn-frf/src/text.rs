//! Text files as instruments and spreadsheets write them.
//!
//! **Encoding** ([`decode`]): UTF-8, with or without a byte-order mark; UTF-16 (little or big
//! endian) with its byte-order mark; anything else is read as Latin-1 (ISO 8859-1: each byte
//! is the character of that code point), which many acquisition systems still write ("µm",
//! "°C" in comments and headers). Numbers are ASCII in all of them, so the fallback never
//! changes a value.
//!
//! **Separators** ([`Dialect`]): commas; or semicolons, with decimal commas allowed in numbers
//! (`1,5` = 1.5), as spreadsheets write CSV in locales whose decimal mark is the comma; or
//! tabs (decimal commas allowed too). The separator is detected from the header line.

use crate::FrfError;
use std::path::Path;

/// How a file's bytes were decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// UTF-8 (a byte-order mark, if any, removed).
    Utf8,
    /// UTF-16 with a byte-order mark.
    Utf16,
    /// Not UTF-8: read as Latin-1.
    Latin1,
}

/// The text of `bytes` (module docs) and how it was decoded.
pub fn decode(bytes: &[u8]) -> (String, Encoding) {
    if let Some(rest) = bytes.strip_prefix(b"\xEF\xBB\xBF") {
        if let Ok(s) = std::str::from_utf8(rest) {
            return (s.to_string(), Encoding::Utf8);
        }
    }
    let utf16 = |rest: &[u8], little: bool| {
        let units: Vec<u16> = rest
            .chunks_exact(2)
            .map(|c| {
                if little {
                    u16::from_le_bytes([c[0], c[1]])
                } else {
                    u16::from_be_bytes([c[0], c[1]])
                }
            })
            .collect();
        String::from_utf16(&units).ok()
    };
    if let Some(rest) = bytes.strip_prefix(b"\xFF\xFE") {
        if let Some(s) = utf16(rest, true) {
            return (s, Encoding::Utf16);
        }
    }
    if let Some(rest) = bytes.strip_prefix(b"\xFE\xFF") {
        if let Some(s) = utf16(rest, false) {
            return (s, Encoding::Utf16);
        }
    }
    match std::str::from_utf8(bytes) {
        Ok(s) => (s.to_string(), Encoding::Utf8),
        Err(_) => (
            bytes.iter().map(|&b| char::from(b)).collect(),
            Encoding::Latin1,
        ),
    }
}

/// Reads a text file (module docs); the error names the file.
///
/// # Errors
/// [`FrfError::File`] when the file cannot be read.
pub fn read_text(path: &Path) -> Result<String, FrfError> {
    let bytes = std::fs::read(path).map_err(|e| FrfError::File {
        path: path.display().to_string(),
        line: 0,
        reason: format!("cannot read it: {e}"),
    })?;
    Ok(decode(&bytes).0)
}

/// The separator of a CSV file and whether numbers may use a decimal comma.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dialect {
    /// `,`, `;` or a tab.
    pub separator: char,
    /// Numbers may be written `1,5` (only with `;` or tab separators).
    pub decimal_comma: bool,
}

impl Default for Dialect {
    fn default() -> Self {
        Self {
            separator: ',',
            decimal_comma: false,
        }
    }
}

impl Dialect {
    /// The dialect of a header line: `;` if it holds semicolons and no commas, a tab if it
    /// holds tabs and neither, else `,`.
    pub fn detect(header: &str) -> Self {
        let separator = if header.contains(';') && !header.contains(',') {
            ';'
        } else if header.contains('\t') && !header.contains(',') && !header.contains(';') {
            '\t'
        } else {
            ','
        };
        Self {
            separator,
            decimal_comma: separator != ',',
        }
    }

    /// The trimmed fields of a line.
    pub fn split<'a>(&self, line: &'a str) -> Vec<&'a str> {
        line.split(self.separator).map(str::trim).collect()
    }

    /// A field as a finite number (a decimal comma read as a point where allowed).
    pub fn number(&self, field: &str) -> Option<f64> {
        let v: f64 = if self.decimal_comma && field.contains(',') {
            if field.contains('.') {
                return None;
            }
            field.replace(',', ".").parse().ok()?
        } else {
            field.parse().ok()?
        };
        v.is_finite().then_some(v)
    }

    /// How the dialect reads in a message ("semicolon-separated, decimal commas").
    pub fn describe(&self) -> &'static str {
        match self.separator {
            ';' => "semicolon-separated, decimal commas allowed",
            '\t' => "tab-separated, decimal commas allowed",
            _ => "comma-separated",
        }
    }
}

/// The data lines of a CSV text: (1-based line number, trimmed line), comments (`#`) and blank
/// lines skipped.
pub fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
}

/// Characters of a field that an error quotes.
const QUOTED: usize = 40;

/// A field of a file as an error quotes it: at most 40 characters, control characters,
/// quotes and backslashes escaped, a cut marked with "...".
pub fn quoted(field: &str) -> String {
    let mut out = String::new();
    for c in field.chars().take(QUOTED) {
        if c.is_control() || c == '\'' || c == '\\' {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    if field.chars().nth(QUOTED).is_some() {
        out.push_str("...");
    }
    out
}

/// A number for a message: six significant digits, plain between 1e-4 and 1e6, scientific
/// outside (never the 20 digits of `{}` nor the 300 of a fixed format of 1e300).
pub fn short(x: f64) -> String {
    if !x.is_finite() || x == 0.0 {
        return format!("{x}");
    }
    let a = x.abs();
    if (1e-4..1e6).contains(&a) {
        let digits = (5 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{x:.digits$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let s = format!("{x:.5e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = if m.contains('.') {
            m.trim_end_matches('0').trim_end_matches('.')
        } else {
            m
        };
        format!("{m}e{e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encodings_give_the_same_text() {
        let text = "# µ-sensor, 20 °C\nf_hz,a\n1,2\n";
        let utf8 = text.as_bytes().to_vec();
        let mut bom = b"\xEF\xBB\xBF".to_vec();
        bom.extend_from_slice(&utf8);
        let latin1: Vec<u8> = text.chars().map(|c| c as u32 as u8).collect();
        let mut utf16 = b"\xFF\xFE".to_vec();
        for u in text.encode_utf16() {
            utf16.extend_from_slice(&u.to_le_bytes());
        }
        assert_eq!(decode(&utf8), (text.to_string(), Encoding::Utf8));
        assert_eq!(decode(&bom), (text.to_string(), Encoding::Utf8));
        assert_eq!(decode(&latin1), (text.to_string(), Encoding::Latin1));
        assert_eq!(decode(&utf16), (text.to_string(), Encoding::Utf16));
    }

    #[test]
    fn quoted_fields_are_bounded_and_escaped() {
        assert_eq!(quoted("a\u{1b}[2J'b"), "a\\u{1b}[2J\\'b");
        let long = "x".repeat(1000);
        assert_eq!(quoted(&long), format!("{}...", "x".repeat(40)));
        assert_eq!(quoted("é"), "é");
    }

    #[test]
    fn short_numbers() {
        assert_eq!(short(0.00007812399999999886), "7.8124e-5");
        assert_eq!(short(0.027304688), "0.0273047");
        assert_eq!(short(25600.0), "25600");
        assert_eq!(short(1.15e169), "1.15e169");
        assert_eq!(short(-3.0), "-3");
        assert_eq!(short(0.0), "0");
    }

    #[test]
    fn dialects_split_and_read_numbers() {
        let d = Dialect::detect("f_hz;a;b");
        assert_eq!(d.split("1,5; 2 ;-3e2"), ["1,5", "2", "-3e2"]);
        assert_eq!(d.number("1,5"), Some(1.5));
        assert_eq!(d.number("1.5"), Some(1.5));
        assert_eq!(d.number("1.000,5"), None);
        let c = Dialect::detect("f_hz,a");
        assert_eq!(c.number("1,5"), None);
        assert_eq!(c.number("NaN"), None);
        assert_eq!(Dialect::detect("f_hz\ta").separator, '\t');
    }
}
