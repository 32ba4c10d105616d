//! Meshes of 4-node or 9-node quadrilaterals on a (possibly curved) mid-surface.
//!
//! A [`Mesh`] holds node positions (m), a unit director per node (the shell normal), the
//! elements (4 or 9 node indices, corners counter-clockwise seen from the directors' side), the
//! element order (MITC4 or MITC9), and named node
//! and element groups. [`Mesh::new`] validates everything an element needs: finite
//! coordinates, node indices in range, no unused node, consistent orientation, no degenerate or
//! inverted element.
//!
//! - [`structured`]: rectangular plates and doubly curved shallow shells over a rectangle.
//! - [`gmsh`]: Gmsh MSH 2.2 and 4.1 ASCII files.
//! - [`refine`]: every element split into m × m ([`Mesh::subdivided`]).
//! - [`Locator`]: measurement points → nearest nodes, or points of the mid-surface with their
//!   shape-function weights ([`SurfacePoint`]).

pub mod gmsh;
mod locate;
pub mod refine;
pub mod structured;

pub use locate::{Locator, SurfacePoint};

use crate::element::{ElementDefect, ElementOrder, Quad4Mitc, Quad9Mitc, ShellElement};
use crate::error::FemError;
use crate::vec3::{V3, add, cross, norm, scale, sub, unit};
use std::collections::{BTreeMap, HashMap};

/// Appends the element whose lower-left node is grid point (a, b) of a structured grid of
/// nodes `at(i, j)`, spanning q grid steps per side (q = 1: 4-node, q = 2: 9-node), in the
/// node order of [`Mesh::quadratic`].
pub(crate) fn push_grid_element(
    connectivity: &mut Vec<usize>,
    at: impl Fn(usize, usize) -> usize,
    (a, b): (usize, usize),
    q: usize,
) {
    connectivity.extend([at(a, b), at(a + q, b), at(a + q, b + q), at(a, b + q)]);
    if q == 2 {
        connectivity.extend([
            at(a + 1, b),
            at(a + 2, b + 1),
            at(a + 1, b + 2),
            at(a, b + 1),
            at(a + 1, b + 1),
        ]);
    }
}

/// How the source of a mesh numbers its nodes and elements, for messages: a file's node and
/// element numbers (tags) and each element's line; empty, the indices from 0 in the order
/// given (meshes built in code).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Numbering {
    /// The file's number of each node, in the mesh's node order.
    pub node_ids: Vec<i64>,
    /// The file's number of each element, in the mesh's element order.
    pub element_ids: Vec<i64>,
    /// The file's line of each element (1-based).
    pub element_lines: Vec<usize>,
}

impl Numbering {
    /// Node `n` as the source numbers it.
    pub fn node(&self, n: usize) -> String {
        self.node_ids
            .get(n)
            .map_or_else(|| n.to_string(), ToString::to_string)
    }

    /// Element `e` as the source numbers it, with its line where known.
    pub fn element(&self, e: usize) -> String {
        let number = self
            .element_ids
            .get(e)
            .map_or_else(|| e.to_string(), ToString::to_string);
        match self.element_lines.get(e) {
            Some(line) => format!("{number} (line {line})"),
            None => number,
        }
    }

    /// Nodes `ns` as the source numbers them, as a list.
    pub fn nodes(&self, ns: &[usize]) -> String {
        let names: Vec<String> = ns.iter().map(|&n| self.node(n)).collect();
        format!("[{}]", names.join(", "))
    }
}

/// A quadrilateral shell mesh of 4-node or 9-node elements.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    nodes: Vec<V3>,
    directors: Vec<V3>,
    order: ElementOrder,
    /// Node indices, [`ElementOrder::nodes`] per element.
    connectivity: Vec<usize>,
    node_groups: BTreeMap<String, Vec<usize>>,
    element_groups: BTreeMap<String, Vec<usize>>,
}

