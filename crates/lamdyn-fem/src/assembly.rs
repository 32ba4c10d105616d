//! Global stiffness and mass in faer sparse matrices, assembled in parallel over elements.
//!
//! Global dof of node n, component c (u_x, u_y, u_z, θ_x, θ_y, θ_z): 6n + c. Both triangles are
//! stored (compressed sparse columns, sorted rows), so M x is one sparse product. The pattern
//! is planned once from the node graph ([`SystemPattern`]); element matrices are computed in
//! parallel in batches and scattered into precomputed positions.
//!
//! K is linear in E at fixed ν (every term of the element is), so for the paper's eq. 4,
//! K*(ω) = K0 E*(ω)/E0, the stiffness assembled with E0 serves every frequency. Elastic supports
//! are kept apart ([`Assembly::springs`]): they do not scale with the laminate's modulus.

use crate::element::{ElementDefect, ElementMatrix, ShellMaterial};
use crate::error::{FemError, check_positive};
use crate::mesh::Mesh;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Each node's neighbours through `elements` (node lists): the nodes it shares an element with,
/// itself included, sorted; empty for a node of no element. The node graph of a sparsity
/// pattern (here and in the layered model's assembly).
pub fn node_neighbours<'a>(
    n_nodes: usize,
    elements: impl IntoIterator<Item = &'a [usize]>,
) -> Vec<Vec<usize>> {
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n_nodes];
    for el in elements {
        for &a in el {
            adj[a].extend_from_slice(el);
        }
    }
    for list in &mut adj {
        list.sort_unstable();
        list.dedup();
    }
    adj
}

/// The sparsity pattern of the global matrices and where each element writes into it.
#[derive(Debug, Clone)]
pub struct SystemPattern {
    n_nodes: usize,
    /// Node adjacency (CSR): neighbours of node n, sorted, including n itself.
    node_ptr: Vec<usize>,
    node_adj: Vec<usize>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Nodes per element.
    per_element: usize,
    /// For element e and local nodes (l, k): 6 × (position of node k among node l's neighbours),
    /// at `offsets[e·p² + p·l + k]` with p nodes per element.
    offsets: Vec<usize>,
}

impl SystemPattern {
    /// Plans the pattern of a mesh.
    pub fn new(mesh: &Mesh) -> Self {
        let n_nodes = mesh.nodes().len();
        let adj = node_neighbours(n_nodes, mesh.elements());
        let mut node_ptr = Vec::with_capacity(n_nodes + 1);
        let mut node_adj = Vec::new();
        node_ptr.push(0);
        for list in &adj {
            node_adj.extend_from_slice(list);
            node_ptr.push(node_adj.len());
        }
        let n_dofs = 6 * n_nodes;
        let mut col_ptr = Vec::with_capacity(n_dofs + 1);
        let mut row_idx = Vec::with_capacity(36 * node_adj.len());
        col_ptr.push(0);
        for n in 0..n_nodes {
            for _ in 0..6 {
                for &m in &node_adj[node_ptr[n]..node_ptr[n + 1]] {
                    row_idx.extend((0..6).map(|c| 6 * m + c));
                }
                col_ptr.push(row_idx.len());
            }
        }
        let per_element = mesh.order().nodes();
        let offsets = mesh
            .elements()
            .flat_map(|el| {
                el.iter().flat_map(|&l| {
                    let nbrs = &node_adj[node_ptr[l]..node_ptr[l + 1]];
                    el.iter()
                        .map(move |k| 6 * nbrs.binary_search(k).unwrap_or(0))
                })
            })
            .collect();
        Self {
            n_nodes,
            node_ptr,
            node_adj,
            col_ptr,
            row_idx,
            per_element,
            offsets,
        }
    }

    /// Number of dofs.
    pub fn n_dofs(&self) -> usize {
        6 * self.n_nodes
    }

    /// Stored entries (both triangles).
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// The node graph (CSR: pointers and sorted neighbour lists, each node its own neighbour).
    pub fn node_graph(&self) -> (&[usize], &[usize]) {
        (&self.node_ptr, &self.node_adj)
    }

