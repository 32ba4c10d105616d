//! Meshes of 4-node quadrilaterals on a (possibly curved) mid-surface.
//!
//! A [`Mesh`] holds node positions (m), a unit director per node (the shell normal), the
//! elements (4 node indices, counter-clockwise seen from the directors' side), and named node
//! and element groups. [`Mesh::new`] validates everything an element needs: finite
//! coordinates, node indices in range, no unused node, consistent orientation, no degenerate or
//! inverted element.
//!
//! - [`structured`]: rectangular plates and doubly curved shallow shells over a rectangle.
//! - [`gmsh`]: Gmsh MSH 2.2 and 4.1 ASCII files.
//! - [`Locator`]: measurement points → nearest nodes, or points of the mid-surface with their
//!   shape-function weights ([`SurfacePoint`]).

pub mod gmsh;
mod locate;
pub mod structured;

pub use locate::{Locator, SurfacePoint};

use crate::element::{ElementDefect, Quad4Mitc};
use crate::error::FemError;
use crate::vec3::{V3, add, cross, norm, scale, sub, unit};
use std::collections::{BTreeMap, HashMap};

/// A quadrilateral shell mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    nodes: Vec<V3>,
    directors: Vec<V3>,
    elements: Vec<[usize; 4]>,
    node_groups: BTreeMap<String, Vec<usize>>,
    element_groups: BTreeMap<String, Vec<usize>>,
}

impl Mesh {
    /// A mesh from node positions (m) and elements. Directors are the normalised average of the
    /// adjacent elements' normals at each node.
    ///
    /// # Errors
    /// [`FemError::InvalidMesh`] naming the node or element: NaN coordinates, an index out of
    /// range, a node no element uses, a repeated node in an element, elements whose orientation
    /// disagrees with a neighbour's, a degenerate or inverted element.
    pub fn new(nodes: Vec<V3>, elements: Vec<[usize; 4]>) -> Result<Self, FemError> {
        check_nodes_and_connectivity(&nodes, &elements)?;
        check_orientation(&elements)?;
        let directors = averaged_normals(&nodes, &elements)?;
        Self::with_directors(nodes, directors, elements)
    }

