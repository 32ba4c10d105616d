//! Discretization error of the natural frequencies, estimated per mode by Richardson
//! extrapolation over nested meshes, and refinement until a tolerance is met.
//!
//! [`converge_modes`] solves the model on the user's mesh split m × m for m = 1, 2, 3, …
//! ([`Mesh::subdivided`]: every node of a coarser mesh is a node of the finer ones, the element
//! size is h_m = h/m). Modes are matched across levels by MAC of their translations at the
//! coarse mesh's nodes, so that a pair whose order swaps between meshes is not mixed up.
//! With the frequencies f₁, f₂, f₃ of one mode on the last three levels and the model
//! f(h) = f∞ + C hᵖ, the observed order p solves
//!
//! (f₁ − f₂) / (f₂ − f₃) = (h₁ᵖ − h₂ᵖ) / (h₂ᵖ − h₃ᵖ)
//!
//! (bisection; for a constant ratio h₁/h₂ = h₂/h₃ = ρ it is p = ln((f₁ − f₂)/(f₂ − f₃)) / ln ρ,
//! Roache's generalised Richardson extrapolation). The p used is the observed one kept within
//! [0.5, p_nominal], p_nominal = 2k for elements of degree k (2 for MITC4, 4 for MITC9: the
//! eigenvalue error of a conforming degree-k discretization), so a lucky cancellation cannot
//! claim more than the element can give. The estimated error of the finest frequency is
//! |C| h₃ᵖ / f₃. Where the differences change sign or do not shrink, the mesh is not in the
//! asymptotic range: p = 1 is assumed and the error is at least |f₂ − f₃|. With two levels only,
//! p = 1 is assumed (the rate of MITC4 on uniform meshes of a free edge).
//!
//! The reported error is Roache's grid convergence index: the estimate times a factor of
//! safety, 1.25 with an observed order, 3 without (two levels, or not asymptotic). Measured on
//! the flat paper plate against its Reissner–Mindlin reference (tests/it/convergence.rs), the
//! bare three-level estimate of MITC9 with edge layers was within 5 % of the true error on
//! either side, so the 1.25 matters.
//!
//! No refinement of a mesh sees what it never resolves: a Reissner–Mindlin shell's free edges
//! carry a boundary layer about δ = t/√10 wide (t/√(12κ), κ = 5/6), and while the outermost
//! elements are much wider than δ, successive meshes converge towards the Kirchhoff answer,
//! up to 2e-3 off for the paper's plate, and the extrapolation follows them. So the result
//! also checks the outermost elements of the finest mesh: wider than δ (MITC4) or 2δ (MITC9,
//! two node intervals per element), it is not converged, whatever the estimates say, and
//! [`Convergence::warnings`] says which edge width against which δ.
//!
//! [`ConvergeParams::tolerance`] is a relative frequency error; refinement stops when every
//! wanted elastic mode meets it on three levels, or at the dof or level cap, reporting how far
//! it got, or as soon as the tolerance is seen to be out of reach within those caps: before
//! any solve when the finest allowed mesh leaves the free edges unresolved, and from the third
//! level on when an error shrunk at the element's nominal order (the most it can give) down to
//! the finest allowed mesh still misses it ([`Reach`]). Tolerances below [`MIN_TOLERANCE`] are
//! refused: the eigenvalues themselves are resolved to about 1e-10 relative (the Lanczos Ritz
//! tolerance), and the differences between levels lose further digits.

use crate::assembly::{Assembly, NodeSpring};
use crate::eigen::{ModalParams, Progress, solve_modes};
use crate::element::{ElementOrder, ShellMaterial};
use crate::error::FemError;
use crate::mesh::refine::Surface;
use crate::mesh::{Locator, Mesh};
use crate::output::mac;
use serde::Serialize;
use std::time::Instant;

/// Factor of safety of the grid convergence index with an observed order (Roache).
pub const SAFETY_OBSERVED: f64 = 1.25;
/// Factor of safety with an assumed order (two levels, or not in the asymptotic range).
pub const SAFETY_ASSUMED: f64 = 3.0;

