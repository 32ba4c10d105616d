//! FRFs of the layered model with a frequency-dependent core, by projection onto a reduced
//! basis, and the direct complex solve that checks them.
//!
//! With the core layers' stiffness assembled at a modulus G_a, the dynamic stiffness at ω is
//!
//!   Z(ω) = (1 + iη_e) K_e + s(ω) K_c + K_s + iω C_s − ω² M,  s(ω) = G*(ω)/G_a,
//!
//! (K_e the elastic layers with a constant loss factor η_e, zero unless set by
//! [`ReducedModel::set_elastic_loss`] — a constant loss factor is not causal, keep it small for
//! time signals; K_s the supports' springs and C_s their dashpots,
//! [`LayeredSystem::add_supports`], causal viscous damping; K_c the core: scaling the whole
//! core matrix by one complex factor assumes a constant Poisson's ratio of the core) and the
//! receptance to a load f is
//! u = Z(ω)⁻¹ f. The reduced basis V holds, at each reference core modulus G_j with
//! K_j = K_e + (G_j/G_a) K_c: the real modes φ of (K_j, M), the static residual vectors
//! (K_j − σM)⁻¹ f of the loads, the modes' static sensitivity to the core
//! (K_j − σM)⁻¹ K_c φ (σ < 0 keeps a free model's matrix invertible) and, on dashpots, the
//! static response to the dashpots' forces on each mode (K_j − σM)⁻¹ C_s φ (the real modes
//! alone left out how those forces deform the plate: 3.1e-4 in λ on damped patches,
//! `inverse::tests::reduced_bases_hold_the_supports_dashpots`); the whole is made
//! M-orthonormal (numerically dependent columns are dropped) [Plouin & Balmès 1999,
//! "Steel/viscoelastic/steel sandwich shells: computational methods and experimental validations",
//! IMAC XVII; Balmès 1996 for the multi-model reduction]. Then u ≈ V (Vᵀ Z(ω) V)⁻¹ Vᵀ f: one small
//! dense complex solve per line. The direct route factors the sparse complex Z(ω) (faer's sparse
//! LU) per line.

pub mod mode_errors;

pub use mode_errors::{ModeError, SCALE_LIMIT};

use crate::error::LayeredError;
use crate::sensitivity::{
    Input, PencilSupports, ReducedDerivative, pencil_eigenvalue_near, pencil_eigenvalues,
};
use crate::seq;
use crate::system::LayeredSystem;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat, Triplet};
use faer::{Mat, c64};
use num_complex::Complex64;

/// The reduced model: basis and projected matrices.
#[derive(Clone)]
pub struct ReducedModel {
    /// Basis V (n × m), M-orthonormal.
    pub basis: Mat<f64>,
    /// Vᵀ K_e V (elastic layers, no springs).
    k_elastic: Mat<f64>,
    /// Vᵀ K_s V (the springs; zero without).
    k_springs: Mat<f64>,
    /// Vᵀ C_s V (the dashpots; zero without).
    c_dampers: Mat<f64>,
    /// Loss factor of the elastic layers.
    elastic_loss: f64,
    /// Vᵀ K_c V at the assembled core modulus.
    k_core: Mat<f64>,
    /// Vᵀ M V (≈ I).
    mass: Mat<f64>,
    /// Derivatives with respect to the inputs ([`crate::sensitivity`]), if computed.
    derivatives: Vec<ReducedDerivative>,
    /// The highest real mode's eigenvalue ω² (rad²/s²) of the softest reference modulus: modes
    /// below it are in the basis at every reference modulus (stiffer cores raise every mode).
    pub top_eigenvalue: f64,
}

/// Stiffness scale per layer: 1 everywhere, `core` on the layers `core_layers`.
fn scales(n_layers: usize, core_layers: &[usize], core: f64) -> Vec<f64> {
    (0..n_layers)
        .map(|l| if core_layers.contains(&l) { core } else { 1.0 })
        .collect()
}

/// K_c = Σ_j K_core,j: the stiffness of the viscoelastic layers `core_layers` of `sys`, which
/// share one law (one scale s(ω)), at their assembled modulus.
pub fn core_stiffness(sys: &LayeredSystem, core_layers: &[usize]) -> SparseColMat<usize, f64> {
    sum_of(&sys.k_layers, core_layers)
}

/// M_c = Σ_j M_core,j: the mass of the viscoelastic layers `core_layers` of `sys`.
pub fn core_mass(sys: &LayeredSystem, core_layers: &[usize]) -> SparseColMat<usize, f64> {
    sum_of(&sys.m_layers, core_layers)
}

/// Σ of `parts[j]` over `layers` (each index once; the layers are checked by the callers).
fn sum_of(parts: &[SparseColMat<usize, f64>], layers: &[usize]) -> SparseColMat<usize, f64> {
    let mut at = layers.iter().map(|&l| &parts[l]);
    let first = at.next().cloned().unwrap_or_else(|| {
        let n = parts.first().map_or(0, |p| p.nrows());
        SparseColMat::try_new_from_triplets(n, n, &[]).expect("an empty matrix")
    });
    at.fold(first, |acc, p| &acc + p)
}

/// Whether `core_layers` names at least one layer of `n_layers`, each once; else why not.
pub fn check_core_layers(n_layers: usize, core_layers: &[usize]) -> Result<(), LayeredError> {
    if core_layers.is_empty() {
        return Err(LayeredError::Invalid(
            "the model needs at least one viscoelastic (core) layer".into(),
        ));
    }
    for (k, &l) in core_layers.iter().enumerate() {
        if l >= n_layers {
            return Err(LayeredError::Invalid(format!(
                "core layer {} of {n_layers} layers",
                l + 1
            )));
        }
        if core_layers[..k].contains(&l) {
            return Err(LayeredError::Invalid(format!(
                "core layer {} named twice",
                l + 1
            )));
        }
    }
    Ok(())
}

