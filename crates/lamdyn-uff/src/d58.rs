//! Dataset 58: function at nodal DOF (time signals, spectra, FRFs, coherence), ASCII and binary.
//!
//! Records (I-DEAS universal file format):
//! 1–5 ID lines (80A1); 6 `2(I5,I10),2(1X,10A1,I10,I4)`: function type, function id, version,
//! load case, response entity, node, direction, reference entity, node, direction;
//! 7 `3I10,3E13.5`: ordinate data type (2 real single, 4 real double, 5 complex single,
//! 6 complex double), number of points, abscissa spacing (1 even, 0 uneven), abscissa minimum,
//! increment, z-axis value; 8–11 `I10,3I5,2(1X,20A1)`: abscissa, ordinate numerator, ordinate
//! denominator and z-axis data characteristics (specific data type, length, force and
//! temperature unit exponents, label, units label); 12: the data.
//!
//! Record 12 layouts (ASCII): even spacing — values only, 6E13.5 (single) or 4E20.12 (double)
//! per line, complex values as (re, im) pairs; uneven spacing — (x, y) pairs 6E13.5, or
//! 2(E13.5,E20.12), or (x, re, im) 6E13.5 or E13.5,2E20.12. The reader takes the numbers as a
//! stream, whatever their count per line. Binary 58b: the same values in the file's byte order,
//! single as f32 and double as f64 — and the abscissa of uneven data always f32, as the
//! conformance files `dataset58_case6/8_binary.unv` show (1602 × (4 + 8) = 19 224 bytes).

use crate::error::{UffError, syntax};
use crate::fields::{cols, int_field, numbers, parse_f64, record};
pub use crate::record7::OrdinateType;
use crate::scan::RawDataset;
use num_complex::Complex64;
use serde::Serialize;
use std::fmt::Write as _;

/// Data characteristics of one axis (records 8–11).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct AxisSpec {
    /// Specific data type (0 unknown, 1 general, 8 displacement, 11 velocity, 12 acceleration,
    /// 13 excitation force, 17 time, 18 frequency, ...).
    pub data_type: i64,
    /// Length unit exponent.
    pub length_exp: i64,
    /// Force unit exponent.
    pub force_exp: i64,
    /// Temperature unit exponent.
    pub temperature_exp: i64,
    /// Axis label.
    pub label: String,
    /// Units label.
    pub units: String,
}

impl AxisSpec {
    /// An axis with no units.
    pub fn none() -> Self {
        Self {
            data_type: 0,
            length_exp: 0,
            force_exp: 0,
            temperature_exp: 0,
            label: "NONE".into(),
            units: "NONE".into(),
        }
    }
}

/// A response or reference: entity name, node and direction (record 6).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Dof {
    /// Entity name (10 characters).
    pub entity: String,
    /// Node label.
    pub node: i64,
    /// Direction: 0 scalar, ±1..±3 translation x, y, z, ±4..±6 rotation.
    pub direction: i64,
}

/// The abscissa.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum Abscissa {
    /// x_k = start + k·step.
    Even {
        /// First value.
        start: f64,
        /// Increment.
        step: f64,
    },
    /// Given values.
    Uneven(Vec<f64>),
}

/// The ordinate values.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum Ordinate {
    /// Real values.
    Real(Vec<f64>),
    /// Complex values.
    Complex(Vec<Complex64>),
}

impl Ordinate {
    /// Number of points.
    pub fn len(&self) -> usize {
        match self {
            Self::Real(v) => v.len(),
            Self::Complex(v) => v.len(),
        }
    }
    /// No points.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Dataset 58.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Function58 {
    /// Records 1–5.
    pub id_lines: [String; 5],
    /// Function type (0 general, 1 time response, 2 auto spectrum, 3 cross spectrum, 4 FRF,
    /// 6 coherence, ...).
    pub function_type: i64,
    /// Function identification number.
    pub function_id: i64,
    /// Version or sequence number.
    pub version: i64,
    /// Load case.
    pub load_case: i64,
    /// Response DOF.
    pub response: Dof,
    /// Reference DOF.
    pub reference: Dof,
    /// Ordinate precision and kind.
    pub ordinate_type: OrdinateType,
    /// Abscissa.
    pub abscissa: Abscissa,
    /// Z-axis value.
    pub z_value: f64,
    /// Records 8–11: abscissa, ordinate numerator, ordinate denominator, z axis.
    pub axes: [AxisSpec; 4],
    /// Values.
    pub data: Ordinate,
}

