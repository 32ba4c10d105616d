//! The pipeline's user-facing sentences that take values: the run's warnings
//! ([`crate::warnings`]), progress lines, and the layered and FRF routes' lines, in one place so
//! that the code stays within the formatter's width and the wording can be read and changed
//! together. A leaf: it formats values, it computes nothing.
//!
//! What is not here, by design: an error's message stays with the check that raises it (the
//! job's field it names is checked beside it), a domain type's own label with its type
//! ([`crate::band::BandSource`], [`crate::frf_route::WhyFrfFit`]), and the report's prose in
//! [`crate::report`], the module whose output it is.

use crate::band::BandSource;
use num_complex::Complex64;
use std::fmt::Display;

/// The layered stage's `line` when it ran again at the supports the law found, `at` (ln
/// stiffness, ln damping) from the job's.
pub fn rerun_at_supports(line: &str, at: [f64; 2]) -> String {
    format!(
        "{line}; run again at the supports the law found, stiffness x {:.3} and damping x \
         {:.3} of the job's",
        at[0].exp(),
        at[1].exp()
    )
}

/// The paper's route failed (`why`) and the layered route went on alone.
pub fn paper_route_failed(why: &str) -> String {
    format!(
        "the paper's route has no result ({why}); the layered route went on from the EMA's \
         poles alone, each started from the modulus its pole implies on the shell model"
    )
}

/// The shell model's supports, appended to its line: `on_plan` of `[[inverse.supports]]`,
/// `node_springs` of the model file, `shapes` static shapes added to its basis, the supports'
/// own modes at `support_hz` (at E_ref; [`lamdyn_fit::synthesis::SUPPORT_SHARE`]).
pub fn shell_model_on_supports(
    on_plan: usize,
    node_springs: usize,
    shapes: usize,
    support_hz: &[f64],
) -> String {
    let modes: Vec<String> = support_hz.iter().map(|f| format!("{f:.2}")).collect();
    format!(
        "; on {on_plan} supports ([[inverse.supports]]) and {node_springs} node springs (model \
         file), {shapes} static shapes added to the basis; the supports' own modes (under \
         {:.0} % of their strain energy in the laminate) at [{}] Hz",
        100.0 * lamdyn_fit::synthesis::SUPPORT_SHARE,
        modes.join(", ")
    )
}

/// The Monte Carlo of the paper's route skipped on a stack of `layers` layers.
pub fn monte_carlo_skipped(layers: usize) -> String {
    format!(
        "uncertainty: the Monte Carlo of the paper's route skipped: the stack has {layers} \
         layers, the paper's sandwich three; the layered route's bands hold the uncertainty"
    )
}

/// A mode without an identified pole near it.
pub fn no_pole_near(freq_hz: f64) -> String {
    format!("no EMA pole within 2 % of {freq_hz:.3} Hz for the target eigenvalue")
}

/// A mode whose pole gives a core that is not passive.
pub fn not_passive(g: Complex64) -> String {
    format!(
        "the pole gives a core G* = {:.4e} {:+.4e}i Pa, not a passive material (G' and G'' \
         must be positive): its damping is below what the faces and the supports' dashpots \
         give that mode, or the mode is a support's",
        g.re, g.im
    )
}

/// The layered model's coarsest mesh `label` has `dofs` above the cap `max_dofs`.
pub fn coarsest_above_cap(label: &str, dofs: usize, max_dofs: usize) -> String {
    format!(
        "the layered model's coarsest mesh ({label}) has {dofs} dofs, above \
         inverse.layered_max_dofs = {max_dofs}: start from a coarser mesh \
         (inverse.layered_elements, inverse.layered_subdivisions or fewer quadrilaterals in \
         the plan's Gmsh mesh) or raise inverse.layered_max_dofs if the memory allows"
    )
}

