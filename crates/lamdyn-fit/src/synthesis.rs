//! Exact modal FRF synthesis for a stiffness that scales with one complex modulus.
//!
//! With K*(ω) = K0 s(ω), s = E*(ω)/E_ref (paper eq. 4), and the real modes of (K0, M) —
//! K0 φ_r = λ_r M φ_r, φ_rᵀ M φ_s = δ_rs — the receptance of eq. 3 is diagonal in the modal
//! basis for every ω and every trial modulus:
//!
//! H(ω) = (−ω² M + s K0)⁻¹ = Σ_r φ_r φ_rᵀ / (λ_r s(ω) − ω²)       (all modes, rigid ones with λ = 0)
//!
//! Kept modes r ≤ m are summed exactly. The omitted ones (λ ≫ ω²) are added as a residual
//! flexibility from two static solves with the factorization of K − σM (σ < 0, the modal
//! solver's shift): with a_r = λ_r − σ,
//!
//! R1 = (K0 − σM)⁻¹ − Σ_{r≤m} φφᵀ/a_r           = Σ_{r>m} φφᵀ/a_r
//! R2 = (K0 − σM)⁻¹M(K0 − σM)⁻¹ − Σ_{r≤m} φφᵀ/a_r² = Σ_{r>m} φφᵀ/a_r²
//!
//! and, expanding 1/(λ s − ω²) = 1/(s a + d) with d = sσ − ω² to first order in d/(s a),
//!
//! H(ω) ≈ Σ_{r≤m} φφᵀ/(λ_r s − ω²) + R1/s − (sσ − ω²) R2/s²,
//!
//! whose error is O((ω²/λ_{m+1})²) relative to the omitted part. Everything is projected on the
//! response probes C = Pᵀ Φ and the forces F = Φᵀ Q once; a line then costs O(n_resp·m·n_ref), and
//! the RMS over responses O(m²) per line through the Gram matrix of the projected terms.
//!
//! **Supports** (springs and dashpots that do not scale with the modulus,
//! [`crate::supports`]) couple the modes: the kept modes' coordinates then solve one dense
//! m × m system per line, Z(ω) q = F, and H = C q plus the same residual terms.

use crate::error::{FitError, inconsistent};
use crate::probe::Probe;
use crate::supports::{GroundedSupport, ModalSupports};
use faer::Mat;
use faer::sparse::SparseColMatRef;
use lamdyn_fem::assembly::Assembly;
use lamdyn_fem::eigen::ModalSolution;
use lamdyn_fem::eigen::factor::{FactorPlan, LltFactor};
use lamdyn_frf::{Channel, FrfSet, Quantity};
use num_complex::Complex64;
use rayon::prelude::*;
use std::f64::consts::PI;

/// The share of a supported mode's strain energy in the laminate below which it is the
/// supports' own mode (bounce, rocking: 8–12 % on the bench's roof on four blocks, whose first
/// elastic mode mixed with them keeps 41 %).
pub const SUPPORT_SHARE: f64 = 0.2;

/// First bytes of a cached free [`ModalModel`] (format version 1).
const CACHE_MAGIC: &[u8] = b"lamdyn modal model v1\n";

/// First bytes of a cached [`ModalModel`] with supports (version 2: version 1's values, then
/// the supports' K̃ and C̃).
const CACHE_MAGIC_SUPPORTED: &[u8] = b"lamdyn modal model v2\n";

/// The residual flexibility of the omitted modes.
#[derive(Debug, Clone)]
struct Residual {
    sigma: f64,
    r1: Mat<f64>,
    r2: Mat<f64>,
}

/// Modal model of the responses to the references: projected modes and residual terms.
#[derive(Debug, Clone)]
pub struct ModalModel {
    lambda: Vec<f64>,
    c: Mat<f64>,
    f: Mat<f64>,
    residual: Option<Residual>,
    /// The supports in the modal basis; `None`: a free part (diagonal synthesis).
    supports: Option<ModalSupports>,
    e_ref_pa: f64,
    /// Estimated signed relative error of each mode's frequency from the discretization
    /// (f_model = f_converged (1 + δ)); empty when not estimated. Not cached.
    freq_error: Vec<f64>,
}

