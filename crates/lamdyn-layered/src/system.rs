//! Assembly of the layered hexahedral model into sparse K and M, and its lowest modes by the
//! shift-invert Lanczos of lamdyn-fem on a faer sparse Cholesky of K − σM.
//!
//! Each layer has its own material; K = Σ_l a_l K_l and M = Σ_l b_l M_l, so a layer's stiffness
//! can later be scaled by a frequency-dependent modulus (the core) and each layer's stiffness
//! and mass by its own factor (a face modulus, a density: [`crate::sensitivity`]). Free-free models have six zero
//! eigenvalues; a negative shift σ keeps K − σM positive definite.

use crate::error::LayeredError;
use crate::hex20::{Elastic, matrices};
use crate::mesh::HexMesh;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use faer::{Conj, Mat, MatMut, MatRef, Par, Side};
use lamdyn_fem::eigen::lanczos::{LanczosParams, ShiftInvert, lanczos};
use rayon::prelude::*;

/// Sparse stiffness per layer and the total mass of a layered hexahedral model.
pub struct LayeredSystem {
    /// Stiffness of each layer's elements (full symmetric storage), N/m.
    pub k_layers: Vec<SparseColMat<usize, f64>>,
    /// Consistent mass, kg: the sum of `m_layers`.
    pub m: SparseColMat<usize, f64>,
    /// Consistent mass of each layer's elements, kg.
    pub m_layers: Vec<SparseColMat<usize, f64>>,
    /// Dofs: 3 per node (u_x, u_y, u_z).
    pub n_dofs: usize,
    /// Grounded springs (supports) on single dofs, N/m, added to every stiffness.
    pub springs: Option<SparseColMat<usize, f64>>,
    /// The supports' dashpots C_s, N·s/m ([`Self::add_supports`]): in no real eigenproblem
    /// here; the reduced model projects them and its basis holds the modes' static response to
    /// their forces ([`crate::reduced::ReducedModel::with_orders`]).
    pub dashpots: Option<SparseColMat<usize, f64>>,
}

