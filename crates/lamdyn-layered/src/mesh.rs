//! Structured meshes of 20-node hexahedra for a layered plate or shallow shell: every layer
//! gets its own elements through the thickness.
//!
//! The reference surface is the laminate's mid-thickness surface z₀(x, y) = −x²/(2R_x) −
//! y²/(2R_y) over [−a/2, a/2] × [−b/2, b/2]: a shallow dome, convex towards +z as a roof is (flat
//! when both radii are infinite) — the same surface and frame as lamdyn-fem's structured shell
//! meshes, so a shell model of the part has its mid-surface nodes under the bench's. A point at
//! height s through the thickness lies at (x, y, z₀) + s n(x, y), n ∝ (x/R_x, y/R_y, 1) the unit
//! normal, so every layer keeps its thickness on the curved part; the top surface is the outer
//! (convex) one.
//!
//! Nodes sit on a fine grid of (2n_x + 1) × (2n_y + 1) × (2n_z + 1) points; the serendipity
//! element uses those with at most one odd index (corners and mid-edges).
//!
//! Edge grading: a free laminate's core shears in a boundary layer along the free edges, of
//! width about the shear-lag length √(E_f h_f h_c / 2G) (5 cm for the paper's roof: one
//! element of an 18 × 18 mesh). With grading g ∈ [0, 1) the element corners along x lie at
//! x(u) = a (u − g sin(2πu)/(2π) − 1/2), u = i/n_x (the same along y): the element widths
//! fall from (1 + g) times the mean at the centre to (1 − g) times it at the edges, smoothly,
//! and mid-edge nodes stay at the middle of their corners.

use crate::error::LayeredError;
use crate::hex20::NODES;

/// One layer of the stack, bottom to top.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerMesh {
    /// Thickness, m.
    pub thickness_m: f64,
    /// Elements through this layer's thickness (at least 1).
    pub elements: usize,
}

/// A layered plate or shallow shell to mesh (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct LayeredPlateSpec {
    /// Length a along x, m.
    pub length_m: f64,
    /// Width b along y, m.
    pub width_m: f64,
    /// Elements along x.
    pub nx: usize,
    /// Elements along y.
    pub ny: usize,
    /// Radius of curvature along x, m (infinite: straight; negative: curved towards +z).
    pub radius_x_m: f64,
    /// Radius of curvature along y, m (infinite: straight; negative: curved towards +z).
    pub radius_y_m: f64,
    /// The layers, bottom to top.
    pub layers: Vec<LayerMesh>,
    /// Edge grading g ∈ [0, 1) of the in-plane element widths (module docs; 0: uniform).
    pub edge_grading: f64,
}

/// Plan coordinate of fine-grid point `i` of `2n + 1` along a side of length `a`, centred,
/// with edge grading `g` (module docs): corners (even i) on the graded map, mid-edge points
/// (odd i) halfway between their corners.
pub fn graded_coordinate(i: usize, n: usize, a: f64, g: f64) -> f64 {
    let corner = |k: usize| {
        let u = k as f64 / n as f64;
        a * (u - g * (2.0 * std::f64::consts::PI * u).sin() / (2.0 * std::f64::consts::PI) - 0.5)
    };
    if i % 2 == 0 {
        corner(i / 2)
    } else {
        0.5 * (corner(i / 2) + corner(i / 2 + 1))
    }
}

/// A hexahedral mesh: nodes, 20-node elements (C3D20 order) and each element's layer.
#[derive(Debug, Clone, PartialEq)]
pub struct HexMesh {
    /// Node coordinates, m.
    pub nodes: Vec<[f64; 3]>,
    /// Element connectivity.
    pub elements: Vec<[usize; 20]>,
    /// Layer index of each element.
    pub layer: Vec<usize>,
    /// Nodes of the top surface with its outward unit normal there.
    pub top: Vec<(usize, [f64; 3])>,
    /// Nodes of the bottom surface with its outward unit normal there (−n).
    pub bottom: Vec<(usize, [f64; 3])>,
}

