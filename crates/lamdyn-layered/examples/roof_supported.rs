//! The paper's roof on four supports near its corners (vertical stiffness K_Z N/m each,
//! horizontal a fifth of it, dashpots C_Z N s/m): `roof_supported N K_Z C_Z [GRADING [PATCH]]`,
//! PATCH the side of a square contact patch (m). Prints each mode below 80 Hz at the demo's core
//! law (its complex fixed point) and how strongly it feels the core, d ln f / d ln G'.

#[path = "common/roof.rs"]
mod roof;

use lamdyn_layered::inverse::LayeredInverse;
use lamdyn_material::law::ViscoelasticLaw;
use num_complex::Complex64;
use std::f64::consts::PI;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: &str| a.get(i).cloned().unwrap_or(d.into());
    let n: usize = arg(1, "16").parse().expect("N");
    let kz: f64 = arg(2, "23000").parse().expect("K_Z");
    let cz: f64 = arg(3, "20").parse().expect("C_Z");
    let grading: f64 = arg(4, "0.2").parse().expect("GRADING");
    let patch: f64 = arg(5, "0").parse().expect("PATCH");
    let mut plate = roof::plate(grading);
    plate.supports = roof::corner_supports(kz, cz, patch);
    let law = roof::law();
    let model = LayeredInverse::build(&plate, [n; 2], 16e6, 30).expect("model");
    let hz = |l: Complex64| l.re.sqrt() / (2.0 * PI);
    for rank in 0..16 {
        // The complex fixed point λ = λ(G*(ω*)), ω* = √λ (the dashpots at ω* too).
        let mut lambda = Complex64::new((2.0 * PI * 30.0f64).powi(2), 0.0);
        for _ in 0..40 {
            let g = law.modulus_at_complex(lambda.sqrt());
            match model.elastic_eigenvalue(g, rank, lambda) {
                Some(l) => lambda = l,
                None => return,
            }
        }
        let f = hz(lambda);
        if f > 80.0 {
            break;
        }
        let g = law.modulus_at_complex(lambda.sqrt());
        let up = model
            .elastic_eigenvalue(g * 1.01, rank, lambda)
            .expect("mode");
        let slope = (hz(up) / f).ln() / 1.01f64.ln();
        let p = Complex64::new(0.0, 1.0) * lambda.sqrt();
        println!(
            "{rank:2} {:8.3} Hz  zeta {:.4}  dlnf/dlnG {slope:.4}",
            p.norm() / (2.0 * PI),
            -p.re / p.norm()
        );
    }
}
