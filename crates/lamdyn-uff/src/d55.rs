//! Dataset 55: data at nodes — mode shapes (real and complex), static and response data.
//!
//! Records: 1–5 ID lines; 6 (6I10) model type, analysis type (1 static, 2 normal mode,
//! 3 complex eigenvalue, 4 transient, 5 frequency response, 6 buckling), data characteristic
//! (1 scalar, 2 3-DOF translation, 3 6-DOF translation and rotation, ...), specific data type,
//! data type (2 real, 5 complex), number of values per node NDV; 7 (8I10) the number of integer
//! values NINT, of real values NRV, then the NINT integers (load case, mode number, ...);
//! 8 (6E13.5) the NRV reals — for normal modes frequency (Hz), modal mass, viscous and
//! hysteretic damping ratios; for complex modes Re λ, Im λ (rad/s), modal A and B (complex);
//! then per node: record 9 (I10) the node label, record 10 (6E13.5) its NDV values (pairs
//! re, im for complex data), on as many lines as they need.

use crate::d58::e13;
use crate::error::{UffError, syntax};
use crate::fields::{ints, ints_n, numbers, record};
use crate::scan::RawDataset;
use num_complex::Complex64;
use serde::Serialize;
use std::fmt::Write as _;

/// Values at one node.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NodeValues {
    /// Node label.
    pub node: i64,
    /// NDV values (imaginary parts zero for real data).
    pub values: Vec<Complex64>,
}

/// Dataset 55.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Modal55 {
    /// Records 1–5.
    pub id_lines: [String; 5],
    /// Model type.
    pub model_type: i64,
    /// Analysis type (2 normal mode, 3 complex eigenvalue, ...).
    pub analysis_type: i64,
    /// Data characteristic (2: 3 translations, 3: 3 translations + 3 rotations, ...).
    pub data_characteristic: i64,
    /// Specific data type (8 displacement, 11 velocity, 12 acceleration, ...).
    pub specific_data_type: i64,
    /// True for complex data (code 5), false for real (code 2).
    pub complex: bool,
    /// Values per node.
    pub values_per_node: usize,
    /// Integer values of record 7 (load case, mode number, ...).
    pub ints: Vec<i64>,
    /// Real values of record 8.
    pub reals: Vec<f64>,
    /// Data per node.
    pub nodes: Vec<NodeValues>,
}

impl Modal55 {
    /// Natural frequency (Hz) of a normal mode, or |λ|/2π of a complex one.
    pub fn frequency_hz(&self) -> Option<f64> {
        match self.analysis_type {
            2 => self.reals.first().copied(),
            3 if self.reals.len() >= 2 => Some(
                Complex64::new(self.reals[0], self.reals[1]).norm() / (2.0 * std::f64::consts::PI),
            ),
            _ => None,
        }
    }
    /// Viscous damping ratio: record 8 for a normal mode, −Re λ/|λ| for a complex one.
    pub fn damping_ratio(&self) -> Option<f64> {
        match self.analysis_type {
            2 => self.reals.get(2).copied(),
            3 if self.reals.len() >= 2 => {
                Some(-self.reals[0] / Complex64::new(self.reals[0], self.reals[1]).norm())
            }
            _ => None,
        }
    }
}

