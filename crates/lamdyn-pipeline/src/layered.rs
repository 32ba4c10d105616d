//! The chain's layered inverse ([`lamdyn_layered::inverse`]), converged over a ladder of meshes
//! ([`lamdyn_layered::convergence`]): for each modal frequency of the fit, the identified pole
//! p of the EMA within 2 % of it gives the target eigenvalue λ = −p² = ω_n²(1 + iη), and the
//! core's G* is solved through a layered solid model of the part built from the job's model
//! ([`lamdyn_layered::plan::Plan`]: a rectangle model's plan and dome radii, or a Gmsh model's
//! mid-surface mesh) and its stack, corrected by the Richardson extrapolation of each mode's
//! eigenvalue over meshes refined from the coarsest (a rectangle: by 4/3 from
//! `inverse.layered_elements`; a Gmsh plan: every element split m × m, m from
//! `inverse.layered_subdivisions` up by one per level) until the estimated frequency error is
//! below `inverse.tolerance`. The start is the exact
//! inverse's G* at that frequency (else the paper's, else 10 MPa (1 + 0.5i)), which also picks
//! the mode branch. Every level's reduced eigenproblem is cached like the shell model (key:
//! the plan (a Gmsh plan's every node), mesh, modes, basis moduli, layers and G_ref snapped to a
//! power of two).
//!
//! Each mode's result gets a 95 % band ([`LayeredBand`]) from four kinds of source, combined
//! in quadrature as independent normal errors of ln G' and ln η, half-width h = 1.96 √(Σ σ²)
//! and band [x e^−h, x e^h] (log-normal: the moduli are positive, and a band of tens of per
//! cent is not symmetric about them):
//! - the inputs known within a tolerance (`[uncertainty]`: the faces' modulus, the thicknesses,
//!   the densities, and on supports their stiffness and damping), each through its
//!   sensitivity dG*/d ln θ on the coarsest model at the converged G* ([`lamdyn_layered::sensitivity`]), to first order: a sensitivity of −20
//!   turns a 1 % face modulus into 20 % of G', so the bands of a stiff-core laminate are wide
//!   and, at tens of per cent, only roughly normal;
//! - those inputs beyond first order (`second_order`): the core found is not linear in
//!   the faces, and the joint law fit, which shares one first-order shift of the inputs among
//!   all modes, must not take a mode's first-order point for more than it is;
//! - the pole's scatter over the stabilization diagram: the sample standard deviation of the
//!   frequency and damping of the stable poles within 1 % of the mode over the model orders
//!   (at least three), or the response groups' spread where larger, with the spread over
//!   the highest model order, through dG* = δλ/(∂λ/∂G) ("EMA pole", `pole_scatter`);
//! - from hammer hits, the delete-one-hit jackknife of the identification, the same way
//!   ([`HITS_JACKKNIFE`]): the hits' noise biases the poles in a way the diagram and the
//!   groups, reading the same FRFs, do not see;
//! - the discretization: the ladder's residual band, read as a 95 % half-width.

use super::CorePoint;
use super::cache::{Cache, Key};
use super::job::Job;
use crate::Reporter;
use crate::error::{Context, Result};
use lamdyn_ema::identify::EmaResult;
use lamdyn_fem::model::MeshSpec;
use lamdyn_fit::joint::{CoreLaw, CoreLawFit, InputPrior, ModePoint, fit_core_law_shifted};
use lamdyn_layered::LayeredError;
use lamdyn_layered::convergence::{
    CountedLevels, LadderSettings, build_level, converge_keeping_levels, level_mesh,
};
use lamdyn_layered::inverse::{BASIS_RATIOS, InverseLayer, LayeredInverse, LayeredPlate};
use lamdyn_layered::plan::Plan;
use lamdyn_layered::sensitivity::{Input, ModeSensitivity, log_parts, relative_parts};
use num_complex::Complex64;
use rayon::prelude::*;
use std::path::Path;

/// The plan of the job's model for the layered model: a rectangle model's plan, radii and
/// `inverse.layered_edge_grading`, or a Gmsh model's mid-surface mesh (read with its unit).
fn plan(job: &Job, base: &Path) -> Result<Plan> {
    let (spec, dir, label) = crate::stages::model_spec(job, base)?;
    Ok(match &spec.mesh {
        MeshSpec::Rectangle(r) => Plan::Rectangle {
            plan_m: [r.length_x_m, r.length_y_m],
            radii_m: [r.radius_x_m, r.radius_y_m],
            edge_grading: job.inverse.layered_edge_grading,
        },
        MeshSpec::Gmsh { .. } => {
            let (mesh, _) = spec
                .build(&dir)
                .with_context(|| format!("invalid model {label}"))?;
            Plan::Surface(Box::new(mesh))
        }
    })
}

/// The coarsest level of the ladder: `inverse.layered_elements` on a rectangle, each element
/// of a Gmsh plan split `inverse.layered_subdivisions` times along each side.
fn start_level(job: &Job, plan: &Plan) -> [usize; 2] {
    match plan {
        Plan::Rectangle { .. } => job.inverse.layered_elements,
        Plan::Surface(_) => [job.inverse.layered_subdivisions; 2],
    }
}

/// The target eigenvalue −p² of the EMA mode nearest `f` within 2 %, positive imaginary part.
fn target(ema: &EmaResult, f: f64) -> Option<Complex64> {
    let m = &ema.modes[crate::stages::nearest_within(ema, f, 0.02)?];
    let l = -(m.pole * m.pole);
    Some(if l.im < 0.0 { l.conj() } else { l })
}

/// The job's plate for the layered model.
fn layered_plate(job: &Job, base: &Path) -> Result<LayeredPlate> {
    let plan = plan(job, base)?;
    let cores = job.stack.layered_cores().context("stack")?;
    let layers = job
        .stack
        .layers
        .iter()
        .enumerate()
        .map(|(k, l)| {
            let core = cores.contains(&k);
            InverseLayer {
                thickness_m: l.thickness_m,
                density_kg_m3: l.density_kg_m3,
                poisson: l.poisson,
                young_pa: if core { None } else { l.young_pa },
                loss_factor: if core {
                    0.0
                } else {
                    l.loss_factor.unwrap_or(0.0)
                },
            }
        })
        .collect();
    Ok(LayeredPlate {
        plan,
        layers,
        supports: job.inverse.supports.iter().map(|s| s.to_point()).collect(),
        elements_per_layer: 1,
    })
}

/// One level's model from the cache, else built and cached; `ratios` empty: the coarsest
/// (three-modulus basis), else a finer level's.
fn cached_model(
    cache: &Cache,
    plate: &LayeredPlate,
    elements: [usize; 2],
    g_ref: f64,
    modes: usize,
    coarsest: bool,
) -> std::result::Result<(LayeredInverse, bool), LayeredError> {
    let mut key = Key::new(concat!("layered basis v7 ", env!("CARGO_PKG_VERSION")))
        .f64(g_ref)
        .bytes(
            format!(
                "{:?} {elements:?} {modes} {coarsest} {:?} {}",
                plate.plan, plate.supports, plate.elements_per_layer
            )
            .as_bytes(),
        );
    for l in &plate.layers {
        key = key.bytes(format!("{l:?}").as_bytes());
    }
    if let Some(m) = cache
        .get("layered", key)
        .and_then(|b| LayeredInverse::from_bytes(&b))
    {
        return Ok((m, true));
    }
    let m = if coarsest {
        LayeredInverse::build_with_inputs(
            plate,
            elements,
            g_ref,
            modes,
            &BASIS_RATIOS,
            &Input::ALL,
        )?
    } else {
        build_level(plate, elements, g_ref, modes)?
    };
    cache
        .put("layered", key, &m.to_bytes())
        .map_err(|e| LayeredError::Invalid(format!("{e:#}")))?;
    Ok((m, false))
}

/// What the layered stage leaves: a line describing the model (None: no layered inverse) and
/// the coarsest model with its inputs' derivatives, on which the joint law fit re-linearises
/// ([`fit_law`]; None when the ladder did not converge).
pub type LayeredOutcome = (Option<String>, Option<LayeredInverse>);