    /// A mesh with given unit directors (e.g. the exact normals of an analytic surface).
    ///
    /// # Errors
    /// As [`Mesh::new`], and for directors that are not unit vectors.
    pub fn with_directors(
        nodes: Vec<V3>,
        directors: Vec<V3>,
        elements: Vec<[usize; 4]>,
    ) -> Result<Self, FemError> {
        check_nodes_and_connectivity(&nodes, &elements)?;
        check_orientation(&elements)?;
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
                    "node {i}: director {d:?} is not a unit vector"
                )));
            }
        }
        let mesh = Self {
            nodes,
            directors,
            elements,
            node_groups: BTreeMap::new(),
            element_groups: BTreeMap::new(),
        };
        for e in 0..mesh.elements.len() {
            // Geometry only: a unit thickness is enough to check the Jacobian's sign.
            let scale_len = mesh.element_size(e);
            mesh.element(e, 1e-3 * scale_len).check_geometry().map_err(|d| {
                let nodes = mesh.elements[e];
                FemError::InvalidMesh(match d {
                    ElementDefect::Degenerate { at } => format!(
                        "element {e} (nodes {nodes:?}) is degenerate (zero area near r = {}, s = {})",
                        at[0], at[1]
                    ),
                    ElementDefect::Inverted { at } => format!(
                        "element {e} (nodes {nodes:?}) is inverted (negative Jacobian near r = {}, s = {}): check the node order",
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
        if let Some(bad) = elements.iter().find(|&&e| e >= self.elements.len()) {
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
    /// Elements as node indices.
    pub fn elements(&self) -> &[[usize; 4]] {
        &self.elements
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

    /// The element `e` as a MITC4 element of thickness `thickness_m`.
    pub fn element(&self, e: usize, thickness_m: f64) -> Quad4Mitc {
        let n = self.elements[e];
        Quad4Mitc::new(
            n.map(|i| self.nodes[i]),
            n.map(|i| self.directors[i]),
            thickness_m,
        )
    }

    /// Longest edge of element `e`, m.
    fn element_size(&self, e: usize) -> f64 {
        let n = self.elements[e];
        (0..4)
            .map(|k| norm(sub(self.nodes[n[(k + 1) % 4]], self.nodes[n[k]])))
            .fold(0.0, f64::max)
    }

    /// Total area of the mid-surface (2×2 Gauss), m².
    pub fn area(&self) -> f64 {
        (0..self.elements.len()).map(|e| self.element_area(e)).sum()
    }

    fn element_area(&self, e: usize) -> f64 {
        let x = self.elements[e].map(|i| self.nodes[i]);
        let g = 0.577_350_269_189_625_8;
        let mut a = 0.0;
        for r in [-g, g] {
            for s in [-g, g] {
                let dr = scale(
                    0.25,
                    add(
                        add(scale(-(1.0 - s), x[0]), scale(1.0 - s, x[1])),
                        add(scale(1.0 + s, x[2]), scale(-(1.0 + s), x[3])),
                    ),
                );
                let ds = scale(
                    0.25,
                    add(
                        add(scale(-(1.0 - r), x[0]), scale(-(1.0 + r), x[1])),
                        add(scale(1.0 + r, x[2]), scale(1.0 - r, x[3])),
                    ),
                );
                a += norm(cross(dr, ds));
            }
        }
        a
    }
}

fn check_nodes_and_connectivity(nodes: &[V3], elements: &[[usize; 4]]) -> Result<(), FemError> {
    if nodes.is_empty() || elements.is_empty() {
        return Err(FemError::InvalidMesh(format!(
            "{} nodes and {} elements: nothing to mesh",
            nodes.len(),
            elements.len()
        )));
    }
    for (i, p) in nodes.iter().enumerate() {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(FemError::InvalidMesh(format!(
                "node {i} has a non-finite coordinate {p:?}"
            )));
        }
    }
    let mut used = vec![false; nodes.len()];
    for (e, el) in elements.iter().enumerate() {
        for &n in el {
            if n >= nodes.len() {
                return Err(FemError::InvalidMesh(format!(
                    "element {e} refers to node {n}, but there are {} nodes",
                    nodes.len()
                )));
            }
            used[n] = true;
        }
        for a in 0..4 {
            for b in a + 1..4 {
                if el[a] == el[b] {
                    return Err(FemError::InvalidMesh(format!(
                        "element {e} (nodes {el:?}) repeats node {}: degenerate",
                        el[a]
                    )));
                }
            }
        }
    }
    if let Some(n) = used.iter().position(|u| !u) {
        return Err(FemError::InvalidMesh(format!(
            "node {n} is not used by any element (a free node makes the stiffness singular)"
        )));
    }
    Ok(())
}

/// Neighbouring elements must run along their shared edge in opposite directions.
fn check_orientation(elements: &[[usize; 4]]) -> Result<(), FemError> {
    let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
    for (e, el) in elements.iter().enumerate() {
        for k in 0..4 {
            let (a, b) = (el[k], el[(k + 1) % 4]);
            if let Some(&other) = edges.get(&(a, b)) {
                return Err(FemError::InvalidMesh(format!(
                    "elements {other} and {e} run along edge {a}-{b} in the same direction: their orientations (normals) disagree"
                )));
            }
            edges.insert((a, b), e);
        }
    }
    Ok(())
}

/// Unit average of the adjacent elements' corner normals at each node.
fn averaged_normals(nodes: &[V3], elements: &[[usize; 4]]) -> Result<Vec<V3>, FemError> {
    let mut sum = vec![[0.0; 3]; nodes.len()];
    for el in elements {
        for k in 0..4 {
            let p = nodes[el[k]];
            let next = sub(nodes[el[(k + 1) % 4]], p);
            let prev = sub(nodes[el[(k + 3) % 4]], p);
            let n = cross(next, prev);
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
                    "node {i}: no normal can be defined (adjacent elements fold back on each other)"
                )))
            }
        })
        .collect()
}
