//! The layered stage's setup, resolved once from the job ([`LayeredSetup`]): the part's
//! layered plate (plan, layers, supports), the ladder's coarsest level and settings, the
//! inputs' priors and the law to fit; then each mode's start G* and target eigenvalue, and the
//! basis modulus G_ref.
//!
//! The plan is a rectangle model's plan and dome radii, or a Gmsh model's mid-surface mesh
//! ([`lamdyn_layered::plan::Plan`]); the ladder starts from `inverse.layered_elements` on a
//! rectangle, or each element of a Gmsh plan split `inverse.layered_subdivisions` times. A
//! mode starts from the exact inverse's G* at its frequency, else the paper's, else the
//! homogenization of the whole stack at the fitted (or pole-implied) laminate modulus, else
//! the core layer's `shear_pa` or 10 MPa (1 + 0.5i); the start also picks the mode branch.

use super::tuning::LayeredTuning;
use crate::chain::{CorePoint, nearest_within};
use crate::error::{Context, Result};
use crate::job::{CoreLawChoice, Job, ModelFile, UncertaintyOptions};
use lamdyn_ema::identify::EmaResult;
use lamdyn_fem::model::MeshSpec;
use lamdyn_layered::convergence::LadderSettings;
use lamdyn_layered::inverse::{InverseLayer, LayeredPlate};
use lamdyn_layered::plan::Plan;
use lamdyn_layered::sensitivity::Input;
use lamdyn_layered::supports::PointSupport;
use lamdyn_material::laminate::StackSpec;
use num_complex::Complex64;

/// The layered stage's configuration: what it takes from the job, resolved once.
#[derive(Debug, Clone)]
pub struct LayeredSetup {
    /// The part: plan, layers (the core's modulus the unknown), supports.
    pub plate: LayeredPlate,
    /// The ladder's coarsest level: elements along x and y of a rectangle, or subdivisions of
    /// each element of a Gmsh plan.
    pub start: [usize; 2],
    /// Modes of the coarsest model (`inverse.layered_modes`).
    pub modes: usize,
    /// The mesh ladder: levels, tolerance, dof cap, modes of the finer levels.
    pub ladder: LadderSettings,
    /// The stack, for the starts the sandwich inverses do not give.
    pub stack: StackSpec,
    /// The inputs' priors (`[uncertainty]`).
    pub priors: UncertaintyOptions,
    /// The law(s) to fit to the modes (`inverse.core_law`).
    pub core_law: CoreLawChoice,
    /// How far (ln) the supports' stiffness and damping lie from the job file's: 0, or where a
    /// re-run at the supports the law found puts them ([`LayeredSetup::at_supports`]).
    pub supports_at: [f64; 2],
    /// The supports as the job file gives them.
    pub job_supports: Vec<PointSupport>,
    /// The steps' tuning (defaults: [`LayeredTuning::default`]).
    pub tuning: LayeredTuning,
}

impl LayeredSetup {
    /// The setup of `job` on its model `model` (as read: [`Job::model_file`]).
    ///
    /// # Errors
    /// The model's plan cannot be read (a Gmsh file), or the stack has no core layer.
    pub fn resolve(job: &Job, model: &ModelFile) -> Result<Self> {
        let plan = plan(job, model)?;
        let start = match &plan {
            Plan::Rectangle { .. } => job.inverse.layered_elements,
            Plan::Surface(_) => [job.inverse.layered_subdivisions; 2],
        };
        let plate = layered_plate(job, plan)?;
        let job_supports = plate.supports.clone();
        let modes = job.inverse.layered_modes;
        Ok(Self {
            plate,
            start,
            modes,
            ladder: LadderSettings {
                max_levels: job.inverse.layered_levels,
                tolerance: job.inverse.tolerance,
                max_dofs: job.inverse.layered_max_dofs,
                modes: (modes * 2 / 3).max(12),
                ..LadderSettings::default()
            },
            stack: job.stack.clone(),
            priors: job.uncertainty.clone(),
            core_law: job.inverse.core_law,
            supports_at: [0.0; 2],
            job_supports,
            tuning: LayeredTuning::default(),
        })
    }

    /// The same setup with every support's stiffness times e^at\[0\] and damping times e^at\[1\]
    /// of the job file's: the re-run at the supports the law found.
    pub fn at_supports(&self, at: [f64; 2]) -> Self {
        let mut moved = self.clone();
        let scale = at.map(f64::exp);
        moved.plate.supports = self
            .job_supports
            .iter()
            .map(|s| PointSupport {
                stiffness_n_m: s.stiffness_n_m.map(|v| v * scale[0]),
                damping_n_s_m: s.damping_n_s_m.map(|v| v * scale[1]),
                ..*s
            })
            .collect();
        moved.supports_at = at;
        moved
    }

    /// Each modal point's start G* (module docs).
    pub fn starts(&self, modal: &[CorePoint]) -> Vec<Complex64> {
        let fallback = start_without_sandwich(&self.stack);
        let passive = |g: &Complex64| g.re > 0.0 && g.im >= 0.0 && g.is_finite();
        modal
            .iter()
            .map(|p| {
                p.exact_g()
                    .or(p.paper_g())
                    .filter(passive)
                    .or_else(|| {
                        homogenized_start(
                            &self.stack,
                            p.freq_hz,
                            p.e_eff_pa.or(p.e_pole_pa)?,
                            fallback,
                        )
                    })
                    .filter(passive)
                    .unwrap_or(fallback)
            })
            .collect()
    }
}