/// Smallest accepted relative frequency tolerance (see the module's text).
pub const MIN_TOLERANCE: f64 = 1e-9;

/// Settings of [`converge_modes`].
#[derive(Debug, Clone, Copy)]
pub struct ConvergeParams {
    /// Lowest modes wanted, rigid-body modes included (the tolerance applies to the elastic
    /// ones among them).
    pub modes: usize,
    /// Relative frequency error every wanted elastic mode must meet.
    pub tolerance: f64,
    /// Largest model solved, dofs.
    pub max_dofs: usize,
    /// Largest subdivision m (levels m = 1..=max_levels).
    pub max_levels: usize,
    /// Stop as soon as the tolerance is seen to be out of reach within the limits (see
    /// [`converge_modes`]); false for a study that wants every level regardless.
    pub stop_when_out_of_reach: bool,
}

impl ConvergeParams {
    /// `modes` lowest modes to `tolerance`, up to 600 000 dofs and 6 levels, stopping when
    /// the tolerance is out of reach.
    pub fn new(modes: usize, tolerance: f64) -> Self {
        Self {
            modes,
            tolerance,
            max_dofs: 600_000,
            max_levels: 6,
            stop_when_out_of_reach: true,
        }
    }

    fn validate(&self) -> Result<(), FemError> {
        let bad = |field: &str, value: String, requirement: String| FemError::InvalidParameter {
            context: "convergence".into(),
            field: field.into(),
            value,
            requirement,
        };
        if !(self.tolerance.is_finite() && self.tolerance < 0.1) {
            return Err(bad(
                "tolerance",
                format!("{}", self.tolerance),
                "must be a relative frequency error below 0.1 (e.g. 1e-4)".into(),
            ));
        }
        if self.tolerance < MIN_TOLERANCE {
            return Err(bad(
                "tolerance",
                format!("{:e}", self.tolerance),
                format!(
                    "is below what double precision allows: the eigensolver resolves frequencies \
                     to about 1e-10 relative and the differences between meshes lose more; use at \
                     least {MIN_TOLERANCE:e}"
                ),
            ));
        }
        if self.modes == 0 {
            return Err(bad("modes", "0".into(), "must be at least 1".into()));
        }
        if self.max_levels < 2 {
            return Err(bad(
                "max_levels",
                self.max_levels.to_string(),
                "must be at least 2 (an estimate needs two meshes)".into(),
            ));
        }
        Ok(())
    }
}

/// One mesh of the sequence.
#[derive(Debug, Clone, Serialize)]
pub struct Level {
    /// Each element of the user's mesh split into m × m.
    pub subdivisions: usize,
    /// Dofs.
    pub n_dofs: usize,
    /// Wall time of assembly and modal solve, s.
    pub seconds: f64,
    /// Frequencies of the finest level's modes, matched on this level, Hz.
    pub freqs_hz: Vec<f64>,
    /// MAC of each match (translations at the user's mesh's nodes).
    pub mac: Vec<f64>,
    /// Index of each match among this level's modes (`usize::MAX`: none).
    pub matched: Vec<usize>,
}

/// One mode's estimate.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ModeEstimate {
    /// Frequency on the finest level, Hz.
    pub freq_hz: f64,
    /// Richardson-extrapolated frequency, Hz.
    pub extrapolated_hz: f64,
    /// Estimated relative error of `freq_hz`: the grid convergence index (0 for rigid-body
    /// modes).
    pub error: f64,
    /// Observed order of convergence (three levels with shrinking, same-sign differences).
    pub order: Option<f64>,
    /// A rigid-body mode.
    pub rigid: bool,
}

/// The result of [`converge_modes`].
#[derive(Debug, Clone, Serialize)]
pub struct Convergence {
    /// The meshes solved, coarsest first.
    pub levels: Vec<Level>,
    /// Per mode (lowest first, rigid included): the finest frequency and its error.
    pub modes: Vec<ModeEstimate>,
    /// The tolerance asked for.
    pub tolerance: f64,
    /// Every wanted elastic mode met the tolerance with three levels, and the free edges were
    /// resolved.
    pub converged: bool,
    /// Why refinement stopped.
    pub stopped: String,
    /// What makes the estimates doubtful (unresolved free edges).
    pub warnings: Vec<String>,
}

