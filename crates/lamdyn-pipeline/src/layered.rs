//! The chain's layered inverse ([`lamdyn_layered::inverse`]), converged over a ladder of meshes
//! ([`lamdyn_layered::convergence`]): for each modal frequency of the fit, the identified pole
//! p of the EMA within 2 % of it gives the target eigenvalue λ = −p² = ω_n²(1 + iη), and the
//! core's G* is solved through a layered solid model of the part built from the job's
//! rectangle model (plan, dome radii) and its stack, corrected by the Richardson extrapolation
//! of each mode's eigenvalue over meshes refined by 4/3 from `inverse.layered_elements` until
//! the estimated frequency error is below `inverse.tolerance`. The start is the exact
//! inverse's G* at that frequency (else the paper's, else 10 MPa (1 + 0.5i)), which also picks
//! the mode branch. Every level's reduced eigenproblem is cached like the shell model (key:
//! plan, radii, grading, mesh, modes, basis moduli, layers and G_ref snapped to a power of two).
//!
//! Each mode's result gets a 95 % band ([`LayeredBand`]) from three kinds of source, combined
//! in quadrature as independent normal errors of ln G' and ln η, half-width h = 1.96 √(Σ σ²)
//! and band [x e^−h, x e^h] (log-normal: the moduli are positive, and a band of tens of per
//! cent is not symmetric about them):
//! - the inputs known within a tolerance (`[uncertainty]`: the faces' modulus, the thicknesses,
//!   the densities), each through its sensitivity dG*/d ln θ on the coarsest model at the
//!   converged G* ([`lamdyn_layered::sensitivity`]), to first order: a sensitivity of −20
//!   turns a 1 % face modulus into 20 % of G', so the bands of a stiff-core laminate are wide
//!   and, at tens of per cent, only roughly normal;
//! - the pole's scatter over the stabilization diagram: the sample standard deviation of the
//!   frequency and damping of the stable poles within 1 % of the mode over the model orders
//!   (at least three), through dG* = δλ/(∂λ/∂G);
//! - the discretization: the ladder's residual band, read as a 95 % half-width.

use super::CorePoint;
use super::cache::{Cache, Key};
use super::job::Job;
use crate::Reporter;
use crate::bail;
use crate::error::{Context, Result};
use lamdyn_ema::identify::EmaResult;
use lamdyn_fem::model::{MeshSpec, ModelSpec};
use lamdyn_layered::LayeredError;
use lamdyn_layered::convergence::{LadderSettings, build_level, converge};
use lamdyn_layered::inverse::{BASIS_RATIOS, InverseLayer, LayeredInverse, LayeredPlate};
use lamdyn_layered::sensitivity::{Input, ModeSensitivity, relative_parts};
use num_complex::Complex64;
use std::path::Path;

/// The rectangle's plan and radii of the job's model.
fn plate(job: &Job, base: &Path) -> Result<([f64; 2], [f64; 2])> {
    let spec: ModelSpec = match (&job.model.file, &job.model.spec) {
        (Some(f), _) => {
            let p = if f.is_absolute() {
                f.clone()
            } else {
                base.join(f)
            };
            crate::io::read_toml(&p)?
        }
        (None, Some(s)) => s.clone(),
        (None, None) => bail!("model: give file or spec"),
    };
    match spec.mesh {
        MeshSpec::Rectangle(r) => Ok(([r.length_x_m, r.length_y_m], [r.radius_x_m, r.radius_y_m])),
        _ => bail!(
            "the layered inverse needs a rectangle model (plan and dome radii); set inverse.layered = false for a Gmsh mesh"
        ),
    }
}

/// The target eigenvalue −p² of the EMA mode within 2 % of `f`, positive imaginary part.
fn target(ema: &EmaResult, f: f64) -> Option<Complex64> {
    let m = ema
        .modes
        .iter()
        .filter(|m| (m.freq_hz / f - 1.0).abs() < 0.02)
        .min_by(|a, b| (a.freq_hz - f).abs().total_cmp(&(b.freq_hz - f).abs()))?;
    let l = -(m.pole * m.pole);
    Some(if l.im < 0.0 { l.conj() } else { l })
}