/// Elastic-layer and core stiffness of `sys` (the cores' alone, and everything else).
fn split_stiffness(
    sys: &LayeredSystem,
    core_layers: &[usize],
) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let n = sys.k_layers.len();
    (
        sys.stiffness(&scales(n, core_layers, 0.0)),
        core_stiffness(sys, core_layers),
    )
}

impl ReducedModel {
    /// Builds the basis (module docs): `modes` real modes at each of the core-modulus ratios
    /// `ratios` (G_j/G_a), plus the residual vectors of `loads`, with shift `shift` (rad²/s²).
    /// `core_layers` are the viscoelastic layers, all scaled by the one s(ω) (one material: a
    /// five-layer glass/PVB/glass/PVB/glass laminate has two).
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] for no core layer, one out of range or named twice, or no load;
    /// [`LayeredError::Solver`] from the eigen or static solves.
    pub fn new(
        sys: &LayeredSystem,
        core_layers: &[usize],
        ratios: &[f64],
        modes: usize,
        loads: &[Vec<f64>],
        shift: f64,
    ) -> Result<Self, LayeredError> {
        Self::with_orders(sys, core_layers, ratios, modes, loads, shift, 1)
    }

    /// [`Self::new`] with the modes' core sensitivities continued to `krylov_orders` terms of
    /// the sequence ((K_j − σM)⁻¹ K_c)^k φ, k = 1 … `krylov_orders` (one solve per mode and
    /// order with the factor the modes used). The first order spans a core modulus near G_j;
    /// a basis at one reference modulus needs three orders to hold a core loss factor of 0.5–1
    /// and G' within a factor two of G_j (measured against the full model in
    /// `inverse::tests::reduced_bases_match_the_full_model_over_the_range`: one order 1e-4 to
    /// 5e-2 in λ, three orders 2e-6 to 6e-4; on the paper's roof the one-order levels of the
    /// mesh ladder put η 0.8 % high).
    ///
    /// # Errors
    /// As [`Self::new`], and [`LayeredError::Invalid`] for zero orders.
    pub fn with_orders(
        sys: &LayeredSystem,
        core_layers: &[usize],
        ratios: &[f64],
        modes: usize,
        loads: &[Vec<f64>],
        shift: f64,
        krylov_orders: usize,
    ) -> Result<Self, LayeredError> {
        if krylov_orders == 0 {
            return Err(LayeredError::Invalid(
                "the basis needs at least the first-order core sensitivities".into(),
            ));
        }
        let n_layers = sys.k_layers.len();
        check_core_layers(n_layers, core_layers)?;
        let k_core = core_stiffness(sys, core_layers);
        if loads.is_empty() || ratios.is_empty() {
            return Err(LayeredError::Invalid(
                "the basis needs at least one load and one reference core modulus".into(),
            ));
        }
        let n = sys.n_dofs;
        let mut cols: Vec<Mat<f64>> = Vec::new();
        let mut top_eigenvalue = f64::INFINITY;
        for &r in ratios {
            let scale = scales(n_layers, core_layers, r);
            // One factor of K_j − σM for the modes and the static solves.
            let llt = sys.shifted_cholesky(&scale, shift)?;
            let (lambda, phi) = sys.modes_with(&llt, modes, shift)?;
            top_eigenvalue = top_eigenvalue.min(lambda.iter().copied().fold(f64::MIN, f64::max));
            let mut f = Mat::from_fn(n, loads.len(), |i, j| loads[j][i]);
            llt.solve_in_place(f.as_mut());
            cols.push(f);
            // How the modes change with the core modulus: (K_j − σM)⁻¹ K_c φ, and the higher
            // orders of the same Krylov sequence.
            let mut sens = seq::sparse_mul(&k_core, phi.as_ref());
            llt.solve_in_place(sens.as_mut());
            // How the supports' dashpots change the modes: the static response to their forces
            // on each mode, (K_j − σM)⁻¹ C_s φ, which the real modes alone leave out (module
            // docs).
            let damped = sys.dashpots.as_ref().map(|c| {
                let mut d = seq::sparse_mul(c, phi.as_ref());
                llt.solve_in_place(d.as_mut());
                d
            });
            cols.push(phi);
            for _ in 1..krylov_orders {
                let mut next = seq::sparse_mul(&k_core, sens.as_ref());
                llt.solve_in_place(next.as_mut());
                cols.push(sens);
                sens = next;
            }
            cols.push(sens);
            cols.extend(damped);
        }
        let width: usize = cols.iter().map(|c| c.ncols()).sum();
        let mut v = Mat::<f64>::zeros(n, width);
        let mut at = 0;
        for c in &cols {
            v.as_mut().subcols_mut(at, c.ncols()).copy_from(c);
            at += c.ncols();
        }
        let basis = m_orthonormal(&v, &sys.m);
        let project = |a: &SparseColMat<usize, f64>| project_on(&basis, a);
        // Each layer projected once: the elastic layers' sum and the core's (K_c = Σ_j K_core,j).
        let mut k_elastic = Mat::<f64>::zeros(basis.ncols(), basis.ncols());
        let mut k_core_projected = Mat::<f64>::zeros(basis.ncols(), basis.ncols());
        for (l, k) in sys.k_layers.iter().enumerate() {
            if core_layers.contains(&l) {
                k_core_projected += project(k);
            } else {
                k_elastic += project(k);
            }
        }
        let project_or_zero = |a: &Option<SparseColMat<usize, f64>>| match a {
            Some(a) => project(a),
            None => Mat::zeros(basis.ncols(), basis.ncols()),
        };
        let (k_springs, c_dampers) = (
            project_or_zero(&sys.springs),
            project_or_zero(&sys.dashpots),
        );
        Ok(Self {
            k_elastic,
            c_dampers,
            k_springs,
            elastic_loss: 0.0,
            k_core: k_core_projected,
            mass: project(&sys.m),
            basis,
            derivatives: Vec::new(),
            top_eigenvalue,
        })
    }

    /// Vᵀ A V.
    pub fn project(&self, a: &SparseColMat<usize, f64>) -> Mat<f64> {
        project_on(&self.basis, a)
    }

    /// Adds the derivatives with respect to `input` ([`crate::sensitivity`]) of this model's
    /// matrices, `sys` being the system it was built from: the face modulus and the densities
    /// from `sys`'s own per-layer operators (exact), the supports' stiffness and damping from
    /// this model's springs and dashpots (exact), a thickness from the central difference
    /// of `plus` and `minus`, the systems assembled with that thickness times 1 ± h (same
    /// mesh topology).
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] for a thickness without the two systems, a bad step, or
    /// systems of another size.
    pub fn add_derivative(
        &mut self,
        input: Input,
        sys: &LayeredSystem,
        core_layers: &[usize],
        thickness: Option<(&LayeredSystem, &LayeredSystem, f64)>,
    ) -> Result<(), LayeredError> {
        check_core_layers(sys.k_layers.len(), core_layers)?;
        let m = self.size();
        let zero = || Mat::<f64>::zeros(m, m);
        let (mut dk_supports, mut dc_supports) = (zero(), zero());
        let (dk_elastic, dk_core, dmass) = match input {
            Input::FaceModulus => (self.k_elastic.clone(), zero(), zero()),
            Input::SupportStiffness => {
                dk_supports = self.k_springs.clone();
                (zero(), zero(), zero())
            }
            Input::SupportDamping => {
                dc_supports = self.c_dampers.clone();
                (zero(), zero(), zero())
            }
            // The faces' mass is all but the core's: Vᵀ M V − Vᵀ M_c V.
            Input::FaceDensity => (
                zero(),
                zero(),
                &self.mass - self.project(&core_mass(sys, core_layers)),
            ),
            Input::CoreDensity => (zero(), zero(), self.project(&core_mass(sys, core_layers))),
            Input::FaceThickness | Input::CoreThickness => {
                let Some((plus, minus, h)) = thickness else {
                    return Err(LayeredError::Invalid(format!(
                        "the {} derivative needs the systems at 1 ± h",
                        input.name()
                    )));
                };
                crate::sensitivity::check_step(h)?;
                if plus.n_dofs != sys.n_dofs || minus.n_dofs != sys.n_dofs {
                    return Err(LayeredError::Invalid(
                        "perturbed systems of another size".into(),
                    ));
                }
                let n_layers = sys.k_layers.len();
                let no_core = scales(n_layers, core_layers, 0.0);
                let diff = |a: SparseColMat<usize, f64>, b: SparseColMat<usize, f64>| {
                    self.project(&(&a - &b)) * (1.0 / (2.0 * h))
                };
                (
                    diff(plus.stiffness(&no_core), minus.stiffness(&no_core)),
                    diff(
                        core_stiffness(plus, core_layers),
                        core_stiffness(minus, core_layers),
                    ),
                    diff(plus.m.clone(), minus.m.clone()),
                )
            }
        };
        self.derivatives.retain(|d| d.input != input);
        self.derivatives.push(ReducedDerivative {
            input,
            dk_elastic,
            dk_core,
            dmass,
            dk_supports,
            dc_supports,
        });
        Ok(())
    }

    /// Sets the constant loss factor η_e of the elastic layers.
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] for a negative or non-finite loss factor.
    pub fn set_elastic_loss(&mut self, eta: f64) -> Result<(), LayeredError> {
        if !(eta.is_finite() && eta >= 0.0) {
            return Err(LayeredError::Invalid(format!(
                "loss factor of the elastic layers: {eta} must be finite and non-negative"
            )));
        }
        self.elastic_loss = eta;
        Ok(())
    }

    /// The projected dynamic stiffness Vᵀ Z(ω) V at ω (rad/s) and core scale s (module docs):
    /// (1 + iη_e) K_e + s K_c + K_s − ω² M + iω C_s, a column at a time.
    pub(crate) fn dynamic_stiffness_matrix(&self, omega: f64, core_scale: Complex64) -> Mat<c64> {
        let m = self.size();
        let elastic = Complex64::new(1.0, self.elastic_loss);
        let omega2 = omega * omega;
        let mut z = Mat::<c64>::zeros(m, m);
        for j in 0..m {
            let parts = self
                .k_elastic
                .col_as_slice(j)
                .iter()
                .zip(self.k_core.col_as_slice(j))
                .zip(self.k_springs.col_as_slice(j))
                .zip(self.mass.col_as_slice(j))
                .zip(self.c_dampers.col_as_slice(j));
            for (zi, ((((&ke, &kc), &ks), &mi), &ci)) in z.col_as_slice_mut(j).iter_mut().zip(parts)
            {
                *zi = elastic * ke + core_scale * kc + Complex64::new(ks - omega2 * mi, omega * ci);
            }
        }
        z
    }

    /// The inputs whose derivatives this model holds, in their order.
    pub fn inputs(&self) -> Vec<Input> {
        self.derivatives.iter().map(|d| d.input).collect()
    }

    /// ∂(Vᵀ K_c V)/∂ln θ of the `k`-th input (core at its assembled modulus).
    pub(crate) fn input_core_derivative(&self, k: usize) -> &Mat<f64> {
        &self.derivatives[k].dk_core
    }

    /// Which of the `k`-th input's matrices ([`ReducedDerivative::matrices`]: ∂K_e, ∂K_c, ∂M,
    /// ∂K_s, ∂C_s) are not all zero: a modulus moves one, a density one, a support's input one
    /// or two.
    pub(crate) fn input_parts(&self, k: usize) -> [bool; 5] {
        self.derivatives[k]
            .matrices()
            .map(|m| (0..m.ncols()).any(|j| (0..m.nrows()).any(|i| m[(i, j)] != 0.0)))
    }

    /// ∂(Vᵀ Z V)/∂ln θ_k at ω (rad/s) and core scale s as its matrices with their factors,
    /// (1 + iη_e) ∂K_e + s ∂K_c − ω² ∂M + ∂K_s + iω ∂C_s, those not in `parts` left out
    /// ([`Self::input_parts`]).
    fn weighted_parts(
        &self,
        k: usize,
        (omega, core_scale): (f64, Complex64),
        parts: [bool; 5],
    ) -> Vec<(Complex64, &Mat<f64>)> {
        let factors = [
            Complex64::new(1.0, self.elastic_loss),
            core_scale,
            Complex64::new(-omega * omega, 0.0),
            Complex64::new(1.0, 0.0),
            Complex64::new(0.0, omega),
        ];
        factors
            .into_iter()
            .zip(self.derivatives[k].matrices())
            .zip(parts)
            .filter_map(|(part, kept)| kept.then_some(part))
            .collect()
    }

    /// z += f ∂(Vᵀ Z V)/∂ln θ_k at ω (rad/s) and core scale s, part by part: the sum without
    /// the derivative matrix formed (a line of the FRF fit adds one per input); `parts` as
    /// [`Self::input_parts`] gives them.
    pub(crate) fn add_input_derivative(
        &self,
        k: usize,
        at: (f64, Complex64),
        parts: [bool; 5],
        f: f64,
        z: &mut Mat<c64>,
    ) {
        for (w, a) in self.weighted_parts(k, at, parts) {
            let w = f * w;
            let w = c64::new(w.re, w.im);
            for j in 0..a.ncols() {
                for (zi, &ai) in z.col_as_slice_mut(j).iter_mut().zip(a.col_as_slice(j)) {
                    *zi += w * ai;
                }
            }
        }
    }

    /// ∂(Vᵀ Z V)/∂ln θ_k · x at ω (rad/s) and core scale s for a block x (m × r), part by
    /// part, without the derivative matrix formed; `parts` as [`Self::input_parts`] gives them.
    pub(crate) fn input_derivative_times(
        &self,
        k: usize,
        at: (f64, Complex64),
        parts: [bool; 5],
        x: &Mat<c64>,
    ) -> Mat<c64> {
        let mut y = Mat::<c64>::zeros(self.size(), x.ncols());
        for (w, a) in self.weighted_parts(k, at, parts) {
            let w = c64::new(w.re, w.im);
            for c in 0..x.ncols() {
                for j in 0..a.ncols() {
                    let wx = w * x[(j, c)];
                    for (yi, &ai) in y.col_as_slice_mut(c).iter_mut().zip(a.col_as_slice(j)) {
                        *yi += wx * ai;
                    }
                }
            }
        }
        y
    }

    /// Vᵀ K_c V at the assembled core modulus: ∂(Vᵀ Z V)/∂s.
    pub(crate) fn core_matrix(&self) -> &Mat<f64> {
        &self.k_core
    }

    /// Complex eigenvalues λ = ω²(1 + iη) of the reduced model with a frequency-independent core
    /// scale s (Vᵀ M V = I, so the eigenvalues of Vᵀ Z(0) V: the dashpots left out), increasing
    /// real part: the natural frequencies √Re λ/2π and modal loss factors Im λ/Re λ.
    pub fn complex_eigenvalues(&self, core_scale: Complex64) -> Vec<Complex64> {
        let z = self.dynamic_stiffness_matrix(0.0, core_scale);
        seq::eigenvalues(z.as_ref())
    }

    /// The free model's reduced eigenproblem: Vᵀ K_e V, Vᵀ K_c V and η_e (supports and
    /// dashpots left out; Vᵀ M V = I).
    pub fn free_eigenproblem(&self) -> ReducedEigen {
        ReducedEigen {
            k_elastic: self.k_elastic.clone(),
            k_core: self.k_core.clone(),
            elastic_loss: self.elastic_loss,
            k_supports: self.k_springs.clone(),
            c_supports: self.c_dampers.clone(),
            derivatives: self.derivatives.clone(),
        }
    }

    /// Basis size m.
    pub fn size(&self) -> usize {
        self.basis.ncols()
    }

    /// The load in the basis, Vᵀ f: computed once, used at every line by [`Self::response`].
    pub fn project_load(&self, load: &[f64]) -> Vec<f64> {
        let f = seq::mul(
            self.basis.transpose(),
            Mat::from_fn(load.len(), 1, |i, _| load[i]).as_ref(),
        );
        (0..f.nrows()).map(|i| f[(i, 0)]).collect()
    }

    /// Responses u at `dofs` to the load with basis coordinates `load_r` ([`Self::project_load`])
    /// at ω (rad/s) with core scale s(ω), m/N.
    pub fn response(
        &self,
        load_r: &[f64],
        omega: f64,
        core_scale: Complex64,
        dofs: &[usize],
    ) -> Vec<Complex64> {
        let m = self.size();
        let z = self.dynamic_stiffness_matrix(omega, core_scale);
        let rhs = Mat::from_fn(m, 1, |i, _| c64::new(load_r[i], 0.0));
        let q = z.partial_piv_lu().solve(&rhs);
        dofs.iter()
            .map(|&d| {
                let mut acc = Complex64::new(0.0, 0.0);
                for k in 0..m {
                    acc += Complex64::new(q[(k, 0)].re, q[(k, 0)].im) * self.basis[(d, k)];
                }
                acc
            })
            .collect()
    }
}

