//! The layered inverse: the core's G* at a measured mode from the layered model itself.
//!
//! The effective-modulus route (paper eqs. 2–10 then 33–45, or the exact Mead–Markus inverse)
//! assumes every mode of the plate sees the bending stiffness of a free wave at its frequency.
//! A sandwich plate's modes do not: a twisting mode of a free plate shears its core mainly
//! near the edges, a bending mode along its wavelength, so one laminate modulus per frequency
//! cannot hold for all modes (the demo shows errors of tens of per cent). Here the plate is
//! modelled as it is — each layer meshed with 20-node hexahedra ([`crate::mesh`],
//! [`crate::hex20`]) — and the core's modulus is found per mode: with the core stiffness
//! assembled at G_a and scaled by s = G*/G_a (constant Poisson's ratio), the reduced model's
//! complex eigenvalues λ(s) of Vᵀ((1 + iη_e)K_e + s K_c)V x = λ x (Vᵀ M V = I, [`crate::reduced`])
//! are matched to the measured pole, λ_meas = −p² = ω_n²(1 + iη) for a pole p of the
//! identification, by a secant iteration on s:
//!
//!   s_{k+1} = s_k − r_k (s_k − s_{k−1}) / (r_k − r_{k−1}),  r = λ_near(s) − λ_meas,
//!
//! (steps cut to half the modulus), with λ_near the eigenvalue of the matched mode. Because the modulus is solved at each mode's own
//! frequency, any frequency dependence of G* is allowed. The basis holds real modes at three
//! core moduli (G_a/4, G_a, 4 G_a) with their core sensitivities, so it spans the range the
//! iteration moves in.

use crate::error::LayeredError;
use crate::hex20::Elastic;
use crate::mesh::{LayerMesh, LayeredPlateSpec};
use crate::reduced::{ReducedEigen, ReducedModel};
use crate::system::LayeredSystem;
use num_complex::Complex64;

/// One layer of the layered inverse's stack.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InverseLayer {
    /// Thickness, m.
    pub thickness_m: f64,
    /// Density, kg/m³.
    pub density_kg_m3: f64,
    /// Poisson's ratio.
    pub poisson: f64,
    /// Young's modulus (faces), Pa; `None` for the core.
    pub young_pa: Option<f64>,
    /// Loss factor of a face (all faces must share it).
    pub loss_factor: f64,
}

/// The part the layered inverse models: a rectangle in plan, flat or a shallow dome, meshed
/// with [`crate::mesh::LayeredPlateSpec`] (one element per layer through the thickness).
#[derive(Debug, Clone, PartialEq)]
pub struct LayeredPlate {
    /// Plan lengths along x and y, m.
    pub plan_m: [f64; 2],
    /// Radii of curvature along x and y, m (infinite: straight).
    pub radii_m: [f64; 2],
    /// Edge grading of the in-plane mesh ([`crate::mesh`]; 0: uniform).
    pub edge_grading: f64,
    /// The stack, bottom to top, with exactly one core layer.
    pub layers: Vec<InverseLayer>,
}

/// The layered model of the inverse.
pub struct LayeredInverse {
    model: ReducedEigen,
    g_assembled_pa: f64,
    dofs: usize,
}

/// The core's modulus found at one mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayeredEstimate {
    /// G* of the core, Pa.
    pub core_shear_pa: Complex64,
    /// The model's eigenvalue matched, rad²/s².
    pub eigenvalue: Complex64,
    /// Secant iterations.
    pub iterations: usize,
    /// Rank of the matched mode among the elastic ones (0: the lowest).
    pub rank: usize,
}

/// How far (relative, in frequency) the nearest mode of the model may lie from a target at the
/// start modulus for the target to count as one of its modes: a pole further off than this
/// from every mode is no mode of the part's layered model (a support's bounce, a spurious pole).
pub const MATCH_WINDOW: f64 = 0.25;

/// The reference moduli of the inverse's basis, as ratios to G_ref (module docs).
pub const BASIS_RATIOS: [f64; 3] = [0.25, 1.0, 4.0];