/// Runs the layered inverse at every modal point ([`LayeredOutcome`]; the flag: every model
/// came from the cache).
///
/// `supports_at`: how far (ln) the job's supports' stiffness and damping already lie from the
/// job file's (0 on a first run; [`supports_found`] for a re-run), recorded in each band so
/// that the joint fit's priors stay about the job file's values.
pub fn run(
    job: &Job,
    base: &Path,
    (set, ema, checks): (&lamdyn_frf::FrfSet, &EmaResult, &PoleChecks),
    modal: &mut [CorePoint],
    cache: &Cache,
    spinner: &dyn Reporter,
    supports_at: [f64; 2],
) -> Result<(LayeredOutcome, bool)> {
    let plate = layered_plate(job, base)?;
    let fallback = start_without_sandwich(job);
    let starts: Vec<Complex64> = modal
        .iter()
        .map(|p| {
            let passive = |g: &Complex64| g.re > 0.0 && g.im >= 0.0 && g.is_finite();
            p.exact_g()
                .or(p.paper_g())
                .filter(passive)
                .or_else(|| {
                    homogenized_start(job, p.freq_hz, p.e_eff_pa.or(p.e_pole_pa)?, fallback)
                })
                .filter(passive)
                .unwrap_or(fallback)
        })
        .collect();
    let mut g: Vec<f64> = starts.iter().map(|s| s.re).collect();
    g.sort_by(f64::total_cmp);
    // G_ref snapped to a power of two (within √2 of the median start, well inside the basis's
    // G_ref/4 .. 4 G_ref): a re-run with another law finds the same model in the cache.
    let g_ref = 2f64.powf(g.get(g.len() / 2).copied().unwrap_or(10e6).log2().round());
    let t = std::time::Instant::now();
    let start = start_level(job, &plate.plan);
    let modes = job.inverse.layered_modes;
    let settings = LadderSettings {
        max_levels: job.inverse.layered_levels,
        tolerance: job.inverse.tolerance,
        max_dofs: job.inverse.layered_max_dofs,
        modes: (modes * 2 / 3).max(12),
        ..LadderSettings::default()
    };
    let all_cached = std::sync::atomic::AtomicBool::new(true);
    let finer_level = |m: [usize; 2]| {
        let (model, hit) = cached_model(cache, &plate, m, g_ref, settings.modes, false)?;
        if !hit {
            all_cached.store(false, std::sync::atomic::Ordering::Relaxed);
        }
        Ok(model)
    };
    // The modal points with a pole: the ladder's targets.
    let with_pole: Vec<(usize, Complex64)> = modal
        .iter()
        .enumerate()
        .filter_map(|(k, p)| target(ema, p.freq_hz).map(|t| (k, t)))
        .collect();
    for p in modal.iter_mut() {
        p.layered = Some(Err(format!(
            "no EMA pole within 2 % of {:.3} Hz for the target eigenvalue",
            p.freq_hz
        )));
        (p.layered_band, p.layered_convergence) = (None, None);
    }
    // A coarsest mesh above the dof cap is not built: every mode says why.
    let coarsest_dofs = plate.dofs(start).context("cannot mesh the layered model")?;
    if coarsest_dofs > settings.max_dofs {
        let why = format!(
            "the layered model's coarsest mesh ({}) has {coarsest_dofs} dofs, above inverse.layered_max_dofs = {}: start from a coarser mesh (inverse.layered_elements, inverse.layered_subdivisions or fewer quadrilaterals in the plan's Gmsh mesh) or raise inverse.layered_max_dofs if the memory allows",
            plate.plan.level_label(start),
            settings.max_dofs
        );
        return Ok((no_layered(modal, &with_pole, "not built", &why), false));
    }
    // The coarsest model and the first finer levels at once, on two lanes, the largest level
    // alone on one (longest first; each build is sequential inside, so the bits do not depend
    // on the schedule): the ladder always needs two finer levels and on a glass laminate
    // usually a third, built here on speculation.
    // Those above the dof cap are left to the ladder, which stops below them and says so.
    let ahead: Vec<[usize; 2]> = (1..=3)
        .filter(|&k| k < settings.max_levels)
        .map(|k| level_mesh(start, settings.ratio, k))
        .take_while(|&m| plate.dofs(m).is_ok_and(|d| d <= settings.max_dofs))
        .collect();
    spinner.stage(&format!(
        "stage 'layered inverse': coarsest layered model and its reduced basis, levels {} and the coarsest with {THROUGH} elements per layer through the thickness built alongside",
        ahead
            .iter()
            .map(|&m| plate.plan.level_label(m))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    let (rest, largest) = ahead.split_at(ahead.len().saturating_sub(1));
    // The coarsest mesh with two elements per layer through the thickness (the band's source
    // 'through the thickness') goes after the largest level, on the lane that frees first.
    // Err: why there is none (above the dof cap, or its build failed), for the stage's line.
    let through_thickness = || -> std::result::Result<_, String> {
        let two = LayeredPlate {
            elements_per_layer: THROUGH,
            ..plate.clone()
        };
        match two.dofs(start) {
            Ok(d) if d > settings.max_dofs => {
                return Err(format!(
                    "the coarsest mesh with {THROUGH} elements per layer has {d} dofs, above inverse.layered_max_dofs"
                ));
            }
            Err(e) => {
                return Err(format!(
                    "the coarsest mesh with {THROUGH} elements per layer: {e}"
                ));
            }
            Ok(_) => {}
        }
        let (model, hit) =
            cached_model(cache, &two, start, g_ref, settings.modes, false).map_err(|e| {
                format!("the model with {THROUGH} elements per layer was not built: {e:#}")
            })?;
        if !hit {
            all_cached.store(false, std::sync::atomic::Ordering::Relaxed);
        }
        Ok(model)
    };
    let ((largest, thick), (coarsest, mut prebuilt)) = rayon::join(
        || {
            let built = largest
                .iter()
                .map(|&m| (m, finer_level(m)))
                .collect::<Vec<_>>();
            (built, through_thickness())
        },
        || {
            let coarsest = cached_model(cache, &plate, start, g_ref, modes, true);
            let rest: Vec<_> = rest.iter().map(|&m| (m, finer_level(m))).collect();
            (coarsest, rest)
        },
    );
    prebuilt.extend(largest);
    let (coarsest, cached) = coarsest.context("cannot build the layered model")?;
    all_cached.fetch_and(cached, std::sync::atomic::Ordering::Relaxed);
    let prebuilt = std::sync::Mutex::new(prebuilt);
    let targets: Vec<Complex64> = with_pole.iter().map(|w| w.1).collect();
    let first: Vec<Complex64> = with_pole.iter().map(|w| starts[w.0]).collect();
    let level = |m: [usize; 2]| {
        let ready = prebuilt.lock().ok().and_then(|mut p| {
            let i = p.iter().position(|b| b.0 == m)?;
            Some(p.swap_remove(i).1)
        });
        ready.unwrap_or_else(|| finer_level(m))
    };
    let levels = CountedLevels {
        build: level,
        dofs: |m: [usize; 2]| plate.dofs(m).ok(),
    };
    let out = converge_keeping_levels(
        &coarsest,
        start,
        &levels,
        &targets,
        &first,
        &settings,
        &|m| spinner.stage(&format!("stage 'layered inverse': {m}")),
    );
    let build_s = t.elapsed().as_secs_f64();
    let (mut out, finer) = match out {
        Ok(o) => o,
        Err(e) => {
            return Ok((
                no_layered(modal, &with_pole, "not converged", &e.to_string()),
                false,
            ));
        }
    };
    let (pair_at, pair_lines) =
        fit_overlapping_pairs((&coarsest, &finer), set, ema, &with_pole, &mut out);
    for (&(k, _), m) in with_pole.iter().zip(&out.modes) {
        let m = m.as_ref().map_err(|e| e.to_string()).and_then(physical);
        modal[k].layered = Some(m.as_ref().map(|m| m.core_shear_pa).map_err(Clone::clone));
        modal[k].layered_convergence = m.ok().copied();
    }
    // Each mode's band on its own (in parallel; sequential inside, so the same bits).
    let moved = MovedBySd::build(&coarsest, &plate, &job.uncertainty);
    let bands: Vec<_> = with_pole
        .par_iter()
        .zip(&out.modes)
        .zip(&pair_at)
        .map(|((&(k, target), m), pair)| {
            let m = m.as_ref().ok()?;
            let scatter = pole_scatter(ema, checks, modal[k].freq_hz);
            let models = (&coarsest, thick.as_ref().ok());
            let target = pair.as_ref().map_or(target, |p| p.0);
            let b = band(models, &moved, m, target, scatter, supports_at);
            Some(match pair {
                // Fitted to the FRFs on the real axis: it holds at the mode's real frequency.
                Some((_, sd, spread)) => b.map(|b| {
                    let mut b = b.with_source(crate::pair_fit::PAIR_FIT, *sd);
                    if let Some(spread) = spread {
                        b = b.with_source(crate::pair_fit::BAND_CHOICE, *spread);
                    }
                    LayeredBand {
                        found_at_hz: Complex64::new(modal[k].freq_hz, 0.0),
                        ..b
                    }
                }),
                None => b,
            })
        })
        .collect();
    for (&(k, _), b) in with_pole.iter().zip(bands) {
        if let Some(b) = b {
            modal[k].layered_band = Some(b.map_err(|e| e.to_string()));
        }
    }
    let meshes: Vec<String> = out
        .meshes
        .iter()
        .zip(&out.dofs)
        .map(|(&m, d)| format!("{} ({d} dofs)", plate.plan.level_label(m)))
        .collect();
    let cached = all_cached.load(std::sync::atomic::Ordering::Relaxed);
    let met = out.modes.iter().filter(|m| m.is_ok()).count();
    let line = format!(
        "C3D20, one per layer through the thickness ({}), plan: {}; meshes {} extrapolated to a frequency error below {:.1e} at {met} of {} modes; coarsest basis at G_ref {:.4e} Pa ({build_s:.1} s{}); targets: the EMA poles",
        match &thick {
            Ok(_) => format!("{THROUGH} on the coarsest mesh for the band's '{THROUGH_THICKNESS}'"),
            Err(why) => format!("{why}: '{THROUGH_THICKNESS}' not in the band"),
        },
        plate.plan.describe(),
        meshes.join(", "),
        settings.tolerance,
        out.modes.len(),
        g_ref,
        if cached { ", cached" } else { "" }
    );
    let line = if pair_lines.is_empty() {
        line
    } else {
        format!("{line}; {}", pair_lines.join("; "))
    };
    Ok(((Some(line), Some(coarsest)), cached))
}

/// Each overlapping pair of converged modes fitted to the FRFs ([`crate::pair_fit`]): their
/// G* in `out` replaced by the pair's; per target (as `with_pole`), the model's eigenvalue the
/// band is taken at and the fit's standard deviations where the mode is one of such a pair;
/// and per pair a line saying what was done (or why not: the modes keep their own poles' G*).
type PairAt = Option<(Complex64, [f64; 2], Option<[f64; 2]>)>;

fn fit_overlapping_pairs(
    (coarsest, finer): (&LayeredInverse, &[LayeredInverse]),
    set: &lamdyn_frf::FrfSet,
    ema: &EmaResult,
    with_pole: &[(usize, Complex64)],
    out: &mut lamdyn_layered::convergence::Converged,
) -> (Vec<PairAt>, Vec<String>) {
    let targets: Vec<Complex64> = with_pole.iter().map(|w| w.1).collect();
    let hz = |l: Complex64| l.re.max(0.0).sqrt() / (2.0 * std::f64::consts::PI);
    let pairs = crate::pair_fit::overlapping_pairs(&targets);
    let meshes = out.meshes.clone();
    let correction = |g: Complex64, rank: usize, target: Complex64| {
        lamdyn_layered::convergence::correction(coarsest, finer, &meshes, g, rank, target)
            .map_err(|e| e.to_string())
    };
    // Pairs in parallel, each sequential inside: the same bits on any thread count.
    let fits: Vec<_> = pairs
        .par_iter()
        .map(|&[a, b]| match (&out.modes[a], &out.modes[b]) {
            (Ok(ma), Ok(mb)) => Some(crate::pair_fit::fit_pair(
                coarsest,
                set,
                ema,
                [targets[a], targets[b]],
                [ma, mb],
                &correction,
            )),
            _ => None,
        })
        .collect();
    let mut at = vec![None; targets.len()];
    let mut lines = Vec::new();
    for (&[a, b], fit) in pairs.iter().zip(fits) {
        let label = format!(
            "the overlapping pair at {:.2} / {:.2} Hz",
            hz(targets[a]),
            hz(targets[b])
        );
        match fit {
            None => {}
            Some(Ok(fit)) => {
                for (i, k) in [a, b].into_iter().enumerate() {
                    if let Ok(m) = &mut out.modes[k] {
                        m.core_shear_pa = fit.g_pa;
                    }
                    at[k] = Some((fit.targets[i], fit.rel_sd, fit.band_choice_sd));
                }
                lines.push(format!(
                    "{label}: one G* for both, fitted to the FRFs over {:.2}-{:.2} Hz ({} lines) with both poles tied to the model (poles {:.3} / {:.3} Hz; misfit {:.4} with the EMA's poles, {:.4} fitted)",
                    fit.band_hz[0],
                    fit.band_hz[1],
                    fit.lines,
                    hz(fit.targets[0]),
                    hz(fit.targets[1]),
                    fit.misfit[0],
                    fit.misfit[1]
                ));
            }
            Some(Err(e)) => lines.push(format!(
                "{label}: no FRF fit ({e}), each mode from its own pole"
            )),
        }
    }
    (at, lines)
}

/// The layered stage's outcome when no mode gets a layered G*: each mode with a pole
/// (`with_pole`, indices into `modal`) says `why`, and so does the line (`what: why`).
fn no_layered(
    modal: &mut [CorePoint],
    with_pole: &[(usize, Complex64)],
    what: &str,
    why: &str,
) -> LayeredOutcome {
    for &(k, _) in with_pole {
        modal[k].layered = Some(Err(why.to_string()));
    }
    (Some(format!("{what}: {why}")), None)
}

/// The layered inverse's start where the effective-modulus route gives none (a stack of other
/// than three layers, a mode it cannot invert): the first core layer's `shear_pa` with its
/// `loss_factor`, if the job gives them, else 10 MPa with a loss factor of 0.5 (a PVB-like
/// interlayer near room temperature, method notes section 6). The basis spans a factor four
/// about it and the secant iteration moves further; a core far softer or stiffer (an EVA at
/// 1 MPa, an ionoplast at 100 MPa) wants its `shear_pa`.
fn start_without_sandwich(job: &Job) -> Complex64 {
    let core = job
        .stack
        .layered_cores()
        .ok()
        .and_then(|c| c.first().copied())
        .and_then(|k| job.stack.layers.get(k));
    match core.and_then(|l| l.shear_pa.map(|g| (g, l.loss_factor.unwrap_or(0.5)))) {
        Some((g, eta)) if g.is_finite() && g > 0.0 && eta.is_finite() && eta >= 0.0 => {
            Complex64::new(g, eta * g)
        }
        _ => Complex64::new(10e6, 5e6),
    }
}

/// The core's G* at `f_hz` for which the paper's homogenization of the job's whole stack
/// (eqs. 11–32, any number of layers: [`lamdyn_material::laminate::LayerStack::homogenize`],
/// plate kinematics, every core layer at the one G*) gives the fitted laminate modulus
/// `e_eff`: the layered inverse's start on a stack the sandwich inverses do not take. A secant
/// iteration on ln G* from `guess`; `None` when it does not settle in 40 steps. The paper's
/// model is tens of per cent off per mode (the reason for the layered route), a start well
/// inside the factor four the layered basis spans; a fixed guess can sit so far off that a
/// pole is matched to the wrong mode of the model.
fn homogenized_start(
    job: &Job,
    f_hz: f64,
    e_eff: Complex64,
    guess: Complex64,
) -> Option<Complex64> {
    use lamdyn_material::laminate::Kinematics;
    let cores = job.stack.layered_cores().ok()?;
    let omega = 2.0 * std::f64::consts::PI * f_hz;
    let kinematics = Kinematics::Plate {
        poisson: job.stack.layers.first()?.poisson,
    };
    // ln E_eff(G*) − ln E_eff,fitted for G* = e^z.
    let residual = |z: Complex64| -> Option<Complex64> {
        let g = z.exp();
        if !(g.re > 0.0 && g.im >= 0.0 && g.is_finite()) {
            return None;
        }
        let mut spec = job.stack.clone();
        for &k in &cores {
            let l = &mut spec.layers[k];
            (l.young_pa, l.young_law, l.shear_law) = (None, None, None);
            l.shear_pa = Some(g.re);
            l.loss_factor = Some(g.im / g.re);
        }
        let h = spec
            .to_layer_stack()
            .ok()?
            .homogenize(omega, kinematics)
            .ok()?;
        Some(h.e_eff.ln() - e_eff.ln())
    };
    if !(e_eff.re > 0.0 && e_eff.is_finite()) {
        return None;
    }
    let (mut z0, mut z1) = (guess.ln(), (guess * 1.1).ln());
    let (mut r0, mut r1) = (residual(z0)?, residual(z1)?);
    for _ in 0..40 {
        if r1.norm() < 1e-10 {
            return Some(z1.exp());
        }
        let slope = (r1 - r0) / (z1 - z0);
        if !slope.is_finite() || slope.norm() == 0.0 {
            return None;
        }
        // Steps of at most 1 in |Δ ln G*|: a factor e in |G*|, 1 rad in phase.
        let mut step = -r1 / slope;
        if step.norm() > 1.0 {
            step /= step.norm();
        }
        let z2 = z1 + step;
        let r2 = residual(z2)?;
        (z0, r0, z1, r1) = (z1, r1, z2, r2);
    }
    None
}

/// A converged mode whose core is passive (G' > 0, G'' > 0), else why not: a pole damped
/// less than the faces and supports alone damp that mode (an EMA damping too low, dashpots
/// too strong) gives G'' < 0, which no material has.
fn physical(
    m: &lamdyn_layered::convergence::ConvergedMode,
) -> std::result::Result<&lamdyn_layered::convergence::ConvergedMode, String> {
    let g = m.core_shear_pa;
    if g.re > 0.0 && g.im > 0.0 {
        Ok(m)
    } else {
        Err(format!(
            "the pole gives a core G* = {:.4e} {:+.4e}i Pa, not a passive material (G' and G'' must be positive): its damping is below what the faces and the supports' dashpots give that mode, or the mode is a support's",
            g.re, g.im
        ))
    }
}

/// The 95 % band of the layered result at one mode and the sources it is made of (module
/// docs).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LayeredBand {
    /// Per source (an input's name, "EMA pole", "inputs beyond first order",
    /// "discretization"): the relative standard deviations of G' and of η it gives.
    pub sources: Vec<(String, [f64; 2])>,
    /// Half-widths h of the 95 % band of ln G' and ln η: 1.96 √(Σ σ²); the band of G' is
    /// [G' e^−h, G' e^h].
    pub half_width: [f64; 2],
    /// Per input known within a tolerance: its name, its prior's relative standard deviation
    /// and the signed ∂ln G'/∂ln θ, ∂ln η/∂ln θ (what the joint law fit needs).
    pub inputs: Vec<(String, f64, [f64; 2])>,
    /// Per input, the second order ∂²ln G'/∂(ln θ)², ∂²ln η/∂(ln θ)² (`second_order`; zero
    /// for an input with a wide prior, which the law fit re-linearises instead).
    pub second_order: Vec<[f64; 2]>,
    /// Per input, how far (ln θ/θ_job) the model's value lies from the job file's: 0 but for
    /// the supports of a re-run at the supports the law found ([`supports_found`]).
    pub inputs_at: Vec<f64>,
    /// The complex frequency ω*/2π = √(−p²)/2π of the pole p the core was matched to, Hz:
    /// where the found G* holds (lamdyn_fit::joint's module docs).
    pub found_at_hz: Complex64,
    /// G* as found at `found_at_hz`, Pa (the mode's `layered` value is it moved to the real
    /// frequency by [`to_real_frequency`]).
    pub found_pa: Complex64,
    /// The mode's rank among the coarsest model's elastic modes and that model's eigenvalue at
    /// `found_pa`, rad²/s²: where the sensitivities were taken, and where the joint fit
    /// re-linearises ([`fit_law`]).
    pub coarse: (usize, Complex64),
}

impl LayeredBand {
    /// The band with one more source of relative standard deviations `sd` (of G' and η).
    pub fn with_source(mut self, name: &str, sd: [f64; 2]) -> Self {
        self.sources.push((name.to_string(), sd));
        self.half_width = half_width(&self.sources);
        self
    }

    /// The source with the largest standard deviation of G' (`part` 0) or η (1).
    pub fn dominant(&self, part: usize) -> &str {
        self.sources
            .iter()
            .max_by(|a, b| a.1[part].total_cmp(&b.1[part]))
            .map_or("-", |s| s.0.as_str())
    }
}

/// The 95 % half-widths of ln G' and ln η of independent `sources` (relative standard
/// deviations): 1.96 √(Σ σ²) per part ([`LayeredBand::half_width`]).
fn half_width(sources: &[(String, [f64; 2])]) -> [f64; 2] {
    [0, 1].map(|k| 1.96 * sources.iter().map(|s| s.1[k].powi(2)).sum::<f64>().sqrt())
}

/// The identifications beside the whole that a pole's scatter is read from (`pole_scatter`).
#[derive(Debug, Clone, Default)]
pub struct PoleChecks {
    /// The identification on each group of responses (stage "ema by response group").
    pub groups: Vec<EmaResult>,
    /// The identification at other highest model orders (stage "ema at other model orders").
    pub orders: Vec<EmaResult>,
    /// The identification without each hammer hit in turn (stage "ema without each hit"):
    /// empty, or one per hit.
    pub hits: Vec<EmaResult>,
}

/// What the identification's noise does to one mode's pole ([`pole_scatter`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct PoleScatter {
    /// Standard deviations (Hz, damping ratio) from the stabilization diagram, the response
    /// groups and the model orders; `None` when nothing measured them.
    noise: Option<[f64; 2]>,
    /// The delete-one-hit jackknife's standard deviations (Hz, damping ratio)
    /// ([`hit_jackknife`]); `None` without enough hits.
    hits: Option<[f64; 2]>,
}

