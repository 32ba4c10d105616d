//! A layered result's 95 % band ([`LayeredBand`]) and the sources it is made of
//! ([`BandSource`]: each with its label in tables and reports and its remedy, what would
//! narrow it).
//!
//! Sources are independent normal errors of ln G' and ln η, combined in quadrature: half-width
//! h = 1.96 √(Σ σ²), band [x e^−h, x e^h] (log-normal: the moduli are positive, and a band of
//! tens of per cent is not symmetric about them). How each source is measured is in
//! the layered route's bands module and docs/run.md.

use lamdyn_layered::sensitivity::Input;
use num_complex::Complex64;
use serde::Serialize;

/// A quantity of G' and the same quantity of η, for a complex modulus G* = G'(1 + iη): relative
/// standard deviations, half-widths of ln G' and ln η, or derivatives of ln G' and ln η.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StorageAndLoss {
    /// Of the storage modulus G'.
    pub storage: f64,
    /// Of the loss factor η.
    pub loss: f64,
}

/// Which of the two parts of a [`StorageAndLoss`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModulusPart {
    /// The storage modulus G'.
    Storage,
    /// The loss factor η.
    Loss,
}

impl StorageAndLoss {
    /// Of G' `storage` and of η `loss`.
    pub const fn new(storage: f64, loss: f64) -> Self {
        Self { storage, loss }
    }

    /// From `[G', η]`.
    pub const fn from_array([storage, loss]: [f64; 2]) -> Self {
        Self { storage, loss }
    }

    /// As `[G', η]`.
    pub const fn to_array(self) -> [f64; 2] {
        [self.storage, self.loss]
    }

    /// The `part`.
    pub const fn part(self, part: ModulusPart) -> f64 {
        match part {
            ModulusPart::Storage => self.storage,
            ModulusPart::Loss => self.loss,
        }
    }

    /// `f` applied to each part.
    pub fn map(self, f: impl Fn(f64) -> f64) -> Self {
        Self::new(f(self.storage), f(self.loss))
    }
}

/// Where a band's width comes from. The label is what tables, JSON and the report print; the
/// remedy says what would narrow it. Both are exhaustive matches, so a new source cannot lack
/// either.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BandSource {
    /// An input known within a tolerance (`[uncertainty]`), to first order.
    Input(Input),
    /// The inputs' second order, which the joint law fit models.
    InputsBeyondFirstOrder,
    /// The inputs beyond the joint fit's second-order model: each point's own noise.
    InputsBeyondSecondOrder,
    /// The part of the remainder beyond second order that all modes share, of G' (`false`) or
    /// of η (`true`): two terms of the joint law fit.
    SharedRemainder {
        /// The term of η (else of G').
        loss: bool,
    },
    /// The identified pole's scatter over the stabilization diagram, the response groups, its
    /// own covariance and the model orders.
    EmaPole,
    /// The identification's delete-one-hit jackknife.
    HitsLeftOut,
    /// The ladder's residual discretization error.
    Discretization,
    /// One element per layer through the thickness against two.
    ThroughThickness,
    /// The FRF fit of an overlapping pair: its own covariance.
    PairFit,
    /// The FRF fit of an overlapping pair: its spread over the width of the fitted band.
    PairFitLines,
    /// The joint law's noise floor.
    NoiseFloor,
    /// The points' scatter about the law beyond their stated noise.
    ScatterAboutTheLaw,
    /// The choice between laws, where the modes lie far apart.
    LawBetweenModes,
}

impl BandSource {
    /// Every source but the inputs, in the order a report lists them.
    pub const OTHERS: [BandSource; 13] = [
        BandSource::InputsBeyondFirstOrder,
        BandSource::InputsBeyondSecondOrder,
        BandSource::SharedRemainder { loss: false },
        BandSource::SharedRemainder { loss: true },
        BandSource::EmaPole,
        BandSource::HitsLeftOut,
        BandSource::Discretization,
        BandSource::ThroughThickness,
        BandSource::PairFit,
        BandSource::PairFitLines,
        BandSource::NoiseFloor,
        BandSource::ScatterAboutTheLaw,
        BandSource::LawBetweenModes,
    ];

    /// Every source: the inputs, then [`Self::OTHERS`].
    pub fn all() -> impl Iterator<Item = BandSource> {
        Input::ALL
            .into_iter()
            .map(BandSource::Input)
            .chain(Self::OTHERS)
    }