/// Progress: the coarsest model and the levels `labels` built ahead.
pub fn building_ahead(labels: &[String], through: usize) -> String {
    format!(
        "stage 'layered inverse': coarsest layered model and its reduced basis, levels {} and \
         the coarsest with {through} elements per layer through the thickness built alongside",
        labels.join(", ")
    )
}

/// Progress: a line of the ladder's.
pub fn layered_progress(what: &str) -> String {
    format!("stage 'layered inverse': {what}")
}

/// The model with `through` elements per layer has `dofs` above the cap.
pub fn through_thickness_above_cap(through: usize, dofs: usize) -> String {
    format!(
        "the coarsest mesh with {through} elements per layer has {dofs} dofs, above \
         inverse.layered_max_dofs"
    )
}

/// The model with `through` elements per layer cannot be meshed.
pub fn through_thickness_not_meshed(through: usize, e: &dyn Display) -> String {
    format!("the coarsest mesh with {through} elements per layer: {e}")
}

/// The model with `through` elements per layer failed to build.
pub fn through_thickness_not_built(through: usize, e: &dyn Display) -> String {
    format!("the model with {through} elements per layer was not built: {e:#}")
}

/// One level of the ladder in the layered line.
pub fn level(label: &str, dofs: usize) -> String {
    format!("{label} ({dofs} dofs)")
}

/// What the layered line says ([`layered_line`]).
pub struct LayeredLine<'a> {
    /// Why there is no model with `through` elements per layer, if there is none.
    pub through_thickness: Option<&'a str>,
    /// Elements per layer of the check through the thickness.
    pub through: usize,
    /// The plan, described.
    pub plan: &'a str,
    /// The ladder's levels ([`level`]).
    pub meshes: &'a [String],
    /// The ladder's frequency tolerance.
    pub tolerance: f64,
    /// Modes that met it, of `modes`.
    pub met: usize,
    /// Modes the ladder followed.
    pub modes: usize,
    /// The coarsest basis's modulus, Pa.
    pub g_ref: f64,
    /// Seconds the models and the ladder took.
    pub build_s: f64,
    /// Whether every model came from the cache.
    pub cached: bool,
}

/// The layered stage's line in the report.
pub fn layered_line(l: &LayeredLine) -> String {
    let source = BandSource::ThroughThickness.label();
    let through = match l.through_thickness {
        None => format!(
            "{} on the coarsest mesh for the band's '{source}'",
            l.through
        ),
        Some(why) => format!("{why}: '{source}' not in the band"),
    };
    format!(
        "C3D20, one per layer through the thickness ({through}), plan: {}; meshes {} \
         extrapolated to a frequency error below {:.1e} at {} of {} modes; coarsest basis at \
         G_ref {:.4e} Pa ({:.1} s{}); targets: the EMA poles",
        l.plan,
        l.meshes.join(", "),
        l.tolerance,
        l.met,
        l.modes,
        l.g_ref,
        l.build_s,
        if l.cached { ", cached" } else { "" }
    )
}

/// An overlapping pair at `pair_hz` fitted to the FRFs over `band_hz` (`lines` lines), its
/// model poles at `poles_hz` and the misfit with the identification's poles and fitted.
pub fn pair_fitted(
    pair_hz: [f64; 2],
    band_hz: [f64; 2],
    lines: usize,
    poles_hz: [f64; 2],
    misfit: [f64; 2],
) -> String {
    format!(
        "{}: one G* for both, fitted to the FRFs over {:.2}-{:.2} Hz ({lines} lines) with both \
         poles tied to the model (poles {:.3} / {:.3} Hz; misfit {:.4} with the EMA's poles, \
         {:.4} fitted)",
        pair_label(pair_hz),
        band_hz[0],
        band_hz[1],
        poles_hz[0],
        poles_hz[1],
        misfit[0],
        misfit[1]
    )
}

/// An overlapping pair at `pair_hz` that could not be fitted.
pub fn pair_not_fitted(pair_hz: [f64; 2], e: &dyn Display) -> String {
    format!(
        "{}: no FRF fit ({e}), each mode from its own pole",
        pair_label(pair_hz)
    )
}

