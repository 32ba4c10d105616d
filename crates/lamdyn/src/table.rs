//! Tables of results, rendered as aligned text (people), CSV or JSON (machines).
//!
//! Text shows each column in a readable unit (GPa, MPa) named in its header; CSV and JSON carry
//! SI values under keys that name the unit (`g_storage_pa`). Rendering is deterministic: the same
//! inputs give the same bytes.

use serde_json::{Map, Value, json};
use std::borrow::Cow;
use std::io::Write;

/// How a number is printed in the text table.
#[derive(Debug, Clone, Copy)]
pub enum Fmt {
    /// Fixed point with this many decimals.
    Fixed(usize),
    /// Scientific with this many decimals in the mantissa.
    Sci(usize),
}

/// One column: machine key (SI), text header, text unit and the divisor from SI to that unit.
#[derive(Debug, Clone)]
pub struct Column {
    /// CSV/JSON key, with the SI unit in its name.
    pub key: Cow<'static, str>,
    /// Header in the text table.
    pub header: Cow<'static, str>,
    /// Unit in the text table ("" for none).
    pub unit: &'static str,
    /// SI value / `scale` is shown in the text table.
    pub scale: f64,
    /// Text format.
    pub fmt: Fmt,
}

impl Column {
    /// A column shown in SI with format `fmt`.
    pub fn new(
        key: impl Into<Cow<'static, str>>,
        header: impl Into<Cow<'static, str>>,
        unit: &'static str,
        fmt: Fmt,
    ) -> Self {
        Self {
            key: key.into(),
            header: header.into(),
            unit,
            scale: 1.0,
            fmt,
        }
    }

    /// Shows the column divided by `scale` (e.g. 1e9 for GPa).
    pub fn scaled(mut self, scale: f64) -> Self {
        self.scale = scale;
        self
    }
}

/// A table cell.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// A number in SI units.
    Num(f64),
    /// Text.
    Text(String),
    /// Nothing (a line where the quantity could not be computed).
    Empty,
}

impl From<f64> for Cell {
    fn from(v: f64) -> Self {
        if v.is_finite() {
            Cell::Num(v)
        } else {
            Cell::Empty
        }
    }
}

impl From<&str> for Cell {
    fn from(v: &str) -> Self {
        Cell::Text(v.to_string())
    }
}

impl From<String> for Cell {
    fn from(v: String) -> Self {
        Cell::Text(v)
    }
}

impl From<Option<f64>> for Cell {
    fn from(v: Option<f64>) -> Self {
        v.map_or(Cell::Empty, Cell::from)
    }
}

/// Output format chosen on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Aligned text for people.
    Text,
    /// CSV, SI units.
    Csv,
    /// JSON, SI units, compact (one line).
    Json,
}

/// A command's result: a table plus what it needs to be read.
#[derive(Debug, Clone)]
pub struct Report {
    /// The command (`core`).
    pub command: &'static str,
    /// Inputs and settings as (key, value) lines, shown above the table.
    pub inputs: Vec<(String, String)>,
    /// Columns.
    pub columns: Vec<Column>,
    /// Rows of cells, one per column.
    pub rows: Vec<Vec<Cell>>,
    /// Notes printed under the text table (conventions, legends).
    pub notes: Vec<String>,
    /// Warnings, printed to stderr in every format and included in JSON.
    pub warnings: Vec<String>,
    /// Extra machine-readable data for JSON (detailed per-line results).
    pub extra: Option<Value>,
    /// Further tables, shown before the main one in text and included in JSON under their key;
    /// CSV carries the main table only.
    pub sections: Vec<Section>,
}

/// A titled table beside a report's main one.
#[derive(Debug, Clone)]
pub struct Section {
    /// JSON key (and CSV file stem for commands that write one file per table).
    pub key: &'static str,
    /// Title in the text output.
    pub title: String,
    /// Columns.
    pub columns: Vec<Column>,
    /// Rows, one cell per column.
    pub rows: Vec<Vec<Cell>>,
}

impl Section {
    /// An empty section.
    pub fn new(key: &'static str, title: impl Into<String>, columns: Vec<Column>) -> Self {
        Self {
            key,
            title: title.into(),
            columns,
            rows: vec![],
        }
    }

