//! Geometry datasets: nodes (15, 2411), elements (2412), trace lines (82) and coordinate systems
//! (18, 2420).
//!
//! - 15 (4I10,1P3E13.5): node label, definition and displacement coordinate systems, colour,
//!   x y z — one line per node.
//! - 2411: record 1 (4I10) label, export and displacement coordinate systems, colour; record 2
//!   (1P3D25.16) x y z.
//! - 2412: record 1 (6I10) label, FE descriptor id, physical and material property, colour,
//!   number of nodes; for beam descriptors (11, 21–24) record 2 (3I10) orientation node and
//!   cross sections; then the node labels (8I10 per line).
//! - 82: record 1 (3I10) trace line number, number of nodes, colour; record 2 (80A1) its name;
//!   record 3 (8I10) node labels, 0 meaning "lift the pen".
//! - 18: per system, record 1 (5I10) label, type (0 cartesian, 1 cylindrical, 2 spherical),
//!   reference system, colour, definition method; record 2 (40A2) name; records 3–4 (6E13.5,
//!   3E13.5) origin, a point on the x axis and a point in the xz plane.
//! - 2420: record 1 (I10) part UID; record 2 (40A2) part name; per system: record 3 (3I10)
//!   label, type, colour; record 4 (40A2) name; records 5–8 (1P3D25.16) the rotation rows
//!   (x, y, z axes in the global frame) and the origin.
//!
//! Both coordinate-system datasets are reduced to an origin and three unit axes in the global
//! frame, which is what expressing sensor directions needs.

use crate::d58::{e13, e25};
use crate::error::{UffError, syntax};
use crate::fields::{cols, ints, ints_n, numbers, record};
use crate::scan::RawDataset;
use serde::Serialize;
use std::fmt::Write as _;

/// A node.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Node {
    /// Label.
    pub label: i64,
    /// Coordinate system of the definition.
    pub definition_cs: i64,
    /// Coordinate system of displacements.
    pub displacement_cs: i64,
    /// Colour.
    pub color: i64,
    /// Coordinates (file units).
    pub xyz: [f64; 3],
}

/// Nodes of a dataset 15 (single precision) or 2411 (double).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Nodes {
    /// 15 or 2411.
    pub dataset: u32,
    /// The nodes in file order.
    pub nodes: Vec<Node>,
}

/// An element of dataset 2412.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Element {
    /// Label.
    pub label: i64,
    /// FE descriptor id (11 rod, 21–24 beams, 41/91 triangles, 44/94 quadrilaterals, ...).
    pub descriptor: i64,
    /// Physical property table.
    pub physical: i64,
    /// Material property table.
    pub material: i64,
    /// Colour.
    pub color: i64,
    /// Beam orientation node and cross sections, for beam descriptors.
    pub beam: Option<[i64; 3]>,
    /// Node labels.
    pub nodes: Vec<i64>,
}

/// A trace line of dataset 82.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct TraceLine {
    /// Number.
    pub number: i64,
    /// Colour.
    pub color: i64,
    /// Name.
    pub name: String,
    /// Node labels; 0 lifts the pen.
    pub nodes: Vec<i64>,
}

/// A coordinate system as origin and unit axes in the global frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CoordinateSystem {
    /// Label.
    pub label: i64,
    /// 0 cartesian, 1 cylindrical, 2 spherical.
    pub kind: i64,
    /// Name.
    pub name: String,
    /// Origin.
    pub origin: [f64; 3],
    /// Rows: the x, y and z axes.
    pub axes: [[f64; 3]; 3],
}

impl CoordinateSystem {
    /// A local direction expressed in the global frame.
    pub fn to_global(&self, d: [f64; 3]) -> [f64; 3] {
        let a = &self.axes;
        [0, 1, 2].map(|c| d[0] * a[0][c] + d[1] * a[1][c] + d[2] * a[2][c])
    }
}

fn is_beam(descriptor: i64) -> bool {
    matches!(descriptor, 11 | 21 | 22 | 23 | 24)
}

/// Parses a dataset 15.
///
/// # Errors
/// [`UffError::Syntax`] naming the line of a bad field.
pub fn parse_15(ds: &RawDataset) -> Result<Nodes, UffError> {
    let mut nodes = Vec::with_capacity(ds.lines.len());
    for (at, line) in &ds.lines {
        if line.trim().is_empty() {
            continue;
        }
        let i = ints_n(cols(line, 0, 40), 4, *at, "dataset 15 node")?;
        let mut xyz = Vec::with_capacity(3);
        numbers(&[(*at, cols(line, 40, line.len()).to_string())], &mut xyz)?;
        if xyz.len() != 3 {
            return Err(syntax(
                *at,
                format!("dataset 15: {} coordinates, expected 3", xyz.len()),
            ));
        }
        nodes.push(Node {
            label: i[0],
            definition_cs: i[1],
            displacement_cs: i[2],
            color: i[3],
            xyz: [xyz[0], xyz[1], xyz[2]],
        });
    }
    Ok(Nodes { dataset: 15, nodes })
}