fn pair_label(pair_hz: [f64; 2]) -> String {
    format!(
        "the overlapping pair at {:.2} / {:.2} Hz",
        pair_hz[0], pair_hz[1]
    )
}

/// The first `n` of `items`, comma-separated, with ", ..." where there are more.
fn first_of(items: &[String], n: usize) -> String {
    let shown = items[..items.len().min(n)].join(", ");
    if items.len() > n {
        shown + ", ..."
    } else {
        shown
    }
}

/// A response `name` with its lowest coherence `gamma2` in the fit band.
pub fn response_with_coherence(name: &str, gamma2: f64) -> String {
    format!("{name} ({gamma2:.2})")
}

/// The responses `poor` (at most six named) below `min_coherence`, of `responses`.
pub fn poor_coherence(min_coherence: f64, poor: &[String], responses: usize) -> String {
    format!(
        "poor coherence (below {}) in the fit band at {} of {} responses: {}",
        min_coherence,
        poor.len(),
        responses,
        first_of(poor, 6)
    )
}

/// A pole the job rejects as a support resonance (`ema.reject_hz`).
pub fn support_resonance_rejected(freq_hz: f64, zeta: f64) -> String {
    format!(
        "EMA: pole at {freq_hz:.3} Hz (zeta {:.2} %) rejected as a support resonance \
         (ema.reject_hz)",
        100.0 * zeta
    )
}

/// A pole set aside from the inverses as a smear over a cluster of modes, with the verdict's
/// `reasons` (a low MPC, or a second shape under a pole whose MPC is high).
pub fn smear_set_aside(freq_hz: f64, zeta: f64, mpc: f64, reasons: &str) -> String {
    format!(
        "EMA: pole at {freq_hz:.3} Hz (zeta {:.2} %, MPC {mpc:.2}) set aside from the inverses: \
         {reasons} (ema.keep_smears = true keeps it)",
        100.0 * zeta
    )
}

/// A frequency the job names (`--near-hz`, `ema.near_hz`) without a stable pole near it.
pub fn no_stable_pole_near(freq_hz: f64) -> String {
    format!("EMA: no stable pole near {freq_hz:.3} Hz")
}

/// The EMA's own warning `w`.
pub fn from_the_ema(w: &str) -> String {
    format!("EMA: {w}")
}

/// A mode where the paper's |φ| is beyond its validity.
pub fn phi_beyond_validity(freq_hz: f64, phi: f64) -> String {
    use lamdyn_material::laminate::PHI_ACCURACY_LIMIT;
    format!(
        "{freq_hz:.2} Hz: |phi| = {phi:.3} > {PHI_ACCURACY_LIMIT}: the paper's inverse is beyond \
         its ~1 % validity; prefer the exact inverse"
    )
}

/// A mode without the `name` inverse's core, and why.
pub fn no_inverse(freq_hz: f64, name: &str, why: &str) -> String {
    format!("{freq_hz:.2} Hz: no {name} inverse: {why}")
}

/// The `name` inverse's G*(f) that fails the Kramers–Kronig check at `bad` of `lines`.
pub fn not_causal(name: &str, bad: usize, lines: usize) -> String {
    format!("the {name} inverse's G*(f) fails the Kramers-Kronig check at {bad} of {lines} lines")
}

/// An EMA mode without an RMS peak in the paper's fit.
pub fn no_rms_peak(freq_hz: f64) -> String {
    format!(
        "EMA mode at {freq_hz:.3} Hz has no RMS peak in the fit (weakly excited, a close pair, or \
         a mode the shell model lacks): the paper's and the exact inverse read the fitted law \
         there, the layered inverse its pole"
    )
}

/// The paper's fit whose best start did not converge, and why.
pub fn fit_not_converged(reason: &str) -> String {
    format!("fit: the best start did not converge ({reason})")
}