/// Whether to add the residual flexibility of the omitted modes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResidualTerm {
    /// Kept modes only.
    None,
    /// Kept modes plus R1/s − (sσ − ω²)R2/s² (two solves per reference).
    Static,
}

impl ModalModel {
    /// Projects the modes of `sol` (computed on `asm` at modulus `e_ref_pa`) on the response and
    /// reference probes; with [`ResidualTerm::Static`], factorizes K0 − σM once more for the
    /// residual terms.
    ///
    /// # Errors
    /// [`FitError::Inconsistent`] when the assembly has springs (the modes must be the free
    /// part's, K0 alone: give the supports to [`ModalModel::supported`]) or shapes of the
    /// wrong size; factorization errors.
    pub fn new(
        asm: &Assembly,
        sol: &ModalSolution,
        responses: &[Probe],
        references: &[Probe],
        e_ref_pa: f64,
        residual: ResidualTerm,
    ) -> Result<Self, FitError> {
        Self::supported(asm, sol, responses, references, e_ref_pa, residual, &[])
    }

    /// [`ModalModel::new`] for a part on grounded `supports` ([`crate::supports`]): the basis
    /// is the free modes of `sol` with the supports' static shapes (Rayleigh–Ritz), and the
    /// supports couple its coordinates at every line. No supports: [`ModalModel::new`].
    ///
    /// # Errors
    /// As [`ModalModel::new`]; a support acting on a dof the model does not have, or with a
    /// negative or non-finite stiffness or damping.
    pub fn supported(
        asm: &Assembly,
        sol: &ModalSolution,
        responses: &[Probe],
        references: &[Probe],
        e_ref_pa: f64,
        residual: ResidualTerm,
        supports: &[GroundedSupport],
    ) -> Result<Self, FitError> {
        if !asm.springs.is_empty() {
            return Err(inconsistent(
                "modal synthesis",
                format!(
                    "the assembly has {} support springs; the modal basis must be the free \
                     part's modes (K0 alone), with the supports given to \
                     ModalModel::supported",
                    asm.springs.len()
                ),
            ));
        }
        let n = asm.n_dofs();
        if sol.shapes.nrows() != n {
            return Err(inconsistent(
                "modal synthesis",
                format!(
                    "shapes have {} rows, the model {n} dofs",
                    sol.shapes.nrows()
                ),
            ));
        }
        let sigma = sol.info.shift;
        let plan = match residual == ResidualTerm::Static || !supports.is_empty() {
            true => Some(FactorPlan::new(&asm.pattern)?),
            false => None,
        };
        let factor = match &plan {
            Some(plan) => Some(shifted_factor(asm, plan, sigma, references.len())?),
            None => None,
        };
        let augmented;
        let (lambda, shapes) = if supports.is_empty() {
            let lambda: Vec<f64> = sol.modes.iter().map(|md| md.eigenvalue).collect();
            (lambda, sol.shapes.as_ref())
        } else {
            let factor = factor.as_ref().expect("factored for supports");
            let (lambda, shapes) = crate::supports::ritz_basis(asm, sol, supports, factor)?;
            augmented = shapes;
            (lambda, augmented.as_ref())
        };
        let m = lambda.len();
        let c = Mat::from_fn(responses.len(), m, |i, r| {
            responses[i].dot(|d| shapes[(d, r)])
        });
        let f = Mat::from_fn(m, references.len(), |r, j| {
            references[j].dot(|d| shapes[(d, r)])
        });
        let residual = match residual {
            ResidualTerm::None => None,
            ResidualTerm::Static => Some(residual_terms(
                asm,
                factor.as_ref().expect("factored for the residual"),
                sigma,
                &lambda,
                &c,
                &f,
                responses,
                references,
            )?),
        };
        let supports = match supports.is_empty() {
            true => None,
            false => Some(ModalSupports::project(shapes, supports)?),
        };
        Ok(Self {
            lambda,
            c,
            f,
            residual,
            supports,
            e_ref_pa,
            freq_error: Vec::new(),
        })
    }

