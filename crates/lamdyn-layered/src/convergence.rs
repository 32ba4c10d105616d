//! Convergence control of the layered inverse: a ladder of meshes, Richardson extrapolation of
//! each mode's complex eigenvalue, and the core's G* of the extrapolated model.
//!
//! For a glass laminate with a stiff interlayer d ln f / d ln G ≈ 0.03, a model 0.03 % too
//! stiff in frequency puts G about 1 % too low, closer than any affordable mesh. So the model
//! is built on a ladder of in-plane meshes n_k = round(n_0 r^k) (r = [`LadderSettings::ratio`],
//! h_k = 1/√(n_x n_y)), and at each mode's G* the same mode's eigenvalue λ_k(G*) is read on
//! every level (its pole, dashpots at that level's own frequency:
//! [`LayeredInverse::pole_eigenvalue`]). With λ_k = λ_∞ + C h_k^p, the last three levels a, b,
//! c give the order p from
//!
//!   (λ_a − λ_b)/(λ_b − λ_c) = (h_a^p − h_b^p)/(h_b^p − h_c^p)   (real parts, bisection on p),
//!
//! and λ_∞ = λ_c + (λ_c − λ_b) h_c^p/(h_b^p − h_c^p) (Richardson); the imaginary part gets its
//! own order. The model used is the coarsest level corrected by δ = λ_∞/λ_0: G* solves
//! λ_0(G*) = λ_meas/δ; two passes re-evaluate δ at the new G*.
//!
//! Per mode: the finest level's error in frequency √(Re λ_c/Re λ_∞) − 1 and in loss factor
//! η_c/η_∞ − 1; the residual error of the extrapolated model, a quarter of the finest level's
//! (the 0.25 beyond 1 of Roache's grid convergence index, GCI, over three grids), which stops
//! the ladder at [`LadderSettings::tolerance`] (or [`LadderSettings::max_levels`]: a mode still
//! beyond it is a [`LayeredError::Tolerance`] saying how far it got); and the band of G*, the
//! GCI of the finest level, 1.25 |λ_c/λ_∞ − 1| per part, mapped to G* by solving again. A part
//! that is not monotone over the three levels, or converges below [`MIN_ORDER`] (outside the
//! asymptotic range, where Richardson's factor extrapolates noise), is extrapolated with p = 2
//! and a residual of half its last difference; the frequency's residual is the real part's.
//!
//! The coarsest level is the caller's [`LayeredInverse`] (basis over G_ref/4 … 4 G_ref); the
//! finer levels have a basis at G_ref with three orders of its core sensitivities
//! ([`crate::inverse::krylov_orders`]); every level refuses a mode above
//! [`crate::inverse::BASIS_COVER`] of its basis's highest mode. Both bases are checked against
//! the full model in `inverse::tests::reduced_bases_match_the_full_model_over_the_range`; the
//! ladder against finer, graded truths in docs/run.md ("Convergence control").

use crate::error::LayeredError;
use crate::inverse::{LayeredEstimate, LayeredInverse, LayeredPlate};
use num_complex::Complex64;
use rayon::prelude::*;

/// Settings of the mesh ladder.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LadderSettings {
    /// Refinement ratio between levels (> 1).
    pub ratio: f64,
    /// Largest number of levels (at least 3, the coarsest included).
    pub max_levels: usize,
    /// Largest residual relative frequency error accepted (module docs).
    pub tolerance: f64,
    /// Modes in each finer level's basis.
    pub modes: usize,
    /// Largest level, in dofs, the ladder builds. A level's dofs are counted before it is
    /// built ([`Levels::dofs`]), or else estimated from the finest level built so far
    /// ([`estimated_dofs`]): a Gmsh plan of
    /// thousands of quadrilaterals split 3 × 3 would otherwise run the machine out of memory
    /// with no word (the sparse Cholesky of the 67 509-dof level of the demo roof's ladder
    /// peaks near 1.8 GB with the rest of the run; memory grows a little faster than the dofs).
    pub max_dofs: usize,
}

impl Default for LadderSettings {
    fn default() -> Self {
        Self {
            ratio: 4.0 / 3.0,
            max_levels: 5,
            tolerance: 1e-4,
            modes: 20,
            max_dofs: 250_000,
        }
    }
}

/// One mode through the ladder.
#[derive(Debug, Clone, PartialEq)]
pub struct ConvergedMode {
    /// G* of the core through the extrapolated model, Pa.
    pub core_shear_pa: Complex64,
    /// G* through the coarsest mesh alone, uncorrected, Pa.
    pub coarsest_pa: Complex64,
    /// The finest level's relative frequency error, √(Re λ_c/Re λ_∞) − 1.
    pub freq_error: f64,
    /// The finest level's relative loss-factor error, η_c/η_∞ − 1.
    pub loss_error: f64,
    /// Estimated relative frequency error left in the extrapolated model (module docs).
    pub residual_freq_error: f64,
    /// Half-width of G' from the finest level's grid convergence index, relative to G'
    /// (module docs).
    pub storage_band: f64,
    /// Half-width of the core's loss factor from the same, relative to it.
    pub loss_band: f64,
    /// Observed order p of Re λ's convergence (2 when not monotone).
    pub order: f64,
    /// Observed order of Im λ's convergence (2 when not monotone).
    pub loss_order: f64,
    /// Whether the last three levels converged monotonically at an order of at least
    /// [`MIN_ORDER`], in both parts (else the part that did not was extrapolated with p = 2 and
    /// its residual is half its last difference: module docs).
    pub asymptotic: bool,
    /// Rank of the mode among the elastic ones (0: the lowest; [`LayeredEstimate::rank`]).
    pub rank: usize,
    /// Per level of the ladder (coarsest first), ln(G*/G*_k): how far the G* that level alone
    /// finds for the target lies from `core_shear_pa`, to first order from that level's
    /// eigenvalue λ_k at G*: −ln(target/λ_k)/S; empty where it could not be taken.
    pub level_corrections: Vec<Complex64>,
    /// S = ∂ln λ/∂ln G* of the mode at `core_shear_pa` on the coarsest level (how strongly its
    /// eigenvalue feels the core), by a step of 1e-4 in ln G' (λ is analytic in G*, so the one
    /// real step gives the complex S); NaN where it could not be taken.
    pub sensitivity: Complex64,
}