/// The reduced eigenproblem of a free layered model, ((1 + iη_e) K_e + s K_c) x = λ x in the
/// M-orthonormal basis: small (basis size), dense, and cacheable as bytes.
#[derive(Debug, Clone, PartialEq)]
pub struct ReducedEigen {
    /// Vᵀ K_e V.
    pub k_elastic: Mat<f64>,
    /// Vᵀ K_c V at the assembled core modulus.
    pub k_core: Mat<f64>,
    /// Loss factor of the elastic layers.
    pub elastic_loss: f64,
    /// Vᵀ K_s V: the supports' springs (zero for a free part).
    pub k_supports: Mat<f64>,
    /// Vᵀ C_s V: the supports' dashpots (zero without).
    pub c_supports: Mat<f64>,
    /// Derivatives with respect to the inputs known within a tolerance
    /// ([`crate::sensitivity`]); empty if not computed.
    pub derivatives: Vec<ReducedDerivative>,
}

/// First bytes of [`ReducedEigen::to_bytes`] (format version 4: with the supports and their
/// derivatives).
const EIGEN_MAGIC: &[u8] = b"lamdyn reduced eigenproblem v4\n";

impl ReducedEigen {
    /// The supports' part of the pencil with the dashpots at angular frequency `omega`.
    fn supports(&self, omega: Complex64) -> PencilSupports<'_> {
        PencilSupports {
            springs: &self.k_supports,
            dashpots: &self.c_supports,
            omega,
        }
    }

    /// The derivative for `input` scaled by `eps`, if the model has it.
    fn perturbation(&self, input: Input, eps: f64) -> Option<(&ReducedDerivative, f64)> {
        self.derivatives
            .iter()
            .find(|d| d.input == input)
            .map(|d| (d, eps))
    }

    /// The model with its inputs moved from nominal by the relative changes `changes`
    /// (δ = ln θ/θ_nominal): each matrix A becomes A + c Σ ∂A/∂ln θ with c = e^δ − 1 for an
    /// input whose matrices scale with it (exact) and c = δ for a thickness (first order,
    /// [`Input::scales_exactly`]), the mass Vᵀ M V = I + c ∂M/∂ln θ likewise; the derivatives
    /// of the exact inputs are scaled by e^δ (they are the moved parts themselves). The pencil
    /// is then brought back to a unit mass by the congruence A ← M^{−1/2} A M^{−1/2} (M^{−1/2}
    /// from the symmetric eigendecomposition of the small mass matrix), which keeps every
    /// eigenvalue [Golub & Van Loan 2013, §8.7.1].
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] for an input the model has no derivative for, a non-finite
    /// change, or a moved mass that is not positive definite (a change far beyond first
    /// order).
    pub fn moved(&self, changes: &[(Input, f64)]) -> Result<Self, LayeredError> {
        let m = self.k_elastic.nrows();
        let mut moved = self.clone();
        let mut mass = Mat::<f64>::identity(m, m);
        for &(input, delta) in changes {
            let Some(d) = self.derivatives.iter().find(|d| d.input == input) else {
                return Err(LayeredError::Invalid(format!(
                    "the reduced model has no derivative for the {}",
                    input.name()
                )));
            };
            if !delta.is_finite() {
                return Err(LayeredError::Invalid(format!(
                    "change of the {}: {delta} is not finite",
                    input.name()
                )));
            }
            let c = if input.scales_exactly() {
                delta.exp_m1()
            } else {
                delta
            };
            moved.k_elastic += &d.dk_elastic * c;
            moved.k_core += &d.dk_core * c;
            moved.k_supports += &d.dk_supports * c;
            moved.c_supports += &d.dc_supports * c;
            mass += &d.dmass * c;
            if input.scales_exactly() {
                let scale = delta.exp();
                for dd in moved.derivatives.iter_mut().filter(|dd| dd.input == input) {
                    for a in dd.matrices_mut() {
                        *a *= scale;
                    }
                }
            }
        }
        let evd = mass
            .self_adjoint_eigen(faer::Side::Lower)
            .map_err(|_| LayeredError::Invalid("the moved mass's eigensolver failed".into()))?;
        let (q, lam) = (evd.U(), evd.S().column_vector());
        if (0..m).any(|k| lam[k].is_nan() || lam[k] <= 0.0) {
            return Err(LayeredError::Invalid(
                "the moved mass is not positive definite: the inputs' changes are far beyond first \
                 order".into(),
            ));
        }
        let root = Mat::from_fn(m, m, |i, k| q[(i, k)] / lam[k].sqrt());
        let inv_sqrt = seq::mul(root.as_ref(), q.transpose());
        let congruence = |a: &mut Mat<f64>| {
            let left = seq::mul(inv_sqrt.as_ref(), a.as_ref());
            *a = seq::mul(left.as_ref(), inv_sqrt.as_ref());
        };
        for a in [
            &mut moved.k_elastic,
            &mut moved.k_core,
            &mut moved.k_supports,
            &mut moved.c_supports,
        ] {
            congruence(a);
        }
        for d in &mut moved.derivatives {
            for a in d.matrices_mut() {
                congruence(a);
            }
        }
        Ok(moved)
    }

    /// Every eigenvalue of the pencil, nominal or perturbed ([`pencil_eigenvalues`]).
    fn all(
        &self,
        core_scale: Complex64,
        omega: Complex64,
        perturbation: Option<(&ReducedDerivative, f64)>,
    ) -> Vec<Complex64> {
        pencil_eigenvalues(
            &self.k_elastic,
            &self.k_core,
            self.elastic_loss,
            core_scale,
            perturbation,
            Some(self.supports(omega)),
        )
    }

    /// The pencil's eigenvalue nearest `guess`, nominal or perturbed
    /// ([`pencil_eigenvalue_near`]).
    fn near(
        &self,
        core_scale: Complex64,
        omega: Complex64,
        perturbation: Option<(&ReducedDerivative, f64)>,
        guess: Complex64,
    ) -> Option<Complex64> {
        pencil_eigenvalue_near(
            &self.k_elastic,
            &self.k_core,
            self.elastic_loss,
            core_scale,
            perturbation,
            Some(self.supports(omega)),
            guess,
        )
    }

    /// Complex eigenvalues λ = ω²(1 + iη) at core scale s, the dashpots acting at angular
    /// frequency `omega` (rad/s; complex at a pole: exact when λ = ω²), increasing real part.
    pub fn eigenvalues(&self, core_scale: Complex64, omega: Complex64) -> Vec<Complex64> {
        self.all(core_scale, omega, None)
    }

    /// The eigenvalue at core scale s (dashpots at `omega`) nearest `guess` (inverse
    /// iteration, [`crate::sensitivity::pencil_eigenvalue_near`]), or `None` when it does not
    /// converge.
    pub fn eigenvalue_near(
        &self,
        core_scale: Complex64,
        omega: Complex64,
        guess: Complex64,
    ) -> Option<Complex64> {
        self.near(core_scale, omega, None, guess)
    }

    /// [`Self::eigenvalue_near`] with `input` changed by the relative amount `eps`; `None`
    /// also if the model has no derivative for it.
    pub fn perturbed_eigenvalue_near(
        &self,
        core_scale: Complex64,
        omega: Complex64,
        input: Input,
        eps: f64,
        guess: Complex64,
    ) -> Option<Complex64> {
        self.near(
            core_scale,
            omega,
            Some(self.perturbation(input, eps)?),
            guess,
        )
    }

    /// [`Self::eigenvalues`] with `input` changed by the relative amount `eps` (first order in
    /// the reduced matrices, [`crate::sensitivity`]); `None` if the model has no derivative for
    /// it.
    pub fn perturbed_eigenvalues(
        &self,
        core_scale: Complex64,
        omega: Complex64,
        input: Input,
        eps: f64,
    ) -> Option<Vec<Complex64>> {
        Some(self.all(core_scale, omega, Some(self.perturbation(input, eps)?)))
    }

    /// The matrices as bytes: a magic line, the size m (u64) and η_e, K_e, K_c, K_s, C_s, then the
    /// number of derivatives (u64) and for each its input's index (u64) and dK_e, dK_c, dM,
    /// dK_s, dC_s (f64, little-endian, column-major).
    pub fn to_bytes(&self) -> Vec<u8> {
        let m = self.k_elastic.nrows();
        let mut out = EIGEN_MAGIC.to_vec();
        out.extend_from_slice(&(m as u64).to_le_bytes());
        out.extend_from_slice(&self.elastic_loss.to_le_bytes());
        let put = |a: &Mat<f64>, out: &mut Vec<u8>| {
            for j in 0..m {
                for i in 0..m {
                    out.extend_from_slice(&a[(i, j)].to_le_bytes());
                }
            }
        };
        for a in [
            &self.k_elastic,
            &self.k_core,
            &self.k_supports,
            &self.c_supports,
        ] {
            put(a, &mut out);
        }
        out.extend_from_slice(&(self.derivatives.len() as u64).to_le_bytes());
        for d in &self.derivatives {
            out.extend_from_slice(&(d.input.index() as u64).to_le_bytes());
            for a in d.matrices() {
                put(a, &mut out);
            }
        }
        out
    }

    /// Reads [`ReducedEigen::to_bytes`]; `None` for anything else (a truncated or foreign file,
    /// non-finite values).
    pub fn from_bytes(bytes: &[u8]) -> Option<Self> {
        let body = bytes.strip_prefix(EIGEN_MAGIC)?;
        let word = |k: usize| -> Option<[u8; 8]> { body.get(8 * k..8 * k + 8)?.try_into().ok() };
        let int = |k: usize| usize::try_from(u64::from_le_bytes(word(k)?)).ok();
        let m = int(0)?;
        let mm = m.checked_mul(m)?;
        let v = |k: usize| word(k).map(f64::from_le_bytes).filter(|x| x.is_finite());
        let elastic_loss = v(1)?;
        let read = |at: usize| -> Option<Mat<f64>> {
            let vals: Option<Vec<f64>> = (0..mm).map(|k| v(at + k)).collect();
            let vals = vals?;
            Some(Mat::from_fn(m, m, |i, j| vals[j * m + i]))
        };
        let count = int(2 + 4 * mm)?;
        if count > Input::ALL.len() || body.len() != 8 * (3 + 4 * mm + count * (1 + 5 * mm)) {
            return None;
        }
        let mut derivatives = Vec::with_capacity(count);
        for k in 0..count {
            let at = 3 + 4 * mm + k * (1 + 5 * mm);
            derivatives.push(ReducedDerivative {
                input: *Input::ALL.get(int(at)?)?,
                dk_elastic: read(at + 1)?,
                dk_core: read(at + 1 + mm)?,
                dmass: read(at + 1 + 2 * mm)?,
                dk_supports: read(at + 1 + 3 * mm)?,
                dc_supports: read(at + 1 + 4 * mm)?,
            });
        }
        Some(Self {
            k_elastic: read(2)?,
            k_core: read(2 + mm)?,
            k_supports: read(2 + 2 * mm)?,
            c_supports: read(2 + 3 * mm)?,
            elastic_loss,
            derivatives,
        })
    }
}