/// Checks a stack's layers: at least one, each with a positive thickness and an element.
///
/// # Errors
/// [`LayeredError::Invalid`] naming the layer (from 1).
pub(crate) fn check_layers(layers: &[LayerMesh]) -> Result<(), LayeredError> {
    let bad = |field: &str, why: String| Err(LayeredError::Invalid(format!("{field}: {why}")));
    if layers.is_empty() {
        return bad("layers", "no layer".into());
    }
    for (i, l) in layers.iter().enumerate() {
        if !(l.thickness_m.is_finite() && l.thickness_m > 0.0) {
            return bad(
                &format!("layer {}", i + 1),
                format!("thickness {} m must be positive", l.thickness_m),
            );
        }
        if l.elements == 0 {
            return bad(
                &format!("layer {}", i + 1),
                "needs at least one element".into(),
            );
        }
    }
    Ok(())
}

/// The heights s of the fine grid through the thickness (2 n_z + 1 of them, bottom to top,
/// the mid-thickness at s = 0) and the layer of each element through the thickness.
pub(crate) fn heights(layers: &[LayerMesh]) -> (Vec<f64>, Vec<usize>) {
    let total: f64 = layers.iter().map(|l| l.thickness_m).sum();
    let mut s = vec![-0.5 * total];
    let mut fine_layer = Vec::new();
    for (li, l) in layers.iter().enumerate() {
        let h = l.thickness_m / (2 * l.elements) as f64;
        for _ in 0..2 * l.elements {
            s.push(s[s.len() - 1] + h);
        }
        fine_layer.extend(std::iter::repeat_n(li, l.elements));
    }
    (s, fine_layer)
}

impl LayeredPlateSpec {
    /// Checks the numbers (positive sizes and counts, radii non-zero: infinite for straight,
    /// negative for curved towards +z).
    fn validate(&self) -> Result<(), LayeredError> {
        let bad = |field: &str, why: String| Err(LayeredError::Invalid(format!("{field}: {why}")));
        for (name, v) in [("length_m", self.length_m), ("width_m", self.width_m)] {
            if !(v.is_finite() && v > 0.0) {
                return bad(name, format!("{v} must be a positive length"));
            }
        }
        for (name, v) in [
            ("radius_x_m", self.radius_x_m),
            ("radius_y_m", self.radius_y_m),
        ] {
            if v.is_nan() || v == 0.0 {
                return bad(
                    name,
                    format!("{v} must be non-zero (inf for straight, negative for a bowl)"),
                );
            }
        }
        if !(0.0..1.0).contains(&self.edge_grading) {
            return bad(
                "edge_grading",
                format!("{} must lie in [0, 1)", self.edge_grading),
            );
        }
        if self.nx == 0 || self.ny == 0 {
            return bad("elements", format!("{} x {} in plane", self.nx, self.ny));
        }
        check_layers(&self.layers)
    }

    /// Mid-surface height and unit normal at (x, y).
    fn surface(&self, x: f64, y: f64) -> (f64, [f64; 3]) {
        let z = -x * x / (2.0 * self.radius_x_m) - y * y / (2.0 * self.radius_y_m);
        let (gx, gy) = (x / self.radius_x_m, y / self.radius_y_m);
        let norm = (1.0 + gx * gx + gy * gy).sqrt();
        (z, [gx / norm, gy / norm, 1.0 / norm])
    }

