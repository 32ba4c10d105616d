//! Monte Carlo uncertainty of the recovered core: the inputs the inverse cannot know
//! exactly are drawn from normal distributions — the faces' Young's modulus (one draw for both
//! faces: one glass), the thickness and density of the faces (one draw for both: the paper's
//! eq. 41 needs identical faces) and of the core, and the law's parameters from the
//! fit's covariance (u + L z in the fit's unconstrained parameters, L L^T = cov) — and both
//! inverses are run for each sample at each frequency. The bands are the 2.5 % and 97.5 %
//! quantiles of the samples that have a solution (a 95 % interval); samples without one (a
//! stiffer E' than the bonded limit, a thickness drawn negative) are counted, not hidden.
//!
//! Sample k draws from its own generator seeded with `seed + k` (SplitMix64 + Box–Muller,
//! `lamdyn_fit::synthetic::Normal`), so the bands are the same on any number of cores. The
//! samples run in parallel (rayon).

use super::job::{KinematicsChoice, UncertaintyOptions};
use crate::Reporter;
use crate::error::Result;
use lamdyn_fit::fit::FitResult;
use lamdyn_fit::synthetic::Normal;
use lamdyn_material::laminate::{Kinematics, PaperInverseOptions, StackSpec, paper_inverse};
use lamdyn_material::sandwich::exact_inverse;
use num_complex::Complex64;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::sync::atomic::{AtomicUsize, Ordering};

/// What the Monte Carlo needs.
pub struct McInput<'a> {
    /// The nominal stack.
    pub stack: &'a StackSpec,
    /// The fit (law, parameters, covariance).
    pub fit: &'a FitResult,
    /// Standard deviations, sample count, seed.
    pub options: &'a UncertaintyOptions,
    /// Beam or plate.
    pub kinematics: KinematicsChoice,
    /// The paper inverse's options (kinematics replaced per sample).
    pub paper: PaperInverseOptions,
    /// Frequencies, Hz.
    pub freqs_hz: Vec<f64>,
}

/// A 95 % band [2.5 %, 97.5 %] of a quantity.
pub type Band = [f64; 2];

/// Bands at one frequency.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct Bands {
    /// E' of the laminate, Pa, and its loss factor.
    pub e_storage: Option<Band>,
    /// η of the laminate.
    pub e_loss_factor: Option<Band>,
    /// G' (Pa) by the paper's inverse.
    pub paper_storage: Option<Band>,
    /// η by the paper's inverse.
    pub paper_loss_factor: Option<Band>,
    /// G' (Pa) by the exact inverse.
    pub exact_storage: Option<Band>,
    /// η by the exact inverse.
    pub exact_loss_factor: Option<Band>,
    /// Samples with a paper / exact solution.
    pub solved: [usize; 2],
}

/// The Monte Carlo's result.
#[derive(Debug, Clone, serde::Serialize)]
pub struct McResult {
    /// Samples drawn.
    pub samples: usize,
    /// Seed.
    pub seed: u64,
    /// Whether the law's parameters were drawn from the fit's covariance.
    pub fit_covariance: bool,
    /// Frequencies, Hz (as given).
    pub freqs_hz: Vec<f64>,
    /// Bands per frequency.
    pub bands: Vec<Bands>,
    /// Wall time, s, and threads.
    pub seconds: f64,
    /// Threads used.
    pub threads: usize,
}

impl McResult {
    /// The bands at `f` Hz (exact match of a frequency given).
    pub fn at(&self, f: f64) -> Option<&Bands> {
        self.freqs_hz
            .iter()
            .position(|x| *x == f)
            .map(|k| &self.bands[k])
    }
}

/// One sample: E* and the two G* (None without a solution) per frequency.
type Sample = Vec<Point>;

/// E*, G*_paper and G*_exact at one frequency of one sample.
type Point = (Complex64, Option<Complex64>, Option<Complex64>);

fn draw_stack(nominal: &StackSpec, o: &UncertaintyOptions, g: &mut Normal) -> StackSpec {
    let mut s = nominal.clone();
    let e_scale = 1.0 + o.face_modulus_rel_sd * g.sample();
    // One draw for the faces, one for the core: the paper's eq. 41 needs identical faces.
    let dt = [o.thickness_sd_m * g.sample(), o.thickness_sd_m * g.sample()];
    let rho = [
        1.0 + o.density_rel_sd * g.sample(),
        1.0 + o.density_rel_sd * g.sample(),
    ];
    for layer in &mut s.layers {
        let face = usize::from(layer.young_pa.is_none());
        if let Some(e) = &mut layer.young_pa {
            *e *= e_scale;
        }
        layer.thickness_m += dt[face];
        layer.density_kg_m3 *= rho[face];
    }
    s
}