impl LayeredInverse {
    /// Meshes and assembles `plate` with `elements` in plane and the core at `g_ref_pa`, and
    /// builds the reduced basis of `modes` modes at each of [`BASIS_RATIOS`] times G_ref.
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] for a stack without exactly one core layer, faces with different
    /// loss factors, or a non-positive size; [`LayeredError::Solver`] from the eigen solves.
    pub fn build(
        plate: &LayeredPlate,
        elements: [usize; 2],
        g_ref_pa: f64,
        modes: usize,
    ) -> Result<Self, LayeredError> {
        Self::build_with_ratios(plate, elements, g_ref_pa, modes, &BASIS_RATIOS)
    }

    /// [`Self::build`] with the basis at the core-modulus `ratios` (to G_ref): a single ratio
    /// gives a cheaper model, accurate near G_ref (the core-sensitivity vectors span the first
    /// order in G), as the convergence ladder's finer meshes use ([`crate::convergence`]).
    ///
    /// # Errors
    /// As [`Self::build`].
    pub fn build_with_ratios(
        plate: &LayeredPlate,
        elements: [usize; 2],
        g_ref_pa: f64,
        modes: usize,
        ratios: &[f64],
    ) -> Result<Self, LayeredError> {
        let layers = &plate.layers;
        let cores: Vec<usize> = (0..layers.len())
            .filter(|&i| layers[i].young_pa.is_none())
            .collect();
        let [core] = cores[..] else {
            return Err(LayeredError::Invalid(format!(
                "the layered inverse needs exactly one core layer (no young_pa), got {}",
                cores.len()
            )));
        };
        if !(g_ref_pa.is_finite() && g_ref_pa > 0.0) {
            return Err(LayeredError::Invalid(format!(
                "reference core modulus {g_ref_pa} Pa must be positive"
            )));
        }
        let eta_e = layers
            .iter()
            .find_map(|l| l.young_pa.map(|_| l.loss_factor));
        if layers
            .iter()
            .any(|l| l.young_pa.is_some() && Some(l.loss_factor) != eta_e)
        {
            return Err(LayeredError::Invalid(
                "the faces must share one loss factor".into(),
            ));
        }
        let materials: Vec<Elastic> = layers
            .iter()
            .map(|l| Elastic {
                young_pa: l.young_pa.unwrap_or(2.0 * g_ref_pa * (1.0 + l.poisson)),
                poisson: l.poisson,
                density_kg_m3: l.density_kg_m3,
            })
            .collect();
        let mesh = LayeredPlateSpec {
            length_m: plate.plan_m[0],
            width_m: plate.plan_m[1],
            nx: elements[0],
            ny: elements[1],
            radius_x_m: plate.radii_m[0],
            radius_y_m: plate.radii_m[1],
            edge_grading: plate.edge_grading,
            layers: layers
                .iter()
                .map(|l| LayerMesh {
                    thickness_m: l.thickness_m,
                    elements: 1,
                })
                .collect(),
        }
        .build()?;
        let system = LayeredSystem::assemble(&mesh, &materials)?;
        // A unit load at the first top node: its static residual vector rounds off the basis.
        let mut load = vec![0.0; system.n_dofs];
        let (node, _) = mesh
            .top
            .first()
            .copied()
            .ok_or_else(|| LayeredError::Invalid("the mesh has no top surface".into()))?;
        load[3 * node + 2] = 1.0;
        let shift = -(2.0 * std::f64::consts::PI).powi(2);
        let mut model = ReducedModel::new(&system, core, ratios, modes, &[load], shift)?;
        model.set_elastic_loss(eta_e.unwrap_or(0.0))?;
        Ok(Self {
            model: model.free_eigenproblem(),
            g_assembled_pa: g_ref_pa,
            dofs: system.n_dofs,
        })
    }

    /// The model as bytes for a cache: G_ref and the full model's size (f64, u64) followed by
    /// [`ReducedEigen::to_bytes`].
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = self.g_assembled_pa.to_le_bytes().to_vec();
        out.extend_from_slice(&(self.dofs as u64).to_le_bytes());
        out.extend_from_slice(&self.model.to_bytes());
        out
    }

    /// Reads [`LayeredInverse::to_bytes`]; `None` for anything else.
    pub fn from_bytes(bytes: &[u8]) -> Option<Self> {
        let g = f64::from_le_bytes(bytes.get(..8)?.try_into().ok()?);
        let dofs = usize::try_from(u64::from_le_bytes(bytes.get(8..16)?.try_into().ok()?)).ok()?;
        (g.is_finite() && g > 0.0).then_some(())?;
        Some(Self {
            model: ReducedEigen::from_bytes(&bytes[16..])?,
            g_assembled_pa: g,
            dofs,
        })
    }

    /// Degrees of freedom of the full model and size of the basis.
    pub fn size(&self) -> (usize, usize) {
        (self.dofs, self.model.k_elastic.nrows())
    }

    /// The model's complex eigenvalues (rad²/s², increasing real part) at core modulus `g`.
    pub fn eigenvalues(&self, g_pa: Complex64) -> Vec<Complex64> {
        self.model.eigenvalues(g_pa / self.g_assembled_pa)
    }

    /// The elastic eigenvalue of `rank` ([`LayeredEstimate::rank`]) at core modulus `g_pa`
    /// (Re λ above 1e-6 of `target`'s counts as elastic), if the model has that many.
    pub fn elastic_eigenvalue(
        &self,
        g_pa: Complex64,
        rank: usize,
        target: Complex64,
    ) -> Option<Complex64> {
        self.elastic(g_pa / self.g_assembled_pa, target)
            .get(rank)
            .copied()
    }

    /// The elastic eigenvalues (Re λ above 1e-6 of the target's) at scale `s`, increasing.
    fn elastic(&self, s: Complex64, target: Complex64) -> Vec<Complex64> {
        self.model
            .eigenvalues(s)
            .into_iter()
            .filter(|l| l.re > 1e-6 * target.re)
            .collect()
    }

    /// G* of the core that puts an eigenvalue of the model at `target` = −p² (module docs),
    /// starting from `g_start`. The mode is the elastic one nearest the target at the start;
    /// it is followed by its rank in frequency (two modes of one target can meet it at
    /// different moduli: the start picks the branch).
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] when no elastic mode lies within [`MATCH_WINDOW`] of the target
    /// in frequency at the start; [`LayeredError::Solver`] when the iteration does not converge
    /// to 1e-9 relative in 40 steps or leaves the physical range (G' ≤ 0).
    pub fn invert(
        &self,
        target: Complex64,
        g_start: Complex64,
    ) -> Result<LayeredEstimate, LayeredError> {
        let fail = |why: String| LayeredError::Solver(format!("layered inverse: {why}"));
        let mut s0 = g_start / self.g_assembled_pa;
        let start = self.elastic(s0, target);
        let rank = (0..start.len())
            .min_by(|&a, &b| {
                (start[a] - target)
                    .norm()
                    .total_cmp(&(start[b] - target).norm())
            })
            .ok_or_else(|| fail("no elastic eigenvalue".into()))?;
        let hz = |l: Complex64| l.re.max(0.0).sqrt() / (2.0 * std::f64::consts::PI);
        if (hz(start[rank]) / hz(target) - 1.0).abs() > MATCH_WINDOW {
            return Err(LayeredError::Invalid(format!(
                "the pole at {:.3} Hz matches no mode of the layered model: the nearest lies at {:.3} Hz with G* = {:.4e} Pa (more than {} % off)",
                hz(target),
                hz(start[rank]),
                g_start,
                100.0 * MATCH_WINDOW
            )));
        }
        let residual = |s: Complex64| -> Result<(Complex64, Complex64), LayeredError> {
            let l = *self
                .elastic(s, target)
                .get(rank)
                .ok_or_else(|| fail(format!("mode {} lost", rank + 1)))?;
            Ok((l - target, l))
        };
        let mut r0 = start[rank] - target;
        let mut s1 = s0 * 1.05;
        for k in 1..=40 {
            let (r1, lambda) = residual(s1)?;
            if r1.norm() <= 1e-9 * target.norm() {
                return Ok(LayeredEstimate {
                    core_shear_pa: s1 * self.g_assembled_pa,
                    eigenvalue: lambda,
                    iterations: k,
                    rank,
                });
            }
            if r1 == r0 {
                return Err(fail("the eigenvalue does not depend on the core".into()));
            }
            // Steps longer than half the modulus are cut back: the secant from a start far
            // off (a factor two) can otherwise overshoot below zero.
            let mut step = -r1 * (s1 - s0) / (r1 - r0);
            if step.norm() > 0.5 * s1.norm() {
                step *= 0.5 * s1.norm() / step.norm();
            }
            let s2 = s1 + step;
            if !(s2.re.is_finite() && s2.re > 0.0) {
                return Err(fail(format!(
                    "the iteration left the physical range (G' = {:.3e} Pa)",
                    s2.re * self.g_assembled_pa
                )));
            }
            (s0, r0, s1) = (s1, r1, s2);
        }
        Err(fail(format!(
            "no convergence in 40 steps at {:.3} Hz",
            target.re.sqrt() / (2.0 * std::f64::consts::PI)
        )))
    }
}

