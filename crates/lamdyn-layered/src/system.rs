//! Assembly of the layered hexahedral model into sparse K and M, and its lowest modes by the
//! shift-invert Lanczos of lamdyn-fem on a faer sparse Cholesky of K − σM.
//!
//! Each layer has its own material; K = Σ_l a_l K_l and M = Σ_l b_l M_l, so a layer's stiffness
//! can later be scaled by a frequency-dependent modulus (the core) and each layer's stiffness
//! and mass by its own factor (a face modulus, a density: [`crate::sensitivity`]). Free-free models
//! have six zero eigenvalues; a negative shift σ keeps K − σM positive definite.

use crate::error::LayeredError;
use crate::hex20::{Elastic, matrices};
use crate::mesh::HexMesh;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat, Triplet};
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
    /// The dofs in the sparse Cholesky's elimination order (nested dissection of the mesh,
    /// [`crate::ordering`]); `None`: approximate minimum degree.
    pub elimination: Option<Vec<usize>>,
}

/// The sparsity of one layer's matrices. Two nodes that share an element of the layer couple
/// in all three directions in its stiffness and each direction with itself in its mass (the
/// hexahedron's consistent mass is ρ N_a N_b I₃). The element matrices are added straight into
/// the values in element order: no triplets to sort, and each layer's matrix holds only its
/// own elements' entries.
struct LayerPattern {
    /// Each node's neighbours in the layer, itself included (sorted; empty off the layer).
    neighbours: Vec<Vec<usize>>,
}

impl LayerPattern {
    fn new(mesh: &HexMesh, layer: usize) -> Self {
        let of_layer = mesh
            .elements
            .iter()
            .zip(&mesh.layer)
            .filter(|e| *e.1 == layer)
            .map(|(conn, _)| conn.as_slice());
        Self {
            neighbours: lamdyn_fem::assembly::node_neighbours(mesh.nodes.len(), of_layer),
        }
    }