impl Convergence {
    /// Signed relative discretization error of each of the first `n_modes` modes of level
    /// `level` (0: the user's mesh), in that level's own mode order:
    /// δ = (f_level − f∞)/f∞ from the extrapolated f∞, its magnitude increased by the finest
    /// mesh's estimate (the uncertainty of f∞ itself). Rigid modes get 0. A mode the estimate
    /// does not cover (beyond the wanted ones) gets the largest magnitude of the modes below it,
    /// positive (meshes are too stiff).
    pub fn errors_of_level(&self, level: usize, n_modes: usize) -> Vec<f64> {
        let mut out = vec![f64::NAN; n_modes];
        let Some(l) = self.levels.get(level) else {
            return out;
        };
        for (j, m) in self.modes.iter().enumerate() {
            let k = l.matched[j];
            if k >= n_modes {
                continue;
            }
            out[k] = if m.rigid {
                0.0
            } else {
                let d = l.freqs_hz[j] / m.extrapolated_hz - 1.0;
                d.signum() * (d.abs() + m.error)
            };
        }
        let mut largest: f64 = 0.0;
        for d in &mut out {
            if d.is_nan() {
                *d = largest;
            } else {
                largest = largest.max(d.abs());
            }
        }
        out
    }

    /// The largest estimated error over the elastic modes, and which mode (0-based).
    pub fn worst(&self) -> Option<(usize, f64)> {
        self.modes
            .iter()
            .enumerate()
            .filter(|(_, m)| !m.rigid)
            .map(|(j, m)| (j, m.error))
            .fold(None, |a, b| match a {
                Some(a) if a.1 >= b.1 => Some(a),
                _ => Some(b),
            })
    }
}