/// Two poles (Hz) the layered inverse matched to one elastic mode (0-based `rank`).
pub fn one_layered_mode_for_two_poles(poles_hz: [f64; 2], rank: usize) -> String {
    format!(
        "layered inverse: the poles at {:.2} Hz and {:.2} Hz both matched the model's elastic \
         mode {} (at their own G*): one of them may sit on a neighbouring mode's branch (a close \
         pair); check the mode shapes, or the law's residuals at those two modes",
        poles_hz[0],
        poles_hz[1],
        rank + 1
    )
}

/// A layered G' (Pa) that falls between two modes (Hz) beyond their bands.
pub fn layered_storage_falls(freqs_hz: [f64; 2], storage_pa: [f64; 2]) -> String {
    format!(
        "layered inverse: G' falls from {:.4} MPa at {:.2} Hz to {:.4} MPa at {:.2} Hz ({:+.1} \
         %), beyond both modes' bands: a passive core's storage modulus does not fall with \
         frequency, so one of the two poles is matched to a neighbouring mode of the model or is \
         not a true pole; check the mode shapes and the core's shear_pa start",
        storage_pa[0] / 1e6,
        freqs_hz[0],
        storage_pa[1] / 1e6,
        freqs_hz[1],
        100.0 * (storage_pa[1] / storage_pa[0] - 1.0)
    )
}

/// A pole as "f Hz (ζ %)".
pub fn pole_with_damping(freq_hz: f64, zeta: f64) -> String {
    format!("{freq_hz:.1} Hz ({:.1} %)", 100.0 * zeta)
}

/// The poles `damped` (as [`pole_with_damping`]) of `poles`, damped beyond `max_damping`.
pub fn damped_poles(damped: &[String], poles: usize, max_damping: f64) -> String {
    format!(
        "EMA: {} of {poles} poles are damped more than {:.0} % ({}): an EMA's poles of such \
         modes can be far off (a core 30 times softer than the damped sandwich's, zeta 16-22 %, \
         came out 104-224 % off in G' from its poles); compare the model's FRFs with the \
         measured ones there before trusting G*",
        damped.len(),
        100.0 * max_damping,
        damped.join(", ")
    )
}

/// Two poles (Hz) `apart_hz` apart, `share` of their half-power half-widths.
pub fn overlapping_poles(poles_hz: [f64; 2], apart_hz: f64, share: f64) -> String {
    format!(
        "EMA: the poles at {:.2} Hz and {:.2} Hz overlap ({apart_hz:.3} Hz apart, {share:.2} of \
         their half-power half-widths): an EMA moves the poles of such a pair by more than their \
         scatter shows (the in-band foam roof's pair at 20.1 / 20.5 Hz: G* 16-24 % off from \
         noise-free FRFs), so G* from each pole alone is less certain than its band: the layered \
         route fits such a pair to the FRFs around it with both poles tied to its model instead \
         (its line says how that went)",
        poles_hz[0], poles_hz[1]
    )
}

/// Why the layered route cannot go on from the poles alone without the paper's fit: the poles
/// `damped` (as [`pole_with_damping`], at most four named) of `poles`, beyond `max_damping`.
pub fn poles_alone_refused(damped: &[String], poles: usize, max_damping: f64) -> String {
    format!(
        "the paper's route failed, and the layered route cannot go on from the poles alone: {} of \
         {poles} poles are damped more than {:.0} % ({}), where the EMA's poles are not to be \
         trusted without a fit to the FRFs (inverse.frf_fit = \"never\")",
        damped.len(),
        100.0 * max_damping,
        first_of(damped, 4)
    )
}

/// Progress: the EMA of response group `g` (0-based) of `groups`, with `n` responses.
pub fn ema_group(g: usize, groups: usize, n: usize) -> String {
    format!(
        "stage 'ema by response group': group {} of {groups} ({n} responses)",
        g + 1
    )
}

