//! The pipeline's user-facing sentences that take values: messages, progress lines and the
//! layered stage's line, in one place so that the code stays within the formatter's width and
//! the wording can be read and changed together. A leaf: it formats values, it computes
//! nothing.

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
}