impl Function58 {
    /// A complex-double FRF (function type 4) from `response` to `reference` on an even
    /// frequency axis (Hz), with unknown units (set `axes` for units) and one ID line.
    pub fn complex_frf(
        id: &str,
        function_id: i64,
        response: Dof,
        reference: Dof,
        start_hz: f64,
        step_hz: f64,
        data: Vec<Complex64>,
    ) -> Self {
        Self {
            id_lines: [
                id.into(),
                "NONE".into(),
                "NONE".into(),
                "NONE".into(),
                "NONE".into(),
            ],
            function_type: 4,
            function_id,
            version: 0,
            load_case: 0,
            response,
            reference,
            ordinate_type: OrdinateType::ComplexDouble,
            abscissa: Abscissa::Even {
                start: start_hz,
                step: step_hz,
            },
            z_value: 0.0,
            axes: [
                AxisSpec::none(),
                AxisSpec::none(),
                AxisSpec::none(),
                AxisSpec::none(),
            ],
            data: Ordinate::Complex(data),
        }
    }

    /// The abscissa values.
    pub fn x(&self) -> Vec<f64> {
        match &self.abscissa {
            Abscissa::Even { start, step } => (0..self.data.len())
                .map(|k| start + step * k as f64)
                .collect(),
            Abscissa::Uneven(x) => x.clone(),
        }
    }
}

fn axis(line: &str, at: usize, what: &str) -> Result<AxisSpec, UffError> {
    // I10,3I5,2(1X,20A1): columns 0-10, 10-15, 15-20, 20-25, then 26-46 and 47-67.
    Ok(AxisSpec {
        data_type: int_field(line, 0, 10, 0, at, what)?,
        length_exp: int_field(line, 10, 15, 0, at, what)?,
        force_exp: int_field(line, 15, 20, 0, at, what)?,
        temperature_exp: int_field(line, 20, 25, 0, at, what)?,
        label: cols(line, 26, 46).trim().to_string(),
        units: cols(line, 47, 67).trim().to_string(),
    })
}

/// Header records 1–11 of a dataset 58 (ASCII or binary), with the point count and spacing.
struct Header {
    f: Function58,
    n: usize,
    even: bool,
}

fn header(ds: &RawDataset) -> Result<Header, UffError> {
    let l = &ds.lines;
    let id = |i: usize| {
        l.get(i)
            .map(|s| s.1.trim_end().to_string())
            .unwrap_or_default()
    };
    let (a6, r6) = record(l, 5, ds.line, "record 6 (function and DOF identification)")?;
    let w = "record 6";
    let response = Dof {
        entity: cols(r6, 31, 41).trim().to_string(),
        node: int_field(r6, 41, 51, 0, a6, w)?,
        direction: int_field(r6, 51, 55, 0, a6, w)?,
    };
    let reference = Dof {
        entity: cols(r6, 56, 66).trim().to_string(),
        node: int_field(r6, 66, 76, 0, a6, w)?,
        direction: int_field(r6, 76, 80, 0, a6, w)?,
    };
    let DataForm {
        ordinate_type,
        n,
        even,
        start,
        step,
        z_value,
    } = data_form(ds)?;
    let axes = axis_records(ds)?;
    let (a6, r6l) = (a6, r6);
    let w = "record 6";
    let f = Function58 {
        id_lines: [id(0), id(1), id(2), id(3), id(4)],
        function_type: int_field(r6l, 0, 5, 0, a6, w)?,
        function_id: int_field(r6l, 5, 15, 0, a6, w)?,
        version: int_field(r6l, 15, 20, 0, a6, w)?,
        load_case: int_field(r6l, 20, 30, 0, a6, w)?,
        response,
        reference,
        ordinate_type,
        abscissa: if even {
            Abscissa::Even { start, step }
        } else {
            Abscissa::Uneven(vec![])
        },
        z_value,
        axes,
        data: Ordinate::Real(vec![]),
    };
    Ok(Header { f, n, even })
}