impl ConvergedMode {
    /// A mode with no discretization error left (the target's own model, as in the coverage
    /// tests): G* `core_shear_pa`, the coarsest level's own answer `coarsest_pa`, elastic rank
    /// `rank`, every error and band 0, orders 2, one level (the coarsest's ln(G*/G*_coarsest)),
    /// sensitivity 1.
    pub fn exact(core_shear_pa: Complex64, coarsest_pa: Complex64, rank: usize) -> Self {
        Self {
            core_shear_pa,
            coarsest_pa,
            freq_error: 0.0,
            loss_error: 0.0,
            residual_freq_error: 0.0,
            storage_band: 0.0,
            loss_band: 0.0,
            order: 2.0,
            loss_order: 2.0,
            asymptotic: true,
            rank,
            level_corrections: vec![(core_shear_pa / coarsest_pa).ln()],
            sensitivity: Complex64::new(1.0, 0.0),
        }
    }
}

/// The ladder's result.
#[derive(Debug, Clone, PartialEq)]
pub struct Converged {
    /// Per target: the mode, or why it failed.
    pub modes: Vec<Result<ConvergedMode, LayeredError>>,
    /// Per target that missed the tolerance on the last level, the ladder's estimate there
    /// (its levels' errors still correct a model on one of them); `None` for the others.
    pub beyond_tolerance: Vec<Option<ConvergedMode>>,
    /// In-plane elements of each level, coarsest first.
    pub meshes: Vec<[usize; 2]>,
    /// Dofs of each level.
    pub dofs: Vec<usize>,
}

/// The lowest observed order the ladder extrapolates with (module docs). The 20-node
/// hexahedron's eigenvalues converge at order 4 on smooth modes; the paper's roof showed 3.2–3.8
/// in frequency and 2.5–5 in loss (free, and on foam blocks away from their resonances). Where
/// the roof's modes mix with its supports' (16–20 Hz on the foam blocks) the loss came out at
/// 0.5–1.2 from three levels, and its extrapolation at that order put η 8–16 % off a 64 × 64
/// truth with a grid convergence band of 1–7 %.
pub const MIN_ORDER: f64 = 1.5;

/// The order p from three levels (module docs), or `None` when they are not monotone.
pub fn observed_order(h: [f64; 3], y: [f64; 3]) -> Option<f64> {
    let (d1, d2) = (y[0] - y[1], y[1] - y[2]);
    if d1 == 0.0 || d2 == 0.0 || (d1 > 0.0) != (d2 > 0.0) {
        return None;
    }
    let want = d1 / d2;
    let f = |p: f64| (h[0].powf(p) - h[1].powf(p)) / (h[1].powf(p) - h[2].powf(p));
    let (mut lo, mut hi) = (0.5, 10.0);
    if want <= f(lo) {
        return Some(lo);
    }
    if want >= f(hi) {
        return Some(hi);
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < want { lo = mid } else { hi = mid }
    }
    Some(0.5 * (lo + hi))
}

/// Richardson's extrapolation of the finest two levels (h_b > h_c) with order p.
pub fn extrapolate(h: [f64; 2], y: [Complex64; 2], p: f64) -> Complex64 {
    let (b, c) = (h[0].powf(p), h[1].powf(p));
    y[1] + (y[1] - y[0]) * (c / (b - c))
}

/// The in-plane mesh of level `k` (0: `start`): each count times ratio^k, rounded, and at
/// least k more than at the start, so that small counts (a surface plan split 1, 2, 3 … times,
/// [`crate::plan`]) still give distinct levels; counts of 4 or more with the default ratio 4/3
/// are the rounded geometric ladder alone.
pub fn level_mesh(start: [usize; 2], ratio: f64, k: usize) -> [usize; 2] {
    start.map(|n| ((n as f64 * ratio.powi(k as i32)).round() as usize).max(n + k))
}

/// The dofs of the level on `mesh`, estimated from a built level's `dofs` on `built`: dofs ∝
/// in-plane elements ∝ 1/h² (through the thickness every level is the same). The edges' nodes
/// grow as 1/h only, so it overestimates, the less the finer the meshes: on the demo roof's
/// ladder each level from the one below 1.4–2.9 % high (38 × 38 from 12 × 12: 8 %); on a
/// small plate 3 × 3 → 4 × 4 elements 10 %, 4 × 4 → 5 × 5 6 %.
pub fn estimated_dofs(dofs: usize, built: [usize; 2], mesh: [usize; 2]) -> usize {
    (dofs as f64 * (h_of(built) / h_of(mesh)).powi(2)).round() as usize
}

/// The mesh parameter h of a level.
fn h_of(mesh: [usize; 2]) -> f64 {
    1.0 / ((mesh[0] * mesh[1]) as f64).sqrt()
}

/// The finer levels' model of `plate` on `elements` (module docs): the basis at G_ref alone,
/// `modes` modes.
///
/// # Errors
/// As [`LayeredInverse::build`].
pub fn build_level(
    plate: &LayeredPlate,
    elements: [usize; 2],
    g_ref_pa: f64,
    modes: usize,
) -> Result<LayeredInverse, LayeredError> {
    LayeredInverse::build_with_ratios(plate, elements, g_ref_pa, modes, &[1.0])
}