/// Solves the model on the mesh split 1×1, 2×2, 3×3, … and estimates each mode's
/// discretization error (see the module's text), until the tolerance is met or a cap is
/// reached. `surface` places new nodes on the exact mid-surface (the rectangle generator's
/// dome); supports stay at their nodes, which every level keeps.
///
/// With [`ConvergeParams::stop_when_out_of_reach`], the tolerance's reach is judged twice
/// before the expensive levels ([`Reach`]): before any solve, the finest mesh the caps allow
/// must resolve the free edges' boundary layer (else no level can be called converged); from
/// the third level on, each mode's bare error (the estimate without its factor of safety) is
/// projected to the finest allowed mesh at the element's nominal order, the most the element
/// can give, and refinement stops when some mode would still miss the tolerance.
///
/// # Errors
/// [`FemError::InvalidParameter`] for a tolerance outside [[`MIN_TOLERANCE`], 0.1), no modes or
/// fewer than two levels, or (when stopping out of reach) free edges that the finest allowed
/// mesh cannot resolve; the first level's assembly or solve errors. A cap reached after two
/// levels is not an error: the result says how far it got.
pub fn converge_modes(
    mesh: &Mesh,
    surface: Option<Surface<'_>>,
    material: &ShellMaterial,
    springs: &[NodeSpring],
    params: &ConvergeParams,
    progress: &dyn Progress,
) -> Result<Convergence, FemError> {
    params.validate()?;
    let reach = Reach::of(mesh, params);
    if params.stop_when_out_of_reach
        && let Some(edges) = EdgeLayer::unresolved(mesh, material, reach.subdivisions)
    {
        return Err(FemError::InvalidParameter {
            context: "convergence".into(),
            field: "tolerance".into(),
            value: format!("{:e}", params.tolerance),
            requirement: format!(
                "cannot be met within the limits: on the finest mesh they allow ({}x{}, {} dofs; \
                 {}) {}",
                reach.subdivisions,
                reach.subdivisions,
                reach.n_dofs,
                reach.limit,
                edges.describe()
            ) + ": grade the mesh towards its free edges (edge layers)",
        });
    }
    let coarse = mesh.nodes().to_vec();
    let nominal = nominal_order(mesh.order());
    let mut solved: Vec<Solved> = Vec::new();
    let mut stopped = reach.limit.clone();
    let mut result = None;
    for m in 1..=reach.subdivisions {
        let refined = if m == 1 {
            mesh.clone()
        } else {
            mesh.subdivided(m, surface)?
        };
        progress.stage(&format!("mesh {m}x{m}: {} dofs", refined.n_dofs()));
        solved.push(solve_level(
            &refined, m, &coarse, material, springs, params,
        )?);
        let estimate = estimate(&solved, params.modes, nominal);
        let met = solved.len() >= 3
            && estimate
                .modes
                .iter()
                .all(|e| e.rigid || e.error <= params.tolerance);
        let out_of_reach = (params.stop_when_out_of_reach && !met && solved.len() >= 3)
            .then(|| reach.shortfall(&estimate.modes, m, nominal, params.tolerance))
            .flatten();
        result = Some(estimate);
        if met {
            stopped = "tolerance met".into();
            break;
        }
        if let Some(why) = out_of_reach {
            stopped = why;
            break;
        }
    }
    let Some((levels, modes)) = result.map(|e| (e.levels, e.modes)) else {
        return Err(FemError::InvalidParameter {
            context: "convergence".into(),
            field: "max_dofs".into(),
            value: params.max_dofs.to_string(),
            requirement: "leaves no mesh to solve".into(),
        });
    };
    let finest = levels.last().map_or(1, |l| l.subdivisions);
    let warnings: Vec<String> = EdgeLayer::unresolved(mesh, material, finest)
        .map(|edges| {
            format!(
                "free edges unresolved: {}; the estimates cannot see it (up to a few \
                 1e-3 in frequency): use edge layers or a mesh graded towards the \
                 edges",
                edges.describe()
            )
        })
        .into_iter()
        .collect();
    let converged = levels.len() >= 3
        && warnings.is_empty()
        && modes.iter().all(|e| e.rigid || e.error <= params.tolerance);
    Ok(Convergence {
        levels,
        modes,
        tolerance: params.tolerance,
        converged,
        stopped,
        warnings,
    })
}

/// How far above the tolerance a projected error must lie before refinement stops: the
/// projection is an estimate, not a bound (docs/fem.md gives the measurement behind the
/// factor), so only a clear miss stops the run.
pub const OUT_OF_REACH_MARGIN: f64 = 2.0;

/// p_nominal: the eigenvalue error's order of a conforming degree-k element, 2k.
fn nominal_order(order: ElementOrder) -> f64 {
    2.0 * order.degree() as f64
}

/// The finest subdivision the caps allow, known before any solve: the level cap, the dof cap
/// (dofs counted from the mesh's topology, [`subdivided_dofs`]) and the memory a modal solve
/// needs.
#[derive(Debug, Clone)]
pub struct Reach {
    /// Largest m whose m × m subdivision is allowed (at least 1).
    pub subdivisions: usize,
    /// Its dofs.
    pub n_dofs: usize,
    /// Which limit stops the refinement there, in words.
    pub limit: String,
}

impl Reach {
    /// The reach of `mesh` under `params`' caps.
    pub fn of(mesh: &Mesh, params: &ConvergeParams) -> Self {
        let mut reach = Reach {
            subdivisions: 1,
            n_dofs: mesh.n_dofs(),
            limit: format!("level cap ({} subdivisions)", params.max_levels),
        };
        let topology = Topology::of(mesh);
        for m in 2..=params.max_levels.min(64) {
            let n_dofs = topology.subdivided_dofs(m);
            if n_dofs > params.max_dofs {
                reach.limit = format!(
                    "dof cap: {m}x{m} subdivision would have {n_dofs} dofs, more than {}",
                    params.max_dofs
                );
                break;
            }
            if let Err(e) = crate::memory::check_modal_memory(n_dofs) {
                reach.limit = format!("memory: {e}");
                break;
            }
            reach.subdivisions = m;
            reach.n_dofs = n_dofs;
        }
        reach
    }

