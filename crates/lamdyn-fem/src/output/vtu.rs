//! VTK XML unstructured grid (`.vtu`, ASCII) with mode shapes as point data, for ParaView.
//!
//! Cells are VTK_QUAD (type 9). Each mode contributes a `mode_NN` vector field (translations, m,
//! mass-normalised) and a `rotation_NN` field (rad); frequencies are in the field names' order
//! in a `frequencies_hz` field data array.

use crate::element::ElementOrder;
use crate::error::FemError;
use crate::mesh::Mesh;
use std::fmt::Write as _;
use std::path::Path;

/// Writes `mesh` with the mode shapes (columns of `shapes`, 6 dofs per node) to `path`,
/// atomically (a temporary file renamed over the target); the text is [`vtu_text`].
///
/// # Errors
/// [`FemError::Write`] when the file cannot be written.
pub fn write_vtu(
    path: &Path,
    mesh: &Mesh,
    freqs_hz: &[f64],
    shapes: &[Vec<f64>],
) -> Result<(), FemError> {
    write_atomic(path, vtu_text(mesh, freqs_hz, shapes).as_bytes())
}

/// The `.vtu` text of `mesh` with the mode shapes (columns of `shapes`, 6 dofs per node).
pub fn vtu_text(mesh: &Mesh, freqs_hz: &[f64], shapes: &[Vec<f64>]) -> String {
    let mut s = String::new();
    let (nn, ne) = (mesh.nodes().len(), mesh.n_elements());
    // VTK_QUAD (9) or VTK_BIQUADRATIC_QUAD (28); both share Gmsh's node order.
    let (per, vtk_type) = match mesh.order() {
        ElementOrder::Linear => (4, 9),
        ElementOrder::Quadratic => (9, 28),
    };
    let _ = writeln!(
        s,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" \
         byte_order=\"LittleEndian\">\n<UnstructuredGrid>"
    );
    let _ = writeln!(
        s,
        "<FieldData>\n<DataArray type=\"Float64\" Name=\"frequencies_hz\" NumberOfTuples=\"{}\" \
         format=\"ascii\">",
        freqs_hz.len()
    );
    for f in freqs_hz {
        let _ = write!(s, "{f:.9e} ");
    }
    let _ = writeln!(s, "\n</DataArray>\n</FieldData>");
    let _ = writeln!(
        s,
        "<Piece NumberOfPoints=\"{nn}\" NumberOfCells=\"{ne}\">\n<Points>\n<DataArray \
         type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
    );
    for p in mesh.nodes() {
        let _ = writeln!(s, "{:.12e} {:.12e} {:.12e}", p[0], p[1], p[2]);
    }
    let _ = writeln!(
        s,
        "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" \
         format=\"ascii\">"
    );
    for e in mesh.elements() {
        let line: Vec<String> = e.iter().map(|n| n.to_string()).collect();
        let _ = writeln!(s, "{}", line.join(" "));
    }
    let _ = writeln!(
        s,
        "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">"
    );
    for i in 1..=ne {
        let _ = write!(s, "{} ", per * i);
    }
    let _ = writeln!(
        s,
        "\n</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">"
    );
    for _ in 0..ne {
        let _ = write!(s, "{vtk_type} ");
    }
    let _ = writeln!(s, "\n</DataArray>\n</Cells>\n<PointData>");
    for (m, shape) in shapes.iter().enumerate() {
        for (name, off) in [("mode", 0), ("rotation", 3)] {
            let _ = writeln!(
                s,
                "<DataArray type=\"Float64\" Name=\"{name}_{:02}\" NumberOfComponents=\"3\" \
                 format=\"ascii\">",
                m + 1
            );
            for i in 0..nn {
                let _ = writeln!(
                    s,
                    "{:.9e} {:.9e} {:.9e}",
                    shape[6 * i + off],
                    shape[6 * i + off + 1],
                    shape[6 * i + off + 2]
                );
            }
            let _ = writeln!(s, "</DataArray>");
        }
    }
    let _ = writeln!(s, "</PointData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>");
    s
}

/// Writes `bytes` to a temporary file next to `path`, then renames it over `path`.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), FemError> {
    let err = |e: std::io::Error| FemError::Write {
        path: path.display().to_string(),
        reason: e.to_string(),
    };
    let tmp = path.with_extension(format!(
        "{}.tmp",
        path.extension().and_then(|e| e.to_str()).unwrap_or("out")
    ));
    std::fs::write(&tmp, bytes).map_err(err)?;
    std::fs::rename(&tmp, path).map_err(err)
}