/// Where the ladder's finer levels come from ([`converge`]): their models, and their sizes
/// where these are known before a build. A closure that builds a level is one, its sizes
/// estimated ([`estimated_dofs`]); [`CountedLevels`] adds the exact count.
pub trait Levels: Sync {
    /// The model on `elements` elements ([`build_level`], or a cached copy of it).
    ///
    /// # Errors
    /// Those of the build.
    fn build(&self, elements: [usize; 2]) -> Result<LayeredInverse, LayeredError>;
    /// The dofs of the model on `elements`, if known without building it.
    fn dofs(&self, _elements: [usize; 2]) -> Option<usize> {
        None
    }
}

impl<F> Levels for F
where
    F: Fn([usize; 2]) -> Result<LayeredInverse, LayeredError> + Sync,
{
    fn build(&self, elements: [usize; 2]) -> Result<LayeredInverse, LayeredError> {
        self(elements)
    }
}

/// Levels built by `build` and counted by `dofs` (e.g. [`LayeredPlate::dofs`], which meshes
/// the plan without assembling): the dof cap ([`LadderSettings::max_dofs`]) then compares
/// exact sizes, where the estimate runs up to 10 % high near it.
pub struct CountedLevels<B, C> {
    /// Builds the model on the elements given.
    pub build: B,
    /// The dofs of the model on the elements given, `None` where unknown.
    pub dofs: C,
}

impl<B, C> Levels for CountedLevels<B, C>
where
    B: Fn([usize; 2]) -> Result<LayeredInverse, LayeredError> + Sync,
    C: Fn([usize; 2]) -> Option<usize> + Sync,
{
    fn build(&self, elements: [usize; 2]) -> Result<LayeredInverse, LayeredError> {
        (self.build)(elements)
    }
    fn dofs(&self, elements: [usize; 2]) -> Option<usize> {
        (self.dofs)(elements)
    }
}

