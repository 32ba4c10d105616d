//! Reader for Gmsh MSH files, ASCII versions 2.2 and 4.1, with 4-node or 9-node quadrilaterals.
//!
//! - 4-node quadrilaterals (type 3) become MITC4 elements, 9-node quadrilaterals (type 10,
//!   `Mesh.ElementOrder = 2`) MITC9 elements; one file holds one kind. 2D physical groups
//!   become element groups.
//! - Points and lines (types 15, 1, 8) are boundary entities: their physical groups become node
//!   groups, the elements themselves are dropped.
//! - Triangles and 8-node (serendipity) quadrilaterals are refused with the setting that fixes
//!   them (`Mesh.RecombineAll = 1`, `Mesh.SecondOrderIncomplete = 0`); volume elements are
//!   refused.
//! - Binary files are refused (`Mesh.Binary = 0` saves ASCII).
//!
//! Gmsh files carry no unit: coordinates are multiplied by `scale_to_m` (1 for metres,
//! 1e-3 for millimetres).

use super::{Mesh, Numbering};
use crate::element::ElementOrder;
use crate::error::FemError;
use crate::vec3::V3;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// Reads a Gmsh MSH file.
///
/// # Errors
/// [`FemError::MeshFile`] naming the file and line for unreadable files, unsupported versions or
/// element types, malformed numbers, counts that disagree with the data, and unknown node tags;
/// [`FemError::InvalidMesh`] when the mesh itself is unusable.
pub fn read_msh(path: &Path, scale_to_m: f64) -> Result<Mesh, FemError> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| FemError::MeshFile {
        path: name.clone(),
        line: 0,
        reason: e.to_string(),
    })?;
    let text = String::from_utf8_lossy(&bytes);
    parse_msh(&name, &text, scale_to_m)
}

/// Parses the text of an MSH file; `name` is used in errors.
///
/// # Errors
/// As [`read_msh`].
pub fn parse_msh(name: &str, text: &str, scale_to_m: f64) -> Result<Mesh, FemError> {
    let mut r = Reader {
        name,
        lines: text.lines().enumerate().peekable(),
        line: 0,
    };
    let mut version = None;
    let mut physical_names: HashMap<(usize, i64), String> = HashMap::new();
    let mut raw = RawMesh::default();
    let mut entity_physicals: HashMap<(usize, i64), Vec<i64>> = HashMap::new();
    while let Some(section) = r.next_section()? {
        match section.as_str() {
            "$MeshFormat" => version = Some(r.mesh_format()?),
            "$PhysicalNames" => physical_names = r.physical_names()?,
            "$Entities" => entity_physicals = r.entities()?,
            "$Nodes" => match version {
                Some(Version::V2) => r.nodes_v2(&mut raw, scale_to_m)?,
                Some(Version::V4) => r.nodes_v4(&mut raw, scale_to_m)?,
                None => return Err(r.err("$Nodes before $MeshFormat")),
            },
            "$Elements" => match version {
                Some(Version::V2) => r.elements_v2(&mut raw)?,
                Some(Version::V4) => r.elements_v4(&mut raw, &entity_physicals)?,
                None => return Err(r.err("$Elements before $MeshFormat")),
            },
            other => r.skip_section(other)?,
        }
    }
    if version.is_none() {
        return Err(FemError::MeshFile {
            path: name.into(),
            line: 0,
            reason: "no $MeshFormat section: not a Gmsh MSH file".into(),
        });
    }
    raw.into_mesh(name, &physical_names)
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Version {
    V2,
    V4,
}

/// Elements read from the file, before conversion to a [`Mesh`].
#[derive(Debug, Default)]
struct RawMesh {
    node_tags: HashMap<i64, usize>,
    nodes: Vec<V3>,
    /// The 4-node or 9-node quadrilaterals.
    quads: Vec<RawQuad>,
    /// (dimension, node tags, physical tags)
    boundary: Vec<(usize, Vec<i64>, Vec<i64>)>,
}

/// A quadrilateral as the file gives it.
#[derive(Debug)]
struct RawQuad {
    /// The element's tag (its number in the file).
    tag: i64,
    /// Node tags.
    nodes: Vec<i64>,
    /// Physical tags.
    physicals: Vec<i64>,
    /// Line in the file (1-based).
    line: usize,
}

/// What is wrong with one node or element of a Gmsh file (the reader adds the file and line).
#[derive(Debug, Clone, Copy, PartialEq)]
enum EntityError {
    /// A node tag given twice.
    NodeTwice { tag: i64 },
    /// Quadrilaterals of another order than the first ones (at `first_line`).
    MixedOrder {
        nodes: usize,
        first: usize,
        first_line: usize,
    },
    /// Triangles.
    Triangles,
    /// 8-node quadrilaterals.
    Serendipity,
    /// A volume element.
    Volume { etype: i64 },
    /// Another element type.
    Unsupported { etype: i64 },
    /// An element with the wrong number of nodes for its type.
    NodeCount { etype: i64, want: usize, got: usize },
}

impl std::fmt::Display for EntityError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Self::NodeTwice { tag } => write!(f, "node tag {tag} appears twice"),
            Self::MixedOrder {
                nodes,
                first,
                first_line,
            } => write!(
                f,
                "a {nodes}-node quadrilateral after {first}-node ones (line {first_line}): one \
                 file must hold one element order"
            ),
            Self::Triangles => f.write_str(
                "triangles are not supported: recombine the mesh into quadrilaterals \
                 (Mesh.RecombineAll = 1)",
            ),
            Self::Serendipity => f.write_str(
                "8-node (serendipity) quadrilaterals are not supported: mesh with \
                 Mesh.SecondOrderIncomplete = 0 for 9-node ones",
            ),
            Self::Volume { etype } => write!(
                f,
                "volume element type {etype}: lamdyn meshes shells (2D quadrilaterals) only"
            ),
            Self::Unsupported { etype } => write!(f, "unsupported element type {etype}"),
            Self::NodeCount { etype, want, got } => {
                write!(f, "element type {etype} needs {want} nodes, got {got}")
            }
        }
    }
}