/// Vᵀ A V.
fn project_on(basis: &Mat<f64>, a: &SparseColMat<usize, f64>) -> Mat<f64> {
    let av = seq::sparse_mul(a, basis.as_ref());
    seq::mul(basis.transpose(), av.as_ref())
}

/// The columns of `v` made M-orthonormal, in order, by Gram–Schmidt in the M inner product
/// applied twice ("twice is enough", Giraud et al. 2005) after scaling each column to unit
/// M-norm; a column whose M-norm falls below 1e-8 after projection is dependent and dropped.
///
/// Blocked [Stewart 2008]: each block of [`ORTHONORMAL_BLOCK`] columns is projected off the
/// columns kept so far by two classical passes X ← X − Q (M Q)ᵀ X (dense products that read Q
/// once per block), then column by column off the block's own kept columns, twice. M Q is
/// kept beside Q, so each column costs one product with M after its scaling.
fn m_orthonormal(v: &Mat<f64>, m: &SparseColMat<usize, f64>) -> Mat<f64> {
    let (n, width) = (v.nrows(), v.ncols());
    let mut q = Mat::<f64>::zeros(n, width);
    let mut mq = Mat::<f64>::zeros(n, width);
    let mut kept = 0;
    for first in (0..width).step_by(ORTHONORMAL_BLOCK) {
        let b = ORTHONORMAL_BLOCK.min(width - first);
        let mut x = v.subcols(first, b).to_owned();
        let mx = seq::sparse_mul(m, x.as_ref());
        for c in 0..b {
            let norm = x.col(c).transpose() * mx.col(c);
            let scale = if norm > 0.0 && norm.is_finite() {
                1.0 / norm.sqrt()
            } else {
                0.0
            };
            // A zero or non-finite column is left as zeros: it is dropped below.
            x.col_mut(c)
                .iter_mut()
                .for_each(|e| *e = if scale > 0.0 { *e * scale } else { 0.0 });
        }
        for _ in 0..2 {
            if kept > 0 {
                let c = seq::mul(mq.subcols(0, kept).transpose(), x.as_ref());
                x -= seq::mul(q.subcols(0, kept), c.as_ref());
            }
        }
        let block_start = kept;
        for c in 0..b {
            let mut col = x.col(c).to_owned();
            for _ in 0..2 {
                for k in block_start..kept {
                    let coefficient = mq.col(k).transpose() * &col;
                    col -= q.col(k) * coefficient;
                }
            }
            let m_col = seq::sparse_mul(m, col.as_mat());
            // f64::max maps NaN to 0: a non-finite column is dropped here too.
            let left = (col.transpose() * m_col.col(0)).max(0.0).sqrt();
            if left < 1e-8 {
                continue;
            }
            q.col_mut(kept).copy_from(&col * (1.0 / left));
            mq.col_mut(kept).copy_from(m_col.col(0) * (1.0 / left));
            kept += 1;
        }
    }
    q.subcols(0, kept).to_owned()
}