/// The band's source made of the delete-one-hit jackknife of the identification
/// (`hit_jackknife`): in the mode's own band, not in the joint law fit's weights
/// (`mode_points` says why).
pub const HITS_JACKKNIFE: &str = "EMA: hits left out (jackknife)";

/// The scatter of the pole of the EMA mode nearest `f` ([`PoleScatter`]): as `noise`, the
/// larger, per part, of the scatter of its stable poles in the stabilization diagram
/// ([`stabilization_scatter`]) and of the spread of the poles the response groups' own
/// identifications find for it ([`group_spread`]), both estimates of the noise's effect, and
/// with it in quadrature the spread across model orders ([`order_spread`]), the method's; as
/// `hits`, the delete-one-hit jackknife ([`hit_jackknife`]).
fn pole_scatter(ema: &EmaResult, checks: &PoleChecks, f: f64) -> PoleScatter {
    let Some(mode) = crate::stages::nearest_within(ema, f, 0.02) else {
        return PoleScatter::default();
    };
    let m = &ema.modes[mode];
    let noise = match (
        stabilization_scatter(ema, mode),
        group_spread(&same_pole(ema, mode, &checks.groups)),
    ) {
        (Some(a), Some(b)) => Some([a[0].max(b[0]), a[1].max(b[1])]),
        (a, b) => a.or(b),
    };
    let orders = order_spread(
        [m.freq_hz, m.damping_ratio],
        &same_pole(ema, mode, &checks.orders),
    );
    let noise = match (noise, orders) {
        (Some(a), Some(b)) => Some([a[0].hypot(b[0]), a[1].hypot(b[1])]),
        (a, b) => a.or(b),
    };
    PoleScatter {
        noise,
        hits: hit_jackknife(&same_pole(ema, mode, &checks.hits)),
    }
}

/// The delete-one jackknife's standard deviation (Hz, damping ratio) of a pole from its
/// estimates `found` without each hit in turn, n ≥ [`crate::measurement::JACKKNIFE_HITS`] of
/// them: √((n − 1)/n Σ (θ_i − θ̄)²) [Efron & Tibshirani 1993, eq. 11.5]. A hit missing from
/// n − 1 averages at a time moves the pole by 1/(n − 1) of what it does to the mean, hence the
/// factor n − 1 over the sample variance. It measures what the hits' noise does to the pole,
/// the identification's bias from it included, where the stabilization diagram and the
/// response groups read the same noisy FRFs and agree with each other: on the damped-sandwich
/// example's hammer data (seed 1, five hits) the first mode's damping ratio came out 2.473,
/// 2.475, 2.480, 2.525 and 2.474 % without each hit, 2.527 % from all five and 2.475 % from
/// noise-free hits; its jackknife sd is 0.040 %, the response groups' 0.01 %.
fn hit_jackknife(found: &[[f64; 2]]) -> Option<[f64; 2]> {
    if found.len() < crate::measurement::JACKKNIFE_HITS {
        return None;
    }
    let n = found.len() as f64;
    Some(sample_sd(found).map(|sd| sd * (n - 1.0) / n.sqrt()))
}

/// Each other identification's pole (Hz, damping ratio) of EMA mode `mode`: its pole nearest
/// the mode, within 1 % and nearer it than any other mode of the whole.
fn same_pole(ema: &EmaResult, mode: usize, others: &[EmaResult]) -> Vec<[f64; 2]> {
    let m = &ema.modes[mode];
    others
        .iter()
        .filter_map(|g| {
            let k = crate::stages::nearest_within(g, m.freq_hz, 0.01)?;
            let p = &g.modes[k];
            (crate::stages::nearest_within(ema, p.freq_hz, 0.02) == Some(mode))
                .then_some([p.freq_hz, p.damping_ratio])
        })
        .collect()
}

/// How much a pole (Hz, damping ratio) depends on the highest model order of the
/// identification: the sample standard deviation of the whole's estimate `main` and those
/// `found` at the other orders ([`crate::stages::OTHER_ORDERS`]); `None` without another. It is
/// not divided by √n: the orders are not independent draws that average out, each is an
/// equally good choice of a setting, and the whole's estimate is one of them.
fn order_spread(main: [f64; 2], found: &[[f64; 2]]) -> Option<[f64; 2]> {
    if found.is_empty() {
        return None;
    }
    let all: Vec<[f64; 2]> = std::iter::once(main).chain(found.iter().copied()).collect();
    Some(sample_sd(&all))
}

/// The standard error of the mean of the response groups' estimates (Hz, damping ratio) of
/// one pole: their sample standard deviation over √n, n ≥ 2 groups. The whole set reads the
/// pole from all n groups' responses at once, so its estimate is about as uncertain as their
/// mean [a delete-a-group jackknife; Efron & Tibshirani 1993, ch. 11].
fn group_spread(found: &[[f64; 2]]) -> Option<[f64; 2]> {
    if found.len() < 2 {
        return None;
    }
    let root_n = (found.len() as f64).sqrt();
    Some(sample_sd(found).map(|sd| sd / root_n))
}