    /// Whether the model has supports (its modes coupled through them).
    pub fn has_supports(&self) -> bool {
        self.supports.is_some()
    }

    /// The model as bytes for a cache file: a magic line, then little-endian u64 sizes and f64
    /// values (λ, C, F, E_ref and the residual terms). [`ModalModel::from_cache_bytes`] reads
    /// it back exactly (bit for bit).
    pub fn to_cache_bytes(&self) -> Vec<u8> {
        let (nr, nf) = self.shape();
        let m = self.lambda.len();
        let magic = match self.supports {
            None => CACHE_MAGIC,
            Some(_) => CACHE_MAGIC_SUPPORTED,
        };
        let mut out = magic.to_vec();
        for v in [m, nr, nf, usize::from(self.residual.is_some())] {
            out.extend_from_slice(&(v as u64).to_le_bytes());
        }
        let mut put = |x: f64| out.extend_from_slice(&x.to_le_bytes());
        put(self.e_ref_pa);
        self.lambda.iter().for_each(|&l| put(l));
        let mat = |a: &Mat<f64>, put: &mut dyn FnMut(f64)| {
            (0..a.ncols()).for_each(|j| (0..a.nrows()).for_each(|i| put(a[(i, j)])))
        };
        mat(&self.c, &mut put);
        mat(&self.f, &mut put);
        if let Some(r) = &self.residual {
            put(r.sigma);
            mat(&r.r1, &mut put);
            mat(&r.r2, &mut put);
        }
        if let Some(sup) = &self.supports {
            mat(&sup.stiffness, &mut put);
            mat(&sup.damping, &mut put);
        }
        out
    }