impl Mesh {
    /// A mesh of 4-node elements from node positions (m). Directors are the normalised average
    /// of the adjacent elements' normals at each node.
    ///
    /// # Errors
    /// [`FemError::InvalidMesh`] naming the node or element: NaN coordinates, an index out of
    /// range, a node no element uses, a repeated node in an element, elements whose orientation
    /// disagrees with a neighbour's, a degenerate or inverted element.
    pub fn new(nodes: Vec<V3>, elements: Vec<[usize; 4]>) -> Result<Self, FemError> {
        Self::of_order(ElementOrder::Linear, nodes, None, elements.concat())
    }

    /// A mesh of 4-node elements with given unit directors (e.g. the exact normals of an
    /// analytic surface).
    ///
    /// # Errors
    /// As [`Mesh::new`], and for directors that are not unit vectors.
    pub fn with_directors(
        nodes: Vec<V3>,
        directors: Vec<V3>,
        elements: Vec<[usize; 4]>,
    ) -> Result<Self, FemError> {
        Self::of_order(
            ElementOrder::Linear,
            nodes,
            Some(directors),
            elements.concat(),
        )
    }

    /// A mesh of 9-node elements (corners counter-clockwise, then the mid-side nodes of edges
    /// 0-1, 1-2, 2-3, 3-0, then the centre: Gmsh's and VTK's order), with given directors or
    /// (None) directors averaged from the elements' normals at each node.
    ///
    /// # Errors
    /// As [`Mesh::with_directors`], and for neighbours that share an edge but not its mid-side
    /// node, or a mid-side or centre node far from where the corners put it (more than a quarter
    /// of the edge from the edge's midpoint).
    pub fn quadratic(
        nodes: Vec<V3>,
        directors: Option<Vec<V3>>,
        elements: Vec<[usize; 9]>,
    ) -> Result<Self, FemError> {
        Self::of_order(ElementOrder::Quadratic, nodes, directors, elements.concat())
    }

    /// A mesh of either order from a flat connectivity list ([`ElementOrder::nodes`] indices
    /// per element).
    ///
    /// # Errors
    /// As [`Mesh::with_directors`] and [`Mesh::quadratic`]; a connectivity whose length is not a
    /// multiple of the element's node count.
    pub fn of_order(
        order: ElementOrder,
        nodes: Vec<V3>,
        directors: Option<Vec<V3>>,
        connectivity: Vec<usize>,
    ) -> Result<Self, FemError> {
        Self::of_order_numbered(order, nodes, directors, connectivity, &Numbering::default())
    }

    /// [`Mesh::of_order`] for a mesh read from a file: errors name nodes and elements as the
    /// file numbers them (`numbering`).
    ///
    /// # Errors
    /// As [`Mesh::of_order`].
    pub fn of_order_numbered(
        order: ElementOrder,
        nodes: Vec<V3>,
        directors: Option<Vec<V3>>,
        connectivity: Vec<usize>,
        numbering: &Numbering,
    ) -> Result<Self, FemError> {
        let per = order.nodes();
        if connectivity.len() % per != 0 {
            return Err(FemError::InvalidMesh(format!(
                "{} node indices do not make whole {per}-node elements",
                connectivity.len()
            )));
        }
        let id = numbering;
        check_nodes_and_connectivity(&nodes, &connectivity, per, id)?;
        check_orientation(&connectivity, per, id)?;
        if order == ElementOrder::Quadratic {
            check_quadratic_nodes(&nodes, &connectivity, id)?;
        }
        let directors = match directors {
            Some(d) => d,
            None => averaged_normals(&nodes, &connectivity, order, id)?,
        };
        if directors.len() != nodes.len() {
            return Err(FemError::InvalidMesh(format!(
                "{} directors for {} nodes",
                directors.len(),
                nodes.len()
            )));
        }
        for (i, d) in directors.iter().enumerate() {
            if (norm(*d) - 1.0).abs().is_nan() || (norm(*d) - 1.0).abs() >= 1e-9 {
                return Err(FemError::InvalidMesh(format!(
                    "node {}: director {d:?} is not a unit vector",
                    id.node(i)
                )));
            }
        }
        let mesh = Self {
            nodes,
            directors,
            order,
            connectivity,
            node_groups: BTreeMap::new(),
            element_groups: BTreeMap::new(),
        };
        for e in 0..mesh.n_elements() {
            // Geometry only: a small thickness is enough to check the Jacobian's sign.
            let scale_len = mesh.element_size(e);
            mesh.element(e, 1e-3 * scale_len).check_geometry().map_err(|d| {
                let (el, nodes) = (id.element(e), id.nodes(mesh.element_nodes(e)));
                FemError::InvalidMesh(match d {
                    ElementDefect::Degenerate { at } => format!(
                        "element {el} (nodes {nodes}) is degenerate (zero area near r = {}, s = \
                         {})",
                        at[0], at[1]
                    ),
                    ElementDefect::Inverted { at } => format!(
                        "element {el} (nodes {nodes}) is inverted (negative Jacobian near r = {}, \
                         s = {}): check the node order",
                        at[0], at[1]
                    ),
                })
            })?;
        }
        Ok(mesh)
    }

