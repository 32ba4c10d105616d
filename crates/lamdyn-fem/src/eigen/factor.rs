//! Sparse Cholesky (LLᵀ) and LDLᵀ of K − σM on faer, planned once per mesh.
//!
//! Numeric factorizations and solves run sequentially (`Par::Seq`): on this project's 2-core
//! machines faer's parallel supernodal LLᵀ and solves measured slower than sequential ones
//! (1.5–2.5 s against 1.4 s for the 155k-dof plate; `examples/solvebench.rs`); blocks of 8 or more
//! right-hand sides are instead split in two halves solved concurrently.
//!
//! The fill-reducing order is AMD on the node graph (6 times smaller than the dof graph), each
//! node's six dofs kept together; the symbolic factorization is shared by every shift. The
//! LDLᵀ (without pivoting) serves the Sturm sequence check: by Sylvester's law of inertia the
//! number of negative pivots of K − cM is the number of eigenvalues of (K, M) below c.

use crate::assembly::SystemPattern;
use crate::error::FemError;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky, simplicial::SimplicialLdltRef, supernodal::SupernodalLdltRef,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

/// The symbolic factorization of a system pattern (ordering and elimination structure).
#[derive(Debug)]
pub struct FactorPlan {
    symbolic: SymbolicCholesky<usize>,
    par: Par,
}

impl FactorPlan {
    /// Orders the node graph by AMD and factorizes the dof pattern symbolically.
    ///
    /// # Errors
    /// [`FemError::Factorization`] if faer runs out of memory or indices.
    pub fn new(pattern: &SystemPattern) -> Result<Self, FemError> {
        let par = Par::Seq;
        let fail = |e: faer::sparse::FaerError| FemError::Factorization {
            shift: f64::NAN,
            reason: format!("symbolic analysis: {e:?}"),
        };
        let (ptr, adj) = pattern.node_graph();
        let n_nodes = ptr.len() - 1;
        let graph = SymbolicSparseColMatRef::new_checked(n_nodes, n_nodes, ptr, None, adj);
        let mut perm = vec![0usize; n_nodes];
        let mut perm_inv = vec![0usize; n_nodes];
        {
            let req = amd::order_scratch::<usize>(n_nodes, adj.len());
            let mut mem =
                MemBuffer::try_new(req).map_err(|_| fail(faer::sparse::FaerError::OutOfMemory))?;
            amd::order(
                &mut perm,
                &mut perm_inv,
                graph,
                amd::Control::default(),
                MemStack::new(&mut mem),
            )
            .map_err(fail)?;
        }
        let n = 6 * n_nodes;
        let mut fwd = vec![0usize; n];
        let mut inv = vec![0usize; n];
        for (k, &node) in perm.iter().enumerate() {
            for c in 0..6 {
                fwd[6 * k + c] = 6 * node + c;
                inv[6 * node + c] = 6 * k + c;
            }
        }
        let ordering = SymmetricOrdering::Custom(PermRef::new_checked(&fwd, &inv, n));
        let sym = pattern.symbolic();
        let symbolic = factorize_symbolic_cholesky(
            sym.as_ref(),
            Side::Lower,
            ordering,
            CholeskySymbolicParams::default(),
        )
        .map_err(fail)?;
        Ok(Self { symbolic, par })
    }

    /// Number of stored entries of the factor L.
    pub fn factor_nnz(&self) -> usize {
        self.symbolic.len_val()
    }