impl RawMesh {
    fn add_node(&mut self, tag: i64, p: V3) -> Result<(), EntityError> {
        if self.node_tags.insert(tag, self.nodes.len()).is_some() {
            return Err(EntityError::NodeTwice { tag });
        }
        self.nodes.push(p);
        Ok(())
    }

    fn add_element(
        &mut self,
        (tag, etype): (i64, i64),
        nodes: Vec<i64>,
        physicals: Vec<i64>,
        line: usize,
    ) -> Result<(), EntityError> {
        match etype {
            3 | 10 => {
                if let Some(first) = self.quads.first()
                    && first.nodes.len() != nodes.len()
                {
                    return Err(EntityError::MixedOrder {
                        nodes: nodes.len(),
                        first: first.nodes.len(),
                        first_line: first.line,
                    });
                }
                self.quads.push(RawQuad {
                    tag,
                    nodes,
                    physicals,
                    line,
                });
            }
            15 => self.boundary.push((0, nodes, physicals)),
            1 | 8 => self.boundary.push((1, nodes, physicals)),
            2 | 9 => return Err(EntityError::Triangles),
            16 => return Err(EntityError::Serendipity),
            4..=7 | 11..=14 | 17..=19 => return Err(EntityError::Volume { etype }),
            t => return Err(EntityError::Unsupported { etype: t }),
        }
        Ok(())
    }