    /// Adds a named group of nodes (indices must exist).
    ///
    /// # Errors
    /// [`FemError::InvalidMesh`] for an index out of range.
    pub fn add_node_group(&mut self, name: &str, nodes: Vec<usize>) -> Result<(), FemError> {
        if let Some(bad) = nodes.iter().find(|&&n| n >= self.nodes.len()) {
            return Err(FemError::InvalidMesh(format!(
                "node group '{name}': node {bad} does not exist"
            )));
        }
        self.node_groups.insert(name.to_string(), nodes);
        Ok(())
    }

    /// Adds a named group of elements (indices must exist).
    ///
    /// # Errors
    /// [`FemError::InvalidMesh`] for an index out of range.
    pub fn add_element_group(&mut self, name: &str, elements: Vec<usize>) -> Result<(), FemError> {
        if let Some(bad) = elements.iter().find(|&&e| e >= self.n_elements()) {
            return Err(FemError::InvalidMesh(format!(
                "element group '{name}': element {bad} does not exist"
            )));
        }
        self.element_groups.insert(name.to_string(), elements);
        Ok(())
    }

    /// Node positions, m.
    pub fn nodes(&self) -> &[V3] {
        &self.nodes
    }
    /// Unit directors (shell normals) per node.
    pub fn directors(&self) -> &[V3] {
        &self.directors
    }
    /// The elements' node indices, one slice of [`ElementOrder::nodes`] per element.
    pub fn elements(&self) -> std::slice::ChunksExact<'_, usize> {
        self.connectivity.chunks_exact(self.order.nodes())
    }
    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.connectivity.len() / self.order.nodes()
    }
    /// The node indices of element `e`.
    pub fn element_nodes(&self, e: usize) -> &[usize] {
        let per = self.order.nodes();
        &self.connectivity[per * e..per * (e + 1)]
    }
    /// The four corner nodes of element `e`, counter-clockwise.
    pub fn corners(&self, e: usize) -> [usize; 4] {
        let n = self.element_nodes(e);
        [n[0], n[1], n[2], n[3]]
    }
    /// The element family: 4-node MITC4 or 9-node MITC9.
    pub fn order(&self) -> ElementOrder {
        self.order
    }
    /// Named node groups.
    pub fn node_groups(&self) -> &BTreeMap<String, Vec<usize>> {
        &self.node_groups
    }
    /// Named element groups.
    pub fn element_groups(&self) -> &BTreeMap<String, Vec<usize>> {
        &self.element_groups
    }
    /// Number of degrees of freedom (6 per node).
    pub fn n_dofs(&self) -> usize {
        6 * self.nodes.len()
    }

    /// The element `e` with thickness `thickness_m`: MITC4 or MITC9 by the mesh's order.
    pub fn element(&self, e: usize, thickness_m: f64) -> ShellElement {
        let n = self.element_nodes(e);
        let x = |k: usize| self.nodes[n[k]];
        let d = |k: usize| self.directors[n[k]];
        match self.order {
            ElementOrder::Linear => ShellElement::Quad4(Quad4Mitc::new(
                std::array::from_fn(x),
                std::array::from_fn(d),
                thickness_m,
            )),
            ElementOrder::Quadratic => ShellElement::Quad9(Quad9Mitc::new(
                std::array::from_fn(x),
                std::array::from_fn(d),
                thickness_m,
            )),
        }
    }

    /// Longest corner-to-corner edge of element `e`, m.
    fn element_size(&self, e: usize) -> f64 {
        let n = self.corners(e);
        (0..4)
            .map(|k| norm(sub(self.nodes[n[(k + 1) % 4]], self.nodes[n[k]])))
            .fold(0.0, f64::max)
    }

    /// Total area of the mid-surface (the element's Gauss rule), m².
    pub fn area(&self) -> f64 {
        (0..self.n_elements()).map(|e| self.element_area(e)).sum()
    }

    fn element_area(&self, e: usize) -> f64 {
        let n = self.element_nodes(e);
        let rule = self.order.gauss();
        let mut a = 0.0;
        for &(r, wr) in rule {
            for &(s, ws) in rule {
                let (_, hr, hs) = self.order.shape(r, s);
                let mut dr = [0.0; 3];
                let mut ds = [0.0; 3];
                for (k, &node) in n.iter().enumerate() {
                    dr = add(dr, scale(hr[k], self.nodes[node]));
                    ds = add(ds, scale(hs[k], self.nodes[node]));
                }
                a += norm(cross(dr, ds)) * wr * ws;
            }
        }
        a
    }
}

