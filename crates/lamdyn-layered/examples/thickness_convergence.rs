//! How far one 20-node hexahedron per layer through the thickness (the layered inverse's mesh;
//! its ladder refines in plane only) is from a mesh refined through the thickness, and what that
//! does to the core's G' found: `thickness_convergence [N [GRADING]]` (defaults 16, 0.3).
//!
//! For each laminate (the paper's roof; an aluminium sandwich with a 2 mm polymer core, stiff
//! and soft; the same with a 10 mm core) and the first ten elastic free modes, with the core
//! real at G: the relative frequency change δ = f(refined)/f(one per layer) − 1, with the
//! refined mesh [2, 4, 2] elements through the faces and core, the slope s = d ln f / d ln G'
//! (a central difference of ±1 % in G on one element per layer) and the G' error it implies,
//! δ/s: a model too stiff by δ finds G' low by δ/s. Prints one row per laminate
//! (docs/run.md, "Through the thickness").

use lamdyn_layered::hex20::Elastic;
use lamdyn_layered::mesh::{LayerMesh, LayeredPlateSpec};
use lamdyn_layered::system::LayeredSystem;
use std::f64::consts::PI;

/// One laminate: name, plan (m), radii (m), layer thicknesses (m), faces' E (Pa), ν, ρ
/// (kg/m³), core's G (Pa), ρ.
struct Laminate {
    name: &'static str,
    plan_m: [f64; 2],
    radii_m: [f64; 2],
    thickness_m: [f64; 3],
    face: (f64, f64, f64),
    core_g_pa: f64,
    core_density: f64,
}

const MODES: usize = 10;

/// The first `MODES` elastic frequencies, Hz, of `lam` with the core at `g` Pa on `n` × `n`
/// elements graded `grading` and `through` elements per layer.
fn frequencies(lam: &Laminate, n: usize, grading: f64, through: [usize; 3], g: f64) -> Vec<f64> {
    let (e, nu, rho) = lam.face;
    let face = Elastic {
        young_pa: e,
        poisson: nu,
        density_kg_m3: rho,
    };
    let core = Elastic {
        young_pa: 2.0 * g * 1.49,
        poisson: 0.49,
        density_kg_m3: lam.core_density,
    };
    let spec = LayeredPlateSpec {
        length_m: lam.plan_m[0],
        width_m: lam.plan_m[1],
        nx: n,
        ny: n,
        radius_x_m: lam.radii_m[0],
        radius_y_m: lam.radii_m[1],
        layers: lam
            .thickness_m
            .iter()
            .zip(through)
            .map(|(&thickness_m, elements)| LayerMesh {
                thickness_m,
                elements,
            })
            .collect(),
        edge_grading: grading,
    };
    let mesh = spec.build().expect("mesh");
    let system = LayeredSystem::assemble(&mesh, &[face, core, face]).expect("assembly");
    // Free: six rigid-body modes at 0, the shift below them.
    let (lambda, _) = system
        .modes(&[1.0; 3], 6 + MODES, -(2.0 * PI).powi(2))
        .expect("modes");
    lambda[6..]
        .iter()
        .map(|l| l.max(0.0).sqrt() / (2.0 * PI))
        .collect()
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let n: usize = a.get(1).map_or(16, |s| s.parse().expect("N"));
    let grading: f64 = a.get(2).map_or(0.3, |s| s.parse().expect("GRADING"));
    let glass = (70e9, 0.22, 2500.0);
    let aluminium = (70e9, 0.33, 2700.0);
    let flat = [f64::INFINITY; 2];
    let sandwich = |name, core_m, g| Laminate {
        name,
        plan_m: [0.5, 0.4],
        radii_m: flat,
        thickness_m: [1e-3, core_m, 1e-3],
        face: aluminium,
        core_g_pa: g,
        core_density: 1100.0,
    };
    let laminates = [
        Laminate {
            name: "roof glass 1.715 / PVB 0.42 / glass, G 20 MPa",
            plan_m: [0.923, 0.8632],
            radii_m: [3.0, 5.0],
            thickness_m: [1.715e-3, 0.42e-3, 1.715e-3],
            face: glass,
            core_g_pa: 20e6,
            core_density: 1070.0,
        },
        sandwich("Al 1 / 2 mm core / Al 1, G 60 MPa", 2e-3, 60e6),
        sandwich("Al 1 / 2 mm core / Al 1, G 2 MPa", 2e-3, 2e6),
        sandwich("Al 1 / 10 mm core / Al 1, G 60 MPa", 10e-3, 60e6),
        sandwich("Al 1 / 10 mm core / Al 1, G 2 MPa", 10e-3, 2e6),
    ];
    println!("{n} x {n} elements, grading {grading}; refined through the thickness: [2, 4, 2]");
    println!("laminate | f range Hz | max |delta| | max |delta/s| in G'");
    for lam in &laminates {
        let g = lam.core_g_pa;
        let one = frequencies(lam, n, grading, [1; 3], g);
        let refined = frequencies(lam, n, grading, [2, 4, 2], g);
        let up = frequencies(lam, n, grading, [1; 3], g * 1.01);
        let down = frequencies(lam, n, grading, [1; 3], g / 1.01);
        let (mut worst_f, mut worst_g) = (0.0f64, 0.0f64);
        for k in 0..MODES {
            let delta = refined[k] / one[k] - 1.0;
            let slope = (up[k] / down[k]).ln() / (2.0 * 1.01f64.ln());
            worst_f = worst_f.max(delta.abs());
            worst_g = worst_g.max((delta / slope).abs());
        }
        println!(
            "{} | {:.1}-{:.1} | {:.1e} | {:.2} %",
            lam.name,
            one[0],
            one[MODES - 1],
            worst_f,
            100.0 * worst_g
        );
    }
}
