//! The layered route's tests: bands and their coverage, the law's choice and
//! re-linearisation, the supports' re-run, the pair fit, the check through the thickness.

use super::bands::{MovedBySd, band};
use super::law::{
    Candidate, SHARED_REMAINDER, Weights, candidates, core_laws, fit_law_with, lowest_akaike,
    share_the_remainder, supports_found, to_real_frequency,
};
use super::pole_scatter::{
    PoleChecks, PoleScatter, group_spread, hit_jackknife, order_spread, pole_scatter,
};
use super::tuning::{LawTuning, LayeredTuning, PairFitTuning};
use super::*;
use crate::band::BandSource;
use crate::job::Job;
use lamdyn_fit::FitError;
use lamdyn_fit::joint::fit_core_law;
use lamdyn_fit::joint::{CoreLaw, CoreLawFit, InputPrior, ModePoint, fit_core_law_shifted};
use lamdyn_fit::synthetic::Normal;
use lamdyn_layered::LayeredError;
use lamdyn_layered::convergence::ConvergedMode;
use lamdyn_layered::convergence::build_level;
use lamdyn_layered::inverse::{BASIS_RATIOS, InverseLayer, LayeredPlate};
use lamdyn_layered::plan::Plan;
use lamdyn_layered::sensitivity::{Input, log_parts};
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
///
/// The first step takes the mode by rank from all eigenvalues at 50 Hz; the next ones the
/// eigenvalue nearest the last ([`LayeredInverse::pole_near`], a few LU solves instead of an
/// eigendecomposition) until a step is below [`POLE_SETTLED`]; the result is checked by rank
/// once more, and where another mode was taken the iteration is done by rank at every step.
fn poles(model: &LayeredInverse, n: usize, free: bool) -> Vec<Complex64> {
    // Elastic: Re λ above 1e-6 of a 1 kHz mode's (above 1 Hz; the rigid modes lie near 0).
    let elastic = Complex64::new((2.0 * PI * 1000.0f64).powi(2), 0.0);
    let at = |l: Complex64| if free || l.re <= 0.0 { elastic } else { l };
    let by_rank = |rank: usize, steps: usize, mut l: Complex64| {
        for _ in 0..steps {
            let w = if l.re > 0.0 {
                l.sqrt()
            } else {
                Complex64::new(2.0 * PI * 50.0, 0.0)
            };
            l = model
                .elastic_eigenvalue(law().modulus_at_complex(w), rank, at(l))
                .unwrap();
        }
        l
    };
    (0..n)
        .map(|rank| {
            let first = by_rank(rank, 1, Complex64::new(0.0, 0.0));
            let mut l = first;
            for _ in 0..POLE_STEPS {
                let g = law().modulus_at_complex(l.sqrt());
                let Some(next) = model.pole_near(g, l) else {
                    return by_rank(rank, POLE_STEPS, first);
                };
                let step = (next - l).norm() / l.norm();
                l = next;
                if step < POLE_SETTLED {
                    break;
                }
            }
            let check = by_rank(rank, 1, l);
            if (check - l).norm() > 1e-6 * l.norm() {
                return by_rank(rank, POLE_STEPS, first);
            }
            l
        })
        .collect()
}

/// Steps of [`poles`]'s fixed point, and the relative step at which it has settled (the
/// reduced eigensolver's own noise is 1e-10 to 1e-8, [`LayeredInverse::pole_eigenvalue`]).
const POLE_STEPS: usize = 40;
const POLE_SETTLED: f64 = 1e-10;

/// One (mode, seed) pair of a coverage run: per band (per-mode, joint) and part (G', η)
/// whether it held the truth, and its half-width of ln G' or ln η.
#[derive(Default)]
struct Observed {
    inside: [[bool; 2]; 2],
    half_width: [[f64; 2]; 2],
}