/// Progress: the EMA with the stabilization diagram up to `order`.
pub fn ema_order(order: usize) -> String {
    format!("stage 'ema at other model orders': highest order {order}")
}

/// Progress: the EMA without hit `k` (0-based) of `hits`.
pub fn ema_without_hit(k: usize, hits: usize) -> String {
    format!(
        "stage 'ema without each hit': without hit {} of {hits}",
        k + 1
    )
}

/// Why the FRF fit did not run under `inverse.frf_fit = "auto"`.
pub const POLE_ROUTE_HOLDS: &str = "the modes are light and separated and each has a layered \
    core: the pole route holds (inverse.frf_fit = \"always\" runs the FRF fit beside it)";

/// What the FRF fit's model line says ([`frf_model_line`]).
pub struct FrfModelLine<'a> {
    /// The ladder level's label.
    pub level: &'a str,
    /// Basis vectors.
    pub basis_size: usize,
    /// The basis's reference modulus, Pa.
    pub g_ref: f64,
    /// The basis's moduli over `g_ref`.
    pub ratios: [f64; 2],
    /// Times the basis was built again about the fitted law.
    pub recentred: usize,
    /// The fitted law's G' range (Pa) where it still leaves the basis's range.
    pub outside: Option<[f64; 2]>,
    /// One line in `step` fitted.
    pub step: usize,
    /// The lines kept per half-power half-width of the narrowest pole.
    pub per_half_width: f64,
    /// The inputs fitted under their priors.
    pub inputs: &'a [&'a str],
}

/// The FRF fit's model line.
pub fn frf_model_line(l: &FrfModelLine) -> String {
    let recentred = if l.recentred > 0 {
        format!(", built again about the fitted law {} time(s)", l.recentred)
    } else {
        String::new()
    };
    let thinned = if l.step > 1 {
        format!(
            "; one line in {} ({} per half-power half-width of the narrowest pole)",
            l.step, l.per_half_width
        )
    } else {
        String::new()
    };
    let outside = match l.outside {
        Some([lo, hi]) => {
            format!("; the fitted law (G' {lo:.3e}-{hi:.3e} Pa) still leaves the basis's range")
        }
        None => String::new(),
    };
    format!(
        "C3D20 {} ({} basis vectors at G_ref {:.4e} Pa x [{:.2}, {:.2}]{recentred}{outside})\
         {thinned}, inputs under their priors: {}",
        l.level,
        l.basis_size,
        l.g_ref,
        l.ratios[0],
        l.ratios[1],
        l.inputs.join(", ")
    )
}

/// Progress: the fitted law's G' (Pa) leaves the FRF fit's basis, which is built again.
pub fn frf_basis_again(lo: f64, hi: f64) -> String {
    format!(
        "FRF fit: the fitted law (G' {lo:.3e}-{hi:.3e} Pa) leaves the basis's range; the basis \
         again about it"
    )
}

/// Progress: the FRF fit's `law` fitted from the `first` law's curve, to compare.
pub fn frf_other_law(law: &str, first: &str) -> String {
    format!("FRF fit: {law} from the {first} curve, to compare")
}

/// Progress: the FRF fit's `law` on `basis_size` vectors over `band_hz`.
pub fn frf_fitting(law: &str, basis_size: usize, band_hz: [f64; 2]) -> String {
    format!(
        "FRF fit: {law} on {basis_size} basis vectors over {:.1}-{:.1} Hz",
        band_hz[0], band_hz[1]
    )
}

/// Progress: the `first` law did not settle; the fractional Zener law instead.
pub fn frf_law_fallback(first: &str) -> String {
    format!("FRF fit: {first} did not settle; fractional_zener")
}

/// Progress: the FRF fit's layered model on `level`, read at the channels and references.
pub fn frf_model_read(level: &str, channels: usize, references: usize) -> String {
    format!(
        "FRF fit: layered model {level} read at {channels} channel(s), {references} reference(s)"
    )
}