/// Parses a dataset 2411.
///
/// # Errors
/// [`UffError::Syntax`] naming the line: bad fields, a node without its coordinate record.
pub fn parse_2411(ds: &RawDataset) -> Result<Nodes, UffError> {
    let l = &ds.lines;
    let mut nodes = Vec::with_capacity(l.len() / 2);
    let mut k = 0;
    while k < l.len() {
        if l[k].1.trim().is_empty() {
            k += 1;
            continue;
        }
        let (at, r1) = (l[k].0, &l[k].1);
        let i = ints_n(r1, 4, at, "dataset 2411 record 1")?;
        let (at2, r2) = record(l, k + 1, at, &format!("the coordinates of node {}", i[0]))?;
        let mut xyz = Vec::with_capacity(3);
        numbers(&[(at2, r2.to_string())], &mut xyz)?;
        if xyz.len() != 3 {
            return Err(syntax(
                at2,
                format!("dataset 2411: {} coordinates, expected 3", xyz.len()),
            ));
        }
        nodes.push(Node {
            label: i[0],
            definition_cs: i[1],
            displacement_cs: i[2],
            color: i[3],
            xyz: [xyz[0], xyz[1], xyz[2]],
        });
        k += 2;
    }
    Ok(Nodes {
        dataset: 2411,
        nodes,
    })
}

/// Parses a dataset 2412.
///
/// # Errors
/// [`UffError::Syntax`] naming the line: bad fields, fewer node labels than announced.
pub fn parse_2412(ds: &RawDataset) -> Result<Vec<Element>, UffError> {
    let l = &ds.lines;
    let mut out = Vec::new();
    let mut k = 0;
    while k < l.len() {
        let (at, r1) = (l[k].0, &l[k].1);
        if r1.trim().is_empty() {
            k += 1;
            continue;
        }
        let h = ints_n(r1, 6, at, "dataset 2412 record 1")?;
        k += 1;
        let beam = if is_beam(h[1]) {
            let (a, r) = record(l, k, at, &format!("record 2 of beam element {}", h[0]))?;
            let b = ints_n(r, 3, a, "dataset 2412 record 2")?;
            k += 1;
            Some([b[0], b[1], b[2]])
        } else {
            None
        };
        let want = usize::try_from(h[5]).map_err(|_| {
            syntax(
                at,
                format!("element {}: node count {} is negative", h[0], h[5]),
            )
        })?;
        let mut nodes = Vec::with_capacity(want.min(64));
        while nodes.len() < want {
            let (a, r) = record(l, k, at, &format!("the nodes of element {}", h[0]))?;
            let v = ints(r, a, "dataset 2412 node labels")?;
            if v.is_empty() || nodes.len() + v.len() > want {
                return Err(syntax(
                    a,
                    format!(
                        "element {}: {} node labels for {want} nodes",
                        h[0],
                        nodes.len() + v.len()
                    ),
                ));
            }
            nodes.extend(v);
            k += 1;
        }
        out.push(Element {
            label: h[0],
            descriptor: h[1],
            physical: h[2],
            material: h[3],
            color: h[4],
            beam,
            nodes,
        });
    }
    Ok(out)
}

/// Parses a dataset 82.
///
/// # Errors
/// [`UffError::Syntax`] naming the line: bad fields, fewer node labels than announced.
pub fn parse_82(ds: &RawDataset) -> Result<TraceLine, UffError> {
    let (at, r1) = record(&ds.lines, 0, ds.line, "record 1 of dataset 82")?;
    let h = ints_n(r1, 3, at, "dataset 82 record 1")?;
    let name = ds
        .lines
        .get(1)
        .map_or(String::new(), |l| l.1.trim().to_string());
    let mut nodes = Vec::new();
    for (a, line) in ds.lines.iter().skip(2) {
        nodes.extend(ints(line, *a, "dataset 82 node labels")?);
    }
    // Padded records: zeros beyond the announced count.
    if h[1] >= 0 && nodes.len() as i64 > h[1] && nodes[h[1] as usize..].iter().all(|n| *n == 0) {
        nodes.truncate(h[1] as usize);
    }
    if nodes.len() as i64 != h[1] {
        return Err(syntax(
            at,
            format!(
                "dataset 82: record 1 announces {} nodes, record 3 holds {}",
                h[1],
                nodes.len()
            ),
        ));
    }
    Ok(TraceLine {
        number: h[0],
        color: h[2],
        name,
        nodes,
    })
}

