//! How the core's G* found by the layered inverse moves with the inputs a user knows only
//! within a tolerance: the faces' Young's modulus, the thicknesses, the densities, and the
//! stiffness and damping of the supports the part rests on.
//!
//! The reduced model keeps the derivative of its matrices with respect to each input, per
//! unit relative change of that input (d/d ln θ): with the basis V of the nominal model,
//!
//!   ∂K_e/∂ln θ ≈ Vᵀ (∂K_e/∂ln θ) V,  ∂K_c/∂ln θ ≈ Vᵀ (∂K_c/∂ln θ) V,  ∂M/∂ln θ ≈ Vᵀ (∂M/∂ln θ) V,
//!
//! and likewise for the supports' springs K_s and dashpots C_s. The face modulus scales the
//! elastic layers' stiffness (∂K_e/∂ln E_f = K_e), a density its layers' mass
//! (∂M/∂ln ρ = M_l), the supports' stiffness their springs (∂K_s/∂ln k = K_s: every support
//! by the same factor, one foam, one batch) and their damping their dashpots
//! (∂C_s/∂ln c = C_s), all exactly; a thickness changes the geometry, and its
//! derivative is a central difference of two assemblies at θ(1 ± h), h = 1e-4 (the matrices
//! are smooth in θ: the truncation error is O(h²), the rounding O(10⁻¹⁶/h)). Because V holds
//! the nominal modes, the Rayleigh–Ritz eigenvalues of the perturbed reduced pencil are exact
//! to first order in the perturbation (the eigenvalue derivative needs only the nominal mode),
//! so the eigenvalue derivatives below are those of the full model on its mesh.
//!
//! At a mode matched to the measured eigenvalue λ_m, λ(G, θ) = λ_m fixes G as a function of θ:
//!
//!   dG/d ln θ = −(∂λ/∂ln θ) / (∂λ/∂G),
//!
//! both derivatives by central differences of the reduced eigenvalues (λ is analytic in G, so a
//! real step in G gives the complex derivative). A measured eigenvalue off by δλ moves G by
//! δλ / (∂λ/∂G) in the same way.

use crate::error::LayeredError;
use faer::linalg::solvers::Solve;
use faer::{Mat, c64};
use num_complex::Complex64;

/// An input of the layered model known within a tolerance. "Faces" are every layer but the
/// core, changed together (one glass, one float process: the same draw for both faces).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Input {
    /// Young's modulus of the faces.
    FaceModulus,
    /// Thickness of the faces.
    FaceThickness,
    /// Thickness of the core.
    CoreThickness,
    /// Density of the faces.
    FaceDensity,
    /// Density of the core.
    CoreDensity,
    /// Stiffness of the supports (all by one factor).
    SupportStiffness,
    /// Damping of the supports' dashpots (all by one factor).
    SupportDamping,
}

impl Input {
    /// Every input, in the order the reduced model stores them.
    pub const ALL: [Input; 7] = [
        Input::FaceModulus,
        Input::FaceThickness,
        Input::CoreThickness,
        Input::FaceDensity,
        Input::CoreDensity,
        Input::SupportStiffness,
        Input::SupportDamping,
    ];

    /// Whether the input belongs to the supports (it has no effect on a free part).
    pub fn of_supports(self) -> bool {
        matches!(self, Input::SupportStiffness | Input::SupportDamping)
    }

    /// Whether the matrices it changes scale with it exactly (a modulus, a density, the
    /// supports' springs or dashpots: ∂A/∂ln θ = A_part, so A(θ e^δ) = A + (e^δ − 1) ∂A/∂ln θ),
    /// rather than to first order (a thickness: A + δ ∂A/∂ln θ).
    pub fn scales_exactly(self) -> bool {
        !matches!(self, Input::FaceThickness | Input::CoreThickness)
    }

    /// A short name for tables ("face modulus", ...).
    pub fn name(self) -> &'static str {
        match self {
            Input::FaceModulus => "face modulus",
            Input::FaceThickness => "face thickness",
            Input::CoreThickness => "core thickness",
            Input::FaceDensity => "face density",
            Input::CoreDensity => "core density",
            Input::SupportStiffness => "support stiffness",
            Input::SupportDamping => "support damping",
        }
    }

    /// The input of that [`Input::name`], if any.
    pub fn named(name: &str) -> Option<Input> {
        Input::ALL.into_iter().find(|i| i.name() == name)
    }

    /// Position in [`Input::ALL`] (the tag of the cached form).
    pub fn index(self) -> usize {
        Input::ALL.iter().position(|&i| i == self).unwrap_or(0)
    }
}

/// The derivatives of the reduced matrices with respect to one input, per unit relative change
/// (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ReducedDerivative {
    /// The input.
    pub input: Input,
    /// ∂(Vᵀ K_e V)/∂ln θ.
    pub dk_elastic: Mat<f64>,
    /// ∂(Vᵀ K_c V)/∂ln θ (core at its assembled modulus).
    pub dk_core: Mat<f64>,
    /// ∂(Vᵀ M V)/∂ln θ.
    pub dmass: Mat<f64>,
    /// ∂(Vᵀ K_s V)/∂ln θ (the supports' springs).
    pub dk_supports: Mat<f64>,
    /// ∂(Vᵀ C_s V)/∂ln θ (the supports' dashpots).
    pub dc_supports: Mat<f64>,
}