/// What a coverage run measured: per band (per-mode, joint) and part (G', η) the share of
/// (mode, seed) pairs whose truth it held and its median half-width of ln G' or ln η.
struct Coverage {
    pairs: usize,
    rate: [[f64; 2]; 2],
    median_half_width: [[f64; 2]; 2],
}

/// The coverage test without the EMA and the mesh: `seeds` virtual tests of the
/// part `make` builds from the inputs' relative changes, drawn from their priors `sd`
/// (order of [`Input::ALL`]), its poles computed by a model built from the drawn inputs
/// (no derivatives: independent of the sensitivities under test), each the complex fixed
/// point of the core's law, and scattered by 0.02 % in frequency and 2e-4 in damping
/// ratio; identified with the nominal inputs (`priors` the job's) and moved to the real
/// frequency ([`to_real_frequency`]); then where the truth G*(f_k) lies against the
/// per-mode band and the joint law's band. Truth and identification share one mesh, so the
/// bands hold no discretization part here (`ConvergedMode` with zero bands).
fn coverage(
    make: &(dyn Fn(&[f64]) -> LayeredPlate + Sync),
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
    let moved = MovedBySd::build(&nominal, &nominal_plate, priors, WIDE);
    let (sd_f_rel, sd_zeta) = (2e-4, 2e-4);
    // One virtual test per seed, each with its own random stream: the seeds run in parallel
    // (each is one-threaded) and draw the same numbers on any thread count.
    let one_seed = |seed: usize| -> Vec<Observed> {
        let mut rng = Normal::new(2026 + seed as u64);
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
            let target = exact * (1.0 + 2.0 * eps_f) + Complex64::new(0.0, 2.0 * exact.re * eps_z);
            let start = law().modulus(2.0 * PI * f) * 1.2;
            let est = match nominal.invert(target, start) {
                // A core that is not passive (G'' < 0: a mode the core barely damps, its
                // pole's scatter beyond what the core gives) has no layered result in the
                // chain either (`physical`).
                Ok(e) if e.core_shear_pa.re > 0.0 && e.core_shear_pa.im > 0.0 => e,
                // A mode the nominal model cannot match (or a support's bounce, which the
                // core barely moves): left out, as the chain does.
                _ => continue,
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
                paper: Err(crate::chain::NoSandwichInverse::NotASandwich),
                exact: Err(crate::chain::NoSandwichInverse::NotASandwich),
                layered: Some(Ok(est.core_shear_pa)),
                layered_convergence: Some(mode),
                ladder_estimate: None,
                layered_band: Some(Ok(b)),
            });
        }
        let joint = fit_law_with(
            (CoreLaw::FractionalZener, 0.0),
            &LawTuning::default(),
            &modal,
            Some(&nominal),
            Weights::Law,
        )
        .unwrap();
        to_real_frequency(&mut modal, Some(&joint));
        let joint = joint.unwrap();
        modal
            .iter()
            .zip(&joint.at_modes)
            .map(|(p, j)| {
                let g = p.layered_g().unwrap();
                let b = p.layered_band.as_ref().unwrap().as_ref().unwrap();
                let t = law().modulus(2.0 * PI * p.freq_hz);
                let truth_log = [t.re.ln(), (t.im / t.re).ln()];
                let per_mode = [g.re.ln(), (g.im / g.re).ln()];
                let joint_band = [
                    [j.storage_ci95[0].ln(), j.storage_ci95[1].ln()],
                    [j.loss_factor_ci95[0].ln(), j.loss_factor_ci95[1].ln()],
                ];
                let mut o = Observed::default();
                for c in 0..2 {
                    let half_width = b.half_width.to_array()[c];
                    o.inside[0][c] = (truth_log[c] - per_mode[c]).abs() <= half_width;
                    let lo_hi = joint_band[c];
                    o.inside[1][c] = lo_hi[0] <= truth_log[c] && truth_log[c] <= lo_hi[1];
                    o.half_width[0][c] = half_width;
                    o.half_width[1][c] = 0.5 * (lo_hi[1] - lo_hi[0]);
                }
                o
            })
            .collect()
    };
    let observed: Vec<Observed> = {
        use rayon::prelude::*;
        (0..seeds).into_par_iter().flat_map_iter(one_seed).collect()
    };
    let total = observed.len();
    let mut inside = [[0usize; 2]; 2];
    let mut widths = [[Vec::new(), Vec::new()], [Vec::new(), Vec::new()]];
    for o in &observed {
        for (band, (ins, hw)) in o.inside.iter().zip(&o.half_width).enumerate() {
            for c in 0..2 {
                inside[band][c] += usize::from(ins[c]);
                widths[band][c].push(hw[c]);
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
        "{total} pairs: coverage per mode {:?}, joint {:?}; median half-widths per mode {:?}, \
         joint {:?}",
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

/// An EMA mode at the pole `pole` (rad/s) with the standard deviations `sd` and nothing
/// else identified.
fn ema_mode(pole: Complex64, sd: Option<lamdyn_ema::lsfd::PoleSd>) -> lamdyn_ema::identify::Mode {
    lamdyn_ema::identify::Mode {
        freq_hz: pole.norm() / (2.0 * PI),
        damping_ratio: -pole.re / pole.norm(),
        loss_factor: -2.0 * pole.re / pole.norm(),
        pole,
        stable_count: 10,
        shape: Vec::new(),
        participation: Vec::new(),
        real_shape: Vec::new(),
        mpc: 1.0,
        mpd_deg: 0.0,
        sd,
        pick: Default::default(),
        diagram_pole: pole,
        refined: false,
        refinement: None,
        quality: Default::default(),
    }
}

/// An identification of `modes` alone (no diagram, no shapes).
fn ema_of(modes: Vec<lamdyn_ema::identify::Mode>) -> EmaResult {
    EmaResult {
        band_hz: [1.0, 500.0],
        diagram: Vec::new(),
        modes,
        rejected: Vec::new(),
        set_aside: Vec::new(),
        auto_mac: Vec::new(),
        correlation: Vec::new(),
        curve_names: Vec::new(),
        cmif: Vec::new(),
        cmif_peaks: Vec::new(),
        missing_hz: Vec::new(),
        fit: None,
        warnings: Vec::new(),
        timings: Default::default(),
        second_shape_calibrated: false,
    }
}

/// The pole's noise is the largest, per part, of its estimates: a pole whose own covariance
/// gives sd(f) 0.05 Hz and sd(ζ) 0.002 keeps them where the response groups' spread is
/// smaller (0.01 Hz, 1e-4), takes the groups' where it is larger (0.2 Hz in f), and has its
/// own alone without groups; a non-finite sd is no estimate.
#[test]
fn the_pole_s_own_sd_joins_its_scatter() {
    let at = |f: f64, zeta: f64| {
        let w = 2.0 * PI * f;
        Complex64::new(-zeta * w, w * (1.0 - zeta * zeta).sqrt())
    };
    let sd = |freq_hz: f64, damping_ratio: f64| lamdyn_ema::lsfd::PoleSd {
        freq_hz,
        damping_ratio,
    };
    let whole = ema_of(vec![ema_mode(at(100.0, 0.05), Some(sd(0.05, 0.002)))]);
    // Two groups a apart have a standard error of their mean of a/2.
    let groups = |df: f64, dz: f64| PoleChecks {
        groups: [-0.5, 0.5]
            .iter()
            .map(|s| ema_of(vec![ema_mode(at(100.0 + s * df, 0.05 + s * dz), None)]))
            .collect(),
        ..Default::default()
    };
    let noise = |checks: &PoleChecks| pole_scatter(&whole, checks, 100.0).noise.unwrap();
    let close = |a: [f64; 2], b: [f64; 2]| (0..2).all(|k| (a[k] / b[k] - 1.0).abs() < 1e-9);
    let n = noise(&groups(0.02, 2e-4));
    assert!(close(n, [0.05, 0.002]), "{n:?}");
    let n = noise(&groups(0.4, 2e-4));
    assert!(close(n, [0.2, 0.002]), "{n:?}");
    let n = noise(&PoleChecks::default());
    assert!(close(n, [0.05, 0.002]), "{n:?}");
    let nan = ema_of(vec![ema_mode(at(100.0, 0.05), Some(sd(f64::NAN, 0.002)))]);
    assert!(
        pole_scatter(&nan, &PoleChecks::default(), 100.0)
            .noise
            .is_none()
    );
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
    type Fits = Vec<(Candidate, std::result::Result<CoreLawFit, FitError>)>;
    let fits = |pts: &[ModePoint]| -> Fits {
        candidates(
            crate::job::CoreLawChoice::Auto,
            &LawTuning::default().prony_offsets,
        )
        .into_iter()
        .map(|c| {
            let fit = fit_core_law_shifted(pts, &[], c.0, c.1);
            (c, fit)
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
        f.1 = Err(no_fit("no start"));
    }
    let (found, why) = chosen(&one);
    assert!(found == (CoreLaw::GeneralizedMaxwell, 0.75) && why.is_none());
    let none = vec![
        ((CoreLaw::FractionalZener, 0.0), Err(no_fit("first"))),
        ((CoreLaw::GeneralizedMaxwell, 0.0), Err(no_fit("second"))),
    ];
    assert_eq!(lowest_akaike(&none).unwrap().unwrap_err(), no_fit("first"));
    assert!(lowest_akaike(&[]).is_none());
    assert!(core_laws(crate::job::CoreLawChoice::None).is_empty());
}

/// The ladder runs again at the supports the law found only when it moved them beyond both
/// [`LawTuning::supports_rerun`] and their 95 % interval: points whose supports are 15 % stiffer
/// than the job says (effects of −3 to −1 on ln G', noise 0.1 %) give the job with every spring
/// times e^0.15 (to the fit's accuracy) and the dashpots as they were; at 1 % they give none, and a
/// free part never.
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
    let setup = setup_of(&supported_job());
    let far = fit_core_law(&points(0.15), &priors, CoreLaw::FractionalZener);
    let at = supports_found(&setup, Some(&far)).expect("a re-run");
    let moved = setup.at_supports(at);
    assert!((at[0] - 0.15).abs() < 0.01, "{at:?}");
    assert_eq!(moved.supports_at, at);
    let factor = moved.plate.supports[0].stiffness_n_m[2] / 400.0;
    assert!((factor - at[0].exp()).abs() < 1e-12, "{factor}");
    assert_eq!(moved.plate.supports[1].damping_n_s_m, [0.0; 3]);
    assert!((moved.plate.supports[0].damping_n_s_m[2] / 2.0 - at[1].exp()).abs() < 1e-12);
    // A second move is taken from the job file's supports, not from the first move's.
    let again = moved.at_supports([0.0; 2]);
    assert_eq!(again.plate.supports, setup.plate.supports);
    let near = fit_core_law(&points(0.01), &priors, CoreLaw::FractionalZener);
    assert!(supports_found(&setup, Some(&near)).is_none());
    let mut free = setup.clone();
    free.plate.supports.clear();
    free.job_supports.clear();
    assert!(supports_found(&free, Some(&far)).is_none());
}

/// The default wide prior ([`LawTuning::wide_prior`]).
const WIDE: f64 = LawTuning::DEFAULT_WIDE_PRIOR;
/// The default shared remainder ([`LawTuning::remainder_shared`]).
const SHARED: f64 = LawTuning::DEFAULT_REMAINDER_SHARED;

/// A failed law fit, for the choice between laws.
fn no_fit(why: &str) -> FitError {
    FitError::Inconsistent {
        context: "test".into(),
        reason: why.into(),
    }
}

/// The layered setup of `job` on a 0.5 x 0.4 m flat plan (its model file is not read).
fn setup_of(job: &Job) -> LayeredSetup {
    let mut p = plate([0.0; 5]);
    p.supports = job.inverse.supports.iter().map(|s| s.to_point()).collect();
    LayeredSetup {
        plate: p.clone(),
        start: job.inverse.layered_elements,
        modes: job.inverse.layered_modes,
        ladder: lamdyn_layered::convergence::LadderSettings::default(),
        stack: job.stack.clone(),
        priors: job.uncertainty.clone(),
        core_law: job.inverse.core_law,
        supports_at: [0.0; 2],
        job_supports: p.supports.clone(),
        tuning: LayeredTuning::default(),
    }
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
            (BandSource::InputsBeyondSecondOrder.label().into(), b),
        ],
    };
    let prior = InputPrior {
        name: "face modulus".into(),
        rel_sd: 0.01,
        at: 0.0,
    };
    let mut points = vec![point([0.04, 0.3]), point([0.01, 0.02]), point([0.02, 0.1])];
    let mut priors = vec![prior.clone()];
    share_the_remainder(&mut points, &mut priors, SHARED);
    let names: Vec<&str> = priors.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "face modulus",
            SHARED_REMAINDER[0].label(),
            SHARED_REMAINDER[1].label()
        ]
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
    share_the_remainder(&mut none, &mut priors, SHARED);
    assert_eq!(priors.len(), 1);
    let mut exact = vec![point([0.0, 0.0])];
    share_the_remainder(&mut exact, &mut priors, SHARED);
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
    // Measured (80 pairs, one random stream per seed): per mode 96 % (G') and 96 % (eta) at
    // half-widths of 15-18 %; joint 100 % and 100 % with median half-widths of 2.0 % and
    // 2.4 %. On one stream for all seeds it was 90 % / 90 % per mode and 98.8 % / 96.3 %
    // joint.
    assert!(total >= 70, "{total} pairs identified");
    assert!(
        rate[1][0] >= 0.9 && rate[1][1] >= 0.9,
        "joint coverage {rate:?}"
    );
    // The per-mode band: at least 3 binomial sd (80 pairs) below its measured 90-96 %.
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
    let moved = MovedBySd::build(&nominal, &plate, &faces_priors(), WIDE);
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
        let back = nominal.invert(b.coarse.eigenvalue, b.found_pa).unwrap();
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
    let pole = super::pair_fit::pole_of;
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
    let off = modes
        .clone()
        .map(|m| (m.core_shear_pa / g_true - 1.0).norm());
    assert!(
        off.iter().all(|&o| o > 3e-3),
        "the given poles miss: {off:?}"
    );
    let ema = ema_of(
        given
            .iter()
            .map(|&t| lamdyn_ema::identify::Mode {
                freq_hz: hz(t),
                damping_ratio: 0.5 * t.im / t.re,
                loss_factor: t.im / t.re,
                ..ema_mode(pole(t), None)
            })
            .collect(),
    );
    let fit = super::pair_fit::fit_pair(
        &model,
        &PairFitTuning::default(),
        &set,
        &ema,
        given,
        [&modes[0], &modes[1]],
        &|_, _, _| {
            Err(LayeredError::Invalid(
                "not used: the two modes have their own ranks".into(),
            ))
        },
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
    let moved = MovedBySd::build(&one, &plate, &faces_priors(), WIDE);
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
            .find(|s| s.0 == BandSource::ThroughThickness)
            .unwrap()
            .1
            .to_array();
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
/// joint fit like the faces' (a "support stiffness" under a prior), and the
/// per-mode band and the joint law's band hold the truth at ≥ 90 % of the pairs.
#[test]
fn bands_cover_the_truth_on_supports_known_within_a_tolerance() {
    let priors = faces_priors();
    let make = |d: &[f64]| supported([d[0], d[1], d[2], d[3], d[4], d[5], d[6]]);
    let sd = [0.01, 0.005, 0.005, 0.005, 0.005, 0.2, 0.3];
    let c = coverage(&make, &sd, &priors, 20, 25.0);
    assert!(c.pairs >= 70, "{} pairs identified", c.pairs);
    // Measured (77 pairs, one random stream per seed): per mode 100 % (G') and 98.7 % (eta);
    // on one stream for all seeds (79 pairs) 100 % and 97 %, against 67 % and 76 % with the
    // supports taken as exact (their priors at 0).
    assert!(
        c.rate[0][0] >= 0.9 && c.rate[0][1] >= 0.9,
        "per-mode coverage {:?}",
        c.rate
    );
    // Measured: the joint band at 90.9 % (G') and 94.8 % (eta), median half-widths 3.4 % and
    // 7.6 % (on one stream for all seeds: 100 % and 97.5 %, 2.5 % and 5.5 %; 92.4 %, 1.9 %
    // and 3.7 % before the remainder beyond second order was partly shared,
    // `share_the_remainder`). Before the fit was re-linearised at the inputs it finds ([`fit_law`])
    // it held the truth at only 67 % and 77 %: the modes pin the shared support stiffness to about
    // ±1 %, through sensitivities taken at the nominal supports, which a 20 % draw leaves
    // far behind.
    assert!(
        c.rate[1][0] >= 0.9 && c.rate[1][1] >= 0.9,
        "joint coverage {:?}",
        c.rate
    );
}

/// The ladder run again ([`converge_again`]) converges a pole from the start it is given, as
/// the layered stage's ladder does from the pole route's: the first four elastic poles of the
/// free plate on a 24 × 20 mesh, converged on the ladder from 6 × 5 with the core's law as the
/// start, land within 2 % of the law's G' (what is left is the 24 × 20 mesh's own error), each
/// with its levels' corrections; a modal point without a pole gets none.
#[test]
fn the_ladder_again_converges_each_pole_from_its_start() {
    let mut setup = setup_of(&supported_job());
    setup.plate.supports.clear();
    setup.job_supports.clear();
    setup.start = [6, 5];
    // The poles of a mesh four times as fine in each direction as the ladder's first.
    let fine = build_level(&setup.plate, [24, 20], 8e6, setup.modes).expect("the fine mesh");
    let eigenvalues = poles(&fine, 4, true);
    // p with −p² = λ: the pole in the upper half plane with a negative real part.
    let pole = |l: Complex64| Complex64::new(0.0, 1.0) * l.sqrt();
    let ema = ema_of(
        eigenvalues
            .iter()
            .map(|&l| ema_mode(pole(l), None))
            .collect(),
    );
    let mut modal: Vec<CorePoint> = ema
        .modes
        .iter()
        .map(|m| crate::frf_route::tests::at(m.freq_hz))
        .collect();
    modal.push(crate::frf_route::tests::at(1000.0));
    let points: Vec<usize> = (0..modal.len()).collect();
    let starts: Vec<Complex64> = modal
        .iter()
        .map(|p| law().modulus(2.0 * PI * p.freq_hz))
        .collect();
    let cache = crate::cache::Cache::new(None);
    let again = LadderAgain {
        cache: &cache,
        ema: &ema,
    };
    let found = converge_again(&setup, again, &modal, (&points, &starts), &crate::Silent).unwrap();
    assert!(found[4].is_none());
    for ((p, start), m) in modal.iter().zip(&starts).zip(&found).take(4) {
        let m = m.as_ref().expect("a converged mode");
        let off = m.core_shear_pa.re / start.re - 1.0;
        assert!(off.abs() < 0.02, "{:.2} Hz: G' {off:+.4}", p.freq_hz);
        assert!(!m.level_corrections.is_empty(), "{m:?}");
    }
}
