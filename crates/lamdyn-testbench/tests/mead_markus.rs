//! The layered hexahedral model against exact sandwich-beam theory (Mead & Markus 1969;
//! method-notes §4) in a beam-like configuration: a simply supported sandwich beam with a
//! viscoelastic core of constant complex shear modulus.
//!
//! For simple supports the modes are sin(nπx/L) exactly, so the theory's complex eigenvalue is
//! λ_n = D(k_n) k_n⁴/m with k_n = nπ/L (D the Mead–Markus bending stiffness per unit width, m
//! the mass per unit area): f_n = √(Re λ_n)/2π, η_n = Im λ_n/Re λ_n. The 3D model: glass
//! 3 mm / core 0.5 mm / glass 3 mm, 0.6 m × 20 mm, 60 × 1 hexahedra in plane and one per layer,
//! all Poisson ratios 0 (so that the narrow beam's plane stress and the constraint below agree),
//! u_z = 0 on both end faces, u_y = 0 everywhere (vertical bending only), u_x = 0 at one
//! mid-span node on the mid-plane; core G* = 2 MPa (1 + 0.8i). Its complex eigenvalues come from
//! the reduced model (modes and core sensitivities at |G*| and G′).

use lamdyn_layered::hex20::Elastic;
use lamdyn_layered::mesh::{LayerMesh, LayeredPlateSpec};
use lamdyn_layered::reduced::ReducedModel;
use lamdyn_layered::system::LayeredSystem;
use lamdyn_material::laminate::{CoreGeometry, Face, Kinematics, SandwichStack};
use lamdyn_material::sandwich::MeadMarkus;
use num_complex::Complex64;
use std::f64::consts::PI;

#[test]
fn simply_supported_sandwich_beam_matches_mead_markus() {
    let (l, b, hf, hc) = (0.6, 0.02, 0.003, 0.0005);
    let (e_glass, rho_glass, g_core, rho_core) = (70e9, 2500.0, 2e6, 1070.0);
    let core_star = Complex64::new(1.0, 0.8);
    let layer = |t: f64| LayerMesh {
        thickness_m: t,
        elements: 1,
    };
    let mesh = LayeredPlateSpec {
        length_m: l,
        width_m: b,
        nx: 60,
        ny: 1,
        radius_x_m: f64::INFINITY,
        radius_y_m: f64::INFINITY,
        edge_grading: 0.0,
        layers: vec![layer(hf), layer(hc), layer(hf)],
    }
    .build()
    .unwrap();
    let glass = Elastic {
        young_pa: e_glass,
        poisson: 0.0,
        density_kg_m3: rho_glass,
    };
    let core = Elastic {
        young_pa: 2.0 * g_core,
        poisson: 0.0,
        density_kg_m3: rho_core,
    };
    let mut sys = LayeredSystem::assemble(&mesh, &[glass, core, glass]).unwrap();
    // Penalty springs 1e6 times a face's axial stiffness per element length.
    let pen = 1e6 * e_glass * hf;
    let mut springs = Vec::new();
    let mut mid = None;
    for (i, p) in mesh.nodes.iter().enumerate() {
        springs.push((3 * i + 1, pen));
        // Ends at x = ±l/2 (the mesh is centred on the origin).
        if (p[0].abs() - 0.5 * l).abs() < 1e-12 {
            springs.push((3 * i + 2, pen));
        }
        if p[0].abs() < 1e-12 && p[2].abs() < 1e-12 && mid.is_none() {
            mid = Some(i);
        }
    }
    let mid = mid.expect("a mid-span node on the mid-plane");
    springs.push((3 * mid, pen));
    sys.add_springs(&springs).unwrap();
    let mut load = vec![0.0; sys.n_dofs];
    load[3 * mid + 2] = 1.0;
    let rb = ReducedModel::new(&sys, &[1], &[1.0, core_star.norm()], 12, &[load], -1.0).unwrap();
    let lambda = rb.complex_eigenvalues(core_star);

    let face = Face {
        thickness_m: hf,
        density_kg_m3: rho_glass,
        young_pa: e_glass,
        poisson: 0.0,
        loss_factor: 0.0,
    };
    let stack = SandwichStack::new(
        face,
        CoreGeometry {
            thickness_m: hc,
            density_kg_m3: rho_core,
            poisson: 0.0,
        },
        face,
        None,
    )
    .unwrap();
    let mm = MeadMarkus::new(&stack, Kinematics::Beam);
    let m = 2.0 * rho_glass * hf + rho_core * hc;
    for n in 1..=3 {
        let k = n as f64 * PI / l;
        let theory = mm.stiffness_at_wavenumber(core_star * g_core, k) * k.powi(4) / m;
        let fe = lambda[n - 1];
        let (f_t, f_fe) = (theory.re.sqrt() / (2.0 * PI), fe.re.sqrt() / (2.0 * PI));
        let (eta_t, eta_fe) = (theory.im / theory.re, fe.im / fe.re);
        eprintln!(
            "mode {n}: f {f_fe:.4} Hz vs Mead-Markus {f_t:.4} Hz ({:+.2e}); eta {eta_fe:.5} vs \
             {eta_t:.5} ({:+.2e})",
            f_fe / f_t - 1.0,
            eta_fe / eta_t - 1.0
        );
        assert!((f_fe / f_t - 1.0).abs() < 0.01);
        assert!((eta_fe / eta_t - 1.0).abs() < 0.03);
    }
}