    /// Why the tolerance is out of reach after level `m`, if it is: some elastic mode's bare
    /// error (its estimate over the factor of safety it carries), shrunk at the `nominal`
    /// order down to the finest allowed mesh and given the smaller factor of safety
    /// ([`SAFETY_OBSERVED`]), still exceeds [`OUT_OF_REACH_MARGIN`] × `tolerance`. None where
    /// level `m` is already the finest allowed (the caps say why it stops).
    fn shortfall(
        &self,
        modes: &[ModeEstimate],
        m: usize,
        nominal: f64,
        tolerance: f64,
    ) -> Option<String> {
        if m >= self.subdivisions {
            return None;
        }
        let shrink = (m as f64 / self.subdivisions as f64).powf(nominal);
        let (j, best) = modes
            .iter()
            .enumerate()
            .filter(|(_, e)| !e.rigid && e.error.is_finite())
            .map(|(j, e)| {
                let safety = if e.order.is_some() {
                    SAFETY_OBSERVED
                } else {
                    SAFETY_ASSUMED
                };
                (j, e.error / safety * shrink * SAFETY_OBSERVED)
            })
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        (best > OUT_OF_REACH_MARGIN * tolerance).then(|| {
            let needed = m as f64 * (modes[j].error / tolerance).powf(1.0 / nominal);
            format!(
                "out of reach: mode {}'s error {:.2e} on {m}x{m} would be about {best:.2e} on the \
                 finest mesh the limits allow ({}x{}, {} dofs; {}), at the element's nominal order \
                 {nominal}; about {}x{} subdivisions would be needed",
                j + 1,
                modes[j].error,
                self.subdivisions,
                self.subdivisions,
                self.n_dofs,
                self.limit,
                needed.ceil(),
                needed.ceil()
            )
        })
    }
}

/// The dofs of `mesh.subdivided(m, _)` from the topology alone, without building it: the
/// distinct corners, (n − 1) new nodes per distinct edge and (n − 1)² per element, with
/// n = q·m grid steps per element side (q = 1 for MITC4, 2 for MITC9); six dofs per node.
pub fn subdivided_dofs(mesh: &Mesh, m: usize) -> usize {
    Topology::of(mesh).subdivided_dofs(m)
}

/// What the dofs of a subdivision depend on: the mesh's distinct corners and edges, its
/// elements and their degree (counted once for every m).
struct Topology {
    corners: usize,
    edges: usize,
    elements: usize,
    degree: usize,
}

impl Topology {
    fn of(mesh: &Mesh) -> Self {
        let mut corners = std::collections::HashSet::new();
        let mut edges = std::collections::HashSet::new();
        for e in 0..mesh.n_elements() {
            let c = mesh.corners(e);
            for i in 0..4 {
                corners.insert(c[i]);
                let (a, b) = (c[i], c[(i + 1) % 4]);
                edges.insert((a.min(b), a.max(b)));
            }
        }
        Self {
            corners: corners.len(),
            edges: edges.len(),
            elements: mesh.n_elements(),
            degree: mesh.order().degree(),
        }
    }

    /// [`subdivided_dofs`] for m.
    fn subdivided_dofs(&self, m: usize) -> usize {
        let inner = self.degree * m - 1;
        6 * (self.corners + self.edges * inner + self.elements * inner * inner)
    }
}

/// The free edges' boundary layer against the outermost elements of a subdivided mesh.
struct EdgeLayer {
    /// The outermost elements' largest width on the m × m subdivision, m.
    edge_m: f64,
    /// The boundary layer's width, t/√10, m.
    layer_m: f64,
    /// Node intervals per element (1 for MITC4, 2 for MITC9).
    per_element: f64,
}

impl EdgeLayer {
    /// The layer at `subdivisions` where the outermost elements are wider than the layer
    /// (MITC4) or than twice it (MITC9); None where it is resolved.
    fn unresolved(mesh: &Mesh, material: &ShellMaterial, subdivisions: usize) -> Option<Self> {
        let layer = EdgeLayer {
            edge_m: outermost_width(mesh) / subdivisions as f64,
            layer_m: material.thickness_m / 10f64.sqrt(),
            per_element: mesh.order().degree() as f64,
        };
        (layer.edge_m > layer.per_element * layer.layer_m).then_some(layer)
    }