    /// The symbolic matrix of the dof pattern.
    pub fn symbolic(&self) -> SymbolicSparseColMat<usize> {
        let n = self.n_dofs();
        SymbolicSparseColMat::new_checked(n, n, self.col_ptr.clone(), None, self.row_idx.clone())
    }

    /// Position of the global entry (row, col) in the value array, if stored.
    pub fn position(&self, row: usize, col: usize) -> Option<usize> {
        let rows = &self.row_idx[self.col_ptr[col]..self.col_ptr[col + 1]];
        rows.binary_search(&row).ok().map(|p| self.col_ptr[col] + p)
    }

    fn scatter(&self, values: &mut [f64], element: usize, nodes: &[usize], m: &ElementMatrix) {
        let p = self.per_element;
        let off = &self.offsets[p * p * element..p * p * (element + 1)];
        for l in 0..p {
            for cb in 0..6 {
                let col = 6 * nodes[l] + cb;
                let base = self.col_ptr[col];
                for k in 0..p {
                    let start = base + off[p * l + k];
                    for ca in 0..6 {
                        values[start + ca] += m[6 * k + ca][6 * l + cb];
                    }
                }
            }
        }
    }
}

/// An elastic support at a node: translational springs (N/m) along x, y, z and rotational
/// springs (N·m/rad) about x, y, z, in the global frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeSpring {
    /// Node index.
    pub node: usize,
    /// Translational stiffnesses k_x, k_y, k_z, N/m.
    pub translational_n_per_m: [f64; 3],
    /// Rotational stiffnesses about x, y, z, N·m/rad.
    #[serde(default)]
    pub rotational_nm_per_rad: [f64; 3],
}

/// K0 (material stiffness at E0), M and the supports of a shell model.
#[derive(Debug, Clone)]
pub struct Assembly {
    /// The planned pattern shared by K and M.
    pub pattern: Arc<SystemPattern>,
    /// Stiffness at the material's E0 (N/m, N, N·m entries), without supports.
    pub stiffness: SparseColMat<usize, f64>,
    /// Consistent mass (kg, kg·m, kg·m² entries), its exact zeros dropped (a third of K's
    /// pattern for flat shells: translations couple only to the same component).
    pub mass: SparseColMat<usize, f64>,
    /// Position of each entry of `mass` in the value array of `stiffness`.
    pub mass_positions: Vec<usize>,
    /// Support springs as (dof, stiffness) diagonal additions.
    pub springs: Vec<(usize, f64)>,
    /// Node positions, m (for rigid-body modes and outputs).
    pub nodes: Vec<crate::V3>,
}

impl Assembly {
    /// Assembles the MITC4 or MITC9 stiffness and mass of `mesh` with `material`, in parallel.
    ///
    /// # Errors
    /// [`FemError::InvalidParameter`] for a non-physical material or a mesh whose modal solve
    /// would need more memory than is available ([`crate::memory`]); [`FemError::InvalidMesh`]
    /// for an element whose Jacobian turns negative through the thickness; invalid springs.
    pub fn new(
        mesh: &Mesh,
        material: &ShellMaterial,
        springs: &[NodeSpring],
    ) -> Result<Self, FemError> {
        validate_material(material)?;
        crate::memory::check_modal_memory(6 * mesh.nodes().len())?;
        let pattern = Arc::new(SystemPattern::new(mesh));
        let nnz = pattern.nnz();
        let mut k = vec![0.0; nnz];
        let mut m = vec![0.0; nnz];
        let n_el = mesh.n_elements();
        const BATCH: usize = 1024;
        for start in (0..n_el).step_by(BATCH) {
            let end = (start + BATCH).min(n_el);
            let mats: Vec<Result<(ElementMatrix, ElementMatrix), (usize, ElementDefect)>> = (start
                ..end)
                .into_par_iter()
                .map(|e| {
                    let el = mesh.element(e, material.thickness_m);
                    let ke = el.stiffness(material).map_err(|d| (e, d))?;
                    Ok((ke, el.mass(material)))
                })
                .collect();
            for (i, r) in mats.into_iter().enumerate() {
                let (ke, me) = r.map_err(|(e, _)| {
                    FemError::InvalidMesh(format!(
                        "element {e} (nodes {:?}): the Jacobian turns negative through the \
                         thickness ({} m): the shell is too thick for its curvature or the element \
                         is folded",
                        mesh.element_nodes(e),
                        material.thickness_m
                    ))
                })?;
                let e = start + i;
                pattern.scatter(&mut k, e, mesh.element_nodes(e), &ke);
                pattern.scatter(&mut m, e, mesh.element_nodes(e), &me);
            }
        }
        let springs = spring_diagonal(springs, mesh.nodes().len())?;
        let sym = pattern.symbolic();
        let full_mass = SparseColMat::new(sym.clone(), m);
        let mass = crate::sparse::drop_zeros(full_mass.as_ref());
        let mass_positions = (0..mass.ncols())
            .flat_map(|j| {
                mass.as_ref()
                    .row_idx_of_col(j)
                    .map(move |i| (i, j))
                    .collect::<Vec<_>>()
            })
            .map(|(i, j)| {
                pattern
                    .position(i, j)
                    .expect("mass pattern within stiffness pattern")
            })
            .collect();
        Ok(Self {
            stiffness: SparseColMat::new(sym, k),
            mass,
            mass_positions,
            pattern,
            springs,
            nodes: mesh.nodes().to_vec(),
        })
    }

