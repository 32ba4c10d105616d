//! Viscoelastic laws: complex modulus against angular frequency.
//!
//! Every law implements [`ViscoelasticLaw`]: `modulus(ω)` returns the complex modulus
//! M*(ω) = M'(ω) + i M''(ω) = M'(ω) (1 + i η(ω)) in Pa at the angular frequency ω in rad/s
//! (paper eqs. 5–6). The same trait serves Young's and shear moduli; which one a law stands for
//! is decided where it is used (a layer's `young_law` or `shear_law`).
//!
//! | law | type | parameters |
//! |---|---|---|
//! | paper eq. 7 | [`PaperEq7Law`] | E0, μ, t0, c |
//! | fractional-derivative Zener | [`FractionalZener`] | G0, G∞, τ, α |
//! | generalized Maxwell (Prony series) | [`GeneralizedMaxwell`] | G_e, (g_k, τ_k) |
//! | constant complex modulus | [`ConstantModulus`] | M', η |
//! | time–temperature shift (WLF) around any law | [`TemperatureShifted`] | C1, C2, T_ref, T |
//!
//! Convention: the time dependence is e^{+iωt}, so a passive material has M'' ≥ 0. Laws are
//! defined for ω ≥ 0.
//!
//! [`LawSpec`] is the serialisable description (TOML/JSON, `kind = "fractional_zener"`, …) that
//! the CLI and job files use; [`LawSpec::build`] validates it into a law.

mod constant;
mod fractional_zener;
mod generalized_maxwell;
mod paper_eq7;
mod spec;
mod wlf;

pub use constant::ConstantModulus;
pub use fractional_zener::FractionalZener;
pub use generalized_maxwell::{GeneralizedMaxwell, PronyTerm};
pub use paper_eq7::PaperEq7Law;
pub use spec::{LawSpec, PronyTermSpec};
pub use wlf::{TemperatureShifted, WlfShift};

use num_complex::Complex64;
use std::fmt::Debug;

/// A linear viscoelastic law: complex modulus (Pa) at angular frequency ω (rad/s).
pub trait ViscoelasticLaw: Debug + Send + Sync {
    /// Complex modulus M*(ω) = M' + i M'' in Pa at `omega_rad_s` ≥ 0 (paper eq. 5).
    fn modulus(&self, omega_rad_s: f64) -> Complex64;

    /// A one-line description with the parameters, for reports.
    fn describe(&self) -> String;

    /// Storage modulus M'(ω) = Re M*(ω), Pa.
    fn storage_modulus(&self, omega_rad_s: f64) -> f64 {
        self.modulus(omega_rad_s).re
    }

    /// Loss factor η(ω) = M''(ω) / M'(ω) (paper eq. 6), dimensionless.
    fn loss_factor(&self, omega_rad_s: f64) -> f64 {
        let m = self.modulus(omega_rad_s);
        m.im / m.re
    }

    /// The law continued to a complex angular frequency ω = ω' + iσ (rad/s, σ ≥ 0), Pa: the
    /// modulus a free vibration e^{iωt} = e^{−σt} e^{iω't} sees, so a mode whose pole is p
    /// (response e^{pt}) feels M*(−i p), not M*(|p|). A law with a closed form in iω overrides
    /// this with its exact continuation; the default is first order about the real axis,
    /// M*(ω') + iσ dM*/dω (central difference over ±10⁻⁴ ω'), whose error is O(σ²).
    fn modulus_at_complex(&self, omega: Complex64) -> Complex64 {
        let w = omega.re.max(0.0);
        let h = 1e-4 * w.max(1e-6);
        let (lo, hi) = ((w - h).max(0.0), w + h);
        let slope = (self.modulus(hi) - self.modulus(lo)) / (hi - lo);
        self.modulus(w) + Complex64::new(0.0, omega.im) * slope
    }
}

impl<L: ViscoelasticLaw + ?Sized> ViscoelasticLaw for Box<L> {
    fn modulus(&self, omega_rad_s: f64) -> Complex64 {
        (**self).modulus(omega_rad_s)
    }
    fn modulus_at_complex(&self, omega: Complex64) -> Complex64 {
        (**self).modulus_at_complex(omega)
    }
    fn describe(&self) -> String {
        (**self).describe()
    }
}

impl<L: ViscoelasticLaw + ?Sized> ViscoelasticLaw for std::sync::Arc<L> {
    fn modulus(&self, omega_rad_s: f64) -> Complex64 {
        (**self).modulus(omega_rad_s)
    }
    fn modulus_at_complex(&self, omega: Complex64) -> Complex64 {
        (**self).modulus_at_complex(omega)
    }
    fn describe(&self) -> String {
        (**self).describe()
    }
}
