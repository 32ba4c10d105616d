//! The layered route's tuning ([`LayeredTuning`]): the settings its steps take beside the job's,
//! with their defaults and why each has its value ([`super::LayeredSetup::tuning`]; a job file
//! does not set them yet).

use crate::frf_route::FrfRule;

/// The layered route's tuning.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LayeredTuning {
    /// The joint law fit ([`super::fit_law`]) and the supports' re-run.
    pub law: LawTuning,
    /// The FRF fit of an overlapping pair.
    pub pair_fit: PairFitTuning,
    /// The FRF fit of the whole band: when it is the answer, and its model's limits.
    pub frf_fit: FrfFitTuning,
}

/// The joint law fit's tuning.
#[derive(Debug, Clone, PartialEq)]
pub struct LawTuning {
    /// The offsets (in their spacing) of a generalized Maxwell law's relaxation times tried:
    /// default a quarter of their spacing apart, which the modes cannot choose between where
    /// they lie far apart.
    pub prony_offsets: Vec<f64>,
    /// The smallest prior standard deviation (relative) of an input that makes the joint fit
    /// re-linearise: default 0.05, so the supports' (20 %, 30 % by default). With the faces'
    /// priors alone (1 %, a few per cent on a thickness) the first order holds: on the
    /// pipeline test's free plate, whose points scatter 2.9x beyond their noise (the truth's
    /// own mesh error), re-linearising dragged the poorly determined core thickness from
    /// +0.2 % to +1.7 % over four steps, chasing that scatter, and the law's η band missed the
    /// truth at 78 Hz. Moving only the supports' inputs, not the faces', left the supported
    /// coverage test's joint η band at 87 % (all inputs: 92 %).
    pub wide_prior: f64,
    /// The re-linearisation stops when no input moved by more than this fraction of its
    /// prior's standard deviation since the last: default 0.05.
    pub settled: f64,
    /// Most re-linearisations of the joint fit: default 4.
    pub relinearisations: usize,
    /// The smallest change (ln) of the supports' stiffness or damping found by the law that
    /// runs the mesh ladder again at the supports found: default 0.05; below it the
    /// re-linearised fit holds it.
    pub supports_rerun: f64,
    /// The part of each point's remainder beyond second order that all modes share (the
    /// square of the correlation between two modes' remainders): default 0.5.
    pub remainder_shared: f64,
}

impl LawTuning {
    /// The default [`LawTuning::wide_prior`].
    pub const DEFAULT_WIDE_PRIOR: f64 = 0.05;
    /// The default [`LawTuning::remainder_shared`].
    pub const DEFAULT_REMAINDER_SHARED: f64 = 0.5;
}

impl Default for LawTuning {
    fn default() -> Self {
        Self {
            prony_offsets: vec![0.0, 0.25, 0.5, 0.75],
            wide_prior: Self::DEFAULT_WIDE_PRIOR,
            settled: 0.05,
            relinearisations: 4,
            supports_rerun: 0.05,
            remainder_shared: Self::DEFAULT_REMAINDER_SHARED,
        }
    }
}

/// The pair fit's tuning.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairFitTuning {
    /// Half-widths each side of the pair whose lines the fit uses: default 3.
    pub half_widths: f64,
    /// The other bands the fit is repeated on, in half-widths each side of the pair, whose
    /// spread is the band's source `PairFitLines`: default 2 and 4.
    pub other_half_widths: [f64; 2],
    /// How far (|ln G'/G'₀|, |ln η/η₀|) the fit may move from its start, the mean of the two
    /// modes' own G*: default ln 2, a factor 2, within the coarsest basis's G_ref/4 … 4 G_ref
    /// about a start that lies within √2 of G_ref. Beyond it the reduced model is not checked,
    /// and a pair whose modes barely feel the core (a hump the residues can follow) let the fit
    /// wander to a G' of 0.5 % and an η of 10⁷ of the start.
    pub reach: f64,
}

impl Default for PairFitTuning {
    fn default() -> Self {
        Self {
            half_widths: 3.0,
            other_half_widths: [2.0, 4.0],
            reach: std::f64::consts::LN_2,
        }
    }
}

/// The FRF fit's tuning: when the run takes it as the answer ([`crate::frf_route::reasons`])
/// and its model's limits ([`super::fit_to_frfs`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrfFitTuning {
    /// When the run takes the fit as the answer (defaults: [`FrfRule::default`]).
    pub rule: FrfRule,
    /// Lines the fit keeps per half-power half-width ζf of the narrowest identified mode:
    /// default 4. A damped part's 1 Hz lines over resonances 30 Hz wide carry the same
    /// information as every seventh of them at a seventh of the cost (each line is one LU;
    /// docs/fit.md).
    pub lines_per_half_width: f64,
    /// The most modes per reference modulus the basis takes when the band needs more than
    /// `inverse.layered_modes`: default 90 (the cost of a line grows with the cube of the
    /// basis).
    pub max_modes: usize,
    /// Times the basis is built again about the fitted law: default 2.
    pub max_recentres: usize,
}

impl Default for FrfFitTuning {
    fn default() -> Self {
        Self {
            rule: FrfRule::default(),
            lines_per_half_width: 4.0,
            max_modes: 90,
            max_recentres: 2,
        }
    }
}
