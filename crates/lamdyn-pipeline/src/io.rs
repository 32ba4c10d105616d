//! Reading input files: text in any of the encodings instruments write
//! ([`lamdyn_frf::text`]), TOML into typed specs, and small numeric CSV tables with a header.

use crate::error::{Context, Result};
use crate::{bail, err};
use lamdyn_frf::text::{Dialect, Encoding, data_lines};
use serde::de::DeserializeOwned;
use std::path::Path;

/// The text of a file: UTF-8 (with or without a byte-order mark), UTF-16 with one, or Latin-1
/// ([`lamdyn_frf::text::decode`]); the error names the file.
///
/// # Errors
/// The file cannot be read (missing, a folder, no permission).
pub fn read_text(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read '{}'", path.display()))?;
    Ok(lamdyn_frf::text::decode(&bytes).0)
}

/// A note naming the encoding of a text file that is not UTF-8 ([`lamdyn_frf::text::decode`]
/// reads it anyway); `None` for UTF-8.
pub fn encoding_note(path: &Path, encoding: Encoding) -> Option<String> {
    match encoding {
        Encoding::Utf8 => None,
        Encoding::Utf16 => Some(format!(
            "'{}' is UTF-16 (it starts with a byte-order mark): read as UTF-16",
            path.display()
        )),
        Encoding::Latin1 => Some(format!(
            "'{}' is not UTF-8: read as Latin-1 (ISO 8859-1); if it was written in another \
             encoding, names and comments in it may be wrong: save it as UTF-8",
            path.display()
        )),
    }
}

/// Notes ([`encoding_note`]) for the text files among `paths` that are not UTF-8; files that
/// cannot be read and universal files ([`is_uff`], binary datasets allowed) are left to their
/// readers.
pub fn encoding_notes<'a>(paths: impl IntoIterator<Item = &'a Path>) -> Vec<String> {
    paths
        .into_iter()
        .filter(|p| !is_uff(p).unwrap_or(true))
        .filter_map(|p| {
            let bytes = std::fs::read(p).ok()?;
            encoding_note(p, lamdyn_frf::text::decode(&bytes).1)
        })
        .collect()
}

/// Whether a file is a universal file: its first non-blank line is the delimiter `-1`.
///
/// # Errors
/// The file cannot be opened or read.
pub fn is_uff(path: &Path) -> Result<bool> {
    use std::io::Read;
    let mut head = [0u8; 512];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .with_context(|| format!("cannot read '{}'", path.display()))?;
    Ok(String::from_utf8_lossy(&head[..n])
        .lines()
        .find(|l| !l.trim().is_empty())
        .is_some_and(|l| l.trim() == "-1"))
}

/// Reads and parses a TOML file; errors name the file and, from the parser, the line, column and
/// key.
///
/// # Errors
/// The file cannot be read or parsed.
pub fn read_toml<T: DeserializeOwned>(path: &Path) -> Result<T> {
    parse_toml(path, &read_text(path)?)
}

/// Parses `text`, read from `path`, as TOML; errors as [`read_toml`]'s, quoting at most a
/// bounded, escaped excerpt of the file.
///
/// # Errors
/// The text is not TOML or not of `T`'s schema.
pub fn parse_toml<T: DeserializeOwned>(path: &Path, text: &str) -> Result<T> {
    toml::from_str(text).map_err(|e| toml_error(path, text, &e))
}

/// Longest line of a file that an error quotes whole (the TOML parser's own message shows the
/// offending line with a caret); a longer one, or one with control characters (binary input),
/// is quoted as a bounded, escaped excerpt around the error.
const QUOTED_LINE: usize = 200;