/// Record 7 of a dataset 58: the ordinate's type, the point count, the spacing and the
/// abscissa's start and step, the z value.
struct DataForm {
    ordinate_type: OrdinateType,
    n: usize,
    even: bool,
    start: f64,
    step: f64,
    z_value: f64,
}

fn data_form(ds: &RawDataset) -> Result<DataForm, UffError> {
    let l = &ds.lines;
    let (a7, r7) = record(l, 6, ds.line, "record 7 (data form)")?;
    let w = "record 7";
    let code = int_field(r7, 0, 10, -1, a7, w)?;
    let ordinate_type = OrdinateType::from_code(code).ok_or_else(|| {
        syntax(
            a7,
            format!("record 7: ordinate data type {code} must be 2, 4, 5 or 6"),
        )
    })?;
    let n = int_field(r7, 10, 20, -1, a7, w)?;
    if n < 0 {
        return Err(syntax(
            a7,
            format!("record 7: number of points {n} must not be negative"),
        ));
    }
    let spacing = int_field(r7, 20, 30, -1, a7, w)?;
    let even = match spacing {
        1 => true,
        0 => false,
        s => {
            return Err(syntax(
                a7,
                format!("record 7: abscissa spacing {s} must be 1 (even) or 0 (uneven)"),
            ));
        }
    };
    let real = |a: usize, b: usize, what: &str| -> Result<f64, UffError> {
        let t = cols(r7, a, b);
        if t.trim().is_empty() {
            return Ok(0.0);
        }
        parse_f64(t).ok_or_else(|| {
            syntax(
                a7,
                format!("record 7: {what} '{}' is not a finite number", t.trim()),
            )
        })
    };
    let (start, step, z_value) = (
        real(30, 43, "abscissa minimum")?,
        real(43, 56, "abscissa increment")?,
        real(56, 69, "z-axis value")?,
    );
    Ok(DataForm {
        ordinate_type,
        n: n as usize,
        even,
        start,
        step,
        z_value,
    })
}

/// Records 8–11 of a dataset 58: the abscissa's, the ordinate's numerator's and
/// denominator's, and the z axis's units.
fn axis_records(ds: &RawDataset) -> Result<[AxisSpec; 4], UffError> {
    let l = &ds.lines;
    let mut axes = Vec::with_capacity(4);
    for (k, what) in [
        "record 8 (abscissa)",
        "record 9 (ordinate numerator)",
        "record 10 (ordinate denominator)",
        "record 11 (z axis)",
    ]
    .iter()
    .enumerate()
    {
        let (at, r) = record(l, 7 + k, ds.line, what)?;
        axes.push(axis(r, at, what)?);
    }
    axes.try_into()
        .map_err(|_| syntax(ds.line, "four axis records expected"))
}

/// A dataset 58 header only (records 1–11), for listings: the function with empty data and the
/// number of points.
pub(crate) fn parse_header(ds: &RawDataset) -> Result<(Function58, usize), UffError> {
    let h = header(ds)?;
    Ok((h.f, h.n))
}

/// Values per point in the data stream: (x?) + 1 or 2.
fn per_point(t: OrdinateType, even: bool) -> usize {
    usize::from(!even) + if t.is_complex() { 2 } else { 1 }
}

fn assemble(mut f: Function58, n: usize, even: bool, values: &[f64]) -> Function58 {
    let p = per_point(f.ordinate_type, even);
    let y0 = usize::from(!even);
    if !even {
        f.abscissa = Abscissa::Uneven((0..n).map(|k| values[k * p]).collect());
    }
    f.data = if f.ordinate_type.is_complex() {
        Ordinate::Complex(
            (0..n)
                .map(|k| Complex64::new(values[k * p + y0], values[k * p + y0 + 1]))
                .collect(),
        )
    } else {
        Ordinate::Real((0..n).map(|k| values[k * p + y0]).collect())
    };
    f
}