    fn describe(&self) -> String {
        format!(
            "the outermost elements are up to {:.3} mm wide, against a boundary layer of \
             t/sqrt(10) = {:.3} mm at the free edges",
            self.edge_m * 1e3,
            self.layer_m * 1e3
        )
    }
}

/// The largest width, normal to the boundary, of an element on the mesh's boundary: the
/// distance between the midpoints of a boundary edge and of the element's opposite edge, m.
/// A boundary edge is one that a single element uses.
pub fn outermost_width(mesh: &Mesh) -> f64 {
    let mut uses: std::collections::HashMap<(usize, usize), usize> =
        std::collections::HashMap::new();
    let edge = |a: usize, b: usize| (a.min(b), a.max(b));
    for e in 0..mesh.n_elements() {
        let c = mesh.corners(e);
        for i in 0..4 {
            *uses.entry(edge(c[i], c[(i + 1) % 4])).or_default() += 1;
        }
    }
    let x = mesh.nodes();
    let mid = |a: usize, b: usize| {
        let (p, q) = (x[a], x[b]);
        [
            0.5 * (p[0] + q[0]),
            0.5 * (p[1] + q[1]),
            0.5 * (p[2] + q[2]),
        ]
    };
    let mut widest: f64 = 0.0;
    for e in 0..mesh.n_elements() {
        let c = mesh.corners(e);
        for i in 0..4 {
            if uses[&edge(c[i], c[(i + 1) % 4])] == 1 {
                let here = mid(c[i], c[(i + 1) % 4]);
                let there = mid(c[(i + 2) % 4], c[(i + 3) % 4]);
                widest = widest.max(crate::vec3::norm(crate::vec3::sub(here, there)));
            }
        }
    }
    widest
}

/// The signed discretization error of the lowest `n_modes` modes of `mesh` itself
/// ([`Convergence::errors_of_level`] of level 0), from the mesh and its 2 × 2 and 3 × 3
/// subdivisions: what a model built on `mesh` carries into a fit. Returns the errors and the
/// study (its warnings say when the free edges are unresolved, which the errors cannot show).
///
/// # Errors
/// As [`converge_modes`].
pub fn mesh_errors(
    mesh: &Mesh,
    surface: Option<Surface<'_>>,
    material: &ShellMaterial,
    springs: &[NodeSpring],
    n_modes: usize,
    progress: &dyn Progress,
) -> Result<(Vec<f64>, Convergence), FemError> {
    let params = ConvergeParams {
        modes: n_modes,
        tolerance: MIN_TOLERANCE,
        max_dofs: usize::MAX,
        max_levels: 3,
        stop_when_out_of_reach: false,
    };
    let study = converge_modes(mesh, surface, material, springs, &params, progress)?;
    Ok((study.errors_of_level(0, n_modes), study))
}

/// A solved level: frequencies, rigid flags and translations at the coarse nodes.
struct Solved {
    subdivisions: usize,
    n_dofs: usize,
    seconds: f64,
    freqs: Vec<f64>,
    rigid: Vec<bool>,
    samples: Vec<Vec<f64>>,
}

/// Modes beyond the wanted ones solved on every level, so that a mode that moves up in order
/// on a coarser mesh still finds its match.
const EXTRA_MODES: usize = 4;