impl ReducedDerivative {
    /// The five derivative matrices in their stored order: dK_e, dK_c, dM, dK_s, dC_s.
    pub fn matrices(&self) -> [&Mat<f64>; 5] {
        [
            &self.dk_elastic,
            &self.dk_core,
            &self.dmass,
            &self.dk_supports,
            &self.dc_supports,
        ]
    }

    /// [`Self::matrices`], mutable.
    pub fn matrices_mut(&mut self) -> [&mut Mat<f64>; 5] {
        [
            &mut self.dk_elastic,
            &mut self.dk_core,
            &mut self.dmass,
            &mut self.dk_supports,
            &mut self.dc_supports,
        ]
    }
}

/// The supports of a reduced pencil: Vᵀ K_s V, Vᵀ C_s V and the (complex) angular frequency
/// ω at which the dashpots act, iω C_s (the frequency of the pole sought: exact there).
#[derive(Debug, Clone, Copy)]
pub struct PencilSupports<'a> {
    /// Vᵀ K_s V, N/m.
    pub springs: &'a Mat<f64>,
    /// Vᵀ C_s V, N·s/m.
    pub dashpots: &'a Mat<f64>,
    /// ω, rad/s.
    pub omega: Complex64,
}

/// The reduced pencil (Z, B) = (e(K_e + ε dK_e) + s(K_c + ε dK_c) + K_s + ε dK_s +
/// iω(C_s + ε dC_s), I + ε dM), e = 1 + iη_e; B = None for the nominal model (Vᵀ M V = I).
fn pencil(
    k_elastic: &Mat<f64>,
    k_core: &Mat<f64>,
    elastic_loss: f64,
    core_scale: Complex64,
    perturbation: Option<(&ReducedDerivative, f64)>,
    supports: Option<PencilSupports<'_>>,
) -> (Mat<c64>, Option<Mat<c64>>) {
    let m = k_elastic.nrows();
    let e = Complex64::new(1.0, elastic_loss);
    let z = Mat::from_fn(m, m, |i, j| {
        let (ke, kc) = match perturbation {
            Some((d, eps)) => (
                k_elastic[(i, j)] + eps * d.dk_elastic[(i, j)],
                k_core[(i, j)] + eps * d.dk_core[(i, j)],
            ),
            None => (k_elastic[(i, j)], k_core[(i, j)]),
        };
        let mut v = e * ke + core_scale * kc;
        if let Some(sup) = &supports {
            let (ks, cs) = match perturbation {
                Some((d, eps)) => (
                    sup.springs[(i, j)] + eps * d.dk_supports[(i, j)],
                    sup.dashpots[(i, j)] + eps * d.dc_supports[(i, j)],
                ),
                None => (sup.springs[(i, j)], sup.dashpots[(i, j)]),
            };
            v += ks + Complex64::new(0.0, 1.0) * sup.omega * cs;
        }
        c64::new(v.re, v.im)
    });
    let mass = perturbation.map(|(d, eps)| {
        Mat::from_fn(m, m, |i, j| {
            let identity = if i == j { 1.0 } else { 0.0 };
            c64::new(identity + eps * d.dmass[(i, j)], 0.0)
        })
    });
    (z, mass)
}

/// Complex eigenvalues of the reduced pencil (e(K_e + ε dK_e) + s(K_c + ε dK_c) + K_s +
/// ε dK_s + iω(C_s + ε dC_s)) x = λ (I + ε dM) x, e = 1 + iη_e, increasing real part (ε = 0 or `d`
/// = None: the nominal model, Vᵀ M V = I; `supports` None: a free part).
pub fn pencil_eigenvalues(
    k_elastic: &Mat<f64>,
    k_core: &Mat<f64>,
    elastic_loss: f64,
    core_scale: Complex64,
    perturbation: Option<(&ReducedDerivative, f64)>,
    supports: Option<PencilSupports<'_>>,
) -> Vec<Complex64> {
    let (z, mass) = pencil(
        k_elastic,
        k_core,
        elastic_loss,
        core_scale,
        perturbation,
        supports,
    );
    let a = match mass {
        Some(mass) => mass.partial_piv_lu().solve(&z),
        None => z,
    };
    crate::seq::eigenvalues(a.as_ref())
}