/// Parses an ASCII or binary dataset 58. Numbers beyond record 7's count are accepted when they
/// are all zero (padded records). With `lenient`, an ASCII record 12 holding fewer points than
/// announced keeps the whole points it has and returns a notice; otherwise that is an error.
///
/// # Errors
/// [`UffError::Syntax`] naming the line: bad header fields, bad numbers, a data count that
/// differs from record 7's, a binary byte count that does not match the layout, a float format
/// other than IEEE 754.
pub fn parse(ds: &RawDataset, lenient: bool) -> Result<(Function58, Option<String>), UffError> {
    let Header { f, mut n, even } = header(ds)?;
    let p = per_point(f.ordinate_type, even);
    let want = n
        .checked_mul(p)
        .ok_or_else(|| syntax(ds.line, format!("record 7: {n} points is too many")))?;
    let mut notice = None;
    let values = match ds.binary {
        None => {
            let mut v = Vec::with_capacity(want.min(1 << 24));
            numbers(&ds.lines[11.min(ds.lines.len())..], &mut v)?;
            let at = ds.lines.last().map_or(ds.line, |l| l.0);
            if v.len() > want && v[want..].iter().all(|x| *x == 0.0) {
                v.truncate(want);
            }
            if v.len() < want && lenient {
                n = v.len() / p;
                v.truncate(n * p);
                notice = Some(format!(
                    "line {}: dataset 58 announces {} points, record 12 holds {n}: kept {n}",
                    ds.line,
                    want / p
                ));
            }
            if v.len() != want && notice.is_none() {
                return Err(syntax(
                    at,
                    format!(
                        "dataset 58 at line {}: record 7 announces {n} points ({want} numbers), \
                         record 12 holds {} numbers",
                        ds.line,
                        v.len()
                    ),
                ));
            }
            v
        }
        Some(h) => {
            if h.float_format != 2 {
                return Err(syntax(
                    ds.line,
                    format!(
                        "58b floating point format {}: only 2 (IEEE 754) is supported",
                        h.float_format
                    ),
                ));
            }
            let size = if f.ordinate_type.is_double() { 8 } else { 4 };
            let y_per = if f.ordinate_type.is_complex() { 2 } else { 1 };
            let bytes_per_point = y_per * size + if even { 0 } else { 4 };
            let expect = n.saturating_mul(bytes_per_point);
            if ds.payload.len() != expect {
                return Err(syntax(
                    ds.line,
                    format!(
                        "dataset 58b: {} bytes of data, but {n} points of this layout take \
                         {expect} (wrong byte count)",
                        ds.payload.len()
                    ),
                ));
            }
            if even && y_per == 2 && size == 8 {
                // The common FRF layout, decoded straight into complex values.
                let data = decode_complex_f64(&ds.payload, h.little_endian);
                if data.iter().any(|c| !(c.re.is_finite() && c.im.is_finite())) {
                    return Err(syntax(
                        ds.line,
                        format!(
                            "dataset 58b at line {}: record 12 holds a value that is not finite",
                            ds.line
                        ),
                    ));
                }
                return Ok((
                    Function58 {
                        data: Ordinate::Complex(data),
                        ..f
                    },
                    None,
                ));
            }
            decode(&ds.payload, n, even, y_per, size, h.little_endian)
        }
    };
    if let Some(k) = values.iter().position(|v| !v.is_finite()) {
        return Err(syntax(
            ds.line,
            format!(
                "dataset 58 at line {}: value {k} of record 12 is not finite",
                ds.line
            ),
        ));
    }
    Ok((assemble(f, n, even, &values), notice))
}

fn decode_complex_f64(b: &[u8], little: bool) -> Vec<Complex64> {
    let f = |c: &[u8]| {
        let a: [u8; 8] = c.try_into().unwrap_or([0; 8]);
        if little {
            f64::from_le_bytes(a)
        } else {
            f64::from_be_bytes(a)
        }
    };
    b.chunks_exact(16)
        .map(|c| Complex64::new(f(&c[..8]), f(&c[8..])))
        .collect()
}