fn solve_level(
    mesh: &Mesh,
    m: usize,
    coarse: &[crate::vec3::V3],
    material: &ShellMaterial,
    springs: &[NodeSpring],
    params: &ConvergeParams,
) -> Result<Solved, FemError> {
    let start = Instant::now();
    let locator = Locator::new(mesh, f64::INFINITY);
    let nodes: Vec<usize> = coarse.iter().map(|&x| locator.nearest(x).0).collect();
    let springs: Vec<NodeSpring> = springs
        .iter()
        .map(|s| NodeSpring {
            node: nodes[s.node],
            ..*s
        })
        .collect();
    let asm = Assembly::new(mesh, material, &springs)?;
    let wanted = (params.modes + EXTRA_MODES).min(mesh.n_dofs());
    let sol = solve_modes(&asm, &ModalParams::lowest(wanted), &crate::eigen::Silent)?;
    let samples = (0..sol.shapes.ncols())
        .map(|j| {
            let col = sol.shapes.col(j);
            nodes
                .iter()
                .flat_map(|&n| (0..3).map(move |c| col[6 * n + c]))
                .collect()
        })
        .collect();
    Ok(Solved {
        subdivisions: m,
        n_dofs: mesh.n_dofs(),
        seconds: start.elapsed().as_secs_f64(),
        freqs: sol.modes.iter().map(|m| m.freq_hz).collect(),
        rigid: sol.modes.iter().map(|m| m.rigid).collect(),
        samples,
    })
}

struct Estimate {
    levels: Vec<Level>,
    modes: Vec<ModeEstimate>,
}

/// Matches the finest level's first `wanted` modes on every level and extrapolates each.
fn estimate(solved: &[Solved], wanted: usize, nominal: f64) -> Estimate {
    let finest = solved.last().expect("at least one level");
    let wanted = wanted.min(finest.freqs.len());
    let levels: Vec<Level> = solved
        .iter()
        .map(|level| {
            let (matched, mac) = match_modes(finest, level, wanted);
            Level {
                subdivisions: level.subdivisions,
                n_dofs: level.n_dofs,
                seconds: level.seconds,
                freqs_hz: matched
                    .iter()
                    .map(|&k| level.freqs.get(k).copied().unwrap_or(f64::NAN))
                    .collect(),
                mac,
                matched,
            }
        })
        .collect();
    let h: Vec<f64> = solved.iter().map(|l| 1.0 / l.subdivisions as f64).collect();
    let modes = (0..wanted)
        .map(|j| {
            if finest.rigid[j] {
                return ModeEstimate {
                    freq_hz: finest.freqs[j],
                    extrapolated_hz: 0.0,
                    error: 0.0,
                    order: None,
                    rigid: true,
                };
            }
            let f: Vec<f64> = levels.iter().map(|l| l.freqs_hz[j]).collect();
            richardson(&h, &f, nominal)
        })
        .collect();
    Estimate { levels, modes }
}

/// For each of the finest level's first `wanted` modes, the index and MAC of its best match
/// on `level` (greedy, each mode of `level` used once; rigid modes match by order;
/// `usize::MAX` where none is left).
fn match_modes(finest: &Solved, level: &Solved, wanted: usize) -> (Vec<usize>, Vec<f64>) {
    let mut taken = vec![false; level.freqs.len()];
    let mut matched = Vec::with_capacity(wanted);
    let mut macs = Vec::with_capacity(wanted);
    for j in 0..wanted {
        let best = if finest.rigid[j] {
            (j < level.freqs.len() && level.rigid[j]).then_some((j, 1.0))
        } else {
            (0..level.freqs.len())
                .filter(|&k| !taken[k] && !level.rigid[k])
                .map(|k| (k, mac(&finest.samples[j], &level.samples[k])))
                .fold(None, |a: Option<(usize, f64)>, b| match a {
                    Some(a) if a.1 >= b.1 => Some(a),
                    _ => Some(b),
                })
        };
        match best {
            Some((k, value)) => {
                taken[k] = true;
                matched.push(k);
                macs.push(value);
            }
            None => {
                matched.push(usize::MAX);
                macs.push(0.0);
            }
        }
    }
    (matched, macs)
}

