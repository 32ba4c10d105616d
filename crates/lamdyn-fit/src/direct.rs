//! Direct solution of the paper's eq. 3 at one frequency, the independent check of the modal
//! synthesis: (−ω² M + s(ω) K0 + K_s + iω C_s) x = q with faer's sparse LU (complex), the
//! pattern analysed once. K_s holds the assembly's node springs and the grounded supports
//! given to [`DirectSolver::with_supports`], C_s their dashpots.

use crate::error::FitError;
use crate::probe::Probe;
use crate::supports::GroundedSupport;
use faer::Mat;
use faer::prelude::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use lamdyn_fem::assembly::Assembly;
use num_complex::Complex64;
use rayon::prelude::*;

/// Direct complex solves on an assembled model.
pub struct DirectSolver<'a> {
    asm: &'a Assembly,
    symbolic: SymbolicSparseColMat<usize>,
    lu_symbolic: SymbolicLu<usize>,
    mass_on_k: Vec<f64>,
    springs_on_k: Vec<f64>,
    /// The grounded supports' K_s and C_s on K0's pattern, if any.
    supports_on_k: Option<[Vec<f64>; 2]>,
}

impl<'a> DirectSolver<'a> {
    /// Analyses the pattern of the model.
    ///
    /// # Errors
    /// [`FitError::DirectSolve`] if faer's symbolic LU fails.
    pub fn new(asm: &'a Assembly) -> Result<Self, FitError> {
        let symbolic = asm
            .stiffness
            .symbolic()
            .to_owned()
            .map_err(|e| FitError::DirectSolve {
                freq_hz: 0.0,
                reason: format!("{e:?}"),
            })?;
        let lu_symbolic =
            SymbolicLu::try_new(symbolic.as_ref()).map_err(|e| FitError::DirectSolve {
                freq_hz: 0.0,
                reason: format!("symbolic LU: {e:?}"),
            })?;
        let zeros = vec![0.0; asm.stiffness.val().len()];
        let mass_on_k = asm.shifted_values(&zeros, -1.0);
        let springs_on_k: Vec<f64> = asm
            .total_stiffness_values(1.0)
            .iter()
            .zip(asm.stiffness.val())
            .map(|(a, b)| a - b)
            .collect();
        Ok(Self {
            asm,
            symbolic,
            lu_symbolic,
            mass_on_k,
            springs_on_k,
            supports_on_k: None,
        })
    }

    /// The solver with grounded `supports` added: K_s = Σ k b bᵀ, C_s = Σ c b bᵀ.
    ///
    /// # Errors
    /// [`FitError::Inconsistent`] when a support couples two dofs outside K0's pattern (its
    /// probe spans more than one element) or acts on a dof the model does not have.
    pub fn with_supports(mut self, supports: &[GroundedSupport]) -> Result<Self, FitError> {
        let nnz = self.asm.stiffness.val().len();
        let (mut k, mut c) = (vec![0.0; nnz], vec![0.0; nnz]);
        let n = self.asm.n_dofs();
        for (i, s) in supports.iter().enumerate() {
            if let Some((d, _)) = s.probe.entries().iter().find(|(d, _)| *d >= n) {
                return Err(crate::error::inconsistent(
                    "direct solver's supports",
                    format!("support {i} acts on dof {d}; the model has {n}"),
                ));
            }
            for &(a, wa) in s.probe.entries() {
                for &(b, wb) in s.probe.entries() {
                    let p = self.asm.pattern.position(a, b).ok_or_else(|| {
                        crate::error::inconsistent(
                            "direct solver's supports",
                            format!("support {i} couples dofs {a} and {b}, outside K0's pattern"),
                        )
                    })?;
                    k[p] += s.stiffness_n_m * wa * wb;
                    c[p] += s.damping_n_s_m * wa * wb;
                }
            }
        }
        self.supports_on_k = Some([k, c]);
        Ok(self)
    }

    /// Receptances (m/N) of `responses` to unit forces at `references` at ω (rad/s) with
    /// s = E*(ω)/E_ref: row-major n_resp × n_ref.
    ///
    /// # Errors
    /// [`FitError::DirectSolve`] when the LU fails (ω at an undamped eigenvalue).
    pub fn receptance(
        &self,
        omega: f64,
        s: Complex64,
        responses: &[Probe],
        references: &[Probe],
    ) -> Result<Vec<Complex64>, FitError> {
        let fail = |reason: String| FitError::DirectSolve {
            freq_hz: omega / (2.0 * std::f64::consts::PI),
            reason,
        };
        let w2 = omega * omega;
        let vals: Vec<Complex64> = self
            .asm
            .stiffness
            .val()
            .iter()
            .zip(&self.mass_on_k)
            .zip(&self.springs_on_k)
            .enumerate()
            .map(|(p, ((k, m), ks))| {
                let a = s * k + ks - w2 * m;
                match &self.supports_on_k {
                    None => a,
                    Some([sk, sc]) => a + Complex64::new(sk[p], omega * sc[p]),
                }
            })
            .collect();
        let a = SparseColMat::new(self.symbolic.clone(), vals);
        let lu = Lu::try_new_with_symbolic(self.lu_symbolic.clone(), a.as_ref())
            .map_err(|e| fail(format!("{e:?}")))?;
        let n = self.asm.n_dofs();
        let mut rhs = Mat::<Complex64>::zeros(n, references.len());
        for (j, q) in references.iter().enumerate() {
            for &(d, w) in q.entries() {
                rhs[(d, j)] += Complex64::new(w, 0.0);
            }
        }
        let x = lu.solve(&rhs);
        let mut h = Vec::with_capacity(responses.len() * references.len());
        for p in responses {
            for j in 0..references.len() {
                h.push(p.entries().iter().map(|(d, w)| x[(*d, j)] * *w).sum());
            }
        }
        Ok(h)
    }

    /// Receptances at every line of `freqs_hz` for the modulus law `modulus` (Pa, of ω in
    /// rad/s), in parallel over lines: one LU factorization per line, the route the paper took
    /// for every trial of its fit.
    ///
    /// # Errors
    /// The first [`FitError::DirectSolve`] of a line.
    pub fn receptance_lines(
        &self,
        freqs_hz: &[f64],
        modulus: &(dyn Fn(f64) -> Complex64 + Sync),
        e_ref_pa: f64,
        responses: &[Probe],
        references: &[Probe],
    ) -> Result<Vec<Vec<Complex64>>, FitError> {
        freqs_hz
            .par_iter()
            .map(|f| {
                let w = 2.0 * std::f64::consts::PI * f;
                self.receptance(w, modulus(w) / e_ref_pa, responses, references)
            })
            .collect()
    }
}