fn decode(b: &[u8], n: usize, even: bool, y_per: usize, size: usize, little: bool) -> Vec<f64> {
    let f32_at = |i: usize| {
        let a = [b[i], b[i + 1], b[i + 2], b[i + 3]];
        f64::from(if little {
            f32::from_le_bytes(a)
        } else {
            f32::from_be_bytes(a)
        })
    };
    let f64_at = |i: usize| {
        let mut a = [0u8; 8];
        a.copy_from_slice(&b[i..i + 8]);
        if little {
            f64::from_le_bytes(a)
        } else {
            f64::from_be_bytes(a)
        }
    };
    let per = usize::from(!even) + y_per;
    let mut out = Vec::with_capacity(n * per);
    let mut i = 0;
    for _ in 0..n {
        if !even {
            out.push(f32_at(i));
            i += 4;
        }
        for _ in 0..y_per {
            out.push(if size == 8 { f64_at(i) } else { f32_at(i) });
            i += size;
        }
    }
    out
}

fn check_len(s: &str, max: usize, what: &str) -> Result<(), UffError> {
    if s.chars().count() > max || s.contains(['\n', '\r']) {
        return Err(UffError::Write(format!(
            "{what} '{s}' must be one line of at most {max} characters"
        )));
    }
    Ok(())
}

/// Records 1–11 as text (each line ends in LF).
fn write_header(
    f: &Function58,
    n: usize,
    binary: Option<(bool, usize)>,
) -> Result<String, UffError> {
    let mut s = String::new();
    match binary {
        None => s.push_str("    -1\n    58\n"),
        Some((little, bytes)) => {
            let _ = writeln!(
                s,
                "    -1\n{:>6}b{:>6}{:>6}{:>12}{:>12}{:>6}{:>6}{:>12}{:>12}",
                58,
                if little { 1 } else { 2 },
                2,
                11,
                bytes,
                0,
                0,
                0,
                0
            );
        }
    }
    for l in &f.id_lines {
        check_len(l, 80, "ID line")?;
        let _ = writeln!(s, "{l:<80}");
    }
    for (e, w) in [
        (&f.response.entity, "response entity"),
        (&f.reference.entity, "reference entity"),
    ] {
        check_len(e, 10, w)?;
    }
    let _ = writeln!(
        s,
        "{:>5}{:>10}{:>5}{:>10} {:<10}{:>10}{:>4} {:<10}{:>10}{:>4}",
        f.function_type,
        f.function_id,
        f.version,
        f.load_case,
        f.response.entity,
        f.response.node,
        f.response.direction,
        f.reference.entity,
        f.reference.node,
        f.reference.direction
    );
    let (even, start, step) = match &f.abscissa {
        Abscissa::Even { start, step } => (1, *start, *step),
        Abscissa::Uneven(_) => (0, 0.0, 0.0),
    };
    let _ = writeln!(
        s,
        "{:>10}{:>10}{:>10}{}{}{}",
        f.ordinate_type.code(),
        n,
        even,
        e13(start),
        e13(step),
        e13(f.z_value)
    );
    for a in &f.axes {
        check_len(&a.label, 20, "axis label")?;
        check_len(&a.units, 20, "axis units label")?;
        let _ = writeln!(
            s,
            "{:>10}{:>5}{:>5}{:>5} {:<20} {:<20}",
            a.data_type, a.length_exp, a.force_exp, a.temperature_exp, a.label, a.units
        );
    }
    Ok(s)
}

/// A number in E13.5 (`  1.23456E+00`).
pub(crate) fn e13(v: f64) -> String {
    format!("{:>13}", fortran_e(v, 5))
}

/// A number in E20.12.
pub(crate) fn e20(v: f64) -> String {
    format!("{:>20}", fortran_e(v, 12))
}

/// A number in E25.16 (for 2411 coordinates and 164 factors).
pub(crate) fn e25(v: f64) -> String {
    format!("{:>25}", fortran_e(v, 16))
}

/// d.ddddE+XX with `digits` decimals and a signed two-or-more digit exponent.
pub(crate) fn fortran_e(v: f64, digits: usize) -> String {
    let s = format!("{v:.digits$E}");
    let (m, e) = s.split_once('E').unwrap_or((&s, "0"));
    let e: i32 = e.parse().unwrap_or(0);
    format!("{m}E{}{:02}", if e < 0 { '-' } else { '+' }, e.abs())
}

