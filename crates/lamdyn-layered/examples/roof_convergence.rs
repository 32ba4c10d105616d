//! Convergence of the free roof's complex eigenvalues with the in-plane mesh and edge grading:
//! `roof_convergence G_RE_PA ETA MODES [N:GRADING ...]`, printing per mesh the dofs, time and
//! each elastic mode's f (Hz) and η.

use lamdyn_layered::hex20::Elastic;
use lamdyn_layered::mesh::{LayerMesh, LayeredPlateSpec};
use lamdyn_layered::reduced::ReducedModel;
use lamdyn_layered::system::LayeredSystem;
use num_complex::Complex64;
use std::f64::consts::PI;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let g: f64 = a[1].parse().unwrap();
    let eta: f64 = a[2].parse().unwrap();
    let modes: usize = a[3].parse().unwrap();
    let glass = Elastic {
        young_pa: 70e9,
        poisson: 0.22,
        density_kg_m3: 2500.0,
    };
    let core = Elastic {
        young_pa: 2.0 * g * 1.49,
        poisson: 0.49,
        density_kg_m3: 1070.0,
    };
    for arg in &a[4..] {
        let (n, grading) = arg.split_once(':').unwrap();
        let n: usize = n.parse().unwrap();
        let grading: f64 = grading.parse().unwrap();
        let t = std::time::Instant::now();
        let mesh = LayeredPlateSpec {
            length_m: 0.923,
            width_m: 0.8632,
            nx: n,
            ny: n,
            radius_x_m: 3.0,
            radius_y_m: 5.0,
            edge_grading: grading,
            layers: [1.715e-3, 0.42e-3, 1.715e-3]
                .iter()
                .map(|&h| LayerMesh {
                    thickness_m: h,
                    elements: 1,
                })
                .collect(),
        }
        .build()
        .unwrap();
        let sys = LayeredSystem::assemble(&mesh, &[glass, core, glass]).unwrap();
        let mut load = vec![0.0; sys.n_dofs];
        load[3 * mesh.top[0].0 + 2] = 1.0;
        let model =
            ReducedModel::new(&sys, &[1], &[1.0], modes, &[load], -(2.0 * PI).powi(2)).unwrap();
        let lambda = model.complex_eigenvalues(Complex64::new(1.0, eta));
        let line: Vec<String> = lambda
            .iter()
            .filter(|l| l.re > 1.0)
            .take(modes - 6)
            .map(|l| format!("{:.6} {:.5}", l.re.sqrt() / (2.0 * PI), l.im / l.re))
            .collect();
        println!(
            "{n} {grading} dofs {} {:.1}s | {}",
            sys.n_dofs,
            t.elapsed().as_secs_f64(),
            line.join(" | ")
        );
    }
}