fn check_nodes_and_connectivity(
    nodes: &[V3],
    connectivity: &[usize],
    per: usize,
    id: &Numbering,
) -> Result<(), FemError> {
    if nodes.is_empty() || connectivity.is_empty() {
        return Err(FemError::InvalidMesh(format!(
            "{} nodes and {} elements: nothing to mesh",
            nodes.len(),
            connectivity.len() / per
        )));
    }
    for (i, p) in nodes.iter().enumerate() {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(FemError::InvalidMesh(format!(
                "node {} has a non-finite coordinate {p:?}",
                id.node(i)
            )));
        }
    }
    let mut used = vec![false; nodes.len()];
    for (e, el) in connectivity.chunks_exact(per).enumerate() {
        for &n in el {
            if n >= nodes.len() {
                return Err(FemError::InvalidMesh(format!(
                    "element {} refers to node {n}, but there are {} nodes",
                    id.element(e),
                    nodes.len()
                )));
            }
            used[n] = true;
        }
        for a in 0..per {
            for b in a + 1..per {
                if el[a] == el[b] {
                    return Err(FemError::InvalidMesh(format!(
                        "element {} (nodes {}) repeats node {}: degenerate",
                        id.element(e),
                        id.nodes(el),
                        id.node(el[a])
                    )));
                }
            }
        }
    }
    if let Some(n) = used.iter().position(|u| !u) {
        return Err(FemError::InvalidMesh(format!(
            "node {} is not used by any element (a free node makes the stiffness singular)",
            id.node(n)
        )));
    }
    Ok(())
}