fn check_data(f: &Function58) -> Result<usize, UffError> {
    let n = f.data.len();
    if let Abscissa::Uneven(x) = &f.abscissa {
        if x.len() != n {
            return Err(UffError::Write(format!(
                "{} abscissa values for {n} ordinate values",
                x.len()
            )));
        }
    }
    let finite = match &f.data {
        Ordinate::Real(v) => v.iter().all(|x| x.is_finite()),
        Ordinate::Complex(v) => v.iter().all(|x| x.re.is_finite() && x.im.is_finite()),
    };
    if !finite {
        return Err(UffError::Write(
            "record 12 holds a value that is not finite".into(),
        ));
    }
    if f.data.is_empty() {
        return Err(UffError::Write("dataset 58 without data".into()));
    }
    let complex = matches!(f.data, Ordinate::Complex(_));
    if complex != f.ordinate_type.is_complex() {
        return Err(UffError::Write(format!(
            "ordinate type {:?} does not match the data",
            f.ordinate_type
        )));
    }
    Ok(n)
}

/// The values of record 12 in stream order.
fn stream(f: &Function58) -> Vec<f64> {
    let x = match &f.abscissa {
        Abscissa::Uneven(x) => Some(x),
        Abscissa::Even { .. } => None,
    };
    let mut out = Vec::new();
    for k in 0..f.data.len() {
        if let Some(x) = x {
            out.push(x[k]);
        }
        match &f.data {
            Ordinate::Real(v) => out.push(v[k]),
            Ordinate::Complex(v) => {
                out.push(v[k].re);
                out.push(v[k].im);
            }
        }
    }
    out
}

/// Writes an ASCII dataset 58 in the layout of its ordinate type (module docs).
///
/// # Errors
/// [`UffError::Write`] for labels too long for their fields, non-finite values, or data that
/// does not match the ordinate type.
pub fn write_ascii(f: &Function58, out: &mut String) -> Result<(), UffError> {
    let n = check_data(f)?;
    out.push_str(&write_header(f, n, None)?);
    let values = stream(f);
    let even = matches!(f.abscissa, Abscissa::Even { .. });
    let double = f.ordinate_type.is_double();
    let per_line = if double {
        if even {
            4
        } else if f.ordinate_type.is_complex() {
            3
        } else {
            4
        }
    } else {
        6
    };
    let period = per_point(f.ordinate_type, even);
    for (i, v) in values.iter().enumerate() {
        // In uneven double layouts the abscissa stays E13.5.
        let is_x = !even && i % period == 0;
        out.push_str(&if double && !is_x { e20(*v) } else { e13(*v) });
        if (i + 1) % per_line == 0 || i + 1 == values.len() {
            out.push('\n');
        }
    }
    out.push_str("    -1\n");
    Ok(())
}

/// Writes a binary dataset 58b, little endian (`little`) or big endian.
///
/// # Errors
/// As [`write_ascii`].
pub fn write_binary(f: &Function58, little: bool, out: &mut Vec<u8>) -> Result<(), UffError> {
    let n = check_data(f)?;
    let even = matches!(f.abscissa, Abscissa::Even { .. });
    let size = if f.ordinate_type.is_double() { 8 } else { 4 };
    let y_per = if f.ordinate_type.is_complex() { 2 } else { 1 };
    let bytes = n * (y_per * size + if even { 0 } else { 4 });
    out.extend_from_slice(write_header(f, n, Some((little, bytes)))?.as_bytes());
    out.reserve(bytes + 8);
    let period = per_point(f.ordinate_type, even);
    for (i, v) in stream(f).into_iter().enumerate() {
        let is_x = !even && i % period == 0;
        if size == 8 && !is_x {
            out.extend_from_slice(&if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            });
        } else {
            let s = v as f32;
            out.extend_from_slice(&if little {
                s.to_le_bytes()
            } else {
                s.to_be_bytes()
            });
        }
    }
    out.extend_from_slice(b"\n    -1\n");
    Ok(())
}