    /// LLᵀ of `a` (= K − σM, positive definite for σ below the lowest eigenvalue).
    ///
    /// # Errors
    /// [`FemError::Factorization`] when `a` is not numerically positive definite.
    /// `max_rhs` sizes the solve workspace for that many columns at once.
    pub fn llt(
        &self,
        a: SparseColMatRef<'_, usize, f64>,
        shift: f64,
        max_rhs: usize,
    ) -> Result<LltFactor<'_>, FemError> {
        let mut values = vec![0.0; self.symbolic.len_val()];
        let req = self
            .symbolic
            .factorize_numeric_llt_scratch::<f64>(self.par, Default::default());
        let mut mem = MemBuffer::try_new(req).map_err(|_| FemError::Factorization {
            shift,
            reason: "out of memory".into(),
        })?;
        self.symbolic
            .factorize_numeric_llt(
                &mut values,
                a,
                Side::Lower,
                Default::default(),
                self.par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| FemError::Factorization {
                shift,
                reason: format!(
                    "{e:?}: K - sigma M is not positive definite (is the model free to \
                     move, or sigma above the lowest eigenvalue?)"
                ),
            })?;
        let solve_req = self
            .symbolic
            .solve_in_place_scratch::<f64>(max_rhs, self.par);
        Ok(LltFactor {
            plan: self,
            values,
            max_rhs,
            solve_mem: std::cell::RefCell::new(MemBuffer::new(solve_req)),
        })
    }

    /// Number of negative pivots of LDLᵀ(a): the number of eigenvalues of (K, M) below c for
    /// a = K − cM.
    ///
    /// # Errors
    /// [`FemError::Factorization`] on a zero pivot (c is an eigenvalue to working precision).
    pub fn negative_pivots(
        &self,
        a: SparseColMatRef<'_, usize, f64>,
        cutoff: f64,
    ) -> Result<usize, FemError> {
        let mut values = vec![0.0; self.symbolic.len_val()];
        let req = self
            .symbolic
            .factorize_numeric_ldlt_scratch::<f64>(self.par, Default::default());
        let mut mem = MemBuffer::try_new(req).map_err(|_| FemError::Factorization {
            shift: cutoff,
            reason: "out of memory".into(),
        })?;
        self.symbolic
            .factorize_numeric_ldlt(
                &mut values,
                a,
                Side::Lower,
                Default::default(),
                self.par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| FemError::Factorization {
                shift: cutoff,
                reason: format!("LDL^T for the Sturm count: {e:?}"),
            })?;
        let mut negative = 0;
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let l = SimplicialLdltRef::new(s, &values);
                let f = l.symbolic().factor();
                for j in 0..f.ncols() {
                    let range = f.col_range(j);
                    let rows = &f.row_idx()[range.clone()];
                    if let Ok(p) = rows.binary_search(&j) {
                        if values[range.start + p] < 0.0 {
                            negative += 1;
                        }
                    }
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let l = SupernodalLdltRef::new(s, &values);
                for k in 0..s.n_supernodes() {
                    let block = l.supernode(k).val();
                    for j in 0..block.ncols() {
                        if block[(j, j)] < 0.0 {
                            negative += 1;
                        }
                    }
                }
            }
        }
        Ok(negative)
    }
}

/// A numeric LLᵀ factor with its solve workspace.
pub struct LltFactor<'p> {
    plan: &'p FactorPlan,
    values: Vec<f64>,
    max_rhs: usize,
    solve_mem: std::cell::RefCell<MemBuffer>,
}

impl LltFactor<'_> {
    /// Solves (K − σM) X = B in place; blocks of 8 or more columns are split in two halves
    /// solved concurrently (on this project's 2-core machines two sequential half-solves beat
    /// faer's parallel solve, which is slower than its sequential one here). The split does not
    /// depend on the thread count, so neither do the results, to the last bit: faer's kernels
    /// may sum in another order for another number of columns.
    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        if rhs.ncols() >= 8 {
            let half = rhs.ncols() / 2;
            let (a, b) = rhs.split_at_col_mut(half);
            let (symbolic, values) = (&self.plan.symbolic, &self.values[..]);
            let solve = |x: MatMut<'_, f64>| {
                let req = symbolic.solve_in_place_scratch::<f64>(x.ncols(), Par::Seq);
                let mut mem = MemBuffer::new(req);
                LltRef::new(symbolic, values).solve_in_place_with_conj(
                    Conj::No,
                    x,
                    Par::Seq,
                    MemStack::new(&mut mem),
                );
            };
            rayon::join(|| solve(a), || solve(b));
            return;
        }
        let plan = self.plan;
        let mut mem = self.solve_mem.borrow_mut();
        if rhs.ncols() > self.max_rhs {
            *mem = MemBuffer::new(
                plan.symbolic
                    .solve_in_place_scratch::<f64>(rhs.ncols(), plan.par),
            );
        }
        LltRef::new(&plan.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            plan.par,
            MemStack::new(&mut mem),
        );
    }
}