/// Runs the ladder (module docs): `coarsest` is the plate's model on `start` elements;
/// `level` builds a finer level's model on the elements it is given and counts its dofs
/// where it can ([`Levels`]); `targets` are the measured −p², `starts` the first guesses of
/// G*.
///
/// # Errors
/// [`LayeredError::Invalid`] for settings out of range or mismatched lengths; errors of the
/// finer levels' builds. A target that fails alone is an `Err` in [`Converged::modes`]: no
/// matching mode, or [`LayeredError::Tolerance`] when the ladder stopped at its last level
/// with that mode's residual above the tolerance (how far it got).
pub fn converge(
    coarsest: &LayeredInverse,
    start: [usize; 2],
    level: &dyn Levels,
    targets: &[Complex64],
    starts: &[Complex64],
    settings: &LadderSettings,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Converged, LayeredError> {
    converge_keeping_levels(coarsest, start, level, targets, starts, settings, progress)
        .map(|(converged, _)| converged)
}

/// [`converge`], also giving back the finer levels it built (in the order of
/// [`Converged::meshes`] after the coarsest), for [`correction`].
///
/// # Errors
/// As [`converge`].
pub fn converge_keeping_levels(
    coarsest: &LayeredInverse,
    start: [usize; 2],
    level: &dyn Levels,
    targets: &[Complex64],
    starts: &[Complex64],
    settings: &LadderSettings,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<(Converged, Vec<LayeredInverse>), LayeredError> {
    validate(settings, targets, starts)?;
    let mut meshes: Vec<[usize; 2]> = (0..3)
        .map(|k| level_mesh(start, settings.ratio, k))
        .collect();
    // A level's size: exact where `level` knows it, else estimated from one built.
    let size = |mesh: [usize; 2], built_dofs: usize, built: [usize; 2]| match level.dofs(mesh) {
        Some(d) => (d, ""),
        None => (estimated_dofs(built_dofs, built, mesh), "about "),
    };
    let (third, about) = size(meshes[2], coarsest.size().0, start);
    if third > settings.max_dofs {
        return Err(LayeredError::Invalid(format!(
            "the ladder's third level, {} x {} elements, would have {about}{} dofs, above \
             inverse.layered_max_dofs = {} (the coarsest has {}): start from a coarser mesh \
             (inverse.layered_elements, inverse.layered_subdivisions or fewer quadrilaterals in \
             the plan's Gmsh mesh) or raise inverse.layered_max_dofs if the memory allows",
            meshes[2][0],
            meshes[2][1],
            third,
            settings.max_dofs,
            coarsest.size().0
        )));
    }
    let build = |m: [usize; 2]| {
        progress(&format!("layered level {} x {}", m[0], m[1]));
        level.build(m)
    };
    // Each target on the coarsest mesh alone: the start of every pass, once for all levels.
    // Modes in parallel: each is sequential inside, so the bits do not depend on the schedule.
    let first: Vec<Result<LayeredEstimate, LayeredError>> = targets
        .par_iter()
        .zip(starts)
        .map(|(&t, &s)| coarsest.invert(t, s))
        .collect();
    let mut finer: Vec<LayeredInverse> = meshes[1..]
        .par_iter()
        .map(|&m| build(m))
        .collect::<Result<_, _>>()?;
    loop {
        let levels: Vec<&LayeredInverse> = std::iter::once(coarsest).chain(finer.iter()).collect();
        let h: Vec<f64> = meshes.iter().map(|&m| h_of(m)).collect();
        let modes: Vec<Result<ConvergedMode, LayeredError>> = targets
            .par_iter()
            .zip(&first)
            .map(|(&t, f)| one_mode(&levels, &h, t, f.clone()?))
            .collect();
        let worst = modes
            .iter()
            .filter_map(|m| m.as_ref().ok())
            .map(|m| m.residual_freq_error)
            .fold(0.0, f64::max);
        let mut dofs = vec![coarsest.size().0];
        dofs.extend(finer.iter().map(|l| l.size().0));
        if worst <= settings.tolerance {
            return Ok((
                Converged {
                    beyond_tolerance: vec![None; modes.len()],
                    modes,
                    meshes,
                    dofs,
                },
                finer,
            ));
        }
        let next = level_mesh(start, settings.ratio, meshes.len());
        let (next_dofs, about) = size(next, dofs[dofs.len() - 1], meshes[meshes.len() - 1]);
        let too_big = next_dofs > settings.max_dofs;
        if meshes.len() >= settings.max_levels || too_big {
            // Each mode that misses the tolerance fails alone and says how far it got; the
            // others stand (a mode mixed with a support's bounce need not hold them back).
            let remedy = if too_big {
                format!(
                    "the next level, {} x {}, would have {about}{} dofs, above \
                     inverse.layered_max_dofs = {}: raise it if the memory allows, or \
                     inverse.tolerance",
                    next[0], next[1], next_dofs, settings.max_dofs
                )
            } else {
                "raise inverse.tolerance or the number of levels".to_string()
            };
            let beyond_tolerance = modes
                .iter()
                .map(|m| {
                    m.as_ref()
                        .ok()
                        .filter(|m| m.residual_freq_error > settings.tolerance)
                        .cloned()
                })
                .collect();
            let modes = out_of_tolerance(modes, settings, &meshes, &dofs, &remedy);
            return Ok((
                Converged {
                    modes,
                    beyond_tolerance,
                    meshes,
                    dofs,
                },
                finer,
            ));
        }
        finer.push(build(next)?);
        meshes.push(next);
    }
}

/// `modes` with each that misses the tolerance turned into an error saying how far it got
/// over `meshes` (`dofs` each) and `remedy`; the others stand (a mode mixed with a support's
/// bounce need not hold them back).
fn out_of_tolerance(
    modes: Vec<Result<ConvergedMode, LayeredError>>,
    settings: &LadderSettings,
    meshes: &[[usize; 2]],
    dofs: &[usize],
    remedy: &str,
) -> Vec<Result<ConvergedMode, LayeredError>> {
    let last = meshes[meshes.len() - 1];
    let finest = dofs[dofs.len() - 1];
    modes
        .into_iter()
        .map(|m| match m {
            Ok(m) if m.residual_freq_error > settings.tolerance => {
                Err(LayeredError::Tolerance(format!(
                    "the layered model's estimated frequency error {:.2e} is above the tolerance \
                     {:.1e} after {} levels up to {} x {} elements ({finest} dofs); {remedy}",
                    m.residual_freq_error,
                    settings.tolerance,
                    meshes.len(),
                    last[0],
                    last[1],
                )))
            }
            other => other,
        })
        .collect()
}

/// Checks the settings and the lengths.
fn validate(
    settings: &LadderSettings,
    targets: &[Complex64],
    starts: &[Complex64],
) -> Result<(), LayeredError> {
    let bad = |why: String| Err(LayeredError::Invalid(why));
    if !(settings.tolerance.is_finite() && settings.tolerance > 0.0) {
        return bad(format!(
            "inverse.tolerance: {} must be a positive relative frequency error",
            settings.tolerance
        ));
    }
    if !(settings.ratio.is_finite() && settings.ratio >= 1.1) {
        return bad(format!(
            "ladder ratio {} must be at least 1.1",
            settings.ratio
        ));
    }
    if settings.max_levels < 3 {
        return bad(format!(
            "the ladder needs at least 3 levels to estimate its order, got {}",
            settings.max_levels
        ));
    }
    if targets.len() != starts.len() {
        return bad(format!(
            "{} targets but {} starting moduli",
            targets.len(),
            starts.len()
        ));
    }
    Ok(())
}

/// One target through the ladder (module docs), from its estimate `first` on the coarsest
/// mesh alone.
fn one_mode(
    levels: &[&LayeredInverse],
    h: &[f64],
    target: Complex64,
    first: LayeredEstimate,
) -> Result<ConvergedMode, LayeredError> {
    let coarsest = levels[0];
    let rank = first.rank;
    let mut g = first.core_shear_pa;
    let mut state = ladder_at(levels, h, g, rank, target)?;
    for _ in 0..2 {
        let delta = state.extrapolated / state.values[0];
        g = coarsest.invert(target / delta, g)?.core_shear_pa;
        state = ladder_at(levels, h, g, rank, target)?;
    }
    let n = state.values.len();
    let finest = state.values[n - 1];
    let ext = state.extrapolated;
    let eta = |l: Complex64| l.im / l.re;
    let freq_error = (finest.re / ext.re).sqrt() - 1.0;
    let loss_error = eta(finest) / eta(ext) - 1.0;
    // Each part's residual: a quarter of the finest level's error where that part converged
    // in the asymptotic range, else half its last difference (module docs).
    let fine_err = finest / ext - 1.0;
    let last = 0.5 * (finest / state.values[n - 2] - 1.0);
    let residual = Complex64::new(
        if state.asymptotic[0] {
            0.25 * fine_err.re
        } else {
            last.re
        },
        if state.asymptotic[1] {
            0.25 * fine_err.im
        } else {
            last.im
        },
    );
    // Relative frequency error: half the relative error of Re λ.
    let residual_freq_error = 0.5 * residual.re.abs();
    // G* with the target moved by the finest level's grid convergence index (module docs):
    // the band's half-width, each part on its own.
    let delta = ext / state.values[0];
    let eta_g = |x: Complex64| x.im / x.re;
    // (A part that did not converge monotonically keeps its larger residual.)
    let gci = Complex64::new(
        (1.25 * fine_err.re).abs().max(residual.re.abs()),
        (1.25 * fine_err.im).abs().max(residual.im.abs()),
    );
    let moved_by = |shift: Complex64| -> Result<Complex64, LayeredError> {
        Ok(coarsest
            .invert(target / (delta * (1.0 + shift)), g)?
            .core_shear_pa)
    };
    let by_re = moved_by(Complex64::new(gci.re, 0.0))?;
    let by_im = moved_by(Complex64::new(0.0, gci.im))?;
    let part = |m: Complex64| [m.re / g.re - 1.0, eta_g(m) / eta_g(g) - 1.0];
    let (a, b) = (part(by_re), part(by_im));
    let (level_corrections, sensitivity) = level_corrections(coarsest, &state, g, rank, target);
    Ok(ConvergedMode {
        rank,
        core_shear_pa: g,
        coarsest_pa: first.core_shear_pa,
        freq_error,
        loss_error,
        residual_freq_error,
        storage_band: a[0].hypot(b[0]),
        loss_band: a[1].hypot(b[1]),
        order: state.order,
        loss_order: state.loss_order,
        asymptotic: state.asymptotic[0] && state.asymptotic[1],
        level_corrections,
        sensitivity,
    })
}

/// Step in ln G' of the derivative in [`level_corrections`].
const LEVEL_STEP: f64 = 1e-4;

/// Per level k of `state` (coarsest first), ln(G*/G*_k) to first order: level k's pole at G*
/// `g` is λ_k, and the G*_k it alone finds for `target` satisfies λ_k(G*_k) = target, so
///
///   ln(G*/G*_k) = −ln(target/λ_k) / S,   S = ∂ln λ/∂ln G*,
///
/// S taken on the coarsest level at `g` by a step of [`LEVEL_STEP`] in ln G' (λ is analytic in
/// G*, so the one real step gives the complex S); and S. Empty and NaN where S cannot be
/// taken.
fn level_corrections(
    coarsest: &LayeredInverse,
    state: &LadderState,
    g: Complex64,
    rank: usize,
    target: Complex64,
) -> (Vec<Complex64>, Complex64) {
    let nan = Complex64::new(f64::NAN, f64::NAN);
    let Some(up) = coarsest.pole_eigenvalue(g * LEVEL_STEP.exp(), rank, target) else {
        return (Vec::new(), nan);
    };
    let s = (up / state.values[0]).ln() / LEVEL_STEP;
    if !(s.norm() > 0.0 && s.is_finite()) {
        return (Vec::new(), nan);
    }
    let corrections = state
        .values
        .iter()
        .map(|v| -(target / v).ln() / s)
        .collect();
    (corrections, s)
}

/// The ladder's correction δ = λ_∞/λ_0 of the mode of elastic rank `rank` at core modulus
/// `g` (module docs): its pole on the coarsest level and on each of `finer` (meshes `meshes`,
/// coarsest first, as [`converge_keeping_levels`] gives them), extrapolated like a mode the
/// ladder follows. For a mode no target was matched to (an overlapping pair whose two poles
/// both matched one mode).
///
/// # Errors
/// [`LayeredError::Solver`] when a level has no such mode; [`LayeredError::Invalid`] for
/// fewer than three levels or a mode above a level's basis.
pub fn correction(
    coarsest: &LayeredInverse,
    finer: &[LayeredInverse],
    meshes: &[[usize; 2]],
    g: Complex64,
    rank: usize,
    target: Complex64,
) -> Result<Complex64, LayeredError> {
    if meshes.len() < 3 || meshes.len() != finer.len() + 1 {
        return Err(LayeredError::Invalid(format!(
            "a correction needs three levels or more, with one mesh each: {} meshes for {} levels",
            meshes.len(),
            finer.len() + 1
        )));
    }
    let levels: Vec<&LayeredInverse> = std::iter::once(coarsest).chain(finer.iter()).collect();
    let h: Vec<f64> = meshes.iter().map(|&m| h_of(m)).collect();
    let state = ladder_at(&levels, &h, g, rank, target)?;
    Ok(state.extrapolated / state.values[0])
}

/// A mode's eigenvalue on every level at one G*, and its extrapolation.
struct LadderState {
    values: Vec<Complex64>,
    extrapolated: Complex64,
    order: f64,
    loss_order: f64,
    /// Monotone convergence at an order of at least [`MIN_ORDER`], of the real and the
    /// imaginary part.
    asymptotic: [bool; 2],
}

/// The eigenvalue of elastic rank `rank` on every level at `g`, extrapolated from the last
/// three (module docs).
fn ladder_at(
    levels: &[&LayeredInverse],
    h: &[f64],
    g: Complex64,
    rank: usize,
    target: Complex64,
) -> Result<LadderState, LayeredError> {
    let values: Vec<Complex64> = levels
        .iter()
        .enumerate()
        .map(|(k, l)| {
            // Each level's own pole (the dashpots at its own frequency,
            // [`LayeredInverse::pole_eigenvalue`]): the coarsest's is what its inverse maps back
            // to G*, so δ = λ_∞/λ_0 corrects like for like.
            let lambda = l.pole_eigenvalue(g, rank, target).ok_or_else(|| {
                LayeredError::Solver(format!(
                    "level {} of the ladder has no elastic mode {}",
                    k + 1,
                    rank + 1
                ))
            })?;
            l.check_held(lambda)?;
            Ok(lambda)
        })
        .collect::<Result<_, _>>()?;
    let n = values.len();
    let hh = [h[n - 3], h[n - 2], h[n - 1]];
    let part = |f: fn(&Complex64) -> f64| {
        let y = [f(&values[n - 3]), f(&values[n - 2]), f(&values[n - 1])];
        let p = observed_order(hh, y);
        let trusted = p.filter(|&p| p >= MIN_ORDER);
        let ext = extrapolate(
            [hh[1], hh[2]],
            [Complex64::new(y[1], 0.0), Complex64::new(y[2], 0.0)],
            trusted.unwrap_or(2.0),
        );
        (ext.re, p, trusted.is_some())
    };
    // Real and imaginary parts each at their own order: the loss converges more slowly.
    let (re, order_re, asymptotic_re) = part(|l| l.re);
    let (im, order_im, asymptotic_im) = part(|l| l.im);
    Ok(LadderState {
        values,
        extrapolated: Complex64::new(re, im),
        order: order_re.unwrap_or(2.0),
        loss_order: order_im.unwrap_or(2.0),
        asymptotic: [asymptotic_re, asymptotic_im],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The order of an exact power law is found, and its extrapolation is exact.
    #[test]
    fn order_and_extrapolation_of_a_power_law() {
        let h: [f64; 3] = [1.0 / 12.0, 1.0 / 16.0, 1.0 / 21.0];
        let y = h.map(|x| 5.0 + 30.0 * x.powf(3.6));
        let p = observed_order(h, y).unwrap();
        assert!((p - 3.6).abs() < 1e-9, "{p}");
        let e = extrapolate(
            [h[1], h[2]],
            [Complex64::new(y[1], 0.0), Complex64::new(y[2], 0.0)],
            p,
        );
        assert!((e.re - 5.0).abs() < 1e-12, "{e}");
        // Not monotone: no order.
        assert!(observed_order(h, [1.0, 0.9, 0.95]).is_none());
    }

    /// A tolerance the ladder cannot meet in its levels is an error per mode that says how far
    /// it got; a met one converges, and the ladder's answer lies nearer the finer meshes' than the
    /// coarsest's; a target far from every mode is refused for that mode alone.
    #[test]
    fn ladder_meets_or_says_how_far_it_got() {
        let plate = crate::inverse::small_test_plate();
        let g_ref = 4e6;
        let start = [3, 3];
        let coarsest = LayeredInverse::build(&plate, start, g_ref, 12).unwrap();
        // Targets: the first two elastic modes of a finer model at a known G*.
        let truth = Complex64::new(3e6, 1.5e6);
        let fine = build_level(&plate, [8, 8], g_ref, 12).unwrap();
        let anchor = Complex64::new(1e3, 0.0);
        let mut targets: Vec<Complex64> = (0..2)
            .map(|r| fine.elastic_eigenvalue(truth, r, anchor).unwrap())
            .collect();
        // A pole at half the first mode's frequency: no mode of the plate.
        targets.push(targets[0] * 0.25);
        let starts = vec![truth * 1.2; 3];
        let level = |m: [usize; 2]| build_level(&plate, m, g_ref, 12);
        let strict = LadderSettings {
            tolerance: 1e-12,
            max_levels: 3,
            modes: 12,
            ..LadderSettings::default()
        };
        let run = |settings: &LadderSettings| {
            converge(
                &coarsest,
                start,
                &level,
                &targets,
                &starts,
                settings,
                &|_| {},
            )
        };
        let out = run(&strict).unwrap();
        // What a mode beyond the tolerance reached stays as its estimate.
        for e in &out.beyond_tolerance[..2] {
            let e = e.as_ref().expect("an estimate beyond the tolerance");
            assert!(
                e.residual_freq_error > 1e-12 && e.level_corrections.len() == 3,
                "{e:?}"
            );
        }
        assert!(out.beyond_tolerance[2].is_none());
        for m in &out.modes[..2] {
            let e = m.as_ref().unwrap_err();
            let text = e.to_string();
            assert!(matches!(e, LayeredError::Tolerance(_)), "{e:?}");
            assert!(
                text.contains("above the tolerance 1.0e-12 after 3 levels up to 5 x 5"),
                "{text}"
            );
        }
        let loose = LadderSettings {
            tolerance: 1e-2,
            ..strict
        };
        let out = run(&loose).unwrap();
        assert_eq!(out.meshes, vec![[3, 3], [4, 4], [5, 5]]);
        assert!(out.beyond_tolerance.iter().all(Option::is_none));
        for (m, &target) in out.modes[..2].iter().zip(&targets) {
            let m = m.as_ref().unwrap();
            assert!(m.residual_freq_error <= 1e-2 && m.freq_error > 0.0, "{m:?}");
            // The correction moves G' the way a too-stiff coarse mesh needs (upwards).
            assert!(m.core_shear_pa.re > m.coarsest_pa.re, "{m:?}");
            // Each level's first-order ln(G*/G*_k) against that level's own inverse.
            assert_eq!(m.level_corrections.len(), 3);
            for (k, mesh) in out.meshes.iter().enumerate() {
                let model = if k == 0 {
                    None
                } else {
                    Some(level(*mesh).unwrap())
                };
                let own = model
                    .as_ref()
                    .unwrap_or(&coarsest)
                    .invert(target, m.core_shear_pa)
                    .unwrap()
                    .core_shear_pa;
                let exact = (m.core_shear_pa / own).ln();
                let first = m.level_corrections[k];
                // First order in corrections of 2-17 % here: measured within 2.6 % of them; the
                // FRF fit's levels are corrected by a few per cent, where the second order is
                // smaller still.
                assert!(
                    (first - exact).norm() <= 0.05 * exact.norm(),
                    "level {k}: first order {first}, the level's own inverse {exact}"
                );
            }
        }
        let e = out.modes[2].as_ref().unwrap_err().to_string();
        assert!(e.contains("matches no mode of the layered model"), "{e}");
        // A dof cap stops the ladder before the level above it, saying so: a cap at the third
        // level's estimate lets the ladder start and stops it before the fourth (7 x 7).
        let capped = LadderSettings {
            max_levels: 5,
            max_dofs: estimated_dofs(out.dofs[0], start, [5, 5]),
            ..strict
        };
        let out = run(&capped).unwrap();
        assert_eq!(out.meshes.len(), 3);
        let text = out.modes[0].as_ref().unwrap_err().to_string();
        assert!(
            text.contains("the next level, 7 x 7, would have about")
                && text.contains("above inverse.layered_max_dofs"),
            "{text}"
        );
        // Each level's estimate from the one below: high, by at most 20 % on meshes this small.
        for k in 1..out.meshes.len() {
            let e = estimated_dofs(out.dofs[k - 1], out.meshes[k - 1], out.meshes[k]) as f64;
            let ratio = e / out.dofs[k] as f64;
            assert!((1.0..1.2).contains(&ratio), "{:?}: {ratio}", out.meshes[k]);
        }
        // A ladder whose third level is already above the cap does not start.
        let tiny = LadderSettings {
            max_dofs: out.dofs[1],
            ..capped
        };
        let e = run(&tiny).unwrap_err().to_string();
        assert!(
            e.contains("the ladder's third level, 5 x 5 elements, would have about"),
            "{e}"
        );
        // Exact counts (`CountedLevels`): a cap at the third level's own size, below its
        // estimate from the coarsest, lets the ladder run its three levels, and the stop before
        // the fourth names that level's exact size.
        let exact_cap = LadderSettings {
            max_dofs: out.dofs[2],
            ..capped
        };
        assert!(estimated_dofs(out.dofs[0], start, [5, 5]) > exact_cap.max_dofs);
        let e = run(&exact_cap).unwrap_err().to_string();
        assert!(e.contains("would have about"), "{e}");
        let counted = CountedLevels {
            build: level,
            dofs: |m: [usize; 2]| plate.dofs(m).ok(),
        };
        let out_counted = converge(
            &coarsest,
            start,
            &counted,
            &targets,
            &starts,
            &exact_cap,
            &|_| {},
        )
        .unwrap();
        assert_eq!(out_counted.meshes, out.meshes);
        assert_eq!(out_counted.dofs, out.dofs);
        let seven = plate.dofs([7, 7]).unwrap();
        let text = out_counted.modes[0].as_ref().unwrap_err().to_string();
        assert!(
            text.contains(&format!("the next level, 7 x 7, would have {seven} dofs")),
            "{text}"
        );
        // Settings out of range name what is wrong.
        let bad = LadderSettings {
            tolerance: 0.0,
            ..loose
        };
        let e = run(&bad).unwrap_err().to_string();
        assert!(e.contains("inverse.tolerance"), "{e}");
    }

    /// On supports with dashpots the ladder compares each level's own pole (the dashpots at
    /// that level's frequency): against a finer model's poles it finds that model's G*. Read
    /// at the target's frequency instead, the levels' eigenvalues differ from their poles by
    /// the dashpots' share of the damping times the levels' frequency error, which the
    /// correction δ = λ_∞/λ_0 carried into the coarsest inverse (whose dashpots act at its own
    /// pole): on the paper's roof on foam blocks 0.4–0.6 % in G' and 0.7–1 % in η at 46–67 Hz,
    /// 2–5 % and more at the modes mixed with the blocks (example roof_ladder against a 64 × 64
    /// truth).
    #[test]
    fn ladder_on_dashpots_compares_each_levels_own_pole() {
        let plate =
            crate::inverse::small_test_plate_on(0.15, [4e3, 7e3, 3e4], [10.0, 15.0, 60.0], 0.06);
        let g_ref = 4e6;
        let truth = Complex64::new(3e6, 1.5e6);
        let fine = build_level(&plate, [18, 18], g_ref, 16).unwrap();
        let anchor = Complex64::new(1e3, 0.0);
        let poles: Vec<Complex64> = (0..16)
            .filter_map(|r| fine.pole_eigenvalue(truth, r, anchor))
            .collect();
        // The first elastic modes above the supports' six (the core moves them).
        let targets: Vec<Complex64> = poles
            .iter()
            .copied()
            .filter(|l| l.re.sqrt() / (2.0 * std::f64::consts::PI) > 40.0)
            .take(2)
            .collect();
        assert_eq!(targets.len(), 2, "{poles:?}");
        let start = [4, 4];
        let coarsest = LayeredInverse::build(&plate, start, g_ref, 16).unwrap();
        let settings = LadderSettings {
            tolerance: 1e-3,
            max_levels: 4,
            modes: 16,
            ..LadderSettings::default()
        };
        let (out, finer) = converge_keeping_levels(
            &coarsest,
            start,
            &|m| build_level(&plate, m, g_ref, 16),
            &targets,
            &vec![truth * 1.2; targets.len()],
            &settings,
            &|_| {},
        )
        .unwrap();
        for (t, m) in targets.iter().zip(&out.modes) {
            let m = m.as_ref().unwrap();
            let g = m.core_shear_pa;
            // `correction` reads the same δ as the ladder: the corrected coarsest pole at the
            // converged G* is the target, but for δ's change over the ladder's last pass (it
            // takes δ at the G* before). Measured: 2.2e-7 and 1.3e-5 (δ = 0.993 and 0.967);
            // a level out of order or another mode is off by the corrections' 1e-3 to 3e-2.
            let delta = correction(&coarsest, &finer, &out.meshes, g, m.rank, *t).unwrap();
            let back = delta * coarsest.pole_eigenvalue(g, m.rank, *t).unwrap();
            let miss = (back / t - 1.0).norm();
            assert!(miss < 1e-4, "{miss:e}");
            let off = [
                g.re / truth.re - 1.0,
                (g.im / g.re) / (truth.im / truth.re) - 1.0,
            ];
            eprintln!(
                "{:.2} Hz: G' {:+.3} %, eta {:+.3} % (coarsest {:+.1} %), band ±{:.3} % / ±{:.3} %",
                t.re.sqrt() / (2.0 * std::f64::consts::PI),
                100.0 * off[0],
                100.0 * off[1],
                100.0 * (m.coarsest_pa.re / truth.re - 1.0),
                100.0 * m.storage_band,
                100.0 * m.loss_band
            );
            // Within twice the ladder's discretization band: the 18 × 18 truth carries its own
            // error, and a ladder of 4 × 4 to 9 × 9 meshes is short of its asymptotic range.
            // Measured: G' −0.22 % / +0.48 %, η +0.22 % / −0.01 % against bands of ±0.29 % /
            // ±2.3 % and ±0.19 % / ±1.7 %; with the levels read at the target's frequency η was
            // −0.74 % at the first mode, beyond twice its ±0.27 %.
            assert!(off[0].abs() <= 2.0 * m.storage_band, "{off:?} {m:?}");
            assert!(off[1].abs() <= 2.0 * m.loss_band, "{off:?} {m:?}");
        }
    }
}

/// The ladder on a Gmsh plan ([`crate::plan::Plan::Surface`]) against the structured mesh.
#[cfg(test)]
mod surface_plan {
    use super::*;
    use crate::plan::Plan;
    use lamdyn_fem::mesh::Mesh;
    use std::collections::HashMap;

    const RADII_M: [f64; 2] = [3.0, 5.0];

    /// The dome's point and unit normal over (x, y) (the structured mesh's surface).
    fn dome(x: f64, y: f64) -> ([f64; 3], [f64; 3]) {
        let z = -x * x / (2.0 * RADII_M[0]) - y * y / (2.0 * RADII_M[1]);
        let (gx, gy) = (x / RADII_M[0], y / RADII_M[1]);
        let n = (1.0 + gx * gx + gy * gy).sqrt();
        ([x, y, z], [gx / n, gy / n, 1.0 / n])
    }

    /// The Gmsh fixture's unstructured 4-node plan made 9-node (mid-sides and centres at the
    /// plan's edge midpoints and bilinear centres) and lifted onto the dome with exact normals.
    fn unstructured_dome() -> Mesh {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("testdata/gmsh/plate-unstructured.msh");
        let flat = lamdyn_fem::mesh::gmsh::read_msh(&path, 1.0).unwrap();
        let mut plan: Vec<[f64; 2]> = flat.nodes().iter().map(|p| [p[0], p[1]]).collect();
        let mut mids: HashMap<(usize, usize), usize> = HashMap::new();
        let mut elements = Vec::new();
        for e in 0..flat.n_elements() {
            let c = flat.corners(e);
            let mut conn = [0; 9];
            conn[..4].copy_from_slice(&c);
            for k in 0..4 {
                let (a, b) = (c[k], c[(k + 1) % 4]);
                conn[4 + k] = *mids.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    plan.push([0, 1].map(|d| 0.5 * (plan[a][d] + plan[b][d])));
                    plan.len() - 1
                });
            }
            plan.push([0, 1].map(|d| 0.25 * c.iter().map(|&n| plan[n][d]).sum::<f64>()));
            conn[8] = plan.len() - 1;
            elements.push(conn);
        }
        let (nodes, directors) = plan.iter().map(|p| dome(p[0], p[1])).unzip();
        Mesh::quadratic(nodes, Some(directors), elements).unwrap()
    }

    /// An unstructured Gmsh plan (26 quadrilaterals, interior nodes of degree 3 to 5) on the
    /// small plate made a dome (radii 3 and 5 m), split 1, 2, 3 … times, and the structured
    /// dome's ladder from 6 × 5 invert the same three poles to the same core: within the sum
    /// of their grid-convergence bands, while the Gmsh plan's coarsest mesh alone is several
    /// times further off. Both ladders converge to one continuum, so this holds for any target;
    /// the targets are a 10 × 8 structured model's at 3 MPa (1 + 0.5i).
    #[test]
    fn an_unstructured_gmsh_plan_converges_to_the_structured_answer() {
        let mut rect = crate::inverse::small_test_plate();
        rect.plan = Plan::Rectangle {
            plan_m: [0.5, 0.4],
            radii_m: RADII_M,
            edge_grading: 0.0,
        };
        let mut gmsh = rect.clone();
        gmsh.plan = Plan::Surface(Box::new(unstructured_dome()));
        let truth = Complex64::new(3e6, 1.5e6);
        let g_ref = 4e6;
        let mut targets: Vec<Complex64> = build_level(&rect, [10, 8], g_ref, 12)
            .unwrap()
            .eigenvalues(truth)
            .into_iter()
            .filter(|l| l.re > (2.0 * std::f64::consts::PI * 20.0f64).powi(2))
            .collect();
        targets.sort_by(|a, b| a.re.total_cmp(&b.re));
        targets.truncate(3);
        let starts = vec![truth * 1.2; targets.len()];
        let settings = LadderSettings {
            tolerance: 1e-3,
            max_levels: 5,
            modes: 12,
            ..LadderSettings::default()
        };
        let run = |plate: &LayeredPlate, start: [usize; 2]| {
            let coarsest = LayeredInverse::build(plate, start, g_ref, 12).unwrap();
            let level = |m: [usize; 2]| build_level(plate, m, g_ref, 12);
            let out = converge(
                &coarsest,
                start,
                &level,
                &targets,
                &starts,
                &settings,
                &|_| {},
            );
            let out = out.unwrap();
            (
                out.meshes,
                out.modes
                    .into_iter()
                    .map(Result::unwrap)
                    .collect::<Vec<_>>(),
            )
        };
        let (_, structured) = run(&rect, [6, 5]);
        let (meshes, surface) = run(&gmsh, [1, 1]);
        assert_eq!(meshes, vec![[1, 1], [2, 2], [3, 3]]);
        for (s, g) in structured.iter().zip(&surface) {
            let eta = |x: Complex64| x.im / x.re;
            let (a, b) = (s.core_shear_pa, g.core_shear_pa);
            let dg = (b.re / a.re - 1.0).abs();
            let deta = (eta(b) / eta(a) - 1.0).abs();
            let coarse = (g.coarsest_pa.re / a.re - 1.0).abs();
            println!(
                "G' {:.5e} / {:.5e} ({dg:.2e}, bands {:.2e} + {:.2e}), eta ({deta:.2e}, bands \
                 {:.2e} + {:.2e}), Gmsh coarsest {coarse:.2e}",
                a.re, b.re, s.storage_band, g.storage_band, s.loss_band, g.loss_band
            );
            assert!(dg <= s.storage_band + g.storage_band, "G': {s:?} {g:?}");
            assert!(deta <= s.loss_band + g.loss_band, "eta: {s:?} {g:?}");
            assert!(coarse > 3.0 * dg && coarse > 0.02, "coarsest {coarse}");
        }
    }
}