    /// Builds the mesh.
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] naming the field for non-positive sizes, thicknesses or counts.
    pub fn build(&self) -> Result<HexMesh, LayeredError> {
        self.validate()?;
        let (s, fine_layer) = heights(&self.layers);
        let (fx, fy, fz) = (2 * self.nx + 1, 2 * self.ny + 1, s.len());
        let mut id = vec![usize::MAX; fx * fy * fz];
        let mut nodes = Vec::new();
        let (mut top, mut bottom) = (Vec::new(), Vec::new());
        for k in 0..fz {
            for j in 0..fy {
                for i in 0..fx {
                    if (i % 2) + (j % 2) + (k % 2) > 1 {
                        continue;
                    }
                    let x = graded_coordinate(i, self.nx, self.length_m, self.edge_grading);
                    let y = graded_coordinate(j, self.ny, self.width_m, self.edge_grading);
                    let (z, n) = self.surface(x, y);
                    id[(k * fy + j) * fx + i] = nodes.len();
                    if k == fz - 1 {
                        top.push((nodes.len(), n));
                    } else if k == 0 {
                        bottom.push((nodes.len(), [-n[0], -n[1], -n[2]]));
                    }
                    nodes.push([x + s[k] * n[0], y + s[k] * n[1], z + s[k] * n[2]]);
                }
            }
        }
        let nz = fz / 2;
        let mut elements = Vec::with_capacity(self.nx * self.ny * nz);
        let mut layer = Vec::with_capacity(elements.capacity());
        for ek in 0..nz {
            for ej in 0..self.ny {
                for ei in 0..self.nx {
                    let mut conn = [0; 20];
                    for (a, c) in NODES.iter().enumerate() {
                        let i = 2 * ei + (c[0] + 1.0) as usize;
                        let j = 2 * ej + (c[1] + 1.0) as usize;
                        let k = 2 * ek + (c[2] + 1.0) as usize;
                        conn[a] = id[(k * fy + j) * fx + i];
                    }
                    elements.push(conn);
                    layer.push(fine_layer[ek]);
                }
            }
        }
        Ok(HexMesh {
            nodes,
            elements,
            layer,
            top,
            bottom,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(rx: f64) -> LayeredPlateSpec {
        LayeredPlateSpec {
            length_m: 0.6,
            width_m: 0.4,
            nx: 3,
            ny: 2,
            radius_x_m: rx,
            radius_y_m: f64::INFINITY,
            edge_grading: 0.0,
            layers: vec![
                LayerMesh {
                    thickness_m: 0.003,
                    elements: 1,
                },
                LayerMesh {
                    thickness_m: 0.001,
                    elements: 2,
                },
                LayerMesh {
                    thickness_m: 0.003,
                    elements: 1,
                },
            ],
        }
    }

    /// Node and element counts of the serendipity grid; every node used; layers in order.
    #[test]
    fn counts_and_layers() {
        let m = spec(f64::INFINITY).build().unwrap();
        let (nx, ny, nz) = (3, 2, 4);
        let corners = (nx + 1) * (ny + 1) * (nz + 1);
        let edges = nx * (ny + 1) * (nz + 1) + ny * (nx + 1) * (nz + 1) + nz * (nx + 1) * (ny + 1);
        assert_eq!(m.nodes.len(), corners + edges);
        assert_eq!(m.elements.len(), nx * ny * nz);
        let mut used = vec![false; m.nodes.len()];
        m.elements.iter().flatten().for_each(|&n| used[n] = true);
        assert!(used.iter().all(|u| *u));
        assert_eq!(m.layer[..6], [0; 6]);
        assert_eq!(m.layer[6..18], [1; 12]);
        assert_eq!(m.layer[18..], [2; 6]);
        // Flat: bottom at −3.5 mm, top at +3.5 mm.
        let zmin = m.nodes.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
        assert!((zmin + 0.0035).abs() < 1e-15);
    }

    /// On a curved mesh each layer keeps its thickness along the normal, and every element has
    /// a positive Jacobian.
    #[test]
    fn curved_layers_keep_their_thickness() {
        let s = spec(1.0);
        let m = s.build().unwrap();
        let glass = crate::hex20::Elastic {
            young_pa: 70e9,
            poisson: 0.22,
            density_kg_m3: 2500.0,
        };
        for e in &m.elements {
            let x: [[f64; 3]; 20] = std::array::from_fn(|a| m.nodes[e[a]]);
            assert!(crate::hex20::matrices(&x, &glass).is_some());
        }
        // Corner node 0 of element 0 (bottom) to node 4 (top of the bottom layer): 3 mm.
        let e = m.elements[0];
        let d: f64 = (0..3)
            .map(|c| (m.nodes[e[4]][c] - m.nodes[e[0]][c]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!((d - 0.003).abs() < 1e-15, "{d}");
    }

    #[test]
    fn bad_specs_name_the_field() {
        let mut s = spec(1.0);
        s.layers[1].thickness_m = 0.0;
        let e = s.build().unwrap_err().to_string();
        assert!(e.contains("layer 2") && e.contains("thickness"), "{e}");
        let mut s = spec(0.0);
        s.nx = 3;
        assert!(s.build().unwrap_err().to_string().contains("radius_x_m"));
    }
}