    /// The label printed in tables, JSON and the report.
    pub fn label(self) -> &'static str {
        match self {
            Self::Input(i) => i.name(),
            Self::InputsBeyondFirstOrder => "inputs beyond first order",
            Self::InputsBeyondSecondOrder => "inputs beyond second order",
            Self::SharedRemainder { loss: false } => "inputs beyond second order, shared (G')",
            Self::SharedRemainder { loss: true } => "inputs beyond second order, shared (eta)",
            Self::EmaPole => "EMA pole",
            Self::HitsLeftOut => "EMA: hits left out (jackknife)",
            Self::Discretization => "discretization",
            Self::ThroughThickness => "through the thickness",
            Self::PairFit => "FRF fit of the overlapping pair",
            Self::PairFitLines => "lines of the pair fit",
            Self::NoiseFloor => lamdyn_fit::joint::NOISE_FLOOR,
            Self::ScatterAboutTheLaw => lamdyn_fit::joint::SCATTER_ABOUT_THE_LAW,
            Self::LawBetweenModes => lamdyn_fit::joint::LAW_BETWEEN_MODES,
        }
    }

    /// The source a label names (the joint law fit's rows name theirs by label); `None` for a
    /// label no source has.
    pub fn from_label(label: &str) -> Option<Self> {
        Self::all().find(|s| s.label() == label)
    }

    /// What would narrow a band that this source dominates.
    pub fn remedy(self) -> &'static str {
        match self {
            Self::Input(Input::FaceModulus) => {
                "a measured face modulus (a coupon or a face's own resonance)"
            }
            Self::Input(Input::FaceThickness) => {
                "measured face thicknesses (a micrometer at several points)"
            }
            Self::Input(Input::CoreThickness) => {
                "a measured core thickness (the stack's total minus the faces')"
            }
            Self::Input(Input::FaceDensity | Input::CoreDensity) => {
                "weighed layers (measured densities)"
            }
            Self::Input(Input::SupportStiffness) => {
                "softer supports (their resonances well below the first mode), or their stiffness \
                 measured"
            }
            Self::Input(Input::SupportDamping) => {
                "softer supports with less damping, or their damping measured"
            }
            Self::InputsBeyondFirstOrder
            | Self::InputsBeyondSecondOrder
            | Self::SharedRemainder { .. } => {
                "narrower priors on the inputs (a measured face modulus and thicknesses): the core \
                 then depends on them nearly linearly"
            }
            Self::EmaPole | Self::NoiseFloor => {
                "a better-identified pole: more averages, more hits, or a reference that excites \
                 the mode"
            }
            Self::HitsLeftOut => {
                "more hits, or cleaner ones (the identification moves when one hit is left out: \
                 check each hit for a double hit, an overload or a weak force)"
            }
            Self::Discretization => "a smaller inverse.tolerance (finer meshes in the ladder)",
            Self::ThroughThickness => {
                "no setting yet: the ladder refines in plane and keeps one element per layer \
                 through the thickness, which a core thick against its faces needs more of \
                 (docs/run.md, 'Through the thickness')"
            }
            Self::PairFit | Self::PairFitLines => {
                "modes further apart in the data: a reference or response point where one of the \
                 pair dominates, or less damping from the supports"
            }
            Self::LawBetweenModes => {
                "more modes between those identified (another hammer or response point that \
                 excites them), or a narrower measured band"
            }
            Self::ScatterAboutTheLaw => {
                "more modes, or a law that follows the modes (generalized Maxwell or a per-mode \
                 table)"
            }
        }
    }
}

impl std::fmt::Display for BandSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

impl Serialize for BandSource {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.label())
    }
}

/// What would narrow a band whose main source has the label `label`: its source's remedy, or
/// for a label no source has, a narrower prior on what it names.
pub fn what_would_narrow(label: &str) -> String {
    match BandSource::from_label(label) {
        Some(s) => s.remedy().to_string(),
        None => format!("a narrower prior on the {label}"),
    }
}

/// One input known within a tolerance, as a mode's band holds it for the joint law fit.
#[derive(Debug, Clone, PartialEq)]
pub struct InputEffect {
    /// The input.
    pub input: Input,
    /// Its prior's relative standard deviation.
    pub rel_sd: f64,
    /// The signed ∂ln G'/∂ln θ, ∂ln η/∂ln θ.
    pub effect: StorageAndLoss,
}