/// The job's plate for the layered model.
fn layered_plate(job: &Job, base: &Path) -> Result<LayeredPlate> {
    let (plan_m, radii_m) = plate(job, base)?;
    let layers = job
        .stack
        .layers
        .iter()
        .enumerate()
        .map(|(k, l)| InverseLayer {
            thickness_m: l.thickness_m,
            density_kg_m3: l.density_kg_m3,
            poisson: l.poisson,
            young_pa: if k == 1 { None } else { l.young_pa },
            loss_factor: if k == 1 {
                0.0
            } else {
                l.loss_factor.unwrap_or(0.0)
            },
        })
        .collect();
    Ok(LayeredPlate {
        plan_m,
        radii_m,
        edge_grading: job.inverse.layered_edge_grading,
        layers,
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
    let mut key = Key::new(concat!("layered ", env!("CARGO_PKG_VERSION")))
        .f64(g_ref)
        .bytes(
            format!(
                "{:?} {:?} {} {elements:?} {modes} {coarsest}",
                plate.plan_m, plate.radii_m, plate.edge_grading
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

/// Runs the layered inverse at every modal point; returns a line describing the model.
pub fn run(
    job: &Job,
    base: &Path,
    ema: &EmaResult,
    modal: &mut [CorePoint],
    cache: &Cache,
    spinner: &dyn Reporter,
) -> Result<(Option<String>, bool)> {
    let plate = layered_plate(job, base)?;
    let starts: Vec<Complex64> = modal
        .iter()
        .map(|p| {
            p.exact_g()
                .or(p.paper_g())
                .filter(|g| g.re > 0.0 && g.im >= 0.0)
                .unwrap_or(Complex64::new(10e6, 5e6))
        })
        .collect();
    let mut g: Vec<f64> = starts.iter().map(|s| s.re).collect();
    g.sort_by(f64::total_cmp);
    // G_ref snapped to a power of two (within √2 of the median start, well inside the basis's
    // G_ref/4 .. 4 G_ref): a re-run with another law finds the same model in the cache.
    let g_ref = 2f64.powf(g.get(g.len() / 2).copied().unwrap_or(10e6).log2().round());
    spinner.stage("stage 'layered inverse': coarsest layered model and its reduced basis");
    let t = std::time::Instant::now();
    let start = job.inverse.layered_elements;
    let modes = job.inverse.layered_modes;
    let (coarsest, cached) = cached_model(cache, &plate, start, g_ref, modes, true)
        .context("cannot build the layered model")?;
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
    }
    let settings = LadderSettings {
        max_levels: job.inverse.layered_levels,
        tolerance: job.inverse.tolerance,
        modes: (modes * 2 / 3).max(12),
        ..LadderSettings::default()
    };
    let targets: Vec<Complex64> = with_pole.iter().map(|w| w.1).collect();
    let first: Vec<Complex64> = with_pole.iter().map(|w| starts[w.0]).collect();
    let all_cached = std::sync::atomic::AtomicBool::new(cached);
    let level = |m: [usize; 2]| {
        let (model, hit) = cached_model(cache, &plate, m, g_ref, settings.modes, false)?;
        if !hit {
            all_cached.store(false, std::sync::atomic::Ordering::Relaxed);
        }
        Ok(model)
    };
    let out = converge(
        &coarsest,
        start,
        &level,
        &targets,
        &first,
        &settings,
        &|m| spinner.stage(&format!("stage 'layered inverse': {m}")),
    );
    let build_s = t.elapsed().as_secs_f64();
    let out = match out {
        Ok(o) => o,
        Err(e) => {
            for &(k, _) in &with_pole {
                modal[k].layered = Some(Err(e.to_string()));
            }
            return Ok((Some(format!("not converged: {e}")), false));
        }
    };
    for (&(k, _), m) in with_pole.iter().zip(&out.modes) {
        modal[k].layered = Some(
            m.as_ref()
                .map(|m| m.core_shear_pa)
                .map_err(|e| e.to_string()),
        );
        modal[k].layered_convergence = m.as_ref().ok().copied();
    }
    for (&(k, target), m) in with_pole.iter().zip(&out.modes) {
        if let Ok(m) = m {
            let scatter = pole_scatter(ema, modal[k].freq_hz);
            modal[k].layered_band = Some(
                band(&coarsest, &plate, &job.uncertainty, m, target, scatter)
                    .map_err(|e| e.to_string()),
            );
        }
    }
    let meshes: Vec<String> = out
        .meshes
        .iter()
        .zip(&out.dofs)
        .map(|(m, d)| format!("{} x {} ({d} dofs)", m[0], m[1]))
        .collect();
    let cached = all_cached.load(std::sync::atomic::Ordering::Relaxed);
    let line = format!(
        "C3D20, one per layer through the thickness, edge grading {}; meshes {} extrapolated to a frequency error below {:.1e}; coarsest basis at G_ref {:.4e} Pa ({build_s:.1} s{}); targets: the EMA poles",
        plate.edge_grading,
        meshes.join(", "),
        settings.tolerance,
        g_ref,
        if cached { ", cached" } else { "" }
    );
    Ok((Some(line), cached))
}

/// The 95 % band of the layered result at one mode and the sources it is made of (module
/// docs).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LayeredBand {
    /// Per source (an input's name, "EMA pole", "discretization"): the relative standard
    /// deviations of G' and of η it gives.
    pub sources: Vec<(String, [f64; 2])>,
    /// Half-widths h of the 95 % band of ln G' and ln η: 1.96 √(Σ σ²); the band of G' is
    /// [G' e^−h, G' e^h].
    pub half_width: [f64; 2],
}

impl LayeredBand {
    /// The source with the largest standard deviation of G' (`part` 0) or η (1).
    pub fn dominant(&self, part: usize) -> &str {
        self.sources
            .iter()
            .max_by(|a, b| a.1[part].total_cmp(&b.1[part]))
            .map_or("-", |s| s.0.as_str())
    }
}

/// Standard deviations (Hz, damping ratio) of the stable poles of the stabilization diagram
/// within 1 % of `f` (at least three), else `None`.
fn pole_scatter(ema: &EmaResult, f: f64) -> Option<[f64; 2]> {
    let near: Vec<[f64; 2]> = ema
        .diagram
        .iter()
        .filter(|p| p.is_stable() && (p.freq_hz / f - 1.0).abs() < 0.01)
        .map(|p| [p.freq_hz, p.damping])
        .collect();
    if near.len() < 3 {
        return None;
    }
    let n = near.len() as f64;
    let sd = |k: usize| {
        let mean = near.iter().map(|p| p[k]).sum::<f64>() / n;
        (near.iter().map(|p| (p[k] - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    };
    Some([sd(0), sd(1)])
}

/// The band of one converged mode (module docs).
fn band(
    coarsest: &LayeredInverse,
    plate: &LayeredPlate,
    priors: &crate::job::UncertaintyOptions,
    mode: &lamdyn_layered::convergence::ConvergedMode,
    target: Complex64,
    scatter: Option<[f64; 2]>,
) -> std::result::Result<LayeredBand, LayeredError> {
    // At the converged G*, about the coarsest model's own eigenvalue there: the ladder
    // corrects that model by a factor per mode, and its relative sensitivities there agree
    // with a 21 x 21 mesh's within 6 % on the demo roof (at its own, coarse solution they fall
    // 5-40 % short; example roof_sensitivity).
    let rank = mode.rank;
    let g0 = mode.core_shear_pa;
    let at = coarsest
        .elastic_eigenvalue(g0, rank, target)
        .ok_or_else(|| LayeredError::Solver(format!("mode {} lost", rank + 1)))?;
    let sens: ModeSensitivity = coarsest.sensitivity(g0, rank, at)?;
    // A change of the measured eigenvalue acts through the corrected model λ_∞ = (λ_∞/λ_c) λ_c.
    let to_model = at / target;
    let thickness = |core: bool| {
        plate
            .layers
            .iter()
            .find(|l| l.young_pa.is_none() == core)
            .map_or(f64::INFINITY, |l| l.thickness_m)
    };
    let mut sources: Vec<(String, [f64; 2])> = sens
        .inputs
        .iter()
        .map(|e| {
            let rel_sd = match e.input {
                Input::FaceModulus => priors.face_modulus_rel_sd,
                Input::FaceThickness => priors.thickness_sd_m / thickness(false),
                Input::CoreThickness => priors.thickness_sd_m / thickness(true),
                Input::FaceDensity | Input::CoreDensity => priors.density_rel_sd,
            };
            (e.input.name().to_string(), e.relative_sd(g0, rel_sd))
        })
        .collect();
    if let Some([sd_f, sd_zeta]) = scatter {
        // λ = ω²(1 + iη), η = 2ζ: δλ = 2λ δf/f from the frequency, i Re λ 2δζ from the damping.
        let f = target.re.sqrt() / (2.0 * std::f64::consts::PI);
        let from_f = relative_parts(
            sens.dg_for_eigenvalue(to_model * target * (2.0 * sd_f / f)),
            g0,
        );
        let from_zeta = relative_parts(
            sens.dg_for_eigenvalue(to_model * Complex64::new(0.0, 2.0 * target.re * sd_zeta)),
            g0,
        );
        sources.push((
            "EMA pole".into(),
            [from_f[0].hypot(from_zeta[0]), from_f[1].hypot(from_zeta[1])],
        ));
    }
    sources.push((
        "discretization".into(),
        [mode.storage_band / 1.96, mode.loss_band / 1.96],
    ));
    let total = |k: usize| 1.96 * sources.iter().map(|s| s.1[k].powi(2)).sum::<f64>().sqrt();
    Ok(LayeredBand {
        half_width: [total(0), total(1)],
        sources,
    })
}