/// The reduced bases' modulus G_ref: the median start's G' snapped to a power of two (within
/// √2 of it, well inside the basis's G_ref/4 .. 4 G_ref), so that a re-run with another law
/// finds the same model in the cache; 2^23 Pa (8.4 MPa, from 10 MPa) without a start.
pub fn basis_modulus(starts: &[Complex64]) -> f64 {
    let mut g: Vec<f64> = starts.iter().map(|s| s.re).collect();
    g.sort_by(f64::total_cmp);
    2f64.powf(g.get(g.len() / 2).copied().unwrap_or(10e6).log2().round())
}

/// A modal point that has an EMA pole: its index among the modal points and the target
/// eigenvalue λ = −p² of the pole.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeTarget {
    /// Index into the modal points.
    pub point: usize,
    /// λ = −p², positive imaginary part, rad²/s².
    pub eigenvalue: Complex64,
}

/// The modal points with an EMA pole within 2 % of their frequency: the ladder's targets.
pub fn targets(ema: &EmaResult, modal: &[CorePoint]) -> Vec<ModeTarget> {
    modal
        .iter()
        .enumerate()
        .filter_map(|(point, p)| {
            let m = &ema.modes[nearest_within(ema, p.freq_hz, 0.02)?];
            let l = -(m.pole * m.pole);
            let eigenvalue = if l.im < 0.0 { l.conj() } else { l };
            Some(ModeTarget { point, eigenvalue })
        })
        .collect()
}

/// The plan of the job's model for the layered model: a rectangle model's plan, radii and
/// `inverse.layered_edge_grading`, or a Gmsh model's mid-surface mesh (read with its unit).
fn plan(job: &Job, model: &ModelFile) -> Result<Plan> {
    let ModelFile { spec, dir, label } = model;
    Ok(match &spec.mesh {
        MeshSpec::Rectangle(r) => Plan::Rectangle {
            plan_m: [r.length_x_m, r.length_y_m],
            radii_m: [r.radius_x_m, r.radius_y_m],
            edge_grading: job.inverse.layered_edge_grading,
        },
        MeshSpec::Gmsh { .. } => {
            let (mesh, _) = spec
                .build(dir)
                .with_context(|| format!("invalid model {label}"))?;
            Plan::Surface(Box::new(mesh))
        }
    })
}

/// The job's plate on `plan` for the layered model: its stack's layers (the cores' modulus
/// left to the inverse) and its supports.
fn layered_plate(job: &Job, plan: Plan) -> Result<LayeredPlate> {
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

/// The layered inverse's start where the effective-modulus route gives none (a stack of other
/// than three layers, a mode it cannot invert): the first core layer's `shear_pa` with its
/// `loss_factor`, if the job gives them, else 10 MPa with a loss factor of 0.5 (a PVB-like
/// interlayer near room temperature, method notes section 6). The basis spans a factor four
/// about it and the secant iteration moves further; a core far softer or stiffer (an EVA at
/// 1 MPa, an ionoplast at 100 MPa) wants its `shear_pa`.
fn start_without_sandwich(stack: &StackSpec) -> Complex64 {
    let core = stack
        .layered_cores()
        .ok()
        .and_then(|c| c.first().copied())
        .and_then(|k| stack.layers.get(k));
    match core.and_then(|l| l.shear_pa.map(|g| (g, l.loss_factor.unwrap_or(0.5)))) {
        Some((g, eta)) if g.is_finite() && g > 0.0 && eta.is_finite() && eta >= 0.0 => {
            Complex64::new(g, eta * g)
        }
        _ => Complex64::new(10e6, 5e6),
    }
}

/// The core's G* at `f_hz` for which the paper's homogenization of the whole `stack`
/// (eqs. 11–32, any number of layers: [`lamdyn_material::laminate::LayerStack::homogenize`],
/// plate kinematics, every core layer at the one G*) gives the fitted laminate modulus
/// `e_eff`: the layered inverse's start on a stack the sandwich inverses do not take. A secant
/// iteration on ln G* from `guess`; `None` when it does not settle in 40 steps. The paper's
/// model is tens of per cent off per mode (the reason for the layered route), a start well
/// inside the factor four the layered basis spans; a fixed guess can sit so far off that a
/// pole is matched to the wrong mode of the model.
fn homogenized_start(
    stack: &StackSpec,
    f_hz: f64,
    e_eff: Complex64,
    guess: Complex64,
) -> Option<Complex64> {
    use lamdyn_material::laminate::Kinematics;
    let cores = stack.layered_cores().ok()?;
    let omega = 2.0 * std::f64::consts::PI * f_hz;
    let kinematics = Kinematics::Plate {
        poisson: stack.layers.first()?.poisson,
    };
    // ln E_eff(G*) − ln E_eff,fitted for G* = e^z.
    let residual = |z: Complex64| -> Option<Complex64> {
        let g = z.exp();
        if !(g.re > 0.0 && g.im >= 0.0 && g.is_finite()) {
            return None;
        }
        let mut spec = stack.clone();
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

/// The relative standard deviation of the job's prior on `input` (`[uncertainty]`; a
/// thickness's sd in m over the first face's or core's thickness in `plate`).
pub(crate) fn input_rel_sd(input: Input, plate: &LayeredPlate, priors: &UncertaintyOptions) -> f64 {
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
