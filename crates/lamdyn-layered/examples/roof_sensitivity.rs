//! How much the sensitivities of the layered inverse depend on the mesh they are computed on:
//! the paper's roof (as `roof_ladder`, the demo's 20 °C law), each mode's target from a
//! `TRUTH_N` × `TRUTH_N` mesh graded 0.2, then d ln G*/d ln θ for every input
//! ([`lamdyn_layered::sensitivity`]) on each mesh `N` given, each at its own solution:
//! `roof_sensitivity TRUTH_N N...`. The chain computes them on its coarsest mesh (12 × 12);
//! docs/run.md quotes this run.

#[path = "common/roof.rs"]
mod roof;

use lamdyn_layered::inverse::{BASIS_RATIOS, LayeredInverse};
use lamdyn_layered::sensitivity::Input;
use lamdyn_material::law::ViscoelasticLaw;
use num_complex::Complex64;
use std::f64::consts::PI;

fn main() {
    let a: Vec<usize> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("mesh sizes"))
        .collect();
    let (truth_n, meshes) = a.split_first().expect("TRUTH_N N...");
    let law = roof::law();
    let g = |f: f64| law.modulus(2.0 * PI * f);
    let plate = roof::plate;
    let g_ref = 2f64.powf(g(40.0).re.log2().round());
    let truth = LayeredInverse::build(&plate(0.2), [*truth_n; 2], g_ref, 20).expect("truth");
    let elastic = Complex64::new((2.0 * PI * 10.0f64).powi(2), 0.0);
    let mut poles = Vec::new();
    for rank in 0..5 {
        let mut f = 30.0;
        let mut lambda = elastic;
        for _ in 0..30 {
            lambda = truth.elastic_eigenvalue(g(f), rank, elastic).expect("mode");
            f = lambda.re.sqrt() / (2.0 * PI);
        }
        poles.push((f, lambda));
    }
    println!(
        "mesh  f_Hz  then Re d ln G/d ln θ for: {:?}",
        Input::ALL.map(|i| i.name())
    );
    for &n in meshes {
        let t = std::time::Instant::now();
        let model = LayeredInverse::build_with_inputs(
            &plate(0.0),
            [n; 2],
            g_ref,
            30,
            &BASIS_RATIOS,
            &Input::ALL,
        )
        .expect("model");
        let build_s = t.elapsed().as_secs_f64();
        for (f, target) in &poles {
            let Ok(est) = model.invert(*target, g(*f)) else {
                println!("{n}  {f:.3}  no solution");
                continue;
            };
            let gs = est.core_shear_pa;
            let s = model
                .sensitivity(gs, est.rank, *target)
                .expect("sensitivity");
            let rel: Vec<String> = s
                .inputs
                .iter()
                .map(|e| format!("{:+.2}", (e.dg_dln / gs).re))
                .collect();
            println!(
                "{n}  {f:.3}  {}  (G' {:+.1} % off)",
                rel.join("  "),
                100.0 * (gs.re / g(*f).re - 1.0)
            );
            // The same model at the converged (here: true) G*, about its own eigenvalue there:
            // what the chain uses (the ladder corrects the coarsest model by a factor per mode).
            let at_true = model
                .elastic_eigenvalue(g(*f), est.rank, *target)
                .expect("mode at the true G*");
            let s = model
                .sensitivity(g(*f), est.rank, at_true)
                .expect("sensitivity");
            let rel: Vec<String> = s
                .inputs
                .iter()
                .map(|e| format!("{:+.2}", (e.dg_dln / g(*f)).re))
                .collect();
            println!("{n}  {f:.3}  {}  (at the true G*)", rel.join("  "));
        }
        println!("{n} x {n}: built with derivatives in {build_s:.1} s");
    }
}