/// Progress: the basis holds the model to `held_hz`, below the band's `top_hz`; `modes` next.
pub fn frf_more_modes(held_hz: f64, top_hz: f64, modes: usize) -> String {
    format!(
        "FRF fit: the basis holds {held_hz:.1} Hz of the band's {top_hz:.1} Hz; again with \
         {modes} modes"
    )
}

/// The FRF fit's progress line where it takes what the line leaves of each mode's mesh error
/// out of its model: the modes taken and those left to the line (Hz).
pub fn frf_mode_by_mode(taken_hz: &[f64], left_hz: &[f64]) -> String {
    format!(
        "FRF fit: what the line leaves of the mesh error taken out mode by mode at {}{}; fitted \
         again from the law fitted with the line",
        hz_list(taken_hz),
        if left_hz.is_empty() {
            String::new()
        } else {
            let limit = 100.0 * (lamdyn_layered::reduced::mode_errors::SCALE_LIMIT - 1.0);
            format!(
                " (left to the line, their scales beyond {limit:.0} % or the mode not found: {})",
                hz_list(left_hz)
            )
        }
    )
}

/// The FRF fit runs the ladder again on poles its law passes far off.
pub fn frf_converge_again(freqs_hz: &[f64]) -> String {
    format!(
        "FRF fit: the ladder again at {} from the law fitted (the pole route's core there is off \
         it by more than a factor 1.5: a pole matched to another branch of the model's modes)",
        hz_list(freqs_hz)
    )
}

/// The ladder run again, or the fit with the line it gave, failed (`why`); the correction
/// keeps the pole route's modes.
pub fn frf_converge_again_failed(why: &str) -> String {
    format!(
        "FRF fit: the ladder run again, or the fit with its line, failed ({why}); the mesh \
         correction keeps the pole route's modes"
    )
}

/// "26.1, 31.3 Hz" (at most eight named; "none" for none).
pub fn hz_list(freqs_hz: &[f64]) -> String {
    if freqs_hz.is_empty() {
        return "none".to_string();
    }
    let items: Vec<String> = freqs_hz.iter().map(|f| format!("{f:.1}")).collect();
    first_of(&items, 8) + " Hz"
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Continued string lines read as one sentence: one space between the words joined.
    #[test]
    fn continued_lines_join_with_one_space() {
        for s in [
            not_passive(Complex64::new(-1.0, 2.0)),
            coarsest_above_cap("12 x 12", 9, 8),
            building_ahead(&["16 x 16".into()], 2),
            pair_fitted([1.0, 2.0], [0.5, 2.5], 10, [1.0, 2.0], [0.1, 0.1]),
        ] {
            assert!(!s.contains("  "), "{s}");
        }
    }

    /// Lists name at most their first few items and say there are more.
    #[test]
    fn lists_name_their_first_items() {
        let items: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
        assert_eq!(first_of(&items, 2), "a, b, ...");
        assert_eq!(first_of(&items, 3), "a, b, c");
        assert!(poor_coherence(0.9, &items, 10).ends_with("at 3 of 10 responses: a, b, c"));
        let five: Vec<String> = (1..=5).map(|k| k.to_string()).collect();
        assert!(poles_alone_refused(&five, 9, 0.1).contains("(1, 2, 3, 4, ...), where"));
        assert_eq!(hz_list(&[]), "none");
        assert_eq!(hz_list(&[16.46, 20.09]), "16.5, 20.1 Hz");
        let nine: Vec<f64> = (1..=9).map(f64::from).collect();
        assert!(hz_list(&nine).ends_with("8.0, ... Hz"));
        let line = frf_mode_by_mode(&[26.1], &[16.5]);
        assert!(line.contains("mode by mode at 26.1 Hz (left to the line"));
        assert!(line.contains("not found: 16.5 Hz); fitted"));
        assert!(!frf_mode_by_mode(&[26.1], &[]).contains("left to the line"));
    }
}