impl LayeredSystem {
    /// Assembles `mesh` with one material per layer.
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] for a material count that differs from the layers, or an element
    /// with a non-positive Jacobian.
    pub fn assemble(mesh: &HexMesh, materials: &[Elastic]) -> Result<Self, LayeredError> {
        let n_layers = mesh.layer.iter().max().map_or(0, |l| l + 1);
        if n_layers == 0 || materials.len() != n_layers {
            return Err(LayeredError::Invalid(format!(
                "{} materials for {n_layers} layers",
                materials.len()
            )));
        }
        let n = 3 * mesh.nodes.len();
        let element: Vec<(usize, Vec<f64>, Vec<f64>)> = mesh
            .elements
            .par_iter()
            .zip(&mesh.layer)
            .enumerate()
            .map(|(e, (conn, &l))| {
                let x: [[f64; 3]; 20] = std::array::from_fn(|a| mesh.nodes[conn[a]]);
                matrices(&x, &materials[l])
                    .map(|(k, m)| (l, k, m))
                    .ok_or_else(|| {
                        LayeredError::Invalid(format!("element {e}: non-positive Jacobian"))
                    })
            })
            .collect::<Result<_, _>>()?;
        let dofs = |conn: &[usize; 20]| -> [usize; 60] {
            std::array::from_fn(|q| 3 * conn[q / 3] + q % 3)
        };
        let mut k_trip: Vec<Vec<Triplet<usize, usize, f64>>> = vec![Vec::new(); n_layers];
        let mut m_trip: Vec<Vec<Triplet<usize, usize, f64>>> = vec![Vec::new(); n_layers];
        for (conn, (l, k, m)) in mesh.elements.iter().zip(&element) {
            let d = dofs(conn);
            for p in 0..60 {
                for q in 0..60 {
                    k_trip[*l].push(Triplet::new(d[p], d[q], k[p * 60 + q]));
                    if m[p * 60 + q] != 0.0 {
                        m_trip[*l].push(Triplet::new(d[p], d[q], m[p * 60 + q]));
                    }
                }
            }
        }
        let build = |t: &[Triplet<usize, usize, f64>]| {
            SparseColMat::try_new_from_triplets(n, n, t)
                .map_err(|e| LayeredError::Solver(format!("sparse assembly: {e:?}")))
        };
        let m_layers: Vec<SparseColMat<usize, f64>> =
            m_trip.iter().map(|t| build(t)).collect::<Result<_, _>>()?;
        let mut m = m_layers[0].clone();
        for ml in &m_layers[1..] {
            m = &m + ml;
        }
        Ok(Self {
            k_layers: k_trip.iter().map(|t| build(t)).collect::<Result<_, _>>()?,
            m,
            m_layers,
            n_dofs: n,
            springs: None,
            dashpots: None,
        })
    }

    /// Adds grounded springs (dof, stiffness N/m): elastic supports, or with a stiffness far
    /// above the structure's (a penalty) fixed dofs.
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] for a dof out of range or a negative or non-finite stiffness.
    pub fn add_springs(&mut self, springs: &[(usize, f64)]) -> Result<(), LayeredError> {
        let mut t: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(springs.len());
        for &(d, k) in springs {
            if d >= self.n_dofs || !(k.is_finite() && k >= 0.0) {
                return Err(LayeredError::Invalid(format!(
                    "spring on dof {d} of {} with stiffness {k} N/m",
                    self.n_dofs
                )));
            }
            t.push(Triplet::new(d, d, k));
        }
        self.accumulate_springs(&t)
    }

    /// Adds the supports' springs k w wᵀ to K_s and records their dashpots c w wᵀ in C_s
    /// ([`crate::supports::SupportTerm`]).
    ///
    /// # Errors
    /// [`LayeredError::Invalid`] for a dof out of range or a negative or non-finite stiffness
    /// or damping.
    pub fn add_supports(
        &mut self,
        terms: &[crate::supports::SupportTerm],
    ) -> Result<(), LayeredError> {
        let (mut k_t, mut c_t): (Vec<Triplet<usize, usize, f64>>, Vec<_>) =
            (Vec::new(), Vec::new());
        for term in terms {
            let (k, c) = (term.stiffness_n_m, term.damping_n_s_m);
            if !(k.is_finite() && k >= 0.0 && c.is_finite() && c >= 0.0)
                || term.weights.iter().any(|w| w.0 >= self.n_dofs)
            {
                return Err(LayeredError::Invalid(format!(
                    "support spring of {k} N/m and dashpot of {c} N s/m on dofs {:?} of {}",
                    term.weights.iter().map(|w| w.0).collect::<Vec<_>>(),
                    self.n_dofs
                )));
            }
            for &(i, wi) in &term.weights {
                for &(j, wj) in &term.weights {
                    k_t.push(Triplet::new(i, j, k * wi * wj));
                    if c > 0.0 {
                        c_t.push(Triplet::new(i, j, c * wi * wj));
                    }
                }
            }
        }
        if !c_t.is_empty() {
            let add = SparseColMat::try_new_from_triplets(self.n_dofs, self.n_dofs, &c_t)
                .map_err(|e| LayeredError::Solver(format!("dashpots: {e:?}")))?;
            self.dashpots = Some(match self.dashpots.take() {
                Some(d) => &d + &add,
                None => add,
            });
        }
        self.accumulate_springs(&k_t)
    }

    /// Adds the spring entries `t` (summed where they repeat) to K_s.
    fn accumulate_springs(&mut self, t: &[Triplet<usize, usize, f64>]) -> Result<(), LayeredError> {
        if t.is_empty() {
            return Ok(());
        }
        let add = SparseColMat::try_new_from_triplets(self.n_dofs, self.n_dofs, t)
            .map_err(|e| LayeredError::Solver(format!("springs: {e:?}")))?;
        self.springs = Some(match self.springs.take() {
            Some(s) => &s + &add,
            None => add,
        });
        Ok(())
    }

    /// Total stiffness with layer l's stiffness scaled by `scale[l]`, springs included.
    pub fn stiffness(&self, scale: &[f64]) -> SparseColMat<usize, f64> {
        let mut k = &self.k_layers[0] * scale[0];
        for (kl, s) in self.k_layers.iter().zip(scale).skip(1) {
            k = &k + &(kl * *s);
        }
        match &self.springs {
            Some(sp) => &k + sp,
            None => k,
        }
    }

    /// The `count` lowest eigenpairs (ω² in rad²/s², M-orthonormal vectors) of K φ = ω² M φ
    /// with layer stiffnesses scaled by `scale`, by shift-invert Lanczos about `shift` (rad²/s²;
    /// negative for a free-free model).
    ///
    /// # Errors
    /// [`LayeredError::Solver`] if K − σM is not positive definite or Lanczos does not converge.
    pub fn modes(
        &self,
        scale: &[f64],
        count: usize,
        shift: f64,
    ) -> Result<(Vec<f64>, Mat<f64>), LayeredError> {
        self.modes_with(&self.shifted_cholesky(scale, shift)?, count, shift)
    }

    /// [`Self::modes`] with the factor of K − σM already made ([`Self::shifted_cholesky`]
    /// with the same `shift`), for callers that solve with it again.
    ///
    /// # Errors
    /// [`LayeredError::Solver`] if Lanczos does not converge.
    pub fn modes_with(
        &self,
        llt: &SeqCholesky,
        count: usize,
        shift: f64,
    ) -> Result<(Vec<f64>, Mat<f64>), LayeredError> {
        let op = Operator {
            llt,
            m: &self.m,
            n: self.n_dofs,
        };
        let block = 4;
        let out = lanczos(
            &op,
            LanczosParams {
                wanted: count,
                subspace: count + 10 * block,
                block,
                tolerance: 1e-12,
                max_restarts: 200,
                seed: 2026,
                par: Par::Seq,
            },
            Mat::<f64>::zeros(self.n_dofs, 0).as_ref(),
            Mat::<f64>::zeros(self.n_dofs, 0).as_ref(),
            &mut |_| {},
        );
        if out.converged < count {
            return Err(LayeredError::Solver(format!(
                "Lanczos converged {} of {count} modes",
                out.converged
            )));
        }
        // θ = 1/(λ − σ), descending θ = ascending λ.
        let lambda = out.theta.iter().map(|t| shift + 1.0 / t).collect();
        Ok((lambda, out.vectors))
    }
}