/// Generalised Richardson extrapolation of one mode over element sizes `h` (decreasing) and
/// frequencies `f`, with the order kept at or below `nominal` (see the module's text for the
/// formulas and the fallbacks). One level gives an infinite error.
pub fn richardson(h: &[f64], f: &[f64], nominal: f64) -> ModeEstimate {
    let n = f.len();
    let last = f[n - 1];
    let single = ModeEstimate {
        freq_hz: last,
        extrapolated_hz: last,
        error: f64::INFINITY,
        order: None,
        rigid: false,
    };
    if n < 2 || f.iter().any(|v| !v.is_finite()) {
        return single;
    }
    let (h2, h3) = (h[n - 2], h[n - 1]);
    let d2 = f[n - 2] - last;
    // With p: C = d2 / (h2ᵖ − h3ᵖ), f∞ = f3 − C h3ᵖ.
    let with_order = |p: f64, order: Option<f64>, floor: f64| {
        let c = d2 / (h2.powf(p) - h3.powf(p));
        let tail = c * h3.powf(p);
        let safety = if order.is_some() {
            SAFETY_OBSERVED
        } else {
            SAFETY_ASSUMED
        };
        ModeEstimate {
            freq_hz: last,
            extrapolated_hz: last - tail,
            error: safety * (tail.abs() / last).max(floor),
            order,
            rigid: false,
        }
    };
    if n < 3 {
        return with_order(1.0, None, 0.0);
    }
    let h1 = h[n - 3];
    let d1 = f[n - 3] - f[n - 2];
    let ratio = d1 / d2;
    let g = |p: f64| (h1.powf(p) - h2.powf(p)) / (h2.powf(p) - h3.powf(p));
    if !(d1 * d2 > 0.0 && ratio.is_finite() && ratio > g(0.5)) {
        // Not in the asymptotic range (differences of opposite sign, or not shrinking).
        return with_order(1.0, None, d2.abs() / last);
    }
    // g increases with p: bisection on [0.5, 30].
    let (mut lo, mut hi) = (0.5, 30.0);
    if ratio >= g(hi) {
        lo = hi;
    } else {
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if g(mid) < ratio {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    }
    let observed = 0.5 * (lo + hi);
    with_order(observed.clamp(0.5, nominal), Some(observed), 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// f(h) = 10 + 3h² is recovered exactly with p = 2 from three levels.
    #[test]
    fn richardson_recovers_a_power_law() {
        let h = [1.0, 0.5, 1.0 / 3.0];
        let f: Vec<f64> = h.iter().map(|h: &f64| 10.0 + 3.0 * h * h).collect();
        let e = richardson(&h, &f, 4.0);
        assert!((e.order.unwrap() - 2.0).abs() < 1e-9, "{:?}", e.order);
        assert!((e.extrapolated_hz - 10.0).abs() < 1e-12);
        let true_error = (f[2] - 10.0) / f[2];
        assert!((e.error - SAFETY_OBSERVED * true_error).abs() < 1e-12);
    }

    /// An observed order above the element's nominal one is not trusted: the estimate uses the
    /// nominal order and is larger (safer) than the lucky one.
    #[test]
    fn order_is_capped_at_the_nominal_one() {
        let h = [1.0, 0.5, 0.25];
        let f: Vec<f64> = h.iter().map(|h: &f64| 10.0 + h.powi(6)).collect();
        let e = richardson(&h, &f, 4.0);
        assert!((e.order.unwrap() - 6.0).abs() < 1e-9);
        let true_error = (f[2] - 10.0) / f[2];
        assert!(e.error > true_error);
    }

    /// Differences of opposite sign: p = 1 and at least the last difference.
    #[test]
    fn oscillating_sequence_is_not_extrapolated_optimistically() {
        let h = [1.0, 0.5, 1.0 / 3.0];
        let f = [10.2, 9.9, 10.05];
        let e = richardson(&h, &f, 4.0);
        assert!(e.order.is_none());
        assert!(e.error >= SAFETY_ASSUMED * 0.15 / 10.05);
    }

    #[test]
    fn tolerance_below_double_precision_is_refused() {
        let p = ConvergeParams::new(10, 1e-14);
        let err = p.validate().unwrap_err().to_string();
        assert!(err.contains("below what double precision allows"), "{err}");
        assert!(ConvergeParams::new(10, f64::NAN).validate().is_err());
        assert!(ConvergeParams::new(10, 1e-4).validate().is_ok());
    }
}
