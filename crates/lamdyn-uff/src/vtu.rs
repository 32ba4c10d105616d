//! Mode shapes with their mesh as a VTK unstructured grid (`.vtu`, ASCII XML) for ParaView.
//!
//! Points: the nodes of datasets 15/2411 (file units). Cells: the elements of 2412 — rods and
//! beams as VTK lines (3), three-node elements as triangles (5), four-node ones as quads (9),
//! other sizes as polygons (7); trace lines (82) as poly-lines (4). Point data: one 3-vector
//! per dataset 55 (its first three values per node, real parts; `<name>_imag` beside it for
//! complex shapes), named `mode_NN_<f>Hz`, zero at nodes the dataset does not list.

use crate::d55::Modal55;
use crate::error::UffError;
use crate::geometry::Node;
use crate::{Dataset, UffFile};
use std::collections::HashMap;
use std::fmt::Write as _;

fn cell_type(n: usize) -> u8 {
    match n {
        2 => 3,
        3 => 5,
        4 => 9,
        _ => 7,
    }
}

/// The file's mesh and mode shapes as VTU text.
///
/// # Errors
/// [`UffError::Convert`] when the file has no nodes, or an element names a node it does not
/// define.
pub fn to_vtu(file: &UffFile) -> Result<String, UffError> {
    let mut nodes = Vec::new();
    let mut cells: Vec<(Vec<i64>, u8)> = Vec::new();
    let mut modes: Vec<&Modal55> = Vec::new();
    for d in &file.datasets {
        match &d.dataset {
            Dataset::Nodes(n) => nodes.extend(n.nodes.iter().cloned()),
            Dataset::Elements(e) => cells.extend(
                e.iter()
                    .map(|e| (e.nodes.clone(), cell_type(e.nodes.len()))),
            ),
            Dataset::TraceLine(t) => {
                // Pen-up zeros split a trace line into poly-lines.
                for run in t.nodes.split(|n| *n == 0).filter(|r| r.len() >= 2) {
                    cells.push((run.to_vec(), if run.len() == 2 { 3 } else { 4 }));
                }
            }
            Dataset::NodalData(m) => modes.push(m),
            _ => {}
        }
    }
    if nodes.is_empty() {
        return Err(UffError::Convert(
            "the file defines no nodes (datasets 15 or 2411): nothing to draw".into(),
        ));
    }
    let index: HashMap<i64, usize> = nodes
        .iter()
        .enumerate()
        .map(|(i, n)| (n.label, i))
        .collect();
    let mut conn = Vec::new();
    let mut offsets = Vec::new();
    let mut types = Vec::new();
    for (c, kind) in &cells {
        for label in c {
            let i = index.get(label).ok_or_else(|| {
                UffError::Convert(format!(
                    "an element uses node {label}, which the file does not define"
                ))
            })?;
            conn.push(*i);
        }
        offsets.push(conn.len());
        types.push(*kind);
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" \
         byte_order=\"LittleEndian\">\n<UnstructuredGrid>"
    );
    let _ = writeln!(
        s,
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n<Points>\n<DataArray type=\"Float64\" \
         NumberOfComponents=\"3\" format=\"ascii\">",
        nodes.len(),
        cells.len()
    );
    for n in &nodes {
        let _ = writeln!(s, "{:e} {:e} {:e}", n.xyz[0], n.xyz[1], n.xyz[2]);
    }
    let _ = writeln!(
        s,
        "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" \
         format=\"ascii\">"
    );
    let join = |v: &mut dyn Iterator<Item = String>| v.collect::<Vec<_>>().join(" ");
    let _ = writeln!(s, "{}", join(&mut conn.iter().map(|v| v.to_string())));
    let _ = writeln!(
        s,
        "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n{}",
        join(&mut offsets.iter().map(|v| v.to_string()))
    );
    let _ = writeln!(
        s,
        "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n{}",
        join(&mut types.iter().map(|v| v.to_string()))
    );
    let _ = writeln!(s, "</DataArray>\n</Cells>\n<PointData>");
    for (k, m) in modes.iter().enumerate() {
        write_mode(&mut s, k, m, &nodes);
    }
    let _ = writeln!(s, "</PointData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>");
    Ok(s)
}

/// Mode `m` (the `k`-th) at `nodes` as point data: its real part, and its imaginary part when
/// it is complex; zero at a node it has no value for.
fn write_mode(s: &mut String, k: usize, m: &Modal55, nodes: &[Node]) {
    let values: HashMap<i64, &[num_complex::Complex64]> = m
        .nodes
        .iter()
        .map(|n| (n.node, n.values.as_slice()))
        .collect();
    let f = m
        .frequency_hz()
        .map_or(String::new(), |f| format!("_{f:.3}Hz"));
    let parts: &[(&str, bool)] = if m.complex {
        &[("", false), ("_imag", true)]
    } else {
        &[("", false)]
    };
    for (suffix, imag) in parts {
        let _ = writeln!(
            s,
            "<DataArray type=\"Float64\" Name=\"mode_{:02}{f}{suffix}\" NumberOfComponents=\"3\" \
             format=\"ascii\">",
            k + 1
        );
        for n in nodes {
            let v = values.get(&n.label).copied().unwrap_or(&[]);
            let c = |i: usize| v.get(i).map_or(0.0, |z| if *imag { z.im } else { z.re });
            let _ = writeln!(s, "{:e} {:e} {:e}", c(0), c(1), c(2));
        }
        let _ = writeln!(s, "</DataArray>");
    }
}