    fn into_mesh(
        self,
        name: &str,
        physical_names: &HashMap<(usize, i64), String>,
    ) -> Result<Mesh, FemError> {
        let index = |tag: i64, line: usize| {
            self.node_tags
                .get(&tag)
                .copied()
                .ok_or_else(|| FemError::MeshFile {
                    path: name.into(),
                    line,
                    reason: format!("element refers to node tag {tag}, which is not in $Nodes"),
                })
        };
        let mut connectivity = Vec::with_capacity(9 * self.quads.len());
        let mut element_groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        for (e, quad) in self.quads.iter().enumerate() {
            for tag in &quad.nodes {
                connectivity.push(index(*tag, quad.line)?);
            }
            for p in &quad.physicals {
                element_groups
                    .entry(group_name(physical_names, 2, *p))
                    .or_default()
                    .push(e);
            }
        }
        let order = match self.quads.first() {
            Some(q) if q.nodes.len() == 9 => ElementOrder::Quadratic,
            Some(_) => ElementOrder::Linear,
            None => {
                return Err(FemError::MeshFile {
                    path: name.into(),
                    line: 0,
                    reason: "no 4-node or 9-node quadrilaterals (element types 3, 10) in the file"
                        .into(),
                });
            }
        };
        let mut node_groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        for (dim, nodes, phys) in &self.boundary {
            for p in phys {
                let group = node_groups
                    .entry(group_name(physical_names, *dim, *p))
                    .or_default();
                for tag in nodes {
                    group.push(index(*tag, 0)?);
                }
            }
        }
        let mut node_ids = vec![0; self.nodes.len()];
        for (&tag, &k) in &self.node_tags {
            node_ids[k] = tag;
        }
        let numbering = Numbering {
            node_ids,
            element_ids: self.quads.iter().map(|q| q.tag).collect(),
            element_lines: self.quads.iter().map(|q| q.line).collect(),
        };
        let mut mesh = Mesh::of_order_numbered(order, self.nodes, None, connectivity, &numbering)
            .map_err(|e| match e {
            FemError::InvalidMesh(m) => FemError::InvalidMesh(format!(
                "'{name}': {m} (nodes and elements by the file's tags)"
            )),
            other => other,
        })?;
        for (g, mut nodes) in node_groups {
            nodes.sort_unstable();
            nodes.dedup();
            mesh.add_node_group(&g, nodes)?;
        }
        for (g, els) in element_groups {
            mesh.add_element_group(&g, els)?;
        }
        Ok(mesh)
    }
}

fn group_name(names: &HashMap<(usize, i64), String>, dim: usize, tag: i64) -> String {
    names
        .get(&(dim, tag))
        .cloned()
        .unwrap_or_else(|| format!("physical {dim}:{tag}"))
}

struct Reader<'a, I: Iterator<Item = (usize, &'a str)>> {
    name: &'a str,
    lines: std::iter::Peekable<I>,
    line: usize,
}