    /// Adds a row.
    ///
    /// # Panics
    /// If the row's length differs from the number of columns (a programming error).
    pub fn row(&mut self, cells: Vec<Cell>) {
        push_row(&self.columns, &mut self.rows, cells);
    }
}

impl Report {
    /// An empty report for `command`.
    pub fn new(command: &'static str, columns: Vec<Column>) -> Self {
        Self {
            command,
            inputs: vec![],
            columns,
            rows: vec![],
            notes: vec![],
            warnings: vec![],
            extra: None,
            sections: vec![],
        }
    }

    /// Adds an input line.
    pub fn input(&mut self, key: &str, value: impl Into<String>) {
        self.inputs.push((key.to_string(), value.into()));
    }

    /// Adds a row.
    ///
    /// # Panics
    /// If the row's length differs from the number of columns (a programming error).
    pub fn row(&mut self, cells: Vec<Cell>) {
        push_row(&self.columns, &mut self.rows, cells);
    }

    /// Writes the report in `format` to `out` and its warnings to `err`.
    pub fn write(
        &self,
        format: Format,
        out: &mut dyn Write,
        err: &mut dyn Write,
    ) -> std::io::Result<()> {
        for w in &self.warnings {
            writeln!(err, "lamdyn: warning: {w}")?;
        }
        // Buffered: stdout flushes at every newline (the text and CSV tables of a long record
        // have thousands). The JSON is compact, one line: a long record's holds 100 000 numbers
        // (the CMIF and its lines), and indenting each on its own line made it half as large
        // again and slower to write and to read; `jq .` shows it indented.
        let mut out = std::io::BufWriter::new(out);
        match format {
            Format::Text => self.write_text(&mut out),
            Format::Csv => self.write_csv(&mut out),
            Format::Json => {
                serde_json::to_writer(&mut out, &self.to_json())?;
                writeln!(out)
            }
        }?;
        out.flush()
    }

    fn write_text(&self, out: &mut dyn Write) -> std::io::Result<()> {
        let key_width = self.inputs.iter().map(|(k, _)| k.len()).max().unwrap_or(0);
        for (k, v) in &self.inputs {
            writeln!(out, "{k:<key_width$}  {v}")?;
        }
        if !self.inputs.is_empty() {
            writeln!(out)?;
        }
        for section in &self.sections {
            writeln!(out, "{}", section.title)?;
            write_text_table(out, &section.columns, &section.rows)?;
            writeln!(out)?;
        }
        write_text_table(out, &self.columns, &self.rows)?;
        if !self.notes.is_empty() {
            writeln!(out)?;
            for n in &self.notes {
                writeln!(out, "{n}")?;
            }
        }
        Ok(())
    }

    /// The main table as CSV (SI units, keys as headers).
    pub fn write_csv(&self, out: &mut dyn Write) -> std::io::Result<()> {
        write_csv_table(out, &self.columns, &self.rows)
    }

    /// The JSON form: inputs, column units, rows as objects keyed by column, warnings, extra,
    /// sections.
    pub fn to_json(&self) -> Value {
        let inputs: Map<String, Value> = self
            .inputs
            .iter()
            .map(|(k, v)| (k.clone(), json!(v)))
            .collect();
        let mut doc = json!({
            "command": self.command,
            "version": env!("CARGO_PKG_VERSION"),
            "inputs": inputs,
            "rows": json_rows(&self.columns, &self.rows),
            "warnings": self.warnings,
        });
        if !self.sections.is_empty() {
            let sections: Map<String, Value> = self
                .sections
                .iter()
                .map(|s| (s.key.to_string(), json_rows(&s.columns, &s.rows)))
                .collect();
            doc["sections"] = Value::Object(sections);
        }
        if let Some(extra) = &self.extra {
            doc["details"] = extra.clone();
        }
        doc
    }
}

/// Appends a row of one cell per column.
///
/// # Panics
/// If the row's length differs from the number of columns (a programming error).
fn push_row(columns: &[Column], rows: &mut Vec<Vec<Cell>>, cells: Vec<Cell>) {
    assert_eq!(cells.len(), columns.len(), "expected one cell per column");
    rows.push(cells);
}