    /// Reads bytes written by [`ModalModel::to_cache_bytes`].
    ///
    /// # Errors
    /// [`FitError::Inconsistent`] for another format, a truncated file or non-finite values.
    pub fn from_cache_bytes(bytes: &[u8]) -> Result<Self, FitError> {
        let bad = |why: &str| inconsistent("modal model cache", why.into());
        let (body, supported) = match bytes.strip_prefix(CACHE_MAGIC) {
            Some(body) => (body, false),
            None => (
                bytes
                    .strip_prefix(CACHE_MAGIC_SUPPORTED)
                    .ok_or_else(|| bad("not a lamdyn modal model cache (version 1 or 2)"))?,
                true,
            ),
        };
        let mut words = body
            .chunks_exact(8)
            .map(|c| <[u8; 8]>::try_from(c).unwrap_or_default());
        let mut size = || -> Result<usize, FitError> {
            let w = words.next().ok_or_else(|| bad("truncated header"))?;
            usize::try_from(u64::from_le_bytes(w)).map_err(|_| bad("size too large"))
        };
        let (m, nr, nf, has_residual) = (size()?, size()?, size()?, size()?);
        let n_values = 1
            + m
            + nr * m
            + m * nf
            + has_residual * (1 + 2 * nr * nf)
            + usize::from(supported) * 2 * m * m;
        if body.len() != 8 * (4 + n_values) || has_residual > 1 {
            return Err(bad("size does not match its header"));
        }
        let values: Vec<f64> = body[32..]
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(<[u8; 8]>::try_from(c).unwrap_or_default()))
            .collect();
        if values.iter().any(|v| !v.is_finite()) {
            return Err(bad("non-finite value"));
        }
        let mut at = 0;
        let mut take = |n: usize| {
            at += n;
            &values[at - n..at]
        };
        let e_ref_pa = take(1)[0];
        let lambda = take(m).to_vec();
        let mat =
            |v: &[f64], rows: usize, cols: usize| Mat::from_fn(rows, cols, |i, j| v[j * rows + i]);
        let c = mat(take(nr * m), nr, m);
        let f = mat(take(m * nf), m, nf);
        let residual = (has_residual == 1).then(|| Residual {
            sigma: take(1)[0],
            r1: mat(take(nr * nf), nr, nf),
            r2: mat(take(nr * nf), nr, nf),
        });
        let supports = supported.then(|| ModalSupports {
            stiffness: mat(take(m * m), m, m),
            damping: mat(take(m * m), m, m),
        });
        Ok(Self {
            lambda,
            c,
            f,
            residual,
            supports,
            e_ref_pa,
            freq_error: Vec::new(),
        })
    }

    /// The same model carrying each mode's estimated discretization error δ_r, a signed
    /// relative frequency error (f_model = f_converged (1 + δ_r);
    /// [`lamdyn_fem::convergence`]): the fit adds what it does to the parameters to their
    /// covariance ([`crate::fit`]).
    ///
    /// # Errors
    /// [`FitError::Inconsistent`] for a count other than the model's modes, or values that are
    /// not finite or not above −1.
    pub fn with_frequency_errors(mut self, errors: Vec<f64>) -> Result<Self, FitError> {
        if errors.len() != self.lambda.len() {
            return Err(inconsistent(
                "modal model",
                format!(
                    "{} frequency errors for {} modes",
                    errors.len(),
                    self.lambda.len()
                ),
            ));
        }
        if let Some(bad) = errors.iter().find(|d| !(d.is_finite() && **d > -1.0)) {
            return Err(inconsistent(
                "modal model",
                format!("frequency error {bad} is not a relative error above -1"),
            ));
        }
        self.freq_error = errors;
        Ok(self)
    }

    /// Each mode's estimated discretization error (empty when not estimated).
    pub fn frequency_errors(&self) -> &[f64] {
        &self.freq_error
    }

    /// The model with the eigenvalues the estimate says a converged mesh would give,
    /// λ_r / (1 + δ_r)² (shapes and residual terms kept); `None` without an estimate.
    pub fn corrected(&self) -> Option<Self> {
        if self.freq_error.is_empty() {
            return None;
        }
        let mut out = self.clone();
        for (l, d) in out.lambda.iter_mut().zip(&self.freq_error) {
            *l /= (1.0 + d) * (1.0 + d);
        }
        out.freq_error.clear();
        Some(out)
    }

    /// The modulus E_ref (Pa) at which K0 was assembled.
    pub fn e_ref_pa(&self) -> f64 {
        self.e_ref_pa
    }

    /// Eigenvalues λ_r at E_ref, rad²/s².
    pub fn eigenvalues(&self) -> &[f64] {
        &self.lambda
    }

    /// Elastic frequencies (Hz) at E_ref, increasing: the modes with λ above 1e-6 of the
    /// highest (not rigid-body modes). With supports: the undamped modes of Λ + K̃ that also
    /// have at least [`SUPPORT_SHARE`] of their strain energy in the laminate (modes mixed with
    /// the supports included); the others are the supports' own modes (bounce and rocking),
    /// which barely scale with the modulus.
    pub fn elastic_hz(&self) -> Vec<f64> {
        if self.supports.is_some() {
            return self.supported_modes_hz(|laminate| laminate >= SUPPORT_SHARE);
        }
        let top = self.lambda.iter().cloned().fold(0.0, f64::max);
        let mut f: Vec<f64> = self
            .lambda
            .iter()
            .filter(|l| **l > 1e-6 * top)
            .map(|l| l.sqrt() / (2.0 * PI))
            .collect();
        f.sort_by(f64::total_cmp);
        f
    }

    /// The supports' own modes (Hz, increasing): the undamped modes of Λ + K̃ at E_ref, not
    /// rigid, with less than [`SUPPORT_SHARE`] of their strain energy in the laminate; empty
    /// for a free model.
    pub fn support_hz(&self) -> Vec<f64> {
        self.supported_modes_hz(|laminate| laminate < SUPPORT_SHARE)
    }

    /// The undamped modes of Λ + K̃ at E_ref (Hz, increasing), not rigid, whose share of strain
    /// energy in the laminate passes `keep`; empty for a free model.
    fn supported_modes_hz(&self, keep: impl Fn(f64) -> bool) -> Vec<f64> {
        let Some(supports) = &self.supports else {
            return Vec::new();
        };
        let floor = self.rigid_floor();
        let mut f: Vec<f64> = supports
            .undamped(&self.lambda)
            .unwrap_or_default()
            .into_iter()
            .filter(|&(l, laminate)| l > floor && keep(laminate))
            .map(|(l, _)| l.sqrt() / (2.0 * PI))
            .collect();
        f.sort_by(f64::total_cmp);
        f
    }

    /// The eigenvalue (rad²/s²) below which a supported model's mode is rigid: 1e-6 of the
    /// median eigenvalue. Not of the highest, as a free model's rule: the supports' static
    /// shapes can have Rayleigh quotients far above the band (a point spring's local dent).
    fn rigid_floor(&self) -> f64 {
        let mut l: Vec<f64> = self.lambda.iter().copied().filter(|l| *l > 0.0).collect();
        l.sort_by(f64::total_cmp);
        l.get(l.len() / 2).map_or(0.0, |median| 1e-6 * median)
    }

    /// With supports, every modulus scale s = E*/E_ref at which the model has the pole `pole`
    /// (Laplace variable, rad/s; [`crate::supports`]); `None` for a free model.
    pub fn supported_pole_scales(&self, pole: Complex64) -> Option<Vec<Complex64>> {
        let supports = self.supports.as_ref()?;
        Some(supports.pole_scales(&self.lambda, pole))
    }

    /// Number of responses and references.
    pub fn shape(&self) -> (usize, usize) {
        (self.c.nrows(), self.f.ncols())
    }

    /// Coefficient functions of the kept modes and of the residual terms at (ω, s).
    fn coefficients(&self, omega: f64, s: Complex64, out: &mut Vec<Complex64>) {
        out.clear();
        let w2 = omega * omega;
        out.extend(self.lambda.iter().map(|l| 1.0 / (l * s - w2)));
        out.extend(self.residual_coefficients(omega, s).into_iter().flatten());
    }

    /// The residual terms' coefficients 1/s and −(sσ − ω²)/s² at (ω, s), if the model has them.
    fn residual_coefficients(&self, omega: f64, s: Complex64) -> Option<[Complex64; 2]> {
        let r = self.residual.as_ref()?;
        Some([1.0 / s, -(s * r.sigma - omega * omega) / (s * s)])
    }

    /// Receptances with supports: the kept modes' coordinates Z(ω)⁻¹F ([`crate::supports`]),
    /// then C q plus the residual terms; row-major n_resp × n_ref.
    fn supported_receptance(
        &self,
        supports: &ModalSupports,
        omega: f64,
        s: Complex64,
    ) -> Vec<Complex64> {
        let (nr, nf) = self.shape();
        let q = supports.solve(&self.lambda, omega, s, self.f.as_ref());
        let residual = self.residual_coefficients(omega, s);
        let mut h = Vec::with_capacity(nr * nf);
        for i in 0..nr {
            for j in 0..nf {
                let mut acc: Complex64 = (0..self.lambda.len())
                    .map(|r| q[(r, j)] * self.c[(i, r)])
                    .sum();
                if let (Some(res), Some([g1, g2])) = (&self.residual, residual) {
                    acc += g1 * res.r1[(i, j)] + g2 * res.r2[(i, j)];
                }
                h.push(acc);
            }
        }
        h
    }

    /// Receptances (m/N) of all responses to all references at ω (rad/s) and s = E*(ω)/E_ref:
    /// row-major n_resp × n_ref.
    pub fn receptance(&self, omega: f64, s: Complex64) -> Vec<Complex64> {
        if let Some(supports) = &self.supports {
            return self.supported_receptance(supports, omega, s);
        }
        let (nr, nf) = self.shape();
        let mut g = Vec::with_capacity(self.lambda.len() + 2);
        self.coefficients(omega, s, &mut g);
        let m = self.lambda.len();
        let mut h = vec![Complex64::new(0.0, 0.0); nr * nf];
        for j in 0..nf {
            let gf: Vec<Complex64> = (0..m).map(|r| g[r] * self.f[(r, j)]).collect();
            for i in 0..nr {
                let mut acc = Complex64::new(0.0, 0.0);
                for r in 0..m {
                    acc += gf[r] * self.c[(i, r)];
                }
                if let Some(res) = &self.residual {
                    acc += g[m] * res.r1[(i, j)] + g[m + 1] * res.r2[(i, j)];
                }
                h[i * nf + j] = acc;
            }
        }
        h
    }

    /// The FRF set at `freqs_hz` for the modulus law `modulus` (Pa, of ω in rad/s), as
    /// `quantity`, computed in parallel over lines.
    ///
    /// # Errors
    /// [`FitError`] from the set's checks (non-finite values, a non-increasing axis).
    pub fn frf_set(
        &self,
        freqs_hz: &[f64],
        modulus: &(dyn Fn(f64) -> Complex64 + Sync),
        quantity: Quantity,
        responses: Vec<Channel>,
        references: Vec<Channel>,
    ) -> Result<FrfSet, FitError> {
        let (nr, nf) = self.shape();
        if responses.len() != nr || references.len() != nf {
            return Err(inconsistent(
                "modal synthesis",
                format!(
                    "{} x {} channels for a model of {nr} x {nf}",
                    responses.len(),
                    references.len()
                ),
            ));
        }
        let lines: Vec<Vec<Complex64>> = freqs_hz
            .par_iter()
            .map(|f| {
                let w = 2.0 * PI * f;
                let s = modulus(w) / self.e_ref_pa;
                let q = quantity.from_receptance(w);
                self.receptance(w, s).into_iter().map(|h| h * q).collect()
            })
            .collect();
        let nl = freqs_hz.len();
        let mut data = vec![Complex64::new(0.0, 0.0); nr * nf * nl];
        for (k, line) in lines.iter().enumerate() {
            for p in 0..nr * nf {
                data[p * nl + k] = line[p];
            }
        }
        Ok(FrfSet::new(
            freqs_hz.to_vec(),
            responses,
            references,
            quantity,
            data,
        )?)
    }

    /// A fast evaluator of the RMS receptance over the responses for reference `j`.
    /// Without supports the forces are folded into the Gram matrix (the terms C_ir F_rj);
    /// with them the terms are C's columns and the coefficients the coordinates q_j.
    pub fn rms_evaluator(&self, j: usize) -> RmsEvaluator {
        let m = self.lambda.len();
        let extra = if self.residual.is_some() { 2 } else { 0 };
        let nr = self.c.nrows();
        let folded = self.supports.is_none();
        let a = Mat::from_fn(nr, m + extra, |i, k| match (k < m, &self.residual) {
            (true, _) if folded => self.c[(i, k)] * self.f[(k, j)],
            (true, _) => self.c[(i, k)],
            (false, Some(res)) => {
                if k == m {
                    res.r1[(i, j)]
                } else {
                    res.r2[(i, j)]
                }
            }
            (false, None) => 0.0,
        });
        let gram = a.transpose() * &a;
        RmsEvaluator {
            model: self.clone(),
            gram,
            n_responses: nr,
            reference: j,
        }
    }
}