fn one_sample(input: &McInput<'_>, k: usize) -> Option<Sample> {
    let o = input.options;
    let mut g = Normal::new(o.seed.wrapping_add(k as u64));
    let spec = draw_stack(input.stack, o, &mut g);
    let params = if o.fit_covariance && input.fit.has_covariance() {
        let z: Vec<f64> = (0..input.fit.parameters.len())
            .map(|_| g.sample())
            .collect();
        input.fit.draw_parameters(&z)?
    } else {
        input.fit.values()
    };
    let stack = spec.to_sandwich().ok()?;
    let kin = match input.kinematics {
        KinematicsChoice::Beam => Kinematics::Beam,
        KinematicsChoice::Plate => Kinematics::Plate {
            poisson: stack.bottom().poisson,
        },
    };
    let mut paper = input.paper;
    paper.kinematics = kin;
    Some(
        input
            .freqs_hz
            .iter()
            .map(|&f| {
                let w = 2.0 * PI * f;
                let e = input.fit.law.modulus(&params, w);
                let p = paper_inverse(&stack, w, e, &paper)
                    .ok()
                    .map(|c| c.core_shear_pa);
                let x = exact_inverse(&stack, w, e, kin)
                    .ok()
                    .map(|c| c.core_shear_pa);
                (e, p, x)
            })
            .collect(),
    )
}

/// The 2.5 % and 97.5 % quantiles (linear interpolation between order statistics); None for
/// fewer than 20 values.
pub fn band95(mut v: Vec<f64>) -> Option<Band> {
    v.retain(|x| x.is_finite());
    if v.len() < 20 {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let q = |p: f64| {
        let x = p * (v.len() - 1) as f64;
        let (i, t) = (x.floor() as usize, x - x.floor());
        v[i] + t * (v[(i + 1).min(v.len() - 1)] - v[i])
    };
    Some([q(0.025), q(0.975)])
}

/// Runs the Monte Carlo (module docs).
///
/// # Errors
/// None today; kept for inputs that may fail in the future (the signature of a stage).
pub fn monte_carlo(input: &McInput<'_>, spinner: &dyn Reporter) -> Result<McResult> {
    let n = input.options.samples;
    let t = std::time::Instant::now();
    let done = AtomicUsize::new(0);
    let samples: Vec<Option<Sample>> = (0..n)
        .into_par_iter()
        .map(|k| {
            let s = one_sample(input, k);
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            if d % 50 == 0 || d == n {
                spinner.stage(&format!("stage 'uncertainty': {d}/{n} Monte Carlo samples"));
            }
            s
        })
        .collect();
    let ok: Vec<&Sample> = samples.iter().flatten().collect();
    let bands = (0..input.freqs_hz.len())
        .map(|i| {
            let col = |f: &dyn Fn(&Point) -> Option<f64>| {
                band95(ok.iter().filter_map(|s| f(&s[i])).collect())
            };
            Bands {
                e_storage: col(&|x| Some(x.0.re)),
                e_loss_factor: col(&|x| Some(x.0.im / x.0.re)),
                paper_storage: col(&|x| x.1.map(|g| g.re)),
                paper_loss_factor: col(&|x| x.1.map(|g| g.im / g.re)),
                exact_storage: col(&|x| x.2.map(|g| g.re)),
                exact_loss_factor: col(&|x| x.2.map(|g| g.im / g.re)),
                solved: [
                    ok.iter().filter(|s| s[i].1.is_some()).count(),
                    ok.iter().filter(|s| s[i].2.is_some()).count(),
                ],
            }
        })
        .collect();
    Ok(McResult {
        samples: n,
        seed: input.options.seed,
        fit_covariance: input.options.fit_covariance && input.fit.has_covariance(),
        freqs_hz: input.freqs_hz.clone(),
        bands,
        seconds: t.elapsed().as_secs_f64(),
        threads: rayon::current_num_threads(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band95_of_a_uniform_grid_is_its_quantiles() {
        let v: Vec<f64> = (0..=1000).map(|k| k as f64).collect();
        let [lo, hi] = band95(v).unwrap();
        assert!((lo - 25.0).abs() < 1e-9 && (hi - 975.0).abs() < 1e-9);
        assert!(band95(vec![1.0; 10]).is_none());
    }
}