/// The tests' small flat laminate: 0.5 × 0.4 m, glass 3 mm / core 0.76 mm / glass 3 mm.
#[cfg(test)]
pub(crate) fn small_test_plate() -> LayeredPlate {
    let face = InverseLayer {
        thickness_m: 3e-3,
        density_kg_m3: 2500.0,
        poisson: 0.22,
        young_pa: Some(70e9),
        loss_factor: 0.0,
    };
    let core = InverseLayer {
        thickness_m: 0.76e-3,
        density_kg_m3: 1070.0,
        poisson: 0.49,
        young_pa: None,
        loss_factor: 0.0,
    };
    LayeredPlate {
        plan_m: [0.5, 0.4],
        radii_m: [f64::INFINITY, f64::INFINITY],
        edge_grading: 0.0,
        layers: vec![face, core, face],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The forward model's eigenvalue at a known G* is inverted back to that G*.
    #[test]
    fn inverts_its_own_eigenvalues() {
        let plate = small_test_plate();
        let inv = LayeredInverse::build(&plate, [4, 4], 5e6, 12).unwrap();
        let truth = Complex64::new(3e6, 1.5e6);
        let lambdas = inv.eigenvalues(truth);
        let elastic: Vec<Complex64> = lambdas.into_iter().filter(|l| l.re > 1.0).collect();
        for target in elastic.iter().take(3) {
            let est = inv.invert(*target, Complex64::new(4e6, 1e6)).unwrap();
            let err = (est.core_shear_pa / truth - 1.0).norm();
            assert!(err < 1e-6, "{err:e} after {} steps", est.iterations);
        }
        // The cached form gives the same eigenvalues, bit for bit.
        let back = LayeredInverse::from_bytes(&inv.to_bytes()).unwrap();
        assert_eq!(back.eigenvalues(truth), inv.eigenvalues(truth));
        assert_eq!(back.size(), inv.size());
        assert!(LayeredInverse::from_bytes(&inv.to_bytes()[..100]).is_none());
    }
}
