//! Mode-shape outputs: the modal assurance criterion, VTK unstructured grids and JSON.

mod mac;
mod vtu;

pub use mac::{mac, mac_matrix};
pub use vtu::{vtu_text, write_vtu};