fn unit(v: [f64; 3]) -> Option<[f64; 3]> {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (n > 0.0 && n.is_finite()).then(|| v.map(|x| x / n))
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// One coordinate-system block: its header integers, name, numbers and line.
struct SystemBlock {
    ints: Vec<i64>,
    name: String,
    values: Vec<f64>,
    line: usize,
}

/// The blocks of a coordinate-system dataset from record `start` on: a line of `n_ints`
/// integers, a name line, then `rows` lines holding `n_values` numbers.
fn system_blocks(
    ds: &RawDataset,
    start: usize,
    n_ints: usize,
    rows: usize,
    n_values: usize,
    what: &str,
) -> Result<Vec<SystemBlock>, UffError> {
    let l = &ds.lines;
    let mut out = Vec::new();
    let mut k = start;
    while k < l.len() {
        let (at, r) = (l[k].0, &l[k].1);
        if r.trim().is_empty() {
            k += 1;
            continue;
        }
        let ints = ints_n(r, n_ints, at, &format!("dataset {what} header"))?;
        let name = record(
            l,
            k + 1,
            at,
            &format!("the name of coordinate system {}", ints[0]),
        )?
        .1
        .trim()
        .to_string();
        let mut values = Vec::new();
        numbers(
            &l[(k + 2).min(l.len())..(k + 2 + rows).min(l.len())],
            &mut values,
        )?;
        if values.len() != n_values {
            return Err(syntax(
                at,
                format!(
                    "coordinate system {}: {} numbers, expected {n_values}",
                    ints[0],
                    values.len()
                ),
            ));
        }
        out.push(SystemBlock {
            ints,
            name,
            values,
            line: at,
        });
        k += 2 + rows;
    }
    Ok(out)
}

/// Parses a dataset 18 (old coordinate systems, defined by three points: origin, a point on
/// the x axis, a point in the xz plane).
///
/// # Errors
/// [`UffError::Syntax`] naming the line: bad fields, degenerate points.
pub fn parse_18(ds: &RawDataset) -> Result<Vec<CoordinateSystem>, UffError> {
    system_blocks(ds, 0, 5, 2, 9, "18")?
        .into_iter()
        .map(|b| {
            let p = &b.values;
            let origin = [p[0], p[1], p[2]];
            let sub = |i: usize| [p[i] - origin[0], p[i + 1] - origin[1], p[i + 2] - origin[2]];
            let bad = || {
                syntax(
                    b.line,
                    format!(
                        "coordinate system {}: its three points do not span a plane",
                        b.ints[0]
                    ),
                )
            };
            let x = unit(sub(3)).ok_or_else(bad)?;
            let z = unit(cross(x, sub(6))).ok_or_else(bad)?;
            Ok(CoordinateSystem {
                label: b.ints[0],
                kind: b.ints[1],
                name: b.name,
                origin,
                axes: [x, cross(z, x), z],
            })
        })
        .collect()
}

/// Parses a dataset 2420 (rows: the x, y, z axes, then the origin).
///
/// # Errors
/// [`UffError::Syntax`] naming the line: bad fields, a system without its four rows.
pub fn parse_2420(ds: &RawDataset) -> Result<Vec<CoordinateSystem>, UffError> {
    Ok(system_blocks(ds, 2, 3, 4, 12, "2420")?
        .into_iter()
        .map(|b| {
            let v = &b.values;
            let row = |i: usize| [v[3 * i], v[3 * i + 1], v[3 * i + 2]];
            CoordinateSystem {
                label: b.ints[0],
                kind: b.ints[1],
                name: b.name,
                origin: row(3),
                axes: [row(0), row(1), row(2)],
            }
        })
        .collect())
}

/// Writes a dataset 15 (coordinates in E13.5 on the node's line).
///
/// # Errors
/// [`UffError::Write`] for non-finite coordinates.
pub fn write_15(nodes: &[Node], out: &mut String) -> Result<(), UffError> {
    write_nodes(nodes, "    15", "", e13, out)
}

/// Writes a dataset 2411 (coordinates in E25.16 on a line of their own).
///
/// # Errors
/// [`UffError::Write`] for non-finite coordinates.
pub fn write_2411(nodes: &[Node], out: &mut String) -> Result<(), UffError> {
    write_nodes(nodes, "  2411", "\n", e25, out)
}

/// The node datasets: labels and systems in 4I10, then `sep` and the coordinates in `coord`.
fn write_nodes(
    nodes: &[Node],
    number: &str,
    sep: &str,
    coord: fn(f64) -> String,
    out: &mut String,
) -> Result<(), UffError> {
    let _ = writeln!(out, "    -1\n{number}");
    for n in nodes {
        if !n.xyz.iter().all(|v| v.is_finite()) {
            return Err(UffError::Write(format!(
                "node {} has a non-finite coordinate",
                n.label
            )));
        }
        let _ = writeln!(
            out,
            "{:>10}{:>10}{:>10}{:>10}{sep}{}{}{}",
            n.label,
            n.definition_cs,
            n.displacement_cs,
            n.color,
            coord(n.xyz[0]),
            coord(n.xyz[1]),
            coord(n.xyz[2])
        );
    }
    out.push_str("    -1\n");
    Ok(())
}