/// RMS over responses of the receptance to one reference, by the Gram matrix of the projected
/// terms: rms²(ω) = gᴴ G g / N with g the coefficient functions at (ω, s) (with supports: the
/// kept modes' coordinates for the reference, then the residual terms' coefficients).
#[derive(Debug, Clone)]
pub struct RmsEvaluator {
    model: ModalModel,
    gram: Mat<f64>,
    n_responses: usize,
    reference: usize,
}

impl RmsEvaluator {
    /// RMS receptance (m/N) at ω (rad/s) for s = E*(ω)/E_ref.
    pub fn rms(&self, omega: f64, s: Complex64) -> f64 {
        let mut g = Vec::new();
        match &self.model.supports {
            None => self.model.coefficients(omega, s, &mut g),
            Some(supports) => {
                let j = self.reference;
                let forces = self.model.f.as_ref().subcols(j, 1);
                let q = supports.solve(&self.model.lambda, omega, s, forces);
                g.extend((0..q.nrows()).map(|r| q[(r, 0)]));
                g.extend(
                    self.model
                        .residual_coefficients(omega, s)
                        .into_iter()
                        .flatten(),
                );
            }
        }
        // G is real symmetric: gᴴGg = Σ_a G_aa |g_a|² + 2 Σ_{a<b} G_ab Re(ḡ_a g_b).
        let k = g.len();
        let mut acc = 0.0;
        for a in 0..k {
            let ga = g[a];
            acc += self.gram[(a, a)] * ga.norm_sqr();
            let mut cross = 0.0;
            for b in a + 1..k {
                let gb = g[b];
                cross += self.gram[(a, b)] * (ga.re * gb.re + ga.im * gb.im);
            }
            acc += 2.0 * cross;
        }
        (acc.max(0.0) / self.n_responses as f64).sqrt()
    }
}