/// The TOML parser's error `e` on `text`, naming `path`: its own message where the offending
/// line is short and printable, else the line, column, message and an excerpt of at most
/// [`EXCERPT`] characters with control characters escaped.
fn toml_error(path: &Path, text: &str, e: &toml::de::Error) -> crate::PipelineError {
    let Some(span) = e.span() else {
        return err!("error in '{}': {e}", path.display());
    };
    let at = span.start.min(text.len());
    let line_start = text[..at].rfind('\n').map_or(0, |k| k + 1);
    let line_end = text[at..].find('\n').map_or(text.len(), |k| at + k);
    let line = &text[line_start..line_end];
    let printable = !line
        .chars()
        .any(|c| c.is_control() && c != '\t' && c != '\r');
    if line.len() <= QUOTED_LINE && printable {
        return err!("error in '{}': {e}", path.display());
    }
    let line_no = text[..line_start].matches('\n').count() + 1;
    let column = text[line_start..at].chars().count() + 1;
    err!(
        "error in '{}': TOML parse error at line {line_no}, column {column}: {} (near \"{}\")",
        path.display(),
        e.message().trim_end(),
        excerpt(line, at - line_start)
    )
}

/// Characters of an excerpt quoted in an error.
pub const EXCERPT: usize = 80;

/// At most [`EXCERPT`] characters of `line` about byte `at`, control characters escaped and
/// cuts marked with "...".
pub fn excerpt(line: &str, at: usize) -> String {
    let at = (0..=at.min(line.len()))
        .rev()
        .find(|&k| line.is_char_boundary(k))
        .unwrap_or(0);
    let before: Vec<char> = line[..at].chars().rev().take(EXCERPT / 2).collect();
    let after: String = line[at..].chars().take(EXCERPT - before.len()).collect();
    let start = at - before.iter().map(|c| c.len_utf8()).sum::<usize>();
    let end = at + after.len();
    let mut out = String::new();
    if start > 0 {
        out.push_str("...");
    }
    for c in line[start..end].chars() {
        if c.is_control() || c == '"' || c == '\\' {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    if end < line.len() {
        out.push_str("...");
    }
    out
}

/// A CSV table of numbers with a header row. Blank lines and lines starting with `#` are
/// skipped; fields are separated by commas, or by semicolons or tabs with decimal commas
/// allowed (detected from the header, [`Dialect`]).
#[derive(Debug, Clone)]
pub struct CsvTable {
    path: String,
    headers: Vec<String>,
    rows: Vec<(usize, Vec<f64>)>,
}

impl CsvTable {
    /// Reads `path`.
    pub fn read(path: &Path) -> Result<Self> {
        Self::parse(&path.display().to_string(), &read_text(path)?)
    }

    /// Reads `path` where only the columns `wanted` must hold numbers: the others may hold
    /// text or nothing (read as NaN), as a table another tool wrote with columns this reader
    /// does not use.
    pub fn read_columns(path: &Path, wanted: &[&str]) -> Result<Self> {
        Self::parse_where(&path.display().to_string(), &read_text(path)?, &|h| {
            wanted.contains(&h)
        })
    }

    /// Parses `text`, naming `path` in errors.
    pub fn parse(path: &str, text: &str) -> Result<Self> {
        Self::parse_where(path, text, &|_| true)
    }

    /// [`CsvTable::parse`] where the columns `numeric` names must hold numbers and the others
    /// are NaN where they do not.
    fn parse_where(path: &str, text: &str, numeric: &dyn Fn(&str) -> bool) -> Result<Self> {
        let mut lines = data_lines(text);
        let Some((_, header)) = lines.next() else {
            bail!("'{path}' is empty: expected a header line of column names");
        };
        let dialect = Dialect::detect(header);
        let headers: Vec<String> = dialect
            .split(header)
            .into_iter()
            .map(String::from)
            .collect();
        let mut rows = Vec::new();
        for (line_no, line) in lines {
            let fields = dialect.split(line);
            if fields.len() != headers.len() {
                bail!(
                    "'{path}' line {line_no}: {} fields, but the header has {} ({})",
                    fields.len(),
                    headers.len(),
                    excerpt(&headers.join(","), 0)
                );
            }
            let values = fields
                .iter()
                .zip(&headers)
                .map(|(f, h)| match dialect.number(f) {
                    Some(v) => Ok(v),
                    None if !numeric(h) => Ok(f64::NAN),
                    None => Err(err!(
                        "'{path}' line {line_no}: column '{}': '{}' is not a finite number",
                        excerpt(h, 0),
                        excerpt(f, 0)
                    )),
                })
                .collect::<Result<Vec<f64>>>()?;
            rows.push((line_no, values));
        }
        if rows.is_empty() {
            bail!("'{path}' has a header but no data lines");
        }
        Ok(Self {
            path: path.to_string(),
            headers,
            rows,
        })
    }

    /// The file's name as given.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Index of column `name`, if present.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.headers.iter().position(|h| h == name)
    }

    /// Index of the first of `names` present, or an error listing what was expected.
    pub fn require_any(&self, names: &[&str]) -> Result<usize> {
        names.iter().find_map(|n| self.find(n)).ok_or_else(|| {
            err!(
                "'{}': no column {}; the header has: {}",
                self.path,
                names
                    .iter()
                    .map(|n| format!("'{n}'"))
                    .collect::<Vec<_>>()
                    .join(" or "),
                excerpt(&self.headers.join(","), 0)
            )
        })
    }

    /// Data rows as (line number, values).
    pub fn rows(&self) -> &[(usize, Vec<f64>)] {
        &self.rows
    }

    /// Checks that column `col` strictly increases and is positive.
    pub fn require_increasing_positive(&self, col: usize) -> Result<()> {
        let mut prev: Option<f64> = None;
        for (line, v) in &self.rows {
            let x = v[col];
            if x <= 0.0 {
                bail!(
                    "'{}' line {line}: column '{}' = {x} must be positive",
                    self.path,
                    excerpt(&self.headers[col], 0)
                );
            }
            if prev.is_some_and(|p| x <= p) {
                bail!(
                    "'{}' line {line}: column '{}' must increase ({x} after {})",
                    self.path,
                    excerpt(&self.headers[col], 0),
                    prev.unwrap_or_default()
                );
            }
            prev = Some(x);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    /// A text file in Latin-1 or UTF-16 is named with its encoding; UTF-8 (with or without a
    /// byte-order mark), a universal file with binary bytes and a missing file are not.
    #[test]
    fn files_not_in_utf8_are_named_with_their_encoding() {
        let dir = lamdyn_testkit::TempDir::new("io-encodings");
        let file = |name: &str, bytes: &[u8]| {
            let p = dir.to_path_buf().join(name);
            std::fs::write(&p, bytes).unwrap();
            p
        };
        let latin1 = file("latin1.csv", b"name,x_m\nr\xe9ponse 1,0.1\n");
        let utf16 = file("utf16.csv", b"\xff\xfen\x00,\x00x\x00\n\x00");
        let utf8 = file("utf8.csv", "name,x_m\nréponse 1,0.1\n".as_bytes());
        let bom = file("bom.csv", b"\xef\xbb\xbfname,x_m\n");
        let uff = file("data.uff", b"    -1\n    58b\n\xff\xfe\x00\x01\n    -1\n");
        let missing = dir.to_path_buf().join("missing.csv");
        let paths = [&latin1, &utf16, &utf8, &bom, &uff, &missing];
        let notes = super::encoding_notes(paths.iter().map(|p| p.as_path()));
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(
            notes[0].contains("latin1.csv") && notes[0].contains("Latin-1"),
            "{}",
            notes[0]
        );
        assert!(
            notes[1].contains("utf16.csv") && notes[1].contains("UTF-16"),
            "{}",
            notes[1]
        );
    }

    /// A job whose error lies on a line of a million characters, or on a line of binary
    /// bytes, quotes at most 80 characters of it, control characters escaped; a short line
    /// keeps the parser's own message with its caret.
    #[test]
    fn toml_errors_quote_a_bounded_printable_excerpt() {
        let dir = lamdyn_testkit::TempDir::new("io-toml");
        let long = dir.to_path_buf().join("long.toml");
        std::fs::write(&long, format!("title = \"{}", "x".repeat(1_000_000))).unwrap();
        let e = super::read_toml::<toml::Table>(&long)
            .unwrap_err()
            .to_string();
        assert!(e.len() < 400, "{} characters", e.len());
        assert!(e.contains("line 1, column") && e.contains("..."), "{e}");
        let binary = dir.to_path_buf().join("binary.toml");
        std::fs::write(&binary, b"a = 1\nb = \x01\x02\x1b[31m\n").unwrap();
        let e = super::read_toml::<toml::Table>(&binary)
            .unwrap_err()
            .to_string();
        assert!(!e.chars().any(|c| c.is_control() && c != '\n'), "{e:?}");
        assert!(e.contains("line 2") && e.contains("\\u{1}"), "{e}");
        let short = dir.to_path_buf().join("short.toml");
        std::fs::write(&short, "a = \n").unwrap();
        let e = super::read_toml::<toml::Table>(&short)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("TOML parse error at line 1") && e.contains('^'),
            "{e}"
        );
    }

    #[test]
    fn csv_tables_quote_bounded_printable_fields() {
        let text = format!("f_hz,g_pa\n1,\u{1b}[2J{}\n", "7".repeat(100_000));
        let e = super::CsvTable::parse("g.csv", &text)
            .unwrap_err()
            .to_string();
        assert!(e.len() < 200 && !e.contains('\u{1b}'), "{e}");
        assert!(e.contains("line 2: column 'g_pa': '\\u{1b}[2J7"), "{e}");
        let text = format!("f_hz,{}\n1\n", "h".repeat(100_000));
        let e = super::CsvTable::parse("g.csv", &text)
            .unwrap_err()
            .to_string();
        assert!(e.len() < 200 && e.ends_with("...)"), "{e}");
    }

    #[test]
    fn excerpts_cut_and_escape() {
        assert_eq!(super::excerpt("a\u{1b}b", 1), "a\\u{1b}b");
        let long = "y".repeat(300);
        let e = super::excerpt(&long, 150);
        assert!(
            e.starts_with("...") && e.ends_with("...") && e.len() == 86,
            "{e}"
        );
        assert_eq!(super::excerpt("é", 1), "é");
    }

    use super::*;

    #[test]
    fn parses_with_comments_and_blank_lines() {
        let t = CsvTable::parse("x.csv", "# comment\nf_hz, e\n\n1, 2\n3,4e9\n").unwrap();
        assert_eq!(t.rows(), &[(4, vec![1.0, 2.0]), (5, vec![3.0, 4e9])]);
        assert_eq!(t.find("e"), Some(1));
    }

    /// `lamdyn ema`'s modes.csv has text columns (pick, verdict) and empty cells (a pole
    /// without a deviation): a reader of two columns takes it, and still names a bad number in
    /// a column it reads.
    #[test]
    fn unused_columns_may_hold_text() {
        let numeric = |h: &str| h != "pick";
        let t = CsvTable::parse_where("m.csv", "f,pick,z\n1,Auto,0.1\n2,,0.2\n", &numeric).unwrap();
        assert!(t.rows()[0].1[1].is_nan());
        assert_eq!(t.rows()[1].1[2], 0.2);
        let e = CsvTable::parse_where("m.csv", "f,pick,z\n1,Auto,x\n", &numeric)
            .unwrap_err()
            .to_string();
        assert_eq!(e, "'m.csv' line 2: column 'z': 'x' is not a finite number");
    }

    #[test]
    fn errors_name_file_line_and_column() {
        let e = CsvTable::parse("x.csv", "f_hz,e\n1,2\n3,abc\n")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "'x.csv' line 3: column 'e': 'abc' is not a finite number"
        );
        let e = CsvTable::parse("x.csv", "f_hz,e\n1,2,3\n")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "'x.csv' line 2: 3 fields, but the header has 2 (f_hz,e)");
        let e = CsvTable::parse("x.csv", "f_hz,e\n1,NaN\n")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "'x.csv' line 2: column 'e': 'NaN' is not a finite number"
        );
        let e = CsvTable::parse("x.csv", "").unwrap_err().to_string();
        assert_eq!(
            e,
            "'x.csv' is empty: expected a header line of column names"
        );
        let e = CsvTable::parse("x.csv", "a,b\n").unwrap_err().to_string();
        assert_eq!(e, "'x.csv' has a header but no data lines");
    }
}
