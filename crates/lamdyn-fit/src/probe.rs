//! Sensors and excitations on the FE mesh: a channel (point and direction) becomes a vector over
//! the global dofs, nonzero on the translations of the nearest node.

use crate::error::{FitError, inconsistent};
use lamdyn_fem::mesh::{Locator, Mesh};
use lamdyn_frf::Channel;

/// A channel mapped to a node: response u = d·(u_x, u_y, u_z) of `node`, or a unit force along d.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Probe {
    /// Node index.
    pub node: usize,
    /// Unit direction in the global frame.
    pub direction: [f64; 3],
}

impl Probe {
    /// The nonzero entries (dof, weight) of the probe's vector over the 6-dof-per-node system.
    pub fn entries(&self) -> [(usize, f64); 3] {
        [0, 1, 2].map(|c| (6 * self.node + c, self.direction[c]))
    }

    /// pᵀ x for a vector over the dofs.
    pub fn dot(&self, x: impl Fn(usize) -> f64) -> f64 {
        self.entries().iter().map(|(d, w)| w * x(*d)).sum()
    }
}

/// Maps channels to nodes within `tolerance_m`.
///
/// # Errors
/// [`FitError::Inconsistent`] naming the channel whose point is off the mesh.
pub fn probes(mesh: &Mesh, channels: &[Channel], tolerance_m: f64) -> Result<Vec<Probe>, FitError> {
    let locator = Locator::new(mesh, tolerance_m);
    channels
        .iter()
        .map(|c| {
            let node = locator.locate_all(&[c.point_m]).map_err(|e| {
                inconsistent(
                    &format!("channel '{}'", c.name),
                    format!("{e} (sensor off the mesh?)"),
                )
            })?[0];
            Ok(Probe {
                node,
                direction: c.direction,
            })
        })
        .collect()
}