/// The eigenvalue of the same pencil nearest `guess`, by inverse iteration
/// [Golub & Van Loan 2013, §7.6.1]: x ← (Z − σB)⁻¹ B x, λ = xᵀZx / xᵀBx (the unconjugated
/// Rayleigh quotient of a complex symmetric pencil: its left and right eigenvectors are
/// transposes, so the quotient is second-order accurate). Three steps with the fixed shift
/// σ = `guess` turn x towards the eigenvector nearest it (each by |λ − σ| / |λ' − σ|, λ' the
/// next nearest eigenvalue); then σ = λ at every step (Rayleigh quotient iteration,
/// quadratic or better), so a cluster (the supports' six bounces) does not slow it down. An
/// LU of an m × m matrix per step against the O(10 m³) of every eigenvalue. It stops when a
/// step changes λ by
/// less than 1e-13 relative, or when the change stops shrinking below 1e-10 (rounding level of
/// an ill-conditioned eigenvalue); `None` when neither happens in 60 steps (the caller falls
/// back to [`pencil_eigenvalues`]).
pub fn pencil_eigenvalue_near(
    k_elastic: &Mat<f64>,
    k_core: &Mat<f64>,
    elastic_loss: f64,
    core_scale: Complex64,
    perturbation: Option<(&ReducedDerivative, f64)>,
    supports: Option<PencilSupports<'_>>,
    guess: Complex64,
) -> Option<Complex64> {
    let (z, mass) = pencil(
        k_elastic,
        k_core,
        elastic_loss,
        core_scale,
        perturbation,
        supports,
    );
    let m = z.nrows();
    let b = |x: &Mat<c64>| match &mass {
        Some(mass) => mass * x,
        None => x.clone(),
    };
    // Z − σB, its shift nudged off by 1e-10 (a shift exactly on an eigenvalue is singular).
    let factor = |shift: Complex64| {
        let sigma = c64::new(shift.re * (1.0 + 1e-10), shift.im);
        let shifted = match &mass {
            Some(mass) => Mat::from_fn(m, m, |i, j| z[(i, j)] - sigma * mass[(i, j)]),
            None => Mat::from_fn(m, m, |i, j| {
                z[(i, j)] - if i == j { sigma } else { c64::new(0.0, 0.0) }
            }),
        };
        shifted.partial_piv_lu()
    };
    let mut lu = factor(guess);
    // A start with a part along every eigenvector (no symmetry of the basis picks it out).
    let mut x = Mat::from_fn(m, 1, |i, _| c64::new(1.0 + 0.37 * (i % 7) as f64, 0.0));
    let mut lambda = guess;
    let mut last_change = f64::INFINITY;
    for step in 0..60 {
        if step >= 3 {
            lu = factor(lambda);
        }
        let y = lu.solve(&b(&x));
        let norm = y.norm_l2();
        if !(norm.is_finite() && norm > 0.0) {
            return None;
        }
        let y = Mat::from_fn(m, 1, |i, _| y[(i, 0)] / norm);
        let (num, den) = (
            (y.transpose() * &z * &y)[(0, 0)],
            (y.transpose() * b(&y))[(0, 0)],
        );
        let next = Complex64::new(num.re, num.im) / Complex64::new(den.re, den.im);
        if !(next.re.is_finite() && next.im.is_finite()) {
            return None;
        }
        // Converged, or stalled at rounding level (an ill-conditioned eigenvalue, as a
        // support's bounce with dashpots, stops improving above 1e-13).
        let change = (next - lambda).norm();
        let done = change <= 1e-13 * next.norm()
            || (change >= last_change && change <= 1e-10 * next.norm());
        (lambda, x, last_change) = (next, y, change);
        if done {
            return Some(lambda);
        }
    }
    None
}

/// How one input moves the core's G* at one mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InputEffect {
    /// The input.
    pub input: Input,
    /// dG*/d ln θ, Pa (complex): the change of G* per unit relative change of the input.
    pub dg_dln: Complex64,
}

/// The relative changes (magnitudes) of G' and η for a small change `dg` of G* = `g`
/// ([`log_parts`] without their signs).
pub fn relative_parts(dg: Complex64, g: Complex64) -> [f64; 2] {
    log_parts(dg, g).map(f64::abs)
}

/// The changes of ln G' and ln η for a small change `dg` of G* = `g`, signed:
/// δ ln G' = Re δG/G', δ ln η = Im δG/G'' − Re δG/G' (η = G''/G').
pub fn log_parts(dg: Complex64, g: Complex64) -> [f64; 2] {
    [dg.re / g.re, dg.im / g.im - dg.re / g.re]
}

/// The sensitivities of the core's G* at one mode (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ModeSensitivity {
    /// ∂λ/∂G of the matched mode, rad²/(s² Pa).
    pub dlambda_dg: Complex64,
    /// One effect per input the model has derivatives for.
    pub inputs: Vec<InputEffect>,
}

impl ModeSensitivity {
    /// dG* for a change `dlambda` (rad²/s²) of the measured eigenvalue, Pa.
    pub fn dg_for_eigenvalue(&self, dlambda: Complex64) -> Complex64 {
        dlambda / self.dlambda_dg
    }
}

/// Checks a relative step for the central differences.
pub(crate) fn check_step(h: f64) -> Result<(), LayeredError> {
    if h.is_finite() && h > 0.0 && h < 0.1 {
        Ok(())
    } else {
        Err(LayeredError::Invalid(format!(
            "relative difference step {h} must lie in (0, 0.1)"
        )))
    }
}