/// Writes an aligned text table (header, unit line if any unit, rows).
fn write_text_table(
    out: &mut dyn Write,
    columns: &[Column],
    rows: &[Vec<Cell>],
) -> std::io::Result<()> {
    let headers: Vec<String> = columns.iter().map(|c| c.header.to_string()).collect();
    let units: Vec<String> = columns
        .iter()
        .map(|c| {
            if c.unit.is_empty() {
                String::new()
            } else {
                format!("[{}]", c.unit)
            }
        })
        .collect();
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            r.iter()
                .zip(columns)
                .map(|(cell, col)| text_cell(cell, col))
                .collect()
        })
        .collect();
    let widths: Vec<usize> = (0..columns.len())
        .map(|j| {
            body.iter()
                .map(|r| r[j].len())
                .chain([headers[j].len(), units[j].len()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let line = |cells: &[String]| {
        cells
            .iter()
            .zip(&widths)
            .map(|(c, w)| format!("{c:>w$}"))
            .collect::<Vec<_>>()
            .join("  ")
    };
    writeln!(out, "{}", line(&headers))?;
    if units.iter().any(|u| !u.is_empty()) {
        writeln!(out, "{}", line(&units))?;
    }
    for r in &body {
        writeln!(out, "{}", line(r))?;
    }
    Ok(())
}

/// Writes a CSV table: keys as the header, SI numbers, text quoted when needed.
pub fn write_csv_table(
    out: &mut dyn Write,
    columns: &[Column],
    rows: &[Vec<Cell>],
) -> std::io::Result<()> {
    let header: Vec<&str> = columns.iter().map(|c| c.key.as_ref()).collect();
    writeln!(out, "{}", header.join(","))?;
    for r in rows {
        let cells: Vec<String> = r
            .iter()
            .map(|c| match c {
                Cell::Num(v) => csv_number(*v),
                Cell::Text(t) if t.contains([',', '"']) => {
                    format!("\"{}\"", t.replace('"', "\"\""))
                }
                Cell::Text(t) => t.clone(),
                Cell::Empty => String::new(),
            })
            .collect();
        writeln!(out, "{}", cells.join(","))?;
    }
    Ok(())
}

/// Rows as JSON objects keyed by column (SI numbers, null for empty cells).
fn json_rows(columns: &[Column], rows: &[Vec<Cell>]) -> Value {
    rows.iter()
        .map(|r| {
            let m: Map<String, Value> = r
                .iter()
                .zip(columns)
                .map(|(cell, col)| {
                    let v = match cell {
                        Cell::Num(v) => json!(v),
                        Cell::Text(t) => json!(t),
                        Cell::Empty => Value::Null,
                    };
                    (col.key.to_string(), v)
                })
                .collect();
            Value::Object(m)
        })
        .collect()
}

/// A number in CSV: Rust's shortest round-trip form, plain between 1e-4 and 1e15, else with an
/// exponent. Reading it back gives the same f64.
fn csv_number(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || (1e-4..1e15).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Whether a fixed-point column can print `x` in a readable width (below 1e9 in magnitude;
/// non-finite values print as themselves).
fn fits_fixed(x: f64) -> bool {
    !x.is_finite() || x.abs() < 1e9
}

fn text_cell(cell: &Cell, col: &Column) -> String {
    match cell {
        Cell::Num(v) => {
            let x = v / col.scale;
            match col.fmt {
                Fmt::Fixed(d) if fits_fixed(x) => format!("{x:.d$}"),
                // Out of a fixed column's range (a garbage value, 1e169): scientific, never
                // hundreds of digits.
                Fmt::Fixed(d) | Fmt::Sci(d) => format!("{x:.d$e}"),
            }
        }
        Cell::Text(t) => t.clone(),
        Cell::Empty => "-".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A garbage fit's t0 = 1.15e169 s printed as 170 digits in a fixed column.
    #[test]
    fn huge_values_in_fixed_columns_print_in_scientific_notation() {
        let col = Column::new("t0_s", "t0", "s", Fmt::Fixed(3));
        let text = text_cell(&Cell::Num(1.15e169), &col);
        assert_eq!(text, "1.150e169");
        assert_eq!(text_cell(&Cell::Num(12.3456), &col), "12.346");
        assert_eq!(text_cell(&Cell::Num(f64::NAN), &col), "NaN");
    }
}