/// A sparse LLᵀ factor computed and applied sequentially (`Par::Seq`): faer's default
/// parallel supernodal kernels split the work by the thread count, and with it the rounding,
/// which the layered inverse amplifies about thirtyfold into G (issue 15.6).
pub struct SeqCholesky {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
}

impl SeqCholesky {
    /// LLᵀ of the symmetric positive definite `a` (lower triangle used), AMD ordered.
    ///
    /// # Errors
    /// [`LayeredError::Solver`] when `a` is not numerically positive definite.
    pub fn new(a: SparseColMatRef<'_, usize, f64>) -> Result<Self, LayeredError> {
        let fail = |what: &str, e: &dyn std::fmt::Debug| {
            LayeredError::Solver(format!("sparse Cholesky, {what}: {e:?}"))
        };
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| fail("symbolic", &e))?;
        let mut values = vec![0.0; symbolic.len_val()];
        let req = symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default());
        let mut mem = MemBuffer::try_new(req).map_err(|e| fail("memory", &e))?;
        symbolic
            .factorize_numeric_llt(
                &mut values,
                a,
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| fail("not positive definite", &e))?;
        Ok(Self { symbolic, values })
    }

    /// Solves A X = B in place.
    pub fn solve_in_place(&self, x: MatMut<'_, f64>) {
        let req = self
            .symbolic
            .solve_in_place_scratch::<f64>(x.ncols(), Par::Seq);
        let mut mem = MemBuffer::new(req);
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            x,
            Par::Seq,
            MemStack::new(&mut mem),
        );
    }
}

impl LayeredSystem {
    /// The sequential LLᵀ of K − σM with layer stiffnesses scaled by `scale` (σ = `shift`,
    /// rad²/s²).
    ///
    /// # Errors
    /// [`LayeredError::Solver`] if K − σM is not positive definite.
    pub fn shifted_cholesky(&self, scale: &[f64], shift: f64) -> Result<SeqCholesky, LayeredError> {
        let shifted = &self.stiffness(scale) + &(&self.m * (-shift));
        SeqCholesky::new(shifted.as_ref())
    }
}

struct Operator<'a> {
    llt: &'a SeqCholesky,
    m: &'a SparseColMat<usize, f64>,
    n: usize,
}

impl ShiftInvert for Operator<'_> {
    fn dim(&self) -> usize {
        self.n
    }
    fn mass(&self, x: MatRef<'_, f64>, y: MatMut<'_, f64>) {
        faer::sparse::linalg::matmul::sparse_dense_matmul(
            y,
            faer::Accum::Replace,
            self.m.as_ref(),
            x,
            1.0,
            Par::Seq,
        );
    }
    fn solve(&self, mut x: MatMut<'_, f64>) {
        self.llt.solve_in_place(x.as_mut());
    }
}