/// Sample standard deviation (n − 1) of each part of `points` (n ≥ 2).
pub(crate) fn sample_sd(points: &[[f64; 2]]) -> [f64; 2] {
    let n = points.len() as f64;
    let sd = |k: usize| {
        let mean = points.iter().map(|p| p[k]).sum::<f64>() / n;
        (points.iter().map(|p| (p[k] - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    };
    [sd(0), sd(1)]
}

/// Standard deviations (Hz, damping ratio) of the stable poles of the stabilization diagram
/// within 1 % of EMA mode `mode` and nearer it than any other mode (a close pair's poles are
/// not pooled), at least three; else `None`.
fn stabilization_scatter(ema: &EmaResult, mode: usize) -> Option<[f64; 2]> {
    let near: Vec<[f64; 2]> = ema
        .diagram
        .iter()
        .filter(|p| {
            p.is_stable() && crate::stages::nearest_within(ema, p.freq_hz, 0.01) == Some(mode)
        })
        .map(|p| [p.freq_hz, p.damping])
        .collect();
    (near.len() >= 3).then(|| sample_sd(&near))
}

/// The relative standard deviation of the job's prior on `input` (`[uncertainty]`; a
/// thickness's sd in m over the first face's or core's thickness in `plate`).
fn input_rel_sd(
    input: Input,
    plate: &LayeredPlate,
    priors: &crate::job::UncertaintyOptions,
) -> f64 {
    let thickness = |core: bool| {
        plate
            .layers
            .iter()
            .find(|l| l.young_pa.is_none() == core)
            .map_or(f64::INFINITY, |l| l.thickness_m)
    };
    match input {
        Input::FaceModulus => priors.face_modulus_rel_sd,
        Input::FaceThickness => priors.thickness_sd_m / thickness(false),
        Input::CoreThickness => priors.thickness_sd_m / thickness(true),
        Input::FaceDensity | Input::CoreDensity => priors.density_rel_sd,
        Input::SupportStiffness => priors.support_stiffness_rel_sd,
        Input::SupportDamping => priors.support_damping_rel_sd,
    }
}

/// Each input's prior and the coarsest model moved by ±1 sd of each input with a prior below
/// [`WIDE_PRIOR`], built once for every mode's band ([`band`], [`second_order`]): neither
/// depends on the mode.
struct MovedBySd {
    /// Per input: its prior's relative sd ([`input_rel_sd`]) and the models at +1 sd and
    /// −1 sd (none for a wide or zero prior, or a move that failed).
    models: Vec<(Input, f64, Option<[LayeredInverse; 2]>)>,
}

impl MovedBySd {
    /// The moves of `coarsest` by the priors of `plate`'s inputs in `priors`.
    fn build(
        coarsest: &LayeredInverse,
        plate: &LayeredPlate,
        priors: &crate::job::UncertaintyOptions,
    ) -> Self {
        let models = coarsest
            .inputs()
            .into_par_iter()
            .map(|input| {
                let sd = input_rel_sd(input, plate, priors);
                let moved = (sd > 0.0 && sd < WIDE_PRIOR)
                    .then(|| {
                        let at = |sign: f64| coarsest.with_inputs_moved(&[(input, sign * sd)]).ok();
                        Some([at(1.0)?, at(-1.0)?])
                    })
                    .flatten();
                (input, sd, moved)
            })
            .collect();
        Self { models }
    }

    /// The models at ±1 sd of `input`, if it has them.
    fn of(&self, input: Input) -> Option<&[LayeredInverse; 2]> {
        self.models
            .iter()
            .find(|(i, _, _)| *i == input)
            .and_then(|(_, _, m)| m.as_ref())
    }

    /// The relative sd of the prior on `input` (0 for an input the model has no derivative for).
    fn rel_sd(&self, input: Input) -> f64 {
        self.models
            .iter()
            .find(|(i, _, _)| *i == input)
            .map_or(0.0, |(_, sd, _)| *sd)
    }
}

/// The band of one converged mode (module docs).
fn band(
    (coarsest, thick): (&LayeredInverse, Option<&LayeredInverse>),
    moved: &MovedBySd,
    mode: &lamdyn_layered::convergence::ConvergedMode,
    target: Complex64,
    scatter: PoleScatter,
    supports_at: [f64; 2],
) -> std::result::Result<LayeredBand, LayeredError> {
    // At the converged G*, about the coarsest model's own eigenvalue there: the ladder
    // corrects that model by a factor per mode, and its relative sensitivities there agree
    // with a 21 x 21 mesh's within 6 % on the demo roof (at its own, coarse solution they fall
    // 5-40 % short; example roof_sensitivity).
    let rank = mode.rank;
    let g0 = mode.core_shear_pa;
    // The coarsest model's pole at G*, the dashpots at its own frequency: what its inverse
    // maps back to G* (the moved models' inverses below start from it).
    let at = coarsest
        .pole_eigenvalue(g0, rank, target)
        .ok_or_else(|| LayeredError::Solver(format!("mode {} lost", rank + 1)))?;
    let sens: ModeSensitivity = coarsest.sensitivity(g0, rank, at)?;
    // A change of the measured eigenvalue acts through the corrected model λ_∞ = (λ_∞/λ_c) λ_c.
    let to_model = at / target;
    let inputs: Vec<(String, f64, [f64; 2])> = sens
        .inputs
        .iter()
        .map(|e| {
            let rel_sd = moved.rel_sd(e.input);
            (e.input.name().to_string(), rel_sd, log_parts(e.dg_dln, g0))
        })
        .collect();
    let inputs_at = sens
        .inputs
        .iter()
        .map(|e| match e.input {
            Input::SupportStiffness => supports_at[0],
            Input::SupportDamping => supports_at[1],
            _ => 0.0,
        })
        .collect();
    let mut sources: Vec<(String, [f64; 2])> = inputs
        .iter()
        .map(|(name, sd, d)| (name.clone(), d.map(|x| (x * sd).abs())))
        .collect();
    // λ = ω²(1 + iη), η = 2ζ: δλ = 2λ δf/f from the frequency, i Re λ 2δζ from the damping.
    let f = target.re.sqrt() / (2.0 * std::f64::consts::PI);
    let pole_source = |[sd_f, sd_zeta]: [f64; 2]| {
        let from_f = relative_parts(
            sens.dg_for_eigenvalue(to_model * target * (2.0 * sd_f / f)),
            g0,
        );
        let from_zeta = relative_parts(
            sens.dg_for_eigenvalue(to_model * Complex64::new(0.0, 2.0 * target.re * sd_zeta)),
            g0,
        );
        [from_f[0].hypot(from_zeta[0]), from_f[1].hypot(from_zeta[1])]
    };
    if let Some(sd) = scatter.noise {
        sources.push(("EMA pole".into(), pole_source(sd)));
    }
    if let Some(sd) = scatter.hits {
        sources.push((HITS_JACKKNIFE.into(), pole_source(sd)));
    }
    if let Some(l) = thick.and_then(|t| through_thickness_eigenvalue(t, g0, rank, at)) {
        // The one-element model is stiffer by λ₁ − λ₂: the G* a measured pole finds on it is
        // off by the dG that change of eigenvalue maps to.
        let dg = sens.dg_for_eigenvalue(at - l);
        sources.push((THROUGH_THICKNESS.into(), log_parts(dg, g0).map(f64::abs)));
    }
    let curvature = second_order(moved, &sens, &inputs, at, g0);
    let second_order: Vec<[f64; 2]> = curvature.iter().map(|c| c.second).collect();
    let [modelled, beyond] = second_order_sd(&inputs, &curvature);
    sources.push((SECOND_ORDER.into(), modelled));
    sources.push((BEYOND_SECOND_ORDER.into(), beyond));
    sources.push((
        "discretization".into(),
        [mode.storage_band / 1.96, mode.loss_band / 1.96],
    ));
    Ok(LayeredBand {
        half_width: half_width(&sources),
        sources,
        inputs,
        second_order,
        inputs_at,
        found_at_hz: target.sqrt() / (2.0 * std::f64::consts::PI),
        found_pa: g0,
        coarse: (rank, at),
    })
}

/// Elements per layer through the thickness of the model that checks the ladder's one
/// ([`THROUGH_THICKNESS`]).
const THROUGH: usize = 2;

/// The band's source for what one element per layer through the thickness leaves: per mode,
/// the G* change that the coarsest mesh with two (`THROUGH`) elements per layer finds at the same
/// pole, |ln G*₂ − ln G*₁| to first order through the mode's sensitivity (`band`), taken as one
/// standard deviation. The ladder refines in plane only; on the laminates of example
/// `thickness_convergence` one element per layer is within 2.5e-4 in frequency and 0.1 % in G'
/// of [2, 4, 2], but a core thick against its faces, or one whose thickness nears a shear
/// wavelength, is not.
pub const THROUGH_THICKNESS: &str = "through the thickness";

/// The eigenvalue at `g` of the mode of `thick` nearest `at` among elastic ranks `rank` − 1 ..=
/// `rank` + 1 (two elements through a layer can swap a close pair's order), within 1 % of
/// it; `None` otherwise.
fn through_thickness_eigenvalue(
    thick: &LayeredInverse,
    g: Complex64,
    rank: usize,
    at: Complex64,
) -> Option<Complex64> {
    (rank.saturating_sub(1)..=rank + 1)
        .filter_map(|r| thick.pole_eigenvalue(g, r, at))
        .min_by(|a, b| (a - at).norm().total_cmp(&(b - at).norm()))
        .filter(|l| (l - at).norm() <= 0.01 * at.norm())
}

/// The second order of the inputs' effect on a mode's core, per input: ∂²ln x/∂(ln θ_j)² for
/// x = G' and η (the "inputs beyond first order" of [`LayeredBand`]). Each input j with a prior
/// s_j below [`WIDE_PRIOR`] (the wide ones are re-linearised by [`fit_law`] instead) is moved
/// by ±s_j on the coarsest model (once for all modes, [`MovedBySd`]) and the mode's coarse
/// eigenvalue inverted there: the second
/// difference d_j = ln x₊ + ln x₋ − 2 ln x₀ gives d_j/s_j². On a glass laminate the core found
/// is far from linear in the faces: on the small test laminate a 1 % face modulus moves G' at
/// its 103 Hz mode by −10.9 % to first order with a second difference of −3.8 % (η: −26.7 %
/// and +8.0 %), and with the faces drawn from their priors the first-order points missed the
/// truth by up to 2.5 % in G' where their other sources said 0.4 %. The joint law fit models
/// this term through one curvature along the inputs' combined shift
/// ([`lamdyn_fit::joint::shared_curvature`]: the differences of the face inputs are one
/// curvature times their e_j², and summed input by input without the cross terms they moved
/// the points further from the truth than the first order alone); the per-mode band takes
/// its root mean square over the priors ([`second_order_sd`]) as a source. An input whose
/// moved inversion fails gets zero.
fn second_order(
    moved: &MovedBySd,
    sens: &ModeSensitivity,
    inputs: &[(String, f64, [f64; 2])],
    at: Complex64,
    g0: Complex64,
) -> Vec<InputCurvature> {
    let log = |x: Complex64| [x.re.ln(), (x.im / x.re).ln()];
    let c = log(g0);
    sens.inputs
        .iter()
        .zip(inputs)
        .map(|(e, (_, sd, first))| {
            let Some([up, down]) = moved.of(e.input) else {
                return InputCurvature::default();
            };
            let found = |m: &LayeredInverse| -> Option<[f64; 2]> {
                let g = m.invert(at, g0).ok()?.core_shear_pa;
                (g.re > 0.0 && g.im > 0.0).then(|| log(g))
            };
            match (found(up), found(down)) {
                (Some(p), Some(m)) => InputCurvature {
                    second: [0, 1].map(|k| (p[k] + m[k] - 2.0 * c[k]) / (sd * sd)),
                    third_at_sd: [0, 1].map(|k| 0.5 * (p[k] - m[k]) - first[k] * sd),
                },
                _ => InputCurvature::default(),
            }
        })
        .collect()
}

/// One input's effect on a mode's core beyond first order, from its ±1 sd moves
/// ([`second_order`]); zero where it was not taken.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct InputCurvature {
    /// ∂²ln x/∂(ln θ)² for x = G', η: the second difference over s².
    second: [f64; 2],
    /// The odd part the first order leaves at 1 sd, ½(ln x₊ − ln x₋) − e s: the third-order
    /// term x⁽³⁾ s³/6 (and the first order's own error).
    third_at_sd: [f64; 2],
}

/// The standard deviations (G', η) of what the inputs do beyond first order under their
/// priors, δ_j ~ N(0, s_j²), as two sources:
/// - **modelled** by the joint law fit: ½ κ u² with u = Σ_j e_j δ_j, σ_u² = Σ_j (e_j s_j)² over
///   the inputs with a second order and κ the curvature along u
///   ([`lamdyn_fit::joint::shared_curvature`]); its root mean square is (√3/2)|κ| σ_u²;
/// - **not modelled**, the point's own noise in that fit: what the one curvature leaves of each
///   input's second difference, (√3/2)|c_j − κ e_j²| s_j², and its third order at 1 sd t_j
///   ([`InputCurvature::third_at_sd`]: t_j z³ with z ~ N(0, 1), root mean square √15 |t_j|),
///   in quadrature. A mode whose core is far from quadratic in the inputs (a mode the faces
///   move by tens of per cent per sd) so weighs less in the law, instead of pulling the
///   shared inputs by a slope that holds only near nominal.
fn second_order_sd(
    inputs: &[(String, f64, [f64; 2])],
    curvature: &[InputCurvature],
) -> [[f64; 2]; 2] {
    let effects: Vec<[f64; 2]> = inputs.iter().map(|i| i.2).collect();
    let sds: Vec<f64> = inputs.iter().map(|i| i.1).collect();
    let second: Vec<[f64; 2]> = curvature.iter().map(|c| c.second).collect();
    let kappa = lamdyn_fit::joint::shared_curvature(&effects, &second, &sds);
    let parts = [0, 1].map(|k| {
        let (mut var_u, mut rest) = (0.0, 0.0);
        for (j, ((e, s), c)) in effects.iter().zip(&sds).zip(curvature).enumerate() {
            if !lamdyn_fit::joint::has_second_order(&second, j) {
                continue;
            }
            var_u += (e[k] * s).powi(2);
            rest += 0.75 * ((c.second[k] - kappa[k] * e[k] * e[k]) * s * s).powi(2)
                + THIRD_ORDER_MOMENT * c.third_at_sd[k].powi(2);
        }
        [(0.75 * (kappa[k] * var_u).powi(2)).sqrt(), rest.sqrt()]
    });
    [[parts[0][0], parts[1][0]], [parts[0][1], parts[1][1]]]
}

/// E(z⁶) = 15 for z ~ N(0, 1): the mean square of the third-order remainder t z³ at δ = z s
/// ([`second_order_sd`]). An odd part that is the first order's own error instead (t z) would
/// have mean square t², so this is the conservative reading of the two; on the in-band foam
/// roof 1 instead of 15 left the bands within 1 % of their width (the remainder that matters
/// there is the curvature's, not the odd part's).
const THIRD_ORDER_MOMENT: f64 = 15.0;

/// The band's source of the inputs' second order that the joint law fit models
/// ([`second_order_sd`]).
const SECOND_ORDER: &str = "inputs beyond first order";

/// The band's source of what the inputs do beyond the joint fit's second-order model: each
/// point's own noise there ([`second_order_sd`]).
const BEYOND_SECOND_ORDER: &str = "inputs beyond second order";

/// The job's core law for the joint fit (`inverse.core_law`), if any.
fn core_laws(choice: crate::job::CoreLawChoice) -> Vec<CoreLaw> {
    use crate::job::CoreLawChoice as C;
    match choice {
        C::Auto => vec![CoreLaw::FractionalZener, CoreLaw::GeneralizedMaxwell],
        C::FractionalZener => vec![CoreLaw::FractionalZener],
        C::GeneralizedMaxwell => vec![CoreLaw::GeneralizedMaxwell],
        C::PerMode => vec![CoreLaw::PerMode],
        C::None => Vec::new(),
    }
}

/// A law to fit: the law and, for the generalized Maxwell law, where its relaxation times
/// sit (offset in their spacing, [`lamdyn_fit::joint::prony_relaxation_times_shifted`]).
type Candidate = (CoreLaw, f64);

/// The offsets of a generalized Maxwell law's relaxation times tried ([`fit_law`]): a quarter
/// of their spacing apart, which the modes cannot choose between where they lie far apart.
const PRONY_OFFSETS: [f64; 4] = [0.0, 0.25, 0.5, 0.75];

/// The candidates of a job's law choice ([`core_laws`], each generalized Maxwell law on every
/// offset of [`PRONY_OFFSETS`]).
fn candidates(choice: crate::job::CoreLawChoice) -> Vec<Candidate> {
    core_laws(choice)
        .into_iter()
        .flat_map(|law| match law {
            CoreLaw::GeneralizedMaxwell => PRONY_OFFSETS.iter().map(|&o| (law, o)).collect(),
            _ => vec![(law, 0.0)],
        })
        .collect()
}

/// The largest difference of Akaike criteria at which another law can still weigh
/// [`lamdyn_fit::joint::LEAST_WEIGHT`] in the band ([`CoreLawFit::with_alternatives`]): its
/// weight is at most e^{−Δ/2}, so Δ = −2 ln(least weight), 13.8 for 1e-3. Laws beyond it are
/// not fitted again.
fn akaike_reach() -> f64 {
    -2.0 * lamdyn_fit::joint::LEAST_WEIGHT.ln()
}

/// Of the laws fitted to the same modes, the index of the one with the lowest Akaike criterion
/// ([`CoreLawFit::akaike`]) and why it was chosen; the first failure when none fitted.
fn lowest_akaike(
    fits: &[(Candidate, std::result::Result<CoreLawFit, String>)],
) -> Option<std::result::Result<(usize, Option<String>), String>> {
    let first_error = fits.iter().find_map(|f| f.1.clone().err());
    let mut ok: Vec<(usize, &CoreLawFit)> = fits
        .iter()
        .enumerate()
        .filter_map(|(k, f)| Some((k, f.1.as_ref().ok()?)))
        .collect();
    ok.sort_by(|a, b| a.1.akaike().total_cmp(&b.1.akaike()));
    let Some(&(best, best_fit)) = ok.first() else {
        return first_error.map(Err);
    };
    let describe = |f: &CoreLawFit| {
        format!(
            "{} (chi2 {:.2}, {} parameters: AICc {:.2})",
            f.form(),
            f.chi2,
            f.parameters.len() - f.inputs().len(),
            f.akaike()
        )
    };
    let others: Vec<String> = ok[1..].iter().map(|o| describe(o.1)).collect();
    let why = (!others.is_empty()).then(|| {
        format!(
            "chosen by Akaike's criterion with the small-sample correction: {} over {}",
            describe(best_fit),
            others.join(", ")
        )
    });
    Some(Ok((best, why)))
}

/// The core's law fitted to every mode with a layered result and a band, jointly with the
/// inputs known within a tolerance ([`lamdyn_fit::joint`]): each mode brings its G*, its
/// signed sensitivities to the inputs and its own noise (the pole's scatter and the
/// discretization, the band's other sources). None when the job asks for no law or no mode
/// has a band. Of several laws (`inverse.core_law = "auto"`) the one Akaike's criterion
/// favours is chosen on the modes' own noise (`Weights::Shape`) and fitted again with the
/// inputs beyond second order as each point's noise too (`Weights::Law`).
///
/// With the `coarsest` model and an input with a wide prior ([`WIDE_PRIOR`]: the supports')
/// the fit is re-linearised (Gauss–Newton on the inputs): the sensitivities are first order
/// at the nominal inputs, and an input the modes pin far from nominal (a support's stiffness
/// known to 20 % moves G' by 2–6 times its own change on a mode mixed with the bounce) leaves
/// that linearisation behind. So the coarsest model is moved to the inputs the fit found
/// ([`LayeredInverse::with_inputs_moved`]), each mode's coarse eigenvalue is inverted there
/// and its sensitivities taken there; the mode's point
/// moves by the ratio of the two coarse solutions, and the fit runs again with the priors
/// still about nominal ([`InputPrior::at`]), until the inputs move by less than 5 % of their
/// prior sd (at most [`RELINEARISATIONS`] times; a mode the moved model cannot match ends
/// the iteration at the last fit).
pub fn fit_law(
    job: &Job,
    modal: &[CorePoint],
    coarsest: Option<&LayeredInverse>,
) -> Option<std::result::Result<CoreLawFit, String>> {
    let candidates = candidates(job.inverse.core_law);
    if candidates.len() < 2 {
        let law = *candidates.first()?;
        return fit_law_with(law, modal, coarsest, Weights::Law);
    }
    // The choice on the modes' own noise, the law's values and bands with all of it.
    let shapes: Vec<_> = candidates
        .into_iter()
        .filter_map(|c| Some((c, fit_law_with(c, modal, coarsest, Weights::Shape)?)))
        .collect();
    let (chosen, why) = match lowest_akaike(&shapes)? {
        Ok(c) => c,
        Err(e) => return Some(Err(e)),
    };
    let criterion = |k: usize| shapes[k].1.as_ref().map_or(f64::INFINITY, |f| f.akaike());
    let own = criterion(chosen);
    // The laws that fit the modes nearly as well share the band (model selection).
    let others: Vec<(f64, CoreLawFit)> = (0..shapes.len())
        .filter(|&k| k != chosen && criterion(k) - own < akaike_reach())
        .filter_map(|k| {
            let fit = fit_law_with(shapes[k].0, modal, coarsest, Weights::Law)?.ok()?;
            Some((criterion(k), fit))
        })
        .collect();
    let fit = fit_law_with(shapes[chosen].0, modal, coarsest, Weights::Law)?;
    Some(fit.map(|f| {
        let mut f = f.with_alternatives(own, others);
        if let Some(why) = why {
            f.selection = Some(format!(
                "{why}, each fitted with the modes' own noise (the inputs beyond second order left out: they act on every mode at once, and as independent noise they hide the law's shape); the law's values and bands are from its fit with them, and its band holds the others' spread where their Akaike weights reach 1e-3"
            ));
        }
        f
    }))
}

/// Which of a mode's band sources weigh its point in the joint law fit ([`fit_law`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Weights {
    /// Every source but the inputs' first and second order (which the fit models): the
    /// law's values and bands.
    Law,
    /// Those without the inputs beyond second order too: the choice between laws by Akaike's
    /// criterion. That remainder is a function of the inputs all modes share; taken as noise
    /// independent per mode it flattens the differences between the laws' χ² (on the free
    /// roof with a Prony core the fractional Zener law, 6.5 % off, won over the generalized
    /// Maxwell law).
    Shape,
}

/// The job with its supports moved to those the joint law found, and how far (ln stiffness,
/// ln damping), when the law moved the supports' stiffness or damping significantly: by more
/// than [`SUPPORTS_RERUN`] and beyond its 95 % interval about the job's value. The mesh ladder
/// then runs again there ([`crate::stages`]): re-linearising the fit on the coarsest model
/// cannot bring back a mode the ladder lost at the job's supports (the mixed modes of a part
/// on foam lie elsewhere when the foam is 20 % stiffer).
pub fn supports_found(
    job: &Job,
    law: Option<&std::result::Result<CoreLawFit, String>>,
) -> Option<(Job, [f64; 2])> {
    let Some(Ok(law)) = law else { return None };
    if job.inverse.supports.is_empty() {
        return None;
    }
    let found = |input: Input| {
        law.inputs()
            .iter()
            .find(|p| p.name == input.name())
            .map(|p| (p.value, p.ci95[0] > 0.0 || p.ci95[1] < 0.0))
    };
    let (k, c) = (
        found(Input::SupportStiffness).unwrap_or((0.0, false)),
        found(Input::SupportDamping).unwrap_or((0.0, false)),
    );
    let moved = |(d, significant): (f64, bool)| significant && d.abs() > SUPPORTS_RERUN;
    if !(moved(k) || moved(c)) {
        return None;
    }
    let mut out = job.clone();
    for s in &mut out.inverse.supports {
        s.stiffness_n_m = s.stiffness_n_m.map(|v| v * k.0.exp());
        s.damping_n_s_m = s.damping_n_s_m.map(|v| v * c.0.exp());
    }
    Some((out, [k.0, c.0]))
}

/// The smallest change (ln) of the supports' stiffness or damping found by the joint law that
/// runs the mesh ladder again at the supports found ([`supports_found`]); below it the
/// re-linearised fit holds it.
pub const SUPPORTS_RERUN: f64 = 0.05;

/// The smallest prior standard deviation (relative) of an input that makes the joint fit
/// re-linearise ([`fit_law`]): the supports' (20 %, 30 % by default). With the faces' priors
/// alone (1 %, a few per cent on a thickness) the first order holds and the fit is not
/// re-linearised: on the pipeline test's free plate, whose points scatter 2.9x beyond their
/// noise (the truth's own mesh error), re-linearising dragged the poorly determined core
/// thickness from +0.2 % to +1.7 % over four steps, chasing that scatter, and the law's η band
/// missed the truth at 78 Hz. Moving only the supports' inputs, not the faces', left the
/// supported coverage test's joint η band at 87 % (all inputs: 92 %).
pub const WIDE_PRIOR: f64 = 0.05;

/// The re-linearisation stops when no input moved by more than this fraction of its prior's
/// standard deviation since the last ([`fit_law`]).
pub const SETTLED: f64 = 0.05;

/// Most re-linearisations of the joint fit ([`fit_law`]).
pub const RELINEARISATIONS: usize = 4;

/// [`fit_law`] with the law given.
fn fit_law_with(
    (law, prony_offset): Candidate,
    modal: &[CorePoint],
    coarsest: Option<&LayeredInverse>,
    weights: Weights,
) -> Option<std::result::Result<CoreLawFit, String>> {
    let (index, points, priors) = mode_points(modal, weights);
    if points.is_empty() {
        return None;
    }
    let mut fit = match fit_core_law_shifted(&points, &priors, law, prony_offset) {
        Ok(f) => f,
        Err(e) => return Some(Err(e.to_string())),
    };
    let Some(coarsest) = coarsest else {
        return Some(Ok(fit));
    };
    // Only where some input has a wide prior (the faces' first order holds over theirs).
    if priors
        .iter()
        .all(|p| p.rel_sd < WIDE_PRIOR || Input::named(&p.name).is_none())
    {
        return Some(Ok(fit));
    }
    let bands: Vec<&LayeredBand> = index
        .iter()
        .filter_map(|&k| modal[k].layered_band.as_ref()?.as_ref().ok())
        .collect();
    // Where the points were taken (the model's own inputs), and where the fit stands now.
    let base: Vec<f64> = priors.iter().map(|p| p.at).collect();
    let mut at = base.clone();
    for _ in 0..RELINEARISATIONS {
        let found: Vec<f64> = fit.inputs().iter().map(|p| p.value).collect();
        let settled = found
            .iter()
            .zip(&at)
            .zip(&priors)
            .all(|((d, a), p)| (d - a).abs() < SETTLED * p.rel_sd);
        if settled {
            break;
        }
        let Some((moved_points, moved_priors)) =
            relinearised(coarsest, &bands, &points, &priors, &found, &base)
        else {
            break;
        };
        match fit_core_law_shifted(&moved_points, &moved_priors, law, prony_offset) {
            Ok(f) => (fit, at) = (f, found),
            Err(_) => break,
        }
    }
    Some(Ok(fit))
}

/// The joint fit's points and priors re-linearised at the inputs' changes `delta` from
/// nominal ([`fit_law`]), the points and `coarsest` being at `base`; None when a mode cannot be
/// matched on the moved model.
fn relinearised(
    coarsest: &LayeredInverse,
    bands: &[&LayeredBand],
    points: &[ModePoint],
    priors: &[InputPrior],
    delta: &[f64],
    base: &[f64],
) -> Option<(Vec<ModePoint>, Vec<InputPrior>)> {
    // The shared remainder's terms (`share_the_remainder`) are no inputs of the model: their
    // effects stay, and the points are not moved along them.
    let inputs: Vec<Option<Input>> = priors.iter().map(|p| Input::named(&p.name)).collect();
    let changes: Vec<(Input, f64)> = inputs
        .iter()
        .zip(delta.iter().zip(base))
        .filter_map(|(&i, (d, b))| Some((i?, d - b)))
        .collect();
    let moved = coarsest.with_inputs_moved(&changes).ok()?;
    let new_points = bands
        .par_iter()
        .zip(points)
        .map(|(band, p)| {
            let (rank, eigenvalue) = band.coarse;
            let g = moved.invert(eigenvalue, band.found_pa).ok()?;
            (g.rank == rank).then_some(())?;
            let g = g.core_shear_pa;
            let sens = moved.sensitivity(g, rank, eigenvalue).ok()?;
            let effects = inputs
                .iter()
                .zip(&p.effects)
                .map(|(&i, &kept)| {
                    let Some(i) = i else {
                        return Some(kept);
                    };
                    let e = sens.inputs.iter().find(|e| e.input == i)?;
                    Some(log_parts(e.dg_dln, g))
                })
                .collect::<Option<Vec<_>>>()?;
            Some(ModePoint {
                core_shear_pa: p.core_shear_pa * (g / band.found_pa),
                effects,
                ..p.clone()
            })
        })
        .collect::<Option<Vec<_>>>()?;
    let new_priors = priors
        .iter()
        .zip(delta)
        .zip(&inputs)
        .map(|((p, &d), i)| match i {
            Some(_) => InputPrior { at: d, ..p.clone() },
            None => p.clone(),
        })
        .collect();
    Some((new_points, new_priors))
}

/// Moves each mode's layered G* from the complex frequency of its pole, where it holds, to
/// the mode's real frequency (lamdyn_fit::joint's module docs): by the fitted `law` when there
/// is one, else by the modes' own log-slope. On the demo roof this takes 1–1.5 % off η and
/// adds 0.3–0.5 % to G'. Idempotent: it starts from each band's `found_pa`.
pub fn to_real_frequency(
    modal: &mut [CorePoint],
    law: Option<&std::result::Result<CoreLawFit, String>>,
) {
    let (index, points, _) = mode_points(modal, Weights::Law);
    let moved: Vec<Complex64> = match law {
        Some(Ok(fit)) if fit.real_frequency_factors.len() == points.len() => fit
            .real_frequency_factors
            .iter()
            .zip(&points)
            .map(|(r, p)| p.core_shear_pa * r)
            .collect(),
        _ => lamdyn_fit::joint::to_real_frequency(&points)
            .iter()
            .zip(&points)
            .map(|(r, p)| p.core_shear_pa * r)
            .collect(),
    };
    for (k, g) in index.into_iter().zip(moved) {
        modal[k].layered = Some(Ok(g));
    }
}

/// The modes with a layered result and a band as the joint fit takes them (their indices in
/// `modal`, the points with their noise as `weights` says, the priors of the inputs known
/// within a tolerance).
fn mode_points(
    modal: &[CorePoint],
    weights: Weights,
) -> (Vec<usize>, Vec<ModePoint>, Vec<InputPrior>) {
    let mut index = Vec::new();
    let mut points: Vec<ModePoint> = Vec::new();
    let mut priors: Vec<InputPrior> = Vec::new();
    for (k, p) in modal.iter().enumerate() {
        let (Some(_), Some(Ok(band))) = (p.layered_g(), p.layered_band.as_ref()) else {
            continue;
        };
        index.push(k);
        if priors.is_empty() {
            priors = band
                .inputs
                .iter()
                .zip(&band.inputs_at)
                .map(|((name, sd, _), &at)| InputPrior {
                    name: name.clone(),
                    rel_sd: *sd,
                    at,
                })
                .collect();
        }
        let is_input = |name: &str| band.inputs.iter().any(|i| i.0 == name);
        points.push(ModePoint {
            freq_hz: p.freq_hz,
            found_at_hz: band.found_at_hz,
            core_shear_pa: band.found_pa,
            effects: band.inputs.iter().map(|i| i.2).collect(),
            second_order: band.second_order.clone(),
            // The inputs, to second order, are the fit's parameters, not the point's noise.
            // The hits' jackknife stays in the mode's own band only: the hits' noise moves
            // every mode's pole at once, and on the damped sandwich (face data known, five
            // seeds) the law held the truth at 285 of 300 lines without it, at 176 as
            // independent noise (Akaike then chose the fractional Zener law) and at 202 as
            // shared inputs, one per hit (the law fit then pinned them by the modes' shape and
            // its band narrowed); the scatter about the law already scales the law's band.
            noise: band
                .sources
                .iter()
                .filter(|s| !is_input(&s.0) && s.0 != SECOND_ORDER && s.0 != HITS_JACKKNIFE)
                .filter(|s| weights == Weights::Law || s.0 != BEYOND_SECOND_ORDER)
                .cloned()
                .collect(),
        });
    }
    // An input whose prior is zero (known exactly) is not a parameter.
    let keep: Vec<bool> = priors.iter().map(|p| p.rel_sd > 0.0).collect();
    priors.retain(|p| p.rel_sd > 0.0);
    let kept = |v: &[[f64; 2]]| -> Vec<[f64; 2]> {
        v.iter()
            .zip(&keep)
            .filter_map(|(e, &k)| k.then_some(*e))
            .collect()
    };
    for pt in &mut points {
        pt.effects = kept(&pt.effects);
        pt.second_order = kept(&pt.second_order);
    }
    if weights == Weights::Law {
        share_the_remainder(&mut points, &mut priors);
    }
    (index, points, priors)
}

/// The part of each point's "inputs beyond second order" that all modes share: the square of
/// the correlation between two modes' remainders (`share_the_remainder`).
pub const REMAINDER_SHARED: f64 = 0.5;

/// Names of the joint fit's two terms for the inputs' remainder beyond second order that the
/// modes share (G', η).
pub const SHARED_REMAINDER: [&str; 2] = [
    "inputs beyond second order, shared (G')",
    "inputs beyond second order, shared (eta)",
];

/// Splits each point's "inputs beyond second order" b_k (G', η) into a part of its own noise,
/// √(1 − ρ) b_k, and a part all modes share, √ρ b_k times one term per quantity under a unit
/// prior (two more "inputs" of the joint fit: [`SHARED_REMAINDER`]), with ρ =
/// [`REMAINDER_SHARED`]; the variance per mode stays b_k². The remainder is a function of the
/// inputs every mode shares, so taken as independent noise it averaged down over the modes
/// while the modes' errors moved together: on the demo roof with the faces drawn from their
/// priors (`chain_coverage`, 20 seeds) the law's η band held the truth at 85 % of the pairs,
/// the law 2.8–4.3 % low in η at every mode of two seeds and 13–25 % high at three; split
/// like this, at 94.7 % (G': 97.9 → 100 %). Its sign differs between modes in G' (seed 9:
/// −15 … +5 %), so it is not all shared either.
fn share_the_remainder(points: &mut [ModePoint], priors: &mut Vec<InputPrior>) {
    let own = (1.0 - REMAINDER_SHARED).sqrt();
    let mut remainders = Vec::with_capacity(points.len());
    for pt in points.iter_mut() {
        let mut b = [0.0; 2];
        for (name, sd) in &mut pt.noise {
            if name == BEYOND_SECOND_ORDER {
                b = *sd;
                *sd = sd.map(|x| x * own);
            }
        }
        remainders.push(b);
    }
    // One shift of every mode alike, of the median remainder: a shift whose size follows the
    // modes' own remainders is told apart from the law by the modes' pattern, and the fit
    // pins it (seed 6 above: the law's η band narrowed from ±3.5 % to ±3.0 %).
    let level = [0, 1].map(|c| {
        let mut v: Vec<f64> = remainders.iter().map(|b| b[c]).collect();
        v.sort_by(f64::total_cmp);
        REMAINDER_SHARED.sqrt() * v.get(v.len() / 2).copied().unwrap_or(0.0)
    });
    if level == [0.0, 0.0] {
        return;
    }
    for pt in points.iter_mut() {
        let with_second = !pt.second_order.is_empty();
        pt.effects.extend([[level[0], 0.0], [0.0, level[1]]]);
        if with_second {
            pt.second_order.extend([[0.0, 0.0]; 2]);
        }
    }
    priors.extend(SHARED_REMAINDER.map(|name| InputPrior {
        name: name.to_string(),
        rel_sd: 1.0,
        at: 0.0,
    }));
}

#[cfg(test)]
mod tests {
    use super::*;
    use lamdyn_fit::joint::fit_core_law;
    use lamdyn_fit::synthetic::Normal;
    use lamdyn_layered::convergence::ConvergedMode;
    use lamdyn_material::law::{FractionalZener, ViscoelasticLaw};
    use std::f64::consts::PI;

    /// A small laminated plate (glass 1 mm / core 1 mm / glass 1 mm, 0.5 x 0.4 m, radii 3 m and
    /// 4 m, free), its inputs off nominal by the relative changes `d` in the order of
    /// [`Input::ALL`] (face modulus, face thickness, core thickness, face density, core
    /// density).
    fn plate(d: [f64; 5]) -> LayeredPlate {
        let face = InverseLayer {
            thickness_m: 1e-3 * d[1].exp(),
            density_kg_m3: 2500.0 * d[3].exp(),
            poisson: 0.22,
            young_pa: Some(70e9 * d[0].exp()),
            loss_factor: 0.0,
        };
        let core = InverseLayer {
            thickness_m: 1e-3 * d[2].exp(),
            density_kg_m3: 1070.0 * d[4].exp(),
            poisson: 0.49,
            young_pa: None,
            loss_factor: 0.0,
        };
        LayeredPlate {
            plan: Plan::Rectangle {
                plan_m: [0.5, 0.4],
                radii_m: [3.0, 4.0],
                edge_grading: 0.0,
            },
            layers: vec![face, core, face],
            supports: Vec::new(),
            elements_per_layer: 1,
        }
    }

    fn law() -> FractionalZener {
        FractionalZener::new(0.8e6, 1.0e9, 3e-7, 0.4).unwrap()
    }

    /// The same plate on four corner supports (5 x 5 cm patches, 2 kN/m in plane, 10 kN/m
    /// vertical, dashpots 5 and 10 N s/m: the bounce near 15 Hz, below the first elastic
    /// mode), the supports' stiffness and damping off nominal by `d[5]` and `d[6]`.
    fn supported(d: [f64; 7]) -> LayeredPlate {
        let mut p = plate([d[0], d[1], d[2], d[3], d[4]]);
        let (k, c) = (d[5].exp(), d[6].exp());
        p.supports = [[0.1, 0.1], [0.9, 0.1], [0.1, 0.9], [0.9, 0.9]]
            .map(|xy_fraction| lamdyn_layered::supports::PointSupport {
                xy_fraction,
                stiffness_n_m: [5e2 * k, 5e2 * k, 2e3 * k],
                damping_n_s_m: [2.0 * c, 2.0 * c, 4.0 * c],
                patch_m: [0.05, 0.05],
            })
            .to_vec();
        p
    }

    /// The first `n` elastic eigenvalues λ = −p² of `model`'s poles p with the core's law:
    /// the fixed point ω* = √λ(G*(ω*)) at the complex frequency ω* = −ip, the law continued
    /// there and the supports' dashpots acting there too (what a free decay of the part feels;
    /// its FRF's pole). `free`: a part without supports (its rigid modes are not counted).
    fn poles(model: &LayeredInverse, n: usize, free: bool) -> Vec<Complex64> {
        // Elastic: Re λ above 1e-6 of a 1 kHz mode's (above 1 Hz; the rigid modes lie near 0).
        let elastic = Complex64::new((2.0 * PI * 1000.0f64).powi(2), 0.0);
        (0..n)
            .map(|rank| {
                let mut w = Complex64::new(2.0 * PI * 50.0, 0.0);
                let mut l = Complex64::new(0.0, 0.0);
                for _ in 0..40 {
                    let at = if free || l.re <= 0.0 { elastic } else { l };
                    l = model
                        .elastic_eigenvalue(law().modulus_at_complex(w), rank, at)
                        .unwrap();
                    w = l.sqrt();
                }
                l
            })
            .collect()
    }

    /// What a coverage run measured: per band (per-mode, joint) and part (G', η) the share of
    /// (mode, seed) pairs whose truth it held and its median half-width of ln G' or ln η.
    struct Coverage {
        pairs: usize,
        rate: [[f64; 2]; 2],
        median_half_width: [[f64; 2]; 2],
    }

    /// Issue 15.4's coverage test without the EMA and the mesh: `seeds` virtual tests of the
    /// part `make` builds from the inputs' relative changes, drawn from their priors `sd`
    /// (order of [`Input::ALL`]), its poles computed by a model built from the drawn inputs
    /// (no derivatives: independent of the sensitivities under test), each the complex fixed
    /// point of the core's law, and scattered by 0.02 % in frequency and 2e-4 in damping
    /// ratio; identified with the nominal inputs (`priors` the job's) and moved to the real
    /// frequency ([`to_real_frequency`]); then where the truth G*(f_k) lies against the
    /// per-mode band and the joint law's band. Truth and identification share one mesh, so the
    /// bands hold no discretization part here (`ConvergedMode` with zero bands).
    fn coverage(
        make: &dyn Fn(&[f64]) -> LayeredPlate,
        sd: &[f64],
        priors: &crate::job::UncertaintyOptions,
        seeds: usize,
        min_hz: f64,
    ) -> Coverage {
        let (elements, modes, g_ref) = ([6, 5], 20, 8e6);
        let nominal_plate = make(&vec![0.0; sd.len()]);
        let free = nominal_plate.supports.is_empty();
        let nominal = LayeredInverse::build_with_inputs(
            &nominal_plate,
            elements,
            g_ref,
            modes,
            &BASIS_RATIOS,
            &Input::ALL,
        )
        .unwrap();
        let moved = MovedBySd::build(&nominal, &nominal_plate, priors);
        let (sd_f_rel, sd_zeta) = (2e-4, 2e-4);
        let mut rng = Normal::new(2026);
        let mut inside = [[0usize; 2]; 2];
        let mut total = 0;
        let mut widths = [[Vec::new(), Vec::new()], [Vec::new(), Vec::new()]];
        for _seed in 0..seeds {
            let d: Vec<f64> = sd.iter().map(|s| s * rng.sample()).collect();
            let truth = LayeredInverse::build(&make(&d), elements, g_ref, modes).unwrap();
            let mut modal = Vec::new();
            for exact in poles(&truth, if free { 4 } else { 10 }, free) {
                let f = exact.re.sqrt() / (2.0 * PI);
                if f < min_hz {
                    continue;
                }
                let eps_f = sd_f_rel * rng.sample();
                let eps_z = sd_zeta * rng.sample();
                let target =
                    exact * (1.0 + 2.0 * eps_f) + Complex64::new(0.0, 2.0 * exact.re * eps_z);
                let start = law().modulus(2.0 * PI * f) * 1.2;
                let est = match nominal.invert(target, start) {
                    Ok(e) => e,
                    // A mode the nominal model cannot match (or a support's bounce, which the
                    // core barely moves): left out, as the chain does.
                    Err(_) => continue,
                };
                let mode = ConvergedMode::exact(est.core_shear_pa, est.core_shear_pa, est.rank);
                let b = band(
                    (&nominal, None),
                    &moved,
                    &mode,
                    target,
                    PoleScatter {
                        noise: Some([sd_f_rel * f, sd_zeta]),
                        ..Default::default()
                    },
                    [0.0; 2],
                )
                .unwrap();
                modal.push(CorePoint {
                    freq_hz: f,
                    e_eff_pa: None,
                    e_pole_pa: None,
                    e_sd: None,
                    paper: Err("not used".into()),
                    exact: Err("not used".into()),
                    layered: Some(Ok(est.core_shear_pa)),
                    layered_convergence: Some(mode),
                    layered_band: Some(Ok(b)),
                });
            }
            let joint = fit_law_with(
                (CoreLaw::FractionalZener, 0.0),
                &modal,
                Some(&nominal),
                Weights::Law,
            )
            .unwrap();
            to_real_frequency(&mut modal, Some(&joint));
            let joint = joint.unwrap();
            for (p, j) in modal.iter().zip(&joint.at_modes) {
                let g = p.layered_g().unwrap();
                let b = p.layered_band.as_ref().unwrap().as_ref().unwrap();
                let t = law().modulus(2.0 * PI * p.freq_hz);
                let truth_log = [t.re.ln(), (t.im / t.re).ln()];
                let per_mode = [g.re.ln(), (g.im / g.re).ln()];
                let joint_band = [
                    [j.storage_ci95[0].ln(), j.storage_ci95[1].ln()],
                    [j.loss_factor_ci95[0].ln(), j.loss_factor_ci95[1].ln()],
                ];
                total += 1;
                for c in 0..2 {
                    let within = (truth_log[c] - per_mode[c]).abs() <= b.half_width[c];
                    inside[0][c] += usize::from(within);
                    let lo_hi = joint_band[c];
                    inside[1][c] +=
                        usize::from(lo_hi[0] <= truth_log[c] && truth_log[c] <= lo_hi[1]);
                    widths[0][c].push(b.half_width[c]);
                    widths[1][c].push(0.5 * (lo_hi[1] - lo_hi[0]));
                }
            }
        }
        let median = |w: &mut Vec<f64>| {
            w.sort_by(f64::total_cmp);
            w[w.len() / 2]
        };
        let c = Coverage {
            pairs: total,
            rate: inside.map(|r| r.map(|n| n as f64 / total.max(1) as f64)),
            median_half_width: widths.map(|mut w| [median(&mut w[0]), median(&mut w[1])]),
        };
        eprintln!(
            "{total} pairs: coverage per mode {:?}, joint {:?}; median half-widths per mode {:?}, joint {:?}",
            c.rate[0], c.rate[1], c.median_half_width[0], c.median_half_width[1]
        );
        c
    }

    /// A job on two supports (its files are not read here).
    fn supported_job() -> Job {
        let text = "[measurement]\nchannels = \"c.csv\"\nfrf = \"f.csv\"\n\
            [model]\nfile = \"m.toml\"\n\
            [[inverse.supports]]\nxy_fraction = [0.1, 0.1]\nstiffness_n_m = [100.0, 100.0, 400.0]\ndamping_n_s_m = [1.0, 1.0, 2.0]\n\
            [[inverse.supports]]\nxy_fraction = [0.9, 0.9]\nstiffness_n_m = [100.0, 100.0, 400.0]\n\
            [[stack.layers]]\nthickness_m = 1e-3\ndensity_kg_m3 = 2500.0\npoisson = 0.22\nyoung_pa = 70e9\n\
            [[stack.layers]]\nthickness_m = 1e-3\ndensity_kg_m3 = 1070.0\npoisson = 0.49\n\
            [[stack.layers]]\nthickness_m = 1e-3\ndensity_kg_m3 = 2500.0\npoisson = 0.22\nyoung_pa = 70e9\n";
        toml::from_str(text).unwrap()
    }

    /// The ladder runs again at the supports the law found only when it moved them beyond
    /// both [`SUPPORTS_RERUN`] and their 95 % interval: points whose supports are 15 % stiffer
    /// than the job says (effects of −3 to −1 on ln G', noise 0.1 %) give the job with every
    /// spring times e^0.15 (to the fit's accuracy) and the dashpots as they were; at 1 % they
    /// give none, and a free part never.
    /// The groups' spread is the standard error of their mean: four estimates 1, 2, 3, 4 have
    /// a sample sd of √(5/3) and a standard error of √(5/3)/2; one group alone gives none.
    #[test]
    fn group_spread_is_the_standard_error_of_the_groups_mean() {
        let found = [[1.0, 0.01], [2.0, 0.02], [3.0, 0.03], [4.0, 0.04]];
        let s = group_spread(&found).unwrap();
        assert!((s[0] - (5.0f64 / 3.0).sqrt() / 2.0).abs() < 1e-15, "{s:?}");
        assert!(
            (s[1] - 0.01 * (5.0f64 / 3.0).sqrt() / 2.0).abs() < 1e-17,
            "{s:?}"
        );
        assert!(group_spread(&found[..1]).is_none());
    }

    /// The jackknife's sd is √((n − 1)/n Σ (θ_i − θ̄)²) over the sets without each hit (Efron
    /// & Tibshirani eq. 11.5, computed here from its definition): the first mode's damping
    /// ratios of the damped sandwich's seed 1 without each of its five hits give 0.040 %,
    /// where one hit moves the pole by 2 % of itself; fewer than three sets give none.
    #[test]
    fn hit_jackknife_is_efron_and_tibshiranis_sd() {
        let zeta = [0.02473, 0.02475, 0.02480, 0.02525, 0.02474];
        let found: Vec<[f64; 2]> = zeta.iter().map(|&z| [67.97, z]).collect();
        let s = hit_jackknife(&found).unwrap();
        let mean = zeta.iter().sum::<f64>() / 5.0;
        let var = 4.0 / 5.0 * zeta.iter().map(|z| (z - mean).powi(2)).sum::<f64>();
        assert!((s[1] - var.sqrt()).abs() < 1e-15, "{s:?}");
        assert!((s[1] - 0.000399).abs() < 1e-6, "{s:?}");
        assert_eq!(s[0], 0.0);
        assert!(hit_jackknife(&found[..2]).is_none());
    }

    /// The orders' spread is the sample sd of the whole's pole and the other orders' (not
    /// divided by √n): the first mode of the damped-sandwich example (seed 1) came out at
    /// damping ratios 2.538 % (orders 40 and 60) and 2.478 % (order 80), an sd of 0.034 %, 1.4 %
    /// of itself; an order that found no pole of the mode gives nothing.
    #[test]
    fn order_spread_is_the_sd_over_the_orders() {
        let main = [67.966, 0.025376];
        let others = [[67.966, 0.025376], [67.977, 0.024780]];
        let s = order_spread(main, &others).unwrap();
        let mean = (2.0 * 0.025376 + 0.024780) / 3.0;
        let var = (2.0 * (0.025376f64 - mean).powi(2) + (0.024780f64 - mean).powi(2)) / 2.0;
        assert!((s[1] - var.sqrt()).abs() < 1e-15, "{s:?}");
        assert!((s[1] / 0.025376 - 0.0136).abs() < 1e-3, "{s:?}");
        assert!(order_spread(main, &[]).is_none());
    }

    /// `auto` keeps the law with the lower small-sample Akaike criterion and says why: the
    /// fractional Zener law on points of a fractional Zener core, the Prony series on points
    /// of a Prony core with one term per decade (which the fractional Zener law misses); a
    /// failed candidate gives way to the other, and with none fitted the first error is kept.
    #[test]
    fn auto_keeps_the_law_the_modes_favour() {
        let prony = |f: f64| -> Complex64 {
            let i = Complex64::new(0.0, 1.0);
            (0..12).fold(Complex64::new(0.5e6, 0.0), |acc, k| {
                let tau = 10f64.powi(2 - k);
                let x = i * 2.0 * PI * f * tau;
                acc + 4e6 * tau.powf(-0.25) * x / (1.0 + x)
            })
        };
        let points = |g: &dyn Fn(f64) -> Complex64| -> Vec<ModePoint> {
            (0..8)
                .map(|k| {
                    let f = 20.0 * 10f64.powf(k as f64 / 7.0);
                    ModePoint {
                        freq_hz: f,
                        found_at_hz: Complex64::new(f, 0.0),
                        core_shear_pa: g(f),
                        effects: Vec::new(),
                        second_order: Vec::new(),
                        noise: vec![("EMA pole".into(), [0.005, 0.005])],
                    }
                })
                .collect()
        };
        type Fits = Vec<(Candidate, std::result::Result<CoreLawFit, String>)>;
        let fits = |pts: &[ModePoint]| -> Fits {
            candidates(crate::job::CoreLawChoice::Auto)
                .into_iter()
                .map(|c| {
                    let fit = fit_core_law_shifted(pts, &[], c.0, c.1);
                    (c, fit.map_err(|e| e.to_string()))
                })
                .collect()
        };
        let chosen = |fits: &Fits| {
            let (k, why) = lowest_akaike(fits).unwrap().unwrap();
            (fits[k].0, why)
        };
        let zener = points(&|f| law().modulus(2.0 * PI * f));
        let (law_found, why) = chosen(&fits(&zener));
        assert_eq!(law_found.0, CoreLaw::FractionalZener);
        let why = why.unwrap();
        assert!(why.contains("over generalized_maxwell"), "{why}");
        assert!(why.contains("moved by 0.25 of their spacing"), "{why}");
        assert_eq!(
            chosen(&fits(&points(&prony))).0.0,
            CoreLaw::GeneralizedMaxwell
        );
        // All but one candidate failed: that one, with nothing to choose between.
        let mut one = fits(&zener);
        for f in &mut one[..4] {
            f.1 = Err("no start".into());
        }
        let (found, why) = chosen(&one);
        assert!(found == (CoreLaw::GeneralizedMaxwell, 0.75) && why.is_none());
        let none = vec![
            ((CoreLaw::FractionalZener, 0.0), Err("first".to_string())),
            (
                (CoreLaw::GeneralizedMaxwell, 0.0),
                Err("second".to_string()),
            ),
        ];
        assert_eq!(lowest_akaike(&none).unwrap().unwrap_err(), "first");
        assert!(lowest_akaike(&[]).is_none());
        assert!(core_laws(crate::job::CoreLawChoice::None).is_empty());
    }

    #[test]
    fn the_ladder_reruns_at_supports_found_far_off() {
        let priors = vec![
            InputPrior {
                name: Input::SupportStiffness.name().into(),
                rel_sd: 0.2,
                at: 0.0,
            },
            InputPrior {
                name: Input::SupportDamping.name().into(),
                rel_sd: 0.3,
                at: 0.0,
            },
        ];
        let points = |off: f64| -> Vec<ModePoint> {
            [30.0, 45.0, 60.0, 80.0, 100.0]
                .iter()
                .enumerate()
                .map(|(k, &f)| {
                    let e = [[-3.0 + 0.5 * k as f64, 0.4], [0.0, 0.0]];
                    // The truth seen through supports `off` stiffer than the job's.
                    let g = law().modulus(2.0 * PI * f);
                    let storage = g.re * (-e[0][0] * off).exp();
                    let eta = g.im / g.re * (-e[0][1] * off).exp();
                    ModePoint {
                        freq_hz: f,
                        found_at_hz: Complex64::new(f, 0.0),
                        core_shear_pa: Complex64::new(storage, storage * eta),
                        effects: e.to_vec(),
                        second_order: Vec::new(),
                        noise: vec![("EMA pole".into(), [1e-3, 1e-3])],
                    }
                })
                .collect()
        };
        let job = supported_job();
        let far = fit_core_law(&points(0.15), &priors, CoreLaw::FractionalZener)
            .map_err(|e| e.to_string());
        let (moved, at) = supports_found(&job, Some(&far)).expect("a re-run");
        assert!((at[0] - 0.15).abs() < 0.01, "{at:?}");
        let factor = moved.inverse.supports[0].stiffness_n_m[2] / 400.0;
        assert!((factor - at[0].exp()).abs() < 1e-12, "{factor}");
        assert_eq!(moved.inverse.supports[1].damping_n_s_m, [0.0; 3]);
        assert!((moved.inverse.supports[0].damping_n_s_m[2] / 2.0 - at[1].exp()).abs() < 1e-12);
        let near = fit_core_law(&points(0.01), &priors, CoreLaw::FractionalZener)
            .map_err(|e| e.to_string());
        assert!(supports_found(&job, Some(&near)).is_none());
        let mut free = job.clone();
        free.inverse.supports.clear();
        assert!(supports_found(&free, Some(&far)).is_none());
    }

    /// The job's priors with the faces' as the coverage tests draw them (1 % on the face
    /// modulus, 5 µm on each thickness, 0.5 % on each density), the supports' at their
    /// defaults (20 % stiffness, 30 % damping).
    fn faces_priors() -> crate::job::UncertaintyOptions {
        crate::job::UncertaintyOptions {
            face_modulus_rel_sd: 0.01,
            thickness_sd_m: 5e-6,
            density_rel_sd: 0.005,
            ..Default::default()
        }
    }

    /// The remainder beyond second order is split half and half: each point keeps √½ of its
    /// own, and two shared terms under unit priors shift every mode by √½ times the median
    /// remainder; no points (a run without layered bands) and no remainder change nothing.
    #[test]
    fn the_remainder_beyond_second_order_is_split_between_own_and_shared() {
        let point = |b: [f64; 2]| ModePoint {
            freq_hz: 100.0,
            found_at_hz: Complex64::new(100.0, 1.0),
            core_shear_pa: Complex64::new(1e7, 5e6),
            effects: vec![[0.1, 0.2]],
            second_order: vec![[0.01, 0.02]],
            noise: vec![
                ("EMA pole".into(), [0.01, 0.02]),
                (BEYOND_SECOND_ORDER.into(), b),
            ],
        };
        let prior = InputPrior {
            name: "face modulus".into(),
            rel_sd: 0.01,
            at: 0.0,
        };
        let mut points = vec![point([0.04, 0.3]), point([0.01, 0.02]), point([0.02, 0.1])];
        let mut priors = vec![prior.clone()];
        share_the_remainder(&mut points, &mut priors);
        let names: Vec<&str> = priors.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(
            names,
            ["face modulus", SHARED_REMAINDER[0], SHARED_REMAINDER[1]]
        );
        assert!(priors[1..].iter().all(|p| p.rel_sd == 1.0 && p.at == 0.0));
        let half = 0.5f64.sqrt();
        for (pt, own) in points.iter().zip([[0.04, 0.3], [0.01, 0.02], [0.02, 0.1]]) {
            assert_eq!(pt.noise[0].1, [0.01, 0.02]);
            assert_eq!(pt.noise[1].1, own.map(|x| x * half));
            // The medians: 0.02 in G', 0.1 in eta.
            assert_eq!(pt.effects[1..], [[0.02 * half, 0.0], [0.0, 0.1 * half]]);
            assert_eq!(pt.second_order.len(), 3);
        }
        let mut none: Vec<ModePoint> = Vec::new();
        let mut priors = vec![prior.clone()];
        share_the_remainder(&mut none, &mut priors);
        assert_eq!(priors.len(), 1);
        let mut exact = vec![point([0.0, 0.0])];
        share_the_remainder(&mut exact, &mut priors);
        assert_eq!((priors.len(), exact[0].effects.len()), (1, 1));
    }

    /// A free plate whose faces, core and densities are drawn from their priors (1 % on the
    /// face modulus, 0.5 % on each thickness and density), 20 seeds ([`coverage`]): the truth
    /// lies inside the joint law's band at ≥ 90 % of the (mode, seed) pairs, in G' and in η,
    /// and the shared inputs make that band narrower than the per-mode one.
    #[test]
    fn bands_cover_the_truth_with_inputs_drawn_from_their_priors() {
        let priors = faces_priors();
        let make = |d: &[f64]| plate([d[0], d[1], d[2], d[3], d[4]]);
        let c = coverage(&make, &[0.01, 0.005, 0.005, 0.005, 0.005], &priors, 20, 0.0);
        let (rate, total) = (c.rate, c.pairs);
        // Measured (80 pairs): per mode 90 % (G') and 90 % (eta), the first order falling a
        // little short at half-widths of 16-17 %; joint 98.8 % and 96.3 % (100 % and 97.5 %
        // before the remainder beyond second order was partly shared), with median
        // half-widths of 2.3 % and 2.8 % against the per-mode 16 % and 17 %.
        assert!(total >= 70, "{total} pairs identified");
        assert!(
            rate[1][0] >= 0.9 && rate[1][1] >= 0.9,
            "joint coverage {rate:?}"
        );
        // The per-mode band: 3 binomial sd (80 pairs) below its measured 90 %.
        assert!(
            rate[0][0] >= 0.8 && rate[0][1] >= 0.8,
            "per-mode coverage {rate:?}"
        );
        for part in 0..2 {
            assert!(
                c.median_half_width[1][part] < 0.5 * c.median_half_width[0][part],
                "the shared inputs narrow the band"
            );
        }
    }

    /// A mode's band is taken where the coarsest model's own inverse maps back to the converged
    /// G*: on supports with dashpots, with the ladder's G* 3 % off the coarsest model's own
    /// solution (the correction a coarse mesh needs), inverting the coarsest model at the
    /// band's eigenvalue gives the converged G* back to 1e-6 (the inverse and the pole settle
    /// to 1e-9 in λ, which a mode with d ln λ/d ln G' of 0.006 makes 2e-7 in G*). The ±1 sd
    /// moves ([`second_order`]) and the re-linearised fit ([`relinearised`]) divide by it.
    /// With the coarsest eigenvalue taken with the dashpots at the measured pole's frequency
    /// instead (before `LayeredInverse::pole_eigenvalue`), it came back 2.3e-3 off here and
    /// −0.1 … +0.7 % (G'), 0.5–9 % (G'') off on the in-band foam roof: a spurious second
    /// difference of tens at a 1 % prior.
    #[test]
    fn band_is_taken_where_the_coarsest_inverse_maps_back() {
        let plate = supported([0.0; 7]);
        let nominal =
            LayeredInverse::build_with_inputs(&plate, [6, 5], 8e6, 20, &BASIS_RATIOS, &Input::ALL)
                .unwrap();
        let moved = MovedBySd::build(&nominal, &plate, &faces_priors());
        let mut checked = 0;
        for target in poles(&nominal, 8, false) {
            let start = law().modulus(target.re.sqrt());
            let Ok(est) = nominal.invert(target, start) else {
                continue;
            };
            let converged = est.core_shear_pa * 1.03;
            let mode = ConvergedMode::exact(converged, est.core_shear_pa, est.rank);
            let scatter = PoleScatter::default();
            let b = band((&nominal, None), &moved, &mode, target, scatter, [0.0; 2]).unwrap();
            let back = nominal.invert(b.coarse.1, b.found_pa).unwrap();
            let err = (back.core_shear_pa / converged - 1.0).norm();
            assert!(
                err < 1e-6,
                "{:.2} Hz: {err:e}",
                target.re.sqrt() / (2.0 * PI)
            );
            checked += 1;
        }
        assert!(checked >= 4, "{checked} modes");
    }

    /// The pair fit ([`crate::pair_fit`]) recovers the core from the FRFs where the poles given
    /// to it are split wrongly: FRFs made of two modes of the supported plate at one G*
    /// (receptance, six curves of fixed residues), the "identified" eigenvalues moved apart to
    /// λ (1 ± 5e-4), whose own inverses put G* more than 0.3 % off (these modes move little
    /// with the core). The model is the data's own and noise-free, so the fit's least-squares
    /// optimum is that G*: within 1e-5 (the fit stops when a step lowers the misfit by less
    /// than 1e-8 of itself), the fitted poles the data's within 1e-6, and the fit's misfit a
    /// thousandth of the given poles' or less.
    #[test]
    fn a_pair_fit_to_the_frfs_recovers_the_core_its_poles_miss() {
        use lamdyn_frf::{Channel, FrfSet, Quantity};
        let plate = supported([0.0; 7]);
        let model =
            LayeredInverse::build_with_inputs(&plate, [6, 5], 8e6, 20, &BASIS_RATIOS, &Input::ALL)
                .unwrap();
        // The lowest two neighbouring modes that feel the core (the lowest are the supports').
        let exact = poles(&model, 10, false);
        let feels = |r: usize| {
            model
                .invert(exact[r], law().modulus(exact[r].re.sqrt()))
                .is_ok()
        };
        let ra = (0..9).find(|&r| feels(r) && feels(r + 1)).unwrap();
        let rb = ra + 1;
        let g_true = law().modulus(0.5 * (exact[ra].re.sqrt() + exact[rb].re.sqrt()));
        let truth = [ra, rb].map(|r| model.pole_eigenvalue(g_true, r, exact[r]).unwrap());
        let pole = crate::pair_fit::pole_of;
        let hz = |l: Complex64| l.re.sqrt() / (2.0 * PI);
        let freqs: Vec<f64> = (1..=2000).map(|k| 0.25 * k as f64).collect();
        let residues = |o: usize, i: usize| {
            Complex64::new(1.0 + 0.3 * o as f64, 0.5 - 0.2 * (o * i) as f64) * 1e-3
        };
        let n_curves = 6;
        // Curve by curve (FrfSet's layout), line by line.
        let mut data = Vec::new();
        for o in 0..n_curves {
            for &f in &freqs {
                let s = Complex64::new(0.0, 2.0 * PI * f);
                data.push((0..2).fold(Complex64::new(0.0, 0.0), |h, i| {
                    let (p, a) = (pole(truth[i]), residues(o, i));
                    h + a / (s - p) + a.conj() / (s - p.conj())
                }));
            }
        }
        let channel = |k: usize| Channel::new(format!("{k}+Z"), [0.0; 3], [0.0, 0.0, 1.0]);
        let set = FrfSet::new(
            freqs.clone(),
            (0..n_curves).map(|k| channel(k).unwrap()).collect(),
            vec![channel(99).unwrap()],
            Quantity::Receptance,
            data,
        )
        .unwrap();
        let given = [truth[0] * 1.0005, truth[1] * 0.9995];
        let modes = given.map(|t| {
            let est = model.invert(t, g_true).unwrap();
            ConvergedMode::exact(est.core_shear_pa, est.core_shear_pa, est.rank)
        });
        let off = modes.map(|m| (m.core_shear_pa / g_true - 1.0).norm());
        assert!(
            off.iter().all(|&o| o > 3e-3),
            "the given poles miss: {off:?}"
        );
        let ema_mode = |t: Complex64| lamdyn_ema::identify::Mode {
            freq_hz: hz(t),
            damping_ratio: 0.5 * t.im / t.re,
            loss_factor: t.im / t.re,
            pole: pole(t),
            stable_count: 10,
            shape: Vec::new(),
            participation: Vec::new(),
            real_shape: Vec::new(),
            mpc: 1.0,
            mpd_deg: 0.0,
        };
        let ema = EmaResult {
            band_hz: [1.0, 500.0],
            diagram: Vec::new(),
            modes: given.iter().map(|&t| ema_mode(t)).collect(),
            rejected: Vec::new(),
            auto_mac: Vec::new(),
            correlation: Vec::new(),
            curve_names: Vec::new(),
            cmif: Vec::new(),
            cmif_peaks: Vec::new(),
            missing_hz: Vec::new(),
            fit: None,
            warnings: Vec::new(),
            seconds: [0.0; 2],
        };
        let fit = crate::pair_fit::fit_pair(
            &model,
            &set,
            &ema,
            given,
            [&modes[0], &modes[1]],
            &|_, _, _| Err("not used: the two modes have their own ranks".into()),
        )
        .unwrap();
        let err = (fit.g_pa / g_true - 1.0).norm();
        assert!(
            err < 1e-5,
            "G* {:.6e} against {g_true:.6e}: {err:e}",
            fit.g_pa
        );
        for (i, (fitted, truth)) in fit.targets.iter().zip(truth).enumerate() {
            let e = (fitted / truth - 1.0).norm();
            assert!(e < 1e-6, "pole {i}: {e:e}");
        }
        assert!(fit.misfit[1] < 1e-3 * fit.misfit[0], "{:?}", fit.misfit);
    }

    /// The band's "through the thickness" is what a whole inverse on the model with two
    /// elements per layer finds: poles of that model (the law's fixed points) inverted on
    /// both, |ln G'₂ − ln G'₁| and |ln η₂ − ln η₁|, agree with the source (a first-order map of
    /// the eigenvalue change) within 5 % of itself plus 1e-5 where the change is tiny, and the
    /// change is there to see (above 1e-4 at some mode on this 1 mm / 1 mm / 1 mm laminate).
    #[test]
    fn through_thickness_is_the_inverse_on_two_elements_per_layer() {
        let plate = plate([0.0; 5]);
        let two_plate = LayeredPlate {
            elements_per_layer: THROUGH,
            ..plate.clone()
        };
        let one =
            LayeredInverse::build_with_inputs(&plate, [6, 5], 8e6, 20, &BASIS_RATIOS, &Input::ALL)
                .unwrap();
        let two = build_level(&two_plate, [6, 5], 8e6, 20).unwrap();
        let moved = MovedBySd::build(&one, &plate, &faces_priors());
        let (mut checked, mut largest) = (0, 0.0f64);
        for target in poles(&two, 6, true) {
            let start = law().modulus(target.re.sqrt());
            let (Ok(g1), Ok(g2)) = (one.invert(target, start), two.invert(target, start)) else {
                continue;
            };
            let mode = ConvergedMode::exact(g1.core_shear_pa, g1.core_shear_pa, g1.rank);
            let scatter = PoleScatter::default();
            let b = band((&one, Some(&two)), &moved, &mode, target, scatter, [0.0; 2]).unwrap();
            let source = b
                .sources
                .iter()
                .find(|s| s.0 == THROUGH_THICKNESS)
                .unwrap()
                .1;
            let whole = log_parts(g2.core_shear_pa - g1.core_shear_pa, g1.core_shear_pa);
            for c in 0..2 {
                assert!(
                    (source[c] - whole[c].abs()).abs() < 0.05 * whole[c].abs() + 1e-5,
                    "{:.1} Hz part {c}: source {:e}, whole inverse {:e}",
                    target.re.sqrt() / (2.0 * PI),
                    source[c],
                    whole[c]
                );
                largest = largest.max(whole[c].abs());
            }
            checked += 1;
        }
        assert!(
            checked >= 4 && largest > 1e-4,
            "{checked} modes, {largest:e}"
        );
    }

    /// The same on corner supports whose stiffness and damping are known to 20 % and 30 % (the
    /// job's defaults) and drawn from those priors with the faces' inputs, the modes above the
    /// supports' bounce and rocking (25 Hz): the supports' inputs enter the bands and the
    /// joint fit like the faces' (issue 15.3's "support stiffness" under a prior), and the
    /// per-mode band and the joint law's band hold the truth at ≥ 90 % of the pairs.
    #[test]
    fn bands_cover_the_truth_on_supports_known_within_a_tolerance() {
        let priors = faces_priors();
        let make = |d: &[f64]| supported([d[0], d[1], d[2], d[3], d[4], d[5], d[6]]);
        let sd = [0.01, 0.005, 0.005, 0.005, 0.005, 0.2, 0.3];
        let c = coverage(&make, &sd, &priors, 20, 25.0);
        assert!(c.pairs >= 70, "{} pairs identified", c.pairs);
        // Measured (79 pairs): per mode 100 % (G') and 97 % (eta), against 67 % and 76 % with
        // the supports taken as exact (their priors at 0).
        assert!(
            c.rate[0][0] >= 0.9 && c.rate[0][1] >= 0.9,
            "per-mode coverage {:?}",
            c.rate
        );
        // Measured: the joint band at 100 % (G') and 97.5 % (eta), median half-widths 2.5 % and
        // 5.5 % (92.4 %, 1.9 % and 3.7 % before the remainder beyond second order was partly
        // shared, `share_the_remainder`). Before the fit was re-linearised at the inputs it finds ([`fit_law`]) it held
        // the truth at only 67 % and 77 %: the modes pin the shared support stiffness to about
        // ±1 %, through sensitivities taken at the nominal supports, which a 20 % draw leaves
        // far behind.
        assert!(
            c.rate[1][0] >= 0.9 && c.rate[1][1] >= 0.9,
            "joint coverage {:?}",
            c.rate
        );
    }
}