impl<'a, I: Iterator<Item = (usize, &'a str)>> Reader<'a, I> {
    fn err(&self, reason: impl Into<String>) -> FemError {
        FemError::MeshFile {
            path: self.name.into(),
            line: self.line,
            reason: reason.into(),
        }
    }

    /// The next non-empty line, trimmed.
    fn next_line(&mut self) -> Result<&'a str, FemError> {
        for (i, l) in self.lines.by_ref() {
            self.line = i + 1;
            let t = l.trim();
            if !t.is_empty() {
                return Ok(t);
            }
        }
        Err(FemError::MeshFile {
            path: self.name.into(),
            line: self.line,
            reason: "unexpected end of file".into(),
        })
    }

    fn next_section(&mut self) -> Result<Option<String>, FemError> {
        loop {
            match self.lines.next() {
                None => return Ok(None),
                Some((i, l)) => {
                    self.line = i + 1;
                    let t = l.trim();
                    if t.is_empty() {
                        continue;
                    }
                    if !t.starts_with('$') {
                        return Err(self.err(format!(
                            "expected a section such as $Nodes, got '{}'",
                            truncate(t)
                        )));
                    }
                    return Ok(Some(t.to_string()));
                }
            }
        }
    }

    fn expect_end(&mut self, section: &str) -> Result<(), FemError> {
        let end = format!("$End{}", &section[1..]);
        let l = self.next_line()?;
        if l != end {
            return Err(self.err(format!(
                "expected {end}, got '{}' (a count in {section} disagrees with the data?)",
                truncate(l)
            )));
        }
        Ok(())
    }

    fn skip_section(&mut self, section: &str) -> Result<(), FemError> {
        let end = format!("$End{}", &section[1..]);
        loop {
            if self.next_line()? == end {
                return Ok(());
            }
        }
    }

    fn numbers<T: std::str::FromStr>(&mut self, what: &str) -> Result<Vec<T>, FemError> {
        let l = self.next_line()?;
        l.split_whitespace()
            .map(|w| {
                w.parse::<T>().map_err(|_| {
                    self.err(format!("{what}: '{}' is not a valid number", truncate(w)))
                })
            })
            .collect()
    }

    fn mesh_format(&mut self) -> Result<Version, FemError> {
        let l = self.next_line()?;
        let f: Vec<&str> = l.split_whitespace().collect();
        if f.len() < 3 {
            return Err(self.err(format!(
                "$MeshFormat: expected 'version file-type data-size', got '{}'",
                truncate(l)
            )));
        }
        if f[1] != "0" {
            return Err(
                self.err("binary MSH files are not supported: save as ASCII (Mesh.Binary = 0)")
            );
        }
        let v = match f[0] {
            "2.2" | "2.1" | "2" => Version::V2,
            "4.1" => Version::V4,
            other => {
                return Err(self.err(format!(
                    "MSH version {other} is not supported: save as \
                     version 4.1 or 2.2 (Mesh.MshFileVersion)"
                )));
            }
        };
        self.expect_end("$MeshFormat")?;
        Ok(v)
    }

    fn physical_names(&mut self) -> Result<HashMap<(usize, i64), String>, FemError> {
        let n = self.count("$PhysicalNames")?;
        let mut out = HashMap::new();
        for _ in 0..n {
            let l = self.next_line()?;
            let mut it = l.splitn(3, char::is_whitespace);
            let dim = it.next().and_then(|w| w.parse::<usize>().ok());
            let tag = it.next().and_then(|w| w.parse::<i64>().ok());
            let name = it.next().map(|w| w.trim().trim_matches('"').to_string());
            match (dim, tag, name) {
                (Some(d), Some(t), Some(nm)) => {
                    out.insert((d, t), nm);
                }
                _ => {
                    return Err(self.err(format!(
                        "$PhysicalNames: expected 'dim tag \"name\"', got '{}'",
                        truncate(l)
                    )));
                }
            }
        }
        self.expect_end("$PhysicalNames")?;
        Ok(out)
    }

    fn count(&mut self, section: &str) -> Result<usize, FemError> {
        let v: Vec<usize> = self.numbers(section)?;
        v.first()
            .copied()
            .ok_or_else(|| self.err(format!("{section}: missing count")))
    }

    /// MSH 4.1 $Entities: physical tags of each (dim, entity tag).
    fn entities(&mut self) -> Result<HashMap<(usize, i64), Vec<i64>>, FemError> {
        let counts: Vec<usize> = self.numbers("$Entities counts")?;
        if counts.len() != 4 {
            return Err(self.err("$Entities: expected 4 counts (points curves surfaces volumes)"));
        }
        let mut out = HashMap::new();
        for (dim, &n) in counts.iter().enumerate() {
            for _ in 0..n {
                let v: Vec<f64> = self.numbers("$Entities")?;
                // points: tag x y z nphys phys...; others: tag 6 bbox nphys phys... nbound bound...
                let first = if dim == 0 { 4 } else { 7 };
                let ok = v.len() > first && v.len() > first + v[first] as usize;
                if !ok {
                    return Err(self.err(format!(
                        "$Entities: malformed {}-dimensional entity line",
                        dim
                    )));
                }
                let np = v[first] as usize;
                out.insert(
                    (dim, v[0] as i64),
                    v[first + 1..first + 1 + np]
                        .iter()
                        .map(|x| *x as i64)
                        .collect(),
                );
            }
        }
        self.expect_end("$Entities")?;
        Ok(out)
    }

    fn nodes_v2(&mut self, raw: &mut RawMesh, scale: f64) -> Result<(), FemError> {
        let n = self.count("$Nodes")?;
        for _ in 0..n {
            let v: Vec<f64> = self.numbers("$Nodes")?;
            if v.len() != 4 {
                return Err(self.err(format!(
                    "$Nodes: expected 'tag x y z', got {} values",
                    v.len()
                )));
            }
            raw.add_node(v[0] as i64, [v[1] * scale, v[2] * scale, v[3] * scale])
                .map_err(|m| self.err(m.to_string()))?;
        }
        self.expect_end("$Nodes")
    }

    fn nodes_v4(&mut self, raw: &mut RawMesh, scale: f64) -> Result<(), FemError> {
        let head: Vec<usize> = self.numbers("$Nodes header")?;
        if head.len() != 4 {
            return Err(
                self.err("$Nodes: expected 'numEntityBlocks numNodes minNodeTag maxNodeTag'")
            );
        }
        let mut total = 0;
        for _ in 0..head[0] {
            let b: Vec<usize> = self.numbers("$Nodes block")?;
            if b.len() != 4 {
                return Err(
                    self.err("$Nodes: expected 'entityDim entityTag parametric numNodesInBlock'")
                );
            }
            let (parametric, count) = (b[2] == 1, b[3]);
            let mut tags = Vec::with_capacity(count);
            for _ in 0..count {
                let t: Vec<i64> = self.numbers("$Nodes tag")?;
                if t.len() != 1 {
                    return Err(self.err("$Nodes: expected one node tag per line"));
                }
                tags.push(t[0]);
            }
            for tag in tags {
                let v: Vec<f64> = self.numbers("$Nodes coordinates")?;
                let want = if parametric { 3 + b[0] } else { 3 };
                if v.len() != want {
                    return Err(self.err(format!(
                        "$Nodes: expected {want} coordinates, got {}",
                        v.len()
                    )));
                }
                raw.add_node(tag, [v[0] * scale, v[1] * scale, v[2] * scale])
                    .map_err(|m| self.err(m.to_string()))?;
            }
            total += count;
        }
        if total != head[1] {
            return Err(self.err(format!(
                "$Nodes: header announces {} nodes, blocks hold {total}",
                head[1]
            )));
        }
        self.expect_end("$Nodes")
    }

    fn elements_v2(&mut self, raw: &mut RawMesh) -> Result<(), FemError> {
        let n = self.count("$Elements")?;
        for _ in 0..n {
            let v: Vec<i64> = self.numbers("$Elements")?;
            if v.len() < 3 || v.len() < 3 + v[2].max(0) as usize {
                return Err(self.err("$Elements: expected 'tag type ntags tags... nodes...'"));
            }
            let (etype, ntags) = (v[1], v[2] as usize);
            let nodes = v[3 + ntags..].to_vec();
            check_node_count(etype, nodes.len()).map_err(|m| self.err(m.to_string()))?;
            let physical = if ntags > 0 && v[3] != 0 {
                vec![v[3]]
            } else {
                vec![]
            };
            let line = self.line;
            raw.add_element((v[0], etype), nodes, physical, line)
                .map_err(|m| self.err(format!("element {}: {m}", v[0])))?;
        }
        self.expect_end("$Elements")
    }

    fn elements_v4(
        &mut self,
        raw: &mut RawMesh,
        physicals: &HashMap<(usize, i64), Vec<i64>>,
    ) -> Result<(), FemError> {
        let head: Vec<usize> = self.numbers("$Elements header")?;
        if head.len() != 4 {
            return Err(self.err("$Elements: expected 'numEntityBlocks numElements minTag maxTag'"));
        }
        let mut total = 0;
        for _ in 0..head[0] {
            let b: Vec<i64> = self.numbers("$Elements block")?;
            if b.len() != 4 {
                return Err(self.err(
                    "$Elements: expected 'entityDim entityTag elementType numElementsInBlock'",
                ));
            }
            let (dim, entity, etype, count) = (b[0] as usize, b[1], b[2], b[3] as usize);
            let phys = physicals.get(&(dim, entity)).cloned().unwrap_or_default();
            for _ in 0..count {
                let v: Vec<i64> = self.numbers("$Elements")?;
                if v.is_empty() {
                    return Err(self.err("$Elements: empty element line"));
                }
                check_node_count(etype, v.len() - 1).map_err(|m| self.err(m.to_string()))?;
                let line = self.line;
                raw.add_element((v[0], etype), v[1..].to_vec(), phys.clone(), line)
                    .map_err(|m| self.err(format!("element {}: {m}", v[0])))?;
            }
            total += count;
        }
        if total != head[1] {
            return Err(self.err(format!(
                "$Elements: header announces {} elements, blocks hold {total}",
                head[1]
            )));
        }
        self.expect_end("$Elements")
    }
}

fn check_node_count(etype: i64, n: usize) -> Result<(), EntityError> {
    let want = match etype {
        15 => 1,
        1 => 2,
        8 => 3,
        2 => 3,
        3 => 4,
        10 => 9,
        _ => return Ok(()),
    };
    if n != want {
        return Err(EntityError::NodeCount {
            etype,
            want,
            got: n,
        });
    }
    Ok(())
}

/// A piece of a line as an error quotes it: at most 60 characters, control characters, quotes
/// and backslashes escaped (a binary file must not reach the terminal raw), a cut marked "...".
fn truncate(s: &str) -> String {
    const QUOTED: usize = 60;
    let mut out = String::new();
    for c in s.chars().take(QUOTED) {
        if c.is_control() || c == '\'' || c == '\\' {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    if s.chars().nth(QUOTED).is_some() {
        out.push_str("...");
    }
    out
}
