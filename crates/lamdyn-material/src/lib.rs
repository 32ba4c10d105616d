//! # lamdyn-material
//!
//! The closed-form pieces of lamdyn: viscoelastic laws, the layered-plate homogenization of the
//! reference paper (eqs. 7–45), exact sandwich theory, and the ASTM E756 beam method.
//!
//! | module | what | paper / source |
//! |---|---|---|
//! | [`law`] | complex modulus laws behind [`law::ViscoelasticLaw`], WLF shift | eqs. 5–9 |
//! | [`causality`] | local Kramers–Kronig check of sampled moduli | method-notes §3 |
//! | [`laminate`] | stacks, neutral plane, B_eq, K_eq, B_K(ω), φ(ω), E_eff, the paper's inverse | eqs. 11–45 |
//! | [`sandwich`] | Mead–Markus sandwich beam and its exact inverse; RKU | method-notes §4 |
//! | [`e756`] | ASTM E756-05 uniform, Oberst and sandwich beams, forward and reduction | method-notes §4 |
//! | [`units`] | plausible ranges of SI inputs, shared by every command | — |
//!
//! Units are SI throughout (m, kg, s, Pa, rad/s); stiffnesses are per unit width (B in N·m,
//! K in N/m). Frequencies enter as angular frequency ω in rad/s; the CLI converts from Hz.
//!
//! ```
//! use lamdyn_material::laminate::{SandwichStack, PaperInverseOptions, paper_inverse};
//! use lamdyn_material::law::{PaperEq7Law, ViscoelasticLaw};
//!
//! // The paper's roof and its Table 2 effective modulus at 16 Hz (ω in rad/s).
//! let stack = SandwichStack::paper_roof();
//! let omega = 2.0 * std::f64::consts::PI * 16.0;
//! let e_eff = PaperEq7Law::paper_table2().modulus(omega);
//! let core = paper_inverse(&stack, omega, e_eff, &PaperInverseOptions::default()).unwrap();
//! assert!(core.storage_pa() > 1e6 && core.storage_pa() < 1e7); // a few MPa
//! assert!(core.phi.norm() < 0.1);                             // within the model's range
//! ```

#![deny(missing_docs)]
#![allow(non_snake_case)]

pub mod causality;
pub mod e756;
mod error;
pub mod laminate;
pub mod law;
mod roots;
pub mod sandwich;
pub mod units;

pub use error::MaterialError;
pub use roots::polynomial_roots;