/// The LLᵀ factor of K0 − σM (σ the modal solver's shift) for `max_rhs` columns at a time,
/// factored once per model: the residual terms and the supports' static shapes solve with it.
pub(crate) fn shifted_factor<'p>(
    asm: &Assembly,
    plan: &'p FactorPlan,
    sigma: f64,
    max_rhs: usize,
) -> Result<LltFactor<'p>, FitError> {
    let k = asm.total_stiffness_values(1.0);
    let shifted = asm.shifted_values(&k, sigma);
    let a = SparseColMatRef::new(asm.stiffness.symbolic(), &shifted);
    Ok(plan.llt(a, sigma, max_rhs)?)
}

/// R1 and R2 of the module doc, projected on the probes.
#[allow(clippy::too_many_arguments)]
fn residual_terms(
    asm: &Assembly,
    factor: &LltFactor<'_>,
    sigma: f64,
    lambda: &[f64],
    c: &Mat<f64>,
    f: &Mat<f64>,
    responses: &[Probe],
    references: &[Probe],
) -> Result<Residual, FitError> {
    let n = asm.n_dofs();
    let mut x = Mat::from_fn(n, references.len(), |d, j| {
        references[j]
            .entries()
            .iter()
            .filter(|(e, _)| *e == d)
            .map(|(_, w)| w)
            .sum()
    });
    factor.solve_in_place(x.as_mut());
    let mut y = Mat::zeros(n, references.len());
    lamdyn_fem::sparse::symmetric_matmul(asm.mass.as_ref(), x.as_ref(), y.as_mut());
    factor.solve_in_place(y.as_mut());
    let m = lambda.len();
    let project = |v: &Mat<f64>, power: i32| {
        Mat::from_fn(responses.len(), references.len(), |i, j| {
            let full = responses[i].dot(|d| v[(d, j)]);
            let kept: f64 = (0..m)
                .map(|r| c[(i, r)] * f[(r, j)] / (lambda[r] - sigma).powi(power))
                .sum();
            full - kept
        })
    };
    Ok(Residual {
        sigma,
        r1: project(&x, 1),
        r2: project(&y, 2),
    })
}
