//! # lamdyn-fem
//!
//! The FE model of the part (paper eqs. 3–4): MITC4 shells on flat and curved meshes, assembled
//! into faer sparse matrices, and free-free modes by a shift-invert Lanczos with a Sturm check.
//!
//! | module | what |
//! |---|---|
//! | [`mesh`] | quadrilateral meshes: structured plates and shallow shells, Gmsh MSH 2.2/4.1, node locator |
//! | [`element`] | the MITC4 shell element (stiffness, consistent mass) and its material |
//! | [`assembly`] | planned sparse pattern, parallel assembly of K0 and M, elastic supports |
//! | [`eigen`] | LLᵀ/LDLᵀ on faer, thick-restart Lanczos, [`eigen::solve_modes`] |
//! | [`convergence`] | per-mode discretization error by Richardson extrapolation over nested meshes |
//! | [`memory`] | the memory a modal solve needs, checked before allocating |
//! | [`model`] | the TOML model description (mesh, material, supports, solver) |
//! | [`output`] | MAC, VTK `.vtu` and JSON mode shapes |
//! | [`sparse`] | parallel symmetric sparse products |
//!
//! Units: m, kg, s, N, Pa, rad; eigenvalues λ = ω² in rad²/s²; six dofs per node
//! (u_x, u_y, u_z, θ_x, θ_y, θ_z) in the global frame.
//!
//! ```
//! use lamdyn_fem::mesh::structured::RectangleSpec;
//! use lamdyn_fem::element::ShellMaterial;
//! use lamdyn_fem::assembly::Assembly;
//! use lamdyn_fem::eigen::{solve_modes, ModalParams, Silent};
//!
//! // NAFEMS FV12 free square plate on a coarse mesh: 6 rigid modes, then 1.622 Hz (Kirchhoff).
//! let mesh = RectangleSpec::flat(10.0, 10.0, 12, 12).build().unwrap();
//! let steel = ShellMaterial { young_pa: 200e9, poisson: 0.3, density_kg_m3: 8000.0, thickness_m: 0.05 };
//! let asm = Assembly::new(&mesh, &steel, &[]).unwrap();
//! let sol = solve_modes(&asm, &ModalParams::lowest(7), &Silent).unwrap();
//! assert!(sol.modes[..6].iter().all(|m| m.rigid));
//! assert!((sol.modes[6].freq_hz / 1.622 - 1.0).abs() < 0.02);
//! ```

#![deny(missing_docs)]
#![allow(non_snake_case)]
// Element and solver kernels index several arrays with the same loop counter (B, C and K at
// once); iterator chains would hide the formulas they transcribe.
#![allow(clippy::needless_range_loop)]

pub mod assembly;
pub mod convergence;
pub mod eigen;
pub mod element;
mod error;
pub mod memory;
pub mod mesh;
pub mod model;
pub mod output;
pub mod sparse;
pub mod vec3;

pub use error::FemError;
pub use vec3::V3;