/// Columns per block of [`m_orthonormal`].
const ORTHONORMAL_BLOCK: usize = 16;

/// The direct route: Z(ω) u = f by a sparse complex LU per line (without loss in the elastic
/// layers and springs: the check of the reduction). K_e, K_c and M are laid on
/// one common sparsity pattern, so the pattern and the symbolic LU (ordering, elimination tree)
/// are built once and each line only sums the values and factors them numerically.
pub struct DirectSolver {
    pattern: SymbolicSparseColMat<usize>,
    symbolic: SymbolicLu<usize>,
    /// Values of K_e, K_c, M and the supports' dashpots C_s on `pattern`.
    values: [Vec<f64>; 4],
}

impl DirectSolver {
    /// The solver of `sys` with the viscoelastic layers `core_layers` (one law).
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] for bad core layers ([`check_core_layers`]);
    /// [`LayeredError::Solver`] if the pattern or its symbolic LU cannot be built.
    pub fn new(sys: &LayeredSystem, core_layers: &[usize]) -> Result<Self, LayeredError> {
        check_core_layers(sys.k_layers.len(), core_layers)?;
        let (ke, kc) = split_stiffness(sys, core_layers);
        let none = SparseColMat::<usize, f64>::try_new_from_triplets(sys.n_dofs, sys.n_dofs, &[])
            .map_err(|e| LayeredError::Solver(format!("sparse assembly: {e:?}")))?;
        let parts = [&ke, &kc, &sys.m, sys.dashpots.as_ref().unwrap_or(&none)];
        let n = sys.n_dofs;
        // Every matrix gets every coordinate of the three (zeros where it has none).
        let on_pattern = |own: usize| {
            let t: Vec<Triplet<usize, usize, f64>> = parts
                .iter()
                .enumerate()
                .flat_map(|(p, a)| {
                    (0..n).flat_map(move |j| {
                        a.row_idx_of_col_raw(j)
                            .iter()
                            .zip(a.val_of_col(j))
                            .map(move |(&i, &v)| Triplet::new(i, j, if p == own { v } else { 0.0 }))
                    })
                })
                .collect();
            SparseColMat::try_new_from_triplets(n, n, &t)
                .map_err(|e| LayeredError::Solver(format!("sparse assembly: {e:?}")))
        };
        let mats = [
            on_pattern(0)?,
            on_pattern(1)?,
            on_pattern(2)?,
            on_pattern(3)?,
        ];
        let pattern = mats[0]
            .symbolic()
            .to_owned()
            .map_err(|e| LayeredError::Solver(format!("{e:?}")))?;
        let symbolic = SymbolicLu::try_new(pattern.as_ref())
            .map_err(|e| LayeredError::Solver(format!("symbolic LU: {e:?}")))?;
        let values = mats.map(|m| m.val().to_vec());
        Ok(Self {
            pattern,
            symbolic,
            values,
        })
    }

    /// u at `dofs` from Z(ω) u = `load` with core scale s(ω), m/N.
    ///
    /// # Errors
    /// [`LayeredError::Solver`] if the numeric LU fails (Z singular).
    pub fn response(
        &self,
        load: &[f64],
        omega: f64,
        core_scale: Complex64,
        dofs: &[usize],
    ) -> Result<Vec<Complex64>, LayeredError> {
        let [e, c, m, _] = &self.values;
        let vals: Vec<c64> = (0..e.len())
            .map(|k| {
                let z = Complex64::new(e[k] - omega * omega * m[k], 0.0) + core_scale * c[k];
                c64::new(z.re, z.im)
            })
            .collect();
        let z = SparseColMatRef::new(self.pattern.as_ref(), &vals);
        let lu = Lu::try_new_with_symbolic(self.symbolic.clone(), z)
            .map_err(|e| LayeredError::Solver(format!("sparse LU of Z(omega): {e:?}")))?;
        let mut rhs = Mat::from_fn(load.len(), 1, |i, _| c64::new(load[i], 0.0));
        lu.solve_in_place(rhs.as_mut());
        Ok(dofs
            .iter()
            .map(|&d| Complex64::new(rhs[(d, 0)].re, rhs[(d, 0)].im))
            .collect())
    }

    /// The full (unreduced) model's pole nearest `guess`: the fixed point λ = λ(ω = √λ) of
    /// [`Self::eigenvalue_near`] with the supports' dashpots iωC_s acting at the pole's own
    /// complex frequency, as [`crate::inverse::LayeredInverse::pole_eigenvalue`] takes it on the
    /// reduced model (without dashpots: [`Self::eigenvalue_near`] itself). Iterated until λ
    /// changes by less than 1e-6 relative: each eigenvalue carries noise, about 1e-7 relative
    /// at a support's mode near 11 Hz, where λ is small beside the stiffness's norm.
    ///
    /// # Errors
    /// As [`Self::eigenvalue_near`], or the fixed point not settling in 30 steps.
    pub fn pole_near(
        &self,
        elastic_loss: f64,
        core_scale: Complex64,
        guess: Complex64,
    ) -> Result<Complex64, LayeredError> {
        let mut lambda = guess;
        for _ in 0..30 {
            let next =
                self.eigenvalue_with_dashpots(elastic_loss, core_scale, lambda.sqrt(), lambda)?;
            if (next - lambda).norm() <= 1e-6 * next.norm() {
                return Ok(next);
            }
            lambda = next;
        }
        Err(LayeredError::Solver(format!(
            "the pole near {guess} with the dashpots at its own frequency did not settle"
        )))
    }

    /// The full (unreduced) model's complex eigenvalue nearest `guess` of
    ///
    ///   ((1 + iη_e) K_e + s K_c) φ = λ M φ,
    ///
    /// K_e with the springs, no dashpots: what a reduced basis is checked against. Rayleigh
    /// quotient iteration for a complex-symmetric pencil, λ = φᵀAφ / φᵀMφ (transpose, not
    /// conjugate), each step one sparse complex LU of A − σM: three steps of inverse iteration
    /// at σ = `guess` first (from a fixed start vector, they pick the eigenvector nearest the
    /// guess), then σ = the last quotient until it changes by less than 1e-7 relative, then
    /// inverse iteration at that σ (σ on the eigenvalue itself leaves a near-singular solve
    /// and noise of about 1e-10 on the quotient) until the quotient changes by less than 1e-11.
    ///
    /// # Errors
    /// [`LayeredError::Solver`] if an LU fails or the iteration does not settle in 20 steps.
    pub fn eigenvalue_near(
        &self,
        elastic_loss: f64,
        core_scale: Complex64,
        guess: Complex64,
    ) -> Result<Complex64, LayeredError> {
        self.eigenvalue_with_dashpots(elastic_loss, core_scale, Complex64::new(0.0, 0.0), guess)
    }

    /// [`Self::eigenvalue_near`] with the dashpots' iωC_s at the complex frequency `omega`
    /// added to A (0: none).
    fn eigenvalue_with_dashpots(
        &self,
        elastic_loss: f64,
        core_scale: Complex64,
        omega: Complex64,
        guess: Complex64,
    ) -> Result<Complex64, LayeredError> {
        let [e, c, m, d] = &self.values;
        let i_omega = Complex64::new(0.0, 1.0) * omega;
        let a: Vec<Complex64> = (0..e.len())
            .map(|k| Complex64::new(1.0, elastic_loss) * e[k] + core_scale * c[k] + i_omega * d[k])
            .collect();
        let m: Vec<Complex64> = m.iter().map(|&v| Complex64::new(v, 0.0)).collect();
        let n = self.pattern.nrows();
        let mut x: Vec<Complex64> = (0..n)
            .map(|i| Complex64::new(1.0 + 0.1 * (i % 7) as f64, 0.05 * (i % 3) as f64))
            .collect();
        let (mut sigma, mut last, mut frozen) = (guess, guess, false);
        for step in 0..20 {
            let vals: Vec<c64> = a
                .iter()
                .zip(&m)
                .map(|(a, m)| {
                    let z = a - sigma * m;
                    c64::new(z.re, z.im)
                })
                .collect();
            let z = SparseColMatRef::new(self.pattern.as_ref(), &vals);
            let lu = Lu::try_new_with_symbolic(self.symbolic.clone(), z)
                .map_err(|e| LayeredError::Solver(format!("sparse LU of A - sigma M: {e:?}")))?;
            let mx = self.pattern_mul(&m, &x);
            let mut y = Mat::from_fn(n, 1, |i, _| c64::new(mx[i].re, mx[i].im));
            lu.solve_in_place(y.as_mut());
            let y: Vec<Complex64> = (0..n)
                .map(|i| Complex64::new(y[(i, 0)].re, y[(i, 0)].im))
                .collect();
            // The quotient of y, yᵀ(A − σM)y / yᵀMy = yᵀMx / yᵀMy: no product with K, whose
            // cancellation costs digits at the low modes.
            let my = self.pattern_mul(&m, &y);
            let dot = |u: &[Complex64], v: &[Complex64]| -> Complex64 {
                u.iter().zip(v).map(|(a, b)| a * b).sum()
            };
            let lambda = sigma + dot(&y, &mx) / dot(&y, &my);
            let norm = y.iter().map(|v| v.norm_sqr()).sum::<f64>().sqrt();
            x = y.iter().map(|v| v / norm).collect();
            let change = (lambda - last).norm() / lambda.norm();
            if step >= 3 {
                if change <= 1e-11 {
                    return Ok(lambda);
                }
                if !frozen {
                    sigma = lambda;
                    frozen = change < 1e-7;
                }
            }
            last = lambda;
        }
        Err(LayeredError::Solver(format!(
            "Rayleigh quotient iteration near {guess} did not settle"
        )))
    }

    /// `values` (on the common pattern) times `x`.
    fn pattern_mul(&self, values: &[Complex64], x: &[Complex64]) -> Vec<Complex64> {
        let p = self.pattern.as_ref();
        let mut y = vec![Complex64::new(0.0, 0.0); x.len()];
        for (j, xj) in x.iter().enumerate() {
            for k in p.col_range(j) {
                y[p.row_idx()[k]] += values[k] * xj;
            }
        }
        y
    }
}