/// Parses a dataset 55.
///
/// # Errors
/// [`UffError::Syntax`] naming the line: bad fields, a data type other than 2 or 5, a node with
/// fewer values than NDV.
pub fn parse(ds: &RawDataset) -> Result<Modal55, UffError> {
    let l = &ds.lines;
    let id = |i: usize| {
        l.get(i)
            .map(|s| s.1.trim_end().to_string())
            .unwrap_or_default()
    };
    let (a6, r6) = record(l, 5, ds.line, "record 6 of dataset 55")?;
    let h = ints_n(r6, 6, a6, "dataset 55 record 6")?;
    let complex = match h[4] {
        2 => false,
        5 => true,
        c => {
            return Err(syntax(
                a6,
                format!("dataset 55 record 6: data type {c} must be 2 (real) or 5 (complex)"),
            ));
        }
    };
    let ndv = usize::try_from(h[5])
        .ok()
        .filter(|n| *n <= 1 << 16)
        .ok_or_else(|| syntax(a6, format!("dataset 55 record 6: {} values per node", h[5])))?;
    let (a7, r7) = record(l, 6, ds.line, "record 7 of dataset 55")?;
    let v7 = ints(r7, a7, "dataset 55 record 7")?;
    if v7.len() < 2 || v7[0] < 0 || v7[1] < 0 || v7.len() < 2 + v7[0] as usize {
        return Err(syntax(
            a7,
            format!(
                "dataset 55 record 7: '{}' must give NINT, NRV and NINT integers",
                r7.trim()
            ),
        ));
    }
    let (nint, nrv) = (v7[0] as usize, v7[1] as usize);
    let int_values = v7[2..2 + nint].to_vec();
    // Record 8: NRV reals on ceil(NRV/6) lines.
    let r8_lines = nrv.div_ceil(6).max(1);
    let mut reals = Vec::new();
    numbers(&l[7.min(l.len())..(7 + r8_lines).min(l.len())], &mut reals)?;
    if reals.len() != nrv {
        return Err(syntax(
            a7 + 1,
            format!(
                "dataset 55 record 8: {} reals, record 7 announces {nrv}",
                reals.len()
            ),
        ));
    }
    let per_node = if complex { 2 * ndv } else { ndv };
    let mut nodes = Vec::new();
    let mut k = 7 + r8_lines;
    while k < l.len() {
        let (at, r) = (l[k].0, &l[k].1);
        if r.trim().is_empty() {
            k += 1;
            continue;
        }
        let node = ints_n(r, 1, at, "dataset 55 record 9 (node label)")?[0];
        k += 1;
        let mut v = Vec::with_capacity(per_node);
        while v.len() < per_node {
            let (a, line) = record(l, k, at, &format!("the values of node {node}"))?;
            numbers(&[(a, line.to_string())], &mut v)?;
            k += 1;
        }
        if v.len() != per_node {
            return Err(syntax(
                l[k - 1].0,
                format!("node {node}: {} values, expected {per_node}", v.len()),
            ));
        }
        let values = if complex {
            v.chunks(2).map(|c| Complex64::new(c[0], c[1])).collect()
        } else {
            v.iter().map(|x| Complex64::new(*x, 0.0)).collect()
        };
        nodes.push(NodeValues { node, values });
    }
    Ok(Modal55 {
        id_lines: [id(0), id(1), id(2), id(3), id(4)],
        model_type: h[0],
        analysis_type: h[1],
        data_characteristic: h[2],
        specific_data_type: h[3],
        complex,
        values_per_node: ndv,
        ints: int_values,
        reals,
        nodes,
    })
}

/// Writes a dataset 55.
///
/// # Errors
/// [`UffError::Write`] for ID lines over 80 characters, nodes with a value count other than
/// NDV, non-finite values.
pub fn write(m: &Modal55, out: &mut String) -> Result<(), UffError> {
    out.push_str("    -1\n    55\n");
    for l in &m.id_lines {
        if l.chars().count() > 80 {
            return Err(UffError::Write(format!(
                "ID line '{l}' is longer than 80 characters"
            )));
        }
        let _ = writeln!(out, "{l:<80}");
    }
    let _ = writeln!(
        out,
        "{:>10}{:>10}{:>10}{:>10}{:>10}{:>10}",
        m.model_type,
        m.analysis_type,
        m.data_characteristic,
        m.specific_data_type,
        if m.complex { 5 } else { 2 },
        m.values_per_node
    );
    let mut r7 = format!("{:>10}{:>10}", m.ints.len(), m.reals.len());
    for i in &m.ints {
        let _ = write!(r7, "{i:>10}");
    }
    let _ = writeln!(out, "{r7}");
    write_reals(&m.reals, out)?;
    for n in &m.nodes {
        if n.values.len() != m.values_per_node {
            return Err(UffError::Write(format!(
                "node {}: {} values for NDV = {}",
                n.node,
                n.values.len(),
                m.values_per_node
            )));
        }
        let _ = writeln!(out, "{:>10}", n.node);
        let v: Vec<f64> = if m.complex {
            n.values.iter().flat_map(|c| [c.re, c.im]).collect()
        } else {
            n.values.iter().map(|c| c.re).collect()
        };
        write_reals(&v, out)?;
    }
    out.push_str("    -1\n");
    Ok(())
}

fn write_reals(v: &[f64], out: &mut String) -> Result<(), UffError> {
    if !v.iter().all(|x| x.is_finite()) {
        return Err(UffError::Write("dataset 55 with a non-finite value".into()));
    }
    for chunk in v.chunks(6) {
        for x in chunk {
            out.push_str(&e13(*x));
        }
        out.push('\n');
    }
    if v.is_empty() {
        out.push('\n');
    }
    Ok(())
}