/// Neighbouring elements must run along their shared edge in opposite directions, and 9-node
/// neighbours must share the edge's mid-side node.
fn check_orientation(connectivity: &[usize], per: usize, id: &Numbering) -> Result<(), FemError> {
    let mut edges: HashMap<(usize, usize), (usize, Option<usize>)> = HashMap::new();
    for (e, el) in connectivity.chunks_exact(per).enumerate() {
        for k in 0..4 {
            let (a, b) = (el[k], el[(k + 1) % 4]);
            let mid = (per == 9).then(|| el[4 + k]);
            if let Some(&(other, _)) = edges.get(&(a, b)) {
                return Err(FemError::InvalidMesh(format!(
                    "elements {} and {} run along edge {}-{} in the same direction: their \
                     orientations (normals) disagree",
                    id.element(other),
                    id.element(e),
                    id.node(a),
                    id.node(b)
                )));
            }
            if let Some(&(other, other_mid)) = edges.get(&(b, a))
                && other_mid != mid
            {
                let name = |m: Option<usize>| m.map_or_else(|| "none".into(), |m| id.node(m));
                return Err(FemError::InvalidMesh(format!(
                    "elements {} and {} share edge {}-{} but not its mid-side node ({} and {})",
                    id.element(other),
                    id.element(e),
                    id.node(a),
                    id.node(b),
                    name(other_mid),
                    name(mid)
                )));
            }
            edges.insert((a, b), (e, mid));
        }
    }
    Ok(())
}

/// A 9-node element's mid-side nodes lie within a quarter of their edge's length of the
/// edge's midpoint, and its centre node within a quarter of the shorter diagonal of the point
/// the other eight nodes put it at (½ Σ mid-sides − ¼ Σ corners, exact for any biquadratic
/// map that is serendipity-consistent).
fn check_quadratic_nodes(
    nodes: &[V3],
    connectivity: &[usize],
    id: &Numbering,
) -> Result<(), FemError> {
    for (e, el) in connectivity.chunks_exact(9).enumerate() {
        let x = |k: usize| nodes[el[k]];
        for k in 0..4 {
            let (a, b) = (x(k), x((k + 1) % 4));
            let chord = norm(sub(b, a));
            let off = norm(sub(x(4 + k), scale(0.5, add(a, b))));
            if off > 0.25 * chord {
                return Err(FemError::InvalidMesh(format!(
                    "element {}: mid-side node {} is {off:.4e} m from the middle of edge {}-{} \
                     ({chord:.4e} m long): more than a quarter of the edge, the element would fold \
                     (check the node order)",
                    id.element(e),
                    id.node(el[4 + k]),
                    id.node(el[k]),
                    id.node(el[(k + 1) % 4])
                )));
            }
        }
        let mut centre = [0.0; 3];
        for k in 0..4 {
            centre = add(centre, add(scale(0.5, x(4 + k)), scale(-0.25, x(k))));
        }
        let diagonal = norm(sub(x(2), x(0))).min(norm(sub(x(3), x(1))));
        let off = norm(sub(x(8), centre));
        if off > 0.25 * diagonal {
            return Err(FemError::InvalidMesh(format!(
                "element {}: centre node {} is {off:.4e} m from where its edges put it, more than \
                 a quarter of the diagonal ({diagonal:.4e} m)",
                id.element(e),
                id.node(el[8])
            )));
        }
    }
    Ok(())
}

/// Unit average of the adjacent elements' normals g_r × g_s at each node.
fn averaged_normals(
    nodes: &[V3],
    connectivity: &[usize],
    order: ElementOrder,
    id: &Numbering,
) -> Result<Vec<V3>, FemError> {
    let mut sum = vec![[0.0; 3]; nodes.len()];
    for el in connectivity.chunks_exact(order.nodes()) {
        for (k, rs) in order.node_rs().iter().enumerate() {
            let (_, hr, hs) = order.shape(rs[0], rs[1]);
            let mut gr = [0.0; 3];
            let mut gs = [0.0; 3];
            for (m, &node) in el.iter().enumerate() {
                gr = add(gr, scale(hr[m], nodes[node]));
                gs = add(gs, scale(hs[m], nodes[node]));
            }
            let n = cross(gr, gs);
            if norm(n) > 0.0 {
                sum[el[k]] = add(sum[el[k]], unit(n));
            }
        }
    }
    sum.into_iter()
        .enumerate()
        .map(|(i, s)| {
            if norm(s) > 1e-12 {
                Ok(unit(s))
            } else {
                Err(FemError::InvalidMesh(format!(
                    "node {}: no normal can be defined (adjacent elements fold back on each other)",
                    id.node(i)
                )))
            }
        })
        .collect()
}
