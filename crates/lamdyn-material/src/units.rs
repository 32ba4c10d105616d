//! Plausible ranges of SI inputs: the one set of unit checks every command shares.
//!
//! lamdyn takes SI units everywhere (m, kg/m³, Pa). The most common input mistakes are other
//! units written into SI fields: a thickness in mm (`1.5` for 1.5 mm), a modulus in GPa or MPa
//! (`70` for 70 GPa), a density in g/cm³ (`2.5`). Each gives a result that looks confident and is
//! wrong by orders of magnitude, so these checks refuse values outside the range any laminate,
//! beam or shell of this tool's scope can have, and say which unit was probably meant.
//!
//! | quantity | accepted | catches |
//! |---|---|---|
//! | layer or shell thickness | 1 µm … 0.1 m | mm (a 1.5 mm glass written `1.5`) |
//! | part or beam length | 5 mm … 100 m | mm coordinates or lengths |
//! | density | 25 … 25 000 kg/m³ (foam core to osmium) | g/cm³ (`2.5`) |
//! | face, beam or shell modulus | 0.1 GPa … 2 TPa | GPa (`70`), MPa |
//! | any modulus (a core, at 10 Hz) | 1 kPa … 2 TPa | MPa (`0.35`), GPa |
//!
//! ```
//! use lamdyn_material::units::{Quantity, check};
//! assert!(check(Quantity::Thickness, 1.715e-3).is_ok());
//! let hint = check(Quantity::Thickness, 1.715).unwrap_err().to_string();
//! assert!(hint.contains("mm"));
//! ```

/// What a value measures, for [`check`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// A layer's, beam's or shell's thickness, m.
    Thickness,
    /// A part's span or a beam's length, m.
    Length,
    /// A density, kg/m³.
    Density,
    /// The Young's modulus of a face, a base beam or a shell: a structural solid, Pa.
    StiffModulus,
    /// Any modulus, a soft core's included, Pa.
    Modulus,
}

impl Quantity {
    /// The accepted closed range (lo, hi) in SI units.
    pub fn range(self) -> (f64, f64) {
        match self {
            Self::Thickness => (1e-6, 0.1),
            Self::Length => (5e-3, 100.0),
            Self::Density => (25.0, 25_000.0),
            Self::StiffModulus => (1e8, 2e12),
            Self::Modulus => (1e3, 2e12),
        }
    }

    fn hint(self, value: f64) -> &'static str {
        let (lo, _) = self.range();
        match (self, value < lo) {
            (Self::Thickness, false) => "thicknesses are in m (1.715 mm is 1.715e-3)",
            (Self::Length, _) => {
                "lengths are in m; is the Gmsh file's unit (\"m\" or \"mm\") right?"
            }
            (Self::Density, true) => "densities are in kg/m^3 (2.5 g/cm^3 is 2500)",
            (Self::StiffModulus | Self::Modulus, true) => {
                "moduli are in Pa (70 GPa is 70e9, 0.35 MPa is 3.5e5)"
            }
            _ => "is this value in SI units?",
        }
    }
}

/// Why a value is not a plausible quantity in SI units ([`check`]); its text is the
/// requirement and a hint at the unit probably meant, for the caller to put in its own error
/// with the file and field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OutOfRange {
    /// NaN or infinite.
    NotFinite,
    /// Zero or negative.
    NotPositive,
    /// Outside the quantity's plausible range [lo, hi].
    Outside {
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
        /// The unit probably meant.
        hint: &'static str,
    },
}

impl std::fmt::Display for OutOfRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NotFinite => f.write_str("must be a finite number"),
            Self::NotPositive => f.write_str("must be positive"),
            Self::Outside { lo, hi, hint } => write!(f, "is outside [{lo:e}, {hi:e}]: {hint}"),
        }
    }
}

impl std::error::Error for OutOfRange {}

/// Checks that `value` is finite and inside `quantity`'s range.
///
/// # Errors
/// [`OutOfRange`]: the requirement and a hint at the unit probably meant.
pub fn check(quantity: Quantity, value: f64) -> Result<f64, OutOfRange> {
    let (lo, hi) = quantity.range();
    if !value.is_finite() {
        return Err(OutOfRange::NotFinite);
    }
    if value <= 0.0 {
        return Err(OutOfRange::NotPositive);
    }
    if value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(OutOfRange::Outside {
            lo,
            hi,
            hint: quantity.hint(value),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn common_unit_mistakes_are_refused_with_the_unit_meant() {
        let cases = [
            (Quantity::Thickness, 1.5, "1.715e-3"),
            (Quantity::Length, 923.0, "mm"),
            (Quantity::Density, 2.5, "g/cm^3"),
            (Quantity::StiffModulus, 70.0, "GPa"),
            (Quantity::Modulus, 0.35, "MPa"),
        ];
        for (q, v, hint) in cases {
            let e = check(q, v).unwrap_err().to_string();
            assert!(e.contains(hint), "{q:?} {v}: {e}");
        }
    }

    #[test]
    fn the_papers_roof_and_a_foam_sandwich_pass() {
        for (q, v) in [
            (Quantity::Thickness, 1.715e-3),
            (Quantity::Thickness, 0.42e-3),
            (Quantity::Thickness, 0.05),
            (Quantity::Length, 0.923),
            (Quantity::Density, 2500.0),
            (Quantity::Density, 30.0),
            (Quantity::StiffModulus, 70e9),
            (Quantity::StiffModulus, 2.4e9),
            (Quantity::Modulus, 3.5e5),
            (Quantity::Modulus, 5e3),
        ] {
            assert_eq!(check(q, v), Ok(v), "{q:?}");
        }
        assert_eq!(
            check(Quantity::Density, f64::NAN),
            Err(OutOfRange::NotFinite)
        );
        assert_eq!(check(Quantity::Density, -1.0), Err(OutOfRange::NotPositive));
    }
}
