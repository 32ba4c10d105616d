//! The chain's layered inverse ([`lamdyn_testbench::inverse`]): for each modal frequency of the
//! fit, the identified pole p of the EMA within 2 % of it gives the target eigenvalue
//! λ = −p² = ω_n²(1 + iη), and the core's G* is solved through a layered solid model of the
//! part built from the job's rectangle model (plan, dome radii) and its stack. The start is
//! the exact inverse's G* at that frequency (else the paper's, else 10 MPa (1 + 0.5i)), which
//! also picks the mode branch. The layered model's reduced eigenproblem is cached like the
//! shell model (key: plan, radii, mesh, modes, layers and G_ref snapped to a power of two).

use super::CorePoint;
use super::cache::{Cache, Key};
use super::job::Job;
use crate::Reporter;
use crate::bail;
use crate::error::{Context, Result};
use lamdyn_ema::identify::EmaResult;
use lamdyn_fem::model::{MeshSpec, ModelSpec};
use lamdyn_testbench::inverse::{InverseLayer, LayeredInverse};
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

/// Runs the layered inverse at every modal point; returns a line describing the model.
pub fn run(
    job: &Job,
    base: &Path,
    ema: &EmaResult,
    modal: &mut [CorePoint],
    cache: &Cache,
    spinner: &dyn Reporter,
) -> Result<(Option<String>, bool)> {
    let (plan, radii) = plate(job, base)?;
    let layers: Vec<InverseLayer> = job
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
    spinner.stage("stage 'layered inverse': layered model and its reduced basis");
    let t = std::time::Instant::now();
    let mut key = Key::new(concat!("layered ", env!("CARGO_PKG_VERSION")))
        .f64(g_ref)
        .bytes(
            format!(
                "{plan:?} {radii:?} {:?} {}",
                job.inverse.layered_elements, job.inverse.layered_modes
            )
            .as_bytes(),
        );
    for l in &layers {
        key = key.bytes(format!("{l:?}").as_bytes());
    }
    let (model, cached) = match cache
        .get("layered", key)
        .and_then(|b| LayeredInverse::from_bytes(&b))
    {
        Some(m) => (m, true),
        None => {
            let m = LayeredInverse::build(
                plan,
                radii,
                job.inverse.layered_elements,
                &layers,
                g_ref,
                job.inverse.layered_modes,
            )
            .context("cannot build the layered model")?;
            cache.put("layered", key, &m.to_bytes())?;
            (m, false)
        }
    };
    let build_s = t.elapsed().as_secs_f64();
    for (p, start) in modal.iter_mut().zip(starts) {
        spinner.stage(&format!("stage 'layered inverse': {:.2} Hz", p.freq_hz));
        p.layered = Some(match target(ema, p.freq_hz) {
            Some(l) => model
                .invert(l, start)
                .map(|e| e.core_shear_pa)
                .map_err(|e| e.to_string()),
            None => Err(format!(
                "no EMA pole within 2 % of {:.3} Hz for the target eigenvalue",
                p.freq_hz
            )),
        });
    }
    let (dofs, basis) = model.size();
    let line = format!(
        "{} x {} C3D20 in plane, one per layer, {dofs} dofs, reduced basis of {basis} vectors at G_ref {:.4e} Pa ({build_s:.1} s{}); targets: the EMA poles",
        job.inverse.layered_elements[0],
        job.inverse.layered_elements[1],
        g_ref,
        if cached { ", cached" } else { "" }
    );
    Ok((Some(line), cached))
}