    /// Column pointers and row indices, with `per_direction` rows of each neighbour in each
    /// column: 3 (stiffness: all directions) or 1 (mass: the column's own direction).
    fn symbolic(&self, per_direction: usize) -> (Vec<usize>, Vec<usize>) {
        let mut col_ptr = Vec::with_capacity(3 * self.neighbours.len() + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for nb in &self.neighbours {
            for c in 0..3 {
                for &b in nb {
                    if per_direction == 3 {
                        row_idx.extend([3 * b, 3 * b + 1, 3 * b + 2]);
                    } else {
                        row_idx.push(3 * b + c);
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        (col_ptr, row_idx)
    }

    /// The layer's stiffness and mass from its elements' matrices (`element`: layer, K, M per
    /// element of the mesh, 60 × 60 row-major).
    fn scatter(
        &self,
        mesh: &HexMesh,
        layer: usize,
        element: &[(usize, Vec<f64>, Vec<f64>)],
    ) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
        let n = 3 * mesh.nodes.len();
        let (k_ptr, k_rows) = self.symbolic(3);
        let (m_ptr, m_rows) = self.symbolic(1);
        let mut k_values = vec![0.0; k_rows.len()];
        let mut m_values = vec![0.0; m_rows.len()];
        for (conn, (_, k, m)) in mesh.elements.iter().zip(element).filter(|e| e.1.0 == layer) {
            for (ia, &a) in conn.iter().enumerate() {
                // Where each of the element's nodes sits among a's neighbours (all of them are).
                let nb = &self.neighbours[a];
                let at: [usize; 20] =
                    std::array::from_fn(|ib| nb.binary_search(&conn[ib]).unwrap_or(0));
                for c in 0..3 {
                    let (q, col) = (3 * ia + c, 3 * a + c);
                    for (ib, &pos) in at.iter().enumerate() {
                        for r in 0..3 {
                            let p = 3 * ib + r;
                            k_values[k_ptr[col] + 3 * pos + r] += k[p * 60 + q];
                        }
                        m_values[m_ptr[col] + pos] += m[(3 * ib + c) * 60 + q];
                    }
                }
            }
        }
        // Rows sorted and unique in every column (the neighbours are): a valid structure.
        let build = |ptr: Vec<usize>, rows: Vec<usize>, values: Vec<f64>| {
            SparseColMat::new(
                SymbolicSparseColMat::new_checked(n, n, ptr, None, rows),
                values,
            )
        };
        (
            build(k_ptr, k_rows, k_values),
            build(m_ptr, m_rows, m_values),
        )
    }
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
        // Layers in parallel, each sequential in element order: the same bits on any thread
        // count.
        let (k_layers, m_layers): (Vec<_>, Vec<_>) = (0..n_layers)
            .into_par_iter()
            .map(|l| LayerPattern::new(mesh, l).scatter(mesh, l, &element))
            .unzip();
        let mut m = m_layers[0].clone();
        for ml in &m_layers[1..] {
            m = &m + ml;
        }
        let neighbours = lamdyn_fem::assembly::node_neighbours(
            mesh.nodes.len(),
            mesh.elements.iter().map(|e| e.as_slice()),
        );
        let nodes = crate::ordering::nested_dissection(&mesh.nodes, &neighbours);
        Ok(Self {
            k_layers,
            m,
            m_layers,
            n_dofs: n,
            springs: None,
            dashpots: None,
            elimination: Some(crate::ordering::dof_order(&nodes, 3)),
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
                tolerance: LANCZOS_TOLERANCE,
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

/// The Ritz residual (relative to θ) at which Lanczos takes a mode as converged. The modes
/// are basis vectors of the reduced model, whose eigenvalues are Rayleigh quotients over the
/// whole basis: a residual r moves them by O(r²), far below the rounding of the reduced
/// eigensolver (2–8e-9, `LayeredInverse::pole_eigenvalue`), and a cluster's span is accurate
/// where its single vectors are not. Measured on the demo roof (five models, 7 293 to
/// 37 149 dofs): 1e-9 ends each run one restart earlier than 1e-12 (80 instead of 100
/// applications), and the per-mode G* moves by at most 2.3e-6 of itself, the inverse's own
/// noise.
const LANCZOS_TOLERANCE: f64 = 1e-9;

/// A sparse LLᵀ factor computed and applied sequentially (`Par::Seq`): faer's default
/// parallel supernodal kernels split the work by the thread count, and with it the rounding,
/// which the layered inverse amplifies about thirtyfold into G.
pub struct SeqCholesky {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
}

impl SeqCholesky {
    /// LLᵀ of the symmetric positive definite `a` (lower triangle used), its rows and columns
    /// eliminated in the order `elimination` (a permutation of the dofs: `elimination[k]` is
    /// the k-th eliminated), or approximate minimum degree without one.
    ///
    /// # Errors
    /// [`LayeredError::Solver`] when `a` is not numerically positive definite or `elimination`
    /// is not a permutation of its dofs.
    pub fn new(
        a: SparseColMatRef<'_, usize, f64>,
        elimination: Option<&[usize]>,
    ) -> Result<Self, LayeredError> {
        let fail = |what: &str, e: &dyn std::fmt::Debug| {
            LayeredError::Solver(format!("sparse Cholesky, {what}: {e:?}"))
        };
        let inverse = elimination
            .map(|order| {
                inverse_permutation(order, a.nrows()).ok_or_else(|| {
                    LayeredError::Solver(format!(
                        "sparse Cholesky: an elimination order of {} entries is not a permutation \
                         of {} dofs",
                        order.len(),
                        a.nrows()
                    ))
                })
            })
            .transpose()?;
        let ordering = match (elimination, &inverse) {
            (Some(fwd), Some(inv)) => {
                SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(fwd, inv, a.nrows()))
            }
            _ => SymmetricOrdering::Amd,
        };
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            ordering,
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
        SeqCholesky::new(shifted.as_ref(), self.elimination.as_deref())
    }
}

/// The inverse of the permutation `order` of 0..n, `None` if it is not one.
fn inverse_permutation(order: &[usize], n: usize) -> Option<Vec<usize>> {
    if order.len() != n {
        return None;
    }
    let mut inverse = vec![usize::MAX; n];
    for (k, &v) in order.iter().enumerate() {
        if v >= n || inverse[v] != usize::MAX {
            return None;
        }
        inverse[v] = k;
    }
    Some(inverse)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{LayerMesh, LayeredPlateSpec};

    /// Each layer's matrices summed from triplets of every element entry (faer's own
    /// duplicate summation), the reference for the scattered assembly.
    fn by_triplets(
        mesh: &HexMesh,
        materials: &[Elastic],
    ) -> Vec<(SparseColMat<usize, f64>, SparseColMat<usize, f64>)> {
        let n = 3 * mesh.nodes.len();
        (0..materials.len())
            .map(|l| {
                let (mut kt, mut mt) = (Vec::new(), Vec::new());
                for (conn, _) in mesh.elements.iter().zip(&mesh.layer).filter(|e| *e.1 == l) {
                    let x: [[f64; 3]; 20] = std::array::from_fn(|a| mesh.nodes[conn[a]]);
                    let (k, m) = matrices(&x, &materials[l]).unwrap();
                    let d = |p: usize| 3 * conn[p / 3] + p % 3;
                    for p in 0..60 {
                        for q in 0..60 {
                            kt.push(Triplet::new(d(p), d(q), k[p * 60 + q]));
                            mt.push(Triplet::new(d(p), d(q), m[p * 60 + q]));
                        }
                    }
                }
                let build = |t: &[Triplet<usize, usize, f64>]| {
                    SparseColMat::try_new_from_triplets(n, n, t).unwrap()
                };
                (build(&kt), build(&mt))
            })
            .collect()
    }

    /// The largest |a − b| over all entries, relative to the largest |b|.
    fn relative_difference(a: &SparseColMat<usize, f64>, b: &SparseColMat<usize, f64>) -> f64 {
        let (a, b) = (a.to_dense(), b.to_dense());
        let scale = b.norm_max();
        (&a - &b).norm_max() / scale
    }

    /// Glass faces and a soft core.
    const GLASS: Elastic = Elastic {
        young_pa: 70e9,
        poisson: 0.22,
        density_kg_m3: 2500.0,
    };
    const CORE: Elastic = Elastic {
        young_pa: 3e7,
        poisson: 0.49,
        density_kg_m3: 1070.0,
    };

    /// A bowl (negative radii) with a symmetric stack is the dome mirrored through its tangent
    /// plane: the free solid's eigenvalues of (K, M), invariant under the mirror, agree within
    /// rounding (dense generalized eigenvalues on a small mesh).
    #[test]
    fn a_bowl_has_the_mirrored_dome_s_eigenvalues() {
        use faer::prelude::Solve;
        let eigenvalues = |r: f64| {
            let layer = |thickness_m| LayerMesh {
                thickness_m,
                elements: 1,
            };
            let mesh = LayeredPlateSpec {
                length_m: 0.3,
                width_m: 0.2,
                nx: 2,
                ny: 2,
                radius_x_m: 2.0 * r,
                radius_y_m: 3.0 * r,
                layers: vec![layer(2e-3), layer(0.8e-3), layer(2e-3)],
                edge_grading: 0.0,
            }
            .build()
            .unwrap();
            let sys = LayeredSystem::assemble(&mesh, &[GLASS, CORE, GLASS]).unwrap();
            let sum = |m: &[SparseColMat<usize, f64>]| {
                m.iter()
                    .map(|a| a.to_dense())
                    .fold(None, |acc: Option<Mat<f64>>, a| {
                        Some(acc.map_or(a.clone(), |b| &b + &a))
                    })
            };
            let (k, m) = (sum(&sys.k_layers).unwrap(), sum(&sys.m_layers).unwrap());
            // K x = λ M x as L⁻¹ K L⁻ᵀ with M = L Lᵀ.
            let l = m.llt(Side::Lower).unwrap().L().to_owned();
            let n = l.nrows();
            let linv = l
                .as_ref()
                .partial_piv_lu()
                .solve(Mat::<f64>::identity(n, n));
            let a = &linv * &k * linv.transpose();
            let a = Mat::from_fn(n, n, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
            let mut lambda: Vec<f64> = a.self_adjoint_eigenvalues(Side::Lower).unwrap();
            lambda.sort_by(f64::total_cmp);
            lambda
        };
        let (dome, bowl) = (eigenvalues(1.0), eigenvalues(-1.0));
        // Six rigid-body modes, then the elastic ones: the lowest 12 of them compared.
        let scale = dome[17];
        for k in 0..18 {
            assert!(
                (dome[k] - bowl[k]).abs() <= 1e-9 * scale,
                "eigenvalue {k}: dome {} vs bowl {}",
                dome[k],
                bowl[k]
            );
        }
        assert!(dome[6] > 1e-6 * scale && dome[5] < 1e-6 * scale);
    }

    /// The scattered assembly is the triplet sum: every entry of every layer's stiffness and
    /// mass within rounding (1e-14 of the largest), on a curved plate of three layers, one of
    /// them split in two through the thickness. Also the symmetry of every stiffness and the
    /// mass being the sum of the layers'.
    #[test]
    fn scattered_assembly_is_the_triplet_sum() {
        let mesh = LayeredPlateSpec {
            length_m: 0.3,
            width_m: 0.2,
            nx: 3,
            ny: 2,
            radius_x_m: 2.0,
            radius_y_m: 3.0,
            layers: vec![
                LayerMesh {
                    thickness_m: 2e-3,
                    elements: 1,
                },
                LayerMesh {
                    thickness_m: 0.8e-3,
                    elements: 2,
                },
                LayerMesh {
                    thickness_m: 3e-3,
                    elements: 1,
                },
            ],
            edge_grading: 0.0,
        }
        .build()
        .unwrap();
        let materials = [GLASS, CORE, GLASS];
        let sys = LayeredSystem::assemble(&mesh, &materials).unwrap();
        let reference = by_triplets(&mesh, &materials);
        for (l, (k, m)) in reference.iter().enumerate() {
            let (dk, dm) = (
                relative_difference(&sys.k_layers[l], k),
                relative_difference(&sys.m_layers[l], m),
            );
            assert!(dk < 1e-14 && dm < 1e-14, "layer {l}: {dk:e} {dm:e}");
            let kd = sys.k_layers[l].to_dense();
            let asym = (&kd - kd.transpose()).norm_max() / kd.norm_max();
            assert!(asym < 1e-14, "layer {l}: asymmetry {asym:e}");
        }
        let sum = &(&sys.m_layers[0] + &sys.m_layers[1]) + &sys.m_layers[2];
        assert!(relative_difference(&sys.m, &sum) < 1e-15);
    }

    /// An elimination order that is not a permutation of the dofs is refused with an error
    /// naming the sizes; a valid one factors a small SPD matrix and solves it to rounding.
    #[test]
    fn an_elimination_order_must_be_a_permutation() {
        let t: Vec<Triplet<usize, usize, f64>> = (0..3)
            .flat_map(|i| {
                let mut v = vec![Triplet::new(i, i, 4.0)];
                if i > 0 {
                    v.push(Triplet::new(i, i - 1, -1.0));
                    v.push(Triplet::new(i - 1, i, -1.0));
                }
                v
            })
            .collect();
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &t).unwrap();
        for bad in [&[0usize, 1][..], &[0, 1, 1], &[0, 1, 3]] {
            let Err(e) = SeqCholesky::new(a.as_ref(), Some(bad)) else {
                panic!("{bad:?} accepted");
            };
            assert!(e.to_string().contains("not a permutation of 3 dofs"), "{e}");
        }
        let llt = SeqCholesky::new(a.as_ref(), Some(&[2, 0, 1])).unwrap();
        let mut x = Mat::from_fn(3, 1, |i, _| [3.0, 2.0, 3.0][i]);
        llt.solve_in_place(x.as_mut());
        // A (1, 1, 1)ᵀ = (3, 2, 3)ᵀ.
        for i in 0..3 {
            assert!((x[(i, 0)] - 1.0).abs() < 1e-14);
        }
    }
}