/// The 95 % band of the layered result at one mode and the sources it is made of (module
/// docs).
#[derive(Debug, Clone, PartialEq)]
pub struct LayeredBand {
    /// Per source: the relative standard deviations of G' and of η it gives.
    pub sources: Vec<(BandSource, StorageAndLoss)>,
    /// Half-widths h of the 95 % band of ln G' and ln η: 1.96 √(Σ σ²); the band of G' is
    /// [G' e^−h, G' e^h].
    pub half_width: StorageAndLoss,
    /// Per input known within a tolerance: its prior and its effect (what the joint law fit
    /// needs).
    pub inputs: Vec<InputEffect>,
    /// Per input, the second order ∂²ln G'/∂(ln θ)², ∂²ln η/∂(ln θ)² (zero for an input with a
    /// wide prior, which the law fit re-linearises instead).
    pub second_order: Vec<StorageAndLoss>,
    /// Per input, how far (ln θ/θ_job) the model's value lies from the job file's: 0 but for
    /// the supports of a re-run at the supports the law found.
    pub inputs_at: Vec<f64>,
    /// The complex frequency ω*/2π = √(−p²)/2π of the pole p the core was matched to, Hz:
    /// where the found G* holds (lamdyn_fit::joint's module docs).
    pub found_at_hz: Complex64,
    /// G* as found at `found_at_hz`, Pa (the mode's layered value is it moved to the real
    /// frequency).
    pub found_pa: Complex64,
    /// Where the sensitivities were taken, and where the joint fit re-linearises.
    pub coarse: CoarsePole,
}

/// A mode on the ladder's coarsest model: its rank among the elastic modes and its
/// eigenvalue at the G* found, rad²/s².
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoarsePole {
    /// Rank among the coarsest model's elastic modes.
    pub rank: usize,
    /// Its eigenvalue at the G* found, rad²/s².
    pub eigenvalue: Complex64,
}

impl LayeredBand {
    /// The band with one more source of relative standard deviations `sd` (of G' and η).
    pub fn with_source(mut self, source: BandSource, sd: StorageAndLoss) -> Self {
        self.sources.push((source, sd));
        self.half_width = half_width(&self.sources);
        self
    }

    /// The source with the largest standard deviation of `part`; `None` without a source.
    pub fn dominant(&self, part: ModulusPart) -> Option<BandSource> {
        self.sources
            .iter()
            .max_by(|a, b| a.1.part(part).total_cmp(&b.1.part(part)))
            .map(|s| s.0)
    }

    /// The label of [`Self::dominant`], "-" without a source.
    pub fn dominant_label(&self, part: ModulusPart) -> &'static str {
        self.dominant(part).map_or("-", BandSource::label)
    }
}

/// The 95 % half-widths of ln G' and ln η of independent `sources` (relative standard
/// deviations): 1.96 √(Σ σ²) per part ([`LayeredBand::half_width`]).
pub fn half_width(sources: &[(BandSource, StorageAndLoss)]) -> StorageAndLoss {
    let quadrature = |part| {
        1.96 * sources
            .iter()
            .map(|s| s.1.part(part).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    StorageAndLoss::new(
        quadrature(ModulusPart::Storage),
        quadrature(ModulusPart::Loss),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every label names its own source and no other, so a renamed label cannot silently lose
    /// its remedy: the labels the joint law fit prints are among them.
    #[test]
    fn each_label_names_one_source() {
        let all: Vec<BandSource> = BandSource::all().collect();
        for s in &all {
            assert_eq!(BandSource::from_label(s.label()), Some(*s), "{s:?}");
        }
        let mut labels: Vec<&str> = all.iter().map(|s| s.label()).collect();
        labels.sort_unstable();
        labels.dedup();
        assert_eq!(labels.len(), all.len(), "two sources share a label");
        for joint in [
            lamdyn_fit::joint::NOISE_FLOOR,
            lamdyn_fit::joint::SCATTER_ABOUT_THE_LAW,
            lamdyn_fit::joint::LAW_BETWEEN_MODES,
        ] {
            assert!(BandSource::from_label(joint).is_some(), "{joint}");
        }
        assert_eq!(
            what_would_narrow("temperature"),
            "a narrower prior on the temperature"
        );
    }

    /// Sources that differ in kind get their own remedy; the inputs' higher orders share one.
    #[test]
    fn remedies_tell_the_kinds_apart() {
        let r = |s: BandSource| s.remedy();
        assert_ne!(r(BandSource::EmaPole), r(BandSource::Discretization));
        assert_ne!(
            r(BandSource::PairFit),
            r(BandSource::Input(Input::FaceModulus))
        );
        assert_eq!(
            r(BandSource::InputsBeyondFirstOrder),
            r(BandSource::SharedRemainder { loss: true })
        );
    }

    #[test]
    fn sources_add_in_quadrature() {
        let sources = [
            (BandSource::EmaPole, StorageAndLoss::new(0.03, 0.0)),
            (BandSource::Discretization, StorageAndLoss::new(0.04, 0.01)),
        ];
        let h = half_width(&sources);
        assert!((h.storage - 1.96 * 0.05).abs() < 1e-15);
        assert!((h.loss - 1.96 * 0.01).abs() < 1e-15);
    }
}