    /// Number of dofs.
    pub fn n_dofs(&self) -> usize {
        self.pattern.n_dofs()
    }

    /// Values of `k_values − sigma·M` on K0's pattern (M scattered into K0's positions).
    pub fn shifted_values(&self, k_values: &[f64], sigma: f64) -> Vec<f64> {
        let mut out = k_values.to_vec();
        for (p, m) in self.mass_positions.iter().zip(self.mass.val()) {
            out[*p] -= sigma * m;
        }
        out
    }

    /// Values of K0 scaled by `factor` plus the supports, on K0's pattern: the stiffness at
    /// modulus factor·E0 (use with `self.stiffness.symbolic()`).
    pub fn total_stiffness_values(&self, factor: f64) -> Vec<f64> {
        let mut vals: Vec<f64> = self.stiffness.val().iter().map(|v| factor * v).collect();
        for &(dof, kk) in &self.springs {
            if let Some(p) = self.pattern.position(dof, dof) {
                vals[p] += kk;
            }
        }
        vals
    }
}

fn validate_material(m: &ShellMaterial) -> Result<(), FemError> {
    let ctx = "shell material";
    check_positive(ctx, "young_pa", m.young_pa)?;
    check_positive(ctx, "density_kg_m3", m.density_kg_m3)?;
    check_positive(ctx, "thickness_m", m.thickness_m)?;
    if !(m.poisson > -1.0 && m.poisson < 0.5) {
        return Err(FemError::InvalidParameter {
            context: ctx.into(),
            field: "poisson".into(),
            value: format!("{}", m.poisson),
            requirement: "must lie in (-1, 0.5)".into(),
        });
    }
    Ok(())
}

fn spring_diagonal(springs: &[NodeSpring], n_nodes: usize) -> Result<Vec<(usize, f64)>, FemError> {
    let mut out = Vec::new();
    for (i, s) in springs.iter().enumerate() {
        if s.node >= n_nodes {
            return Err(FemError::InvalidParameter {
                context: format!("support {i}"),
                field: "node".into(),
                value: s.node.to_string(),
                requirement: format!("must be a node of the mesh (0..{n_nodes})"),
            });
        }
        for (c, k) in s
            .translational_n_per_m
            .iter()
            .chain(&s.rotational_nm_per_rad)
            .enumerate()
        {
            if !(k.is_finite() && *k >= 0.0) {
                return Err(FemError::InvalidParameter {
                    context: format!("support {i} (node {})", s.node),
                    field: if c < 3 {
                        "translational_n_per_m".into()
                    } else {
                        "rotational_nm_per_rad".into()
                    },
                    value: format!("{k}"),
                    requirement: "must be finite and not negative".into(),
                });
            }
            if *k > 0.0 {
                out.push((6 * s.node + c, *k));
            }
        }
    }
    Ok(out)
}
