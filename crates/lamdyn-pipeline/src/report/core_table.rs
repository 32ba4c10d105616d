//! The core at the modal frequencies as one table ([`core_table`]): each column's name, SI
//! unit, meaning and the way a terminal shows it ([`CoreColumn`]) are defined here once, and
//! the report's `core_modal.csv`, the CLI's summary and the Python module's `ModalTable` are
//! all read from it.

use super::{LayeredColumns, loss, modal_bands, rel_err, storage};
use crate::ChainResult;
use crate::chain::CorePoint;
use crate::uncertainty::Band;
use crate::uncertainty::Bands;
use lamdyn_fit::frf_fit::FrfLawPoint;
use lamdyn_material::laminate::PHI_ACCURACY_LIMIT;
use num_complex::Complex64;

/// How a table for people shows a column: in `unit`, the SI value divided by `scale`, with
/// `digits` after the point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shown {
    /// The unit shown ("MPa", "%", "" for a ratio).
    pub unit: &'static str,
    /// The SI value per shown unit (1e6 for MPa over Pa, 0.01 for %).
    pub scale: f64,
    /// Digits after the decimal point.
    pub digits: usize,
}

/// One column of the core table.
#[derive(Debug, Clone, PartialEq)]
pub struct CoreColumn {
    /// The column's name: the CSV header, the JSON key and the Python attribute.
    pub key: String,
    /// A short label for a terminal's header.
    pub label: String,
    /// The SI unit of its values ("" for a ratio or a text).
    pub unit: &'static str,
    /// What it holds, in a line.
    pub about: String,
    /// How a terminal shows it; `None` for a text column.
    pub shown: Option<Shown>,
    /// Whether the CLI's summary shows it.
    pub in_summary: bool,
}

/// One cell of the core table.
#[derive(Debug, Clone, PartialEq)]
pub enum CoreValue {
    /// A number in the column's SI unit; `None` where the route has no value.
    Number(Option<f64>),
    /// A text; `None` where there is none.
    Text(Option<String>),
}

impl CoreValue {
    /// The number, if the cell holds one.
    pub fn number(&self) -> Option<f64> {
        match self {
            Self::Number(v) => *v,
            Self::Text(_) => None,
        }
    }

    /// The cell as a CSV field: a number in full precision (`{:e}`), a text as it is, empty
    /// where there is no value.
    pub fn csv_field(&self) -> String {
        match self {
            Self::Number(v) => v.map_or(String::new(), |x| format!("{x:e}")),
            Self::Text(t) => t.clone().unwrap_or_default(),
        }
    }
}

/// Which of the optional groups of columns a table has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Groups {
    /// The truth and each route's error against it (a virtual test).
    pub truth: bool,
    /// The FRF fit's core (the layered model fitted to the FRFs).
    pub frf: bool,
}

impl Groups {
    /// Every group: the columns the Python module's `ModalTable` has (NaN where a run has none).
    pub const ALL: Groups = Groups {
        truth: true,
        frf: true,
    };

    /// The groups `r` has values for.
    pub fn of(r: &ChainResult) -> Self {
        Self {
            truth: r.truth.is_some(),
            frf: r.frf.route().is_some(),
        }
    }
}

/// The core table: its columns and one row per modal frequency, each as long as the columns.
#[derive(Debug, Clone, PartialEq)]
pub struct CoreTable {
    /// The columns, in order.
    pub columns: Vec<CoreColumn>,
    /// One row per modal frequency.
    pub rows: Vec<Vec<CoreValue>>,
}

impl CoreTable {
    /// The table as CSV: the keys as header, then the rows ([`CoreValue::csv_field`]).
    pub fn csv(&self) -> String {
        let mut out = self
            .columns
            .iter()
            .map(|c| c.key.as_str())
            .collect::<Vec<_>>()
            .join(",");
        out.push('\n');
        for row in &self.rows {
            let fields: Vec<String> = row.iter().map(CoreValue::csv_field).collect();
            out.push_str(&fields.join(","));
            out.push('\n');
        }
        out
    }
}

/// Shown in MPa with 3 digits.
const MPA: Shown = Shown {
    unit: "MPa",
    scale: 1e6,
    digits: 3,
};
/// A ratio with 3 digits.
const RATIO: Shown = Shown {
    unit: "",
    scale: 1.0,
    digits: 3,
};
/// A relative error in per cent with 1 digit.
const PERCENT: Shown = Shown {
    unit: "%",
    scale: 0.01,
    digits: 1,
};

/// A column and how each row's value is read.
struct Def {
    column: CoreColumn,
    value: Box<dyn Fn(&Row<'_>) -> CoreValue>,
}

/// What a row's values are read from: the run, its modal point, and what is derived from the
/// point once for all the columns (the Monte Carlo's bands, the layered route's columns, the
/// FRF fit's G* and band).
struct Row<'a> {
    r: &'a ChainResult,
    p: &'a CorePoint,
    bands: Bands,
    layered: LayeredColumns,
    frf: Option<(Complex64, FrfLawPoint)>,
}

impl<'a> Row<'a> {
    fn of(r: &'a ChainResult, p: &'a CorePoint) -> Self {
        Self {
            r,
            p,
            bands: modal_bands(r, p),
            layered: LayeredColumns::of(p),
            frf: r
                .frf
                .route()
                .map(|route| (route.modulus(p.freq_hz), route.at(p.freq_hz))),
        }
    }
}

/// A numeric column.
fn number(
    key: &str,
    label: &str,
    unit: &'static str,
    about: &str,
    shown: Shown,
    value: impl Fn(&Row<'_>) -> Option<f64> + 'static,
) -> Def {
    Def {
        column: CoreColumn {
            key: key.into(),
            label: label.into(),
            unit,
            about: about.into(),
            shown: Some(shown),
            in_summary: false,
        },
        value: Box::new(move |row| CoreValue::Number(value(row))),
    }
}

/// A text column.
fn text(key: &str, about: &str, value: impl Fn(&Row<'_>) -> Option<String> + 'static) -> Def {
    Def {
        column: CoreColumn {
            key: key.into(),
            label: key.into(),
            unit: "",
            about: about.into(),
            shown: None,
            in_summary: false,
        },
        value: Box::new(move |row| CoreValue::Text(value(row))),
    }
}

impl Def {
    /// The column in the CLI's summary.
    fn summary(mut self) -> Self {
        self.column.in_summary = true;
        self
    }
}

/// A route to the core: its key's name, its summary label's suffix and how a row gives its G*.
#[derive(Clone, Copy)]
struct Route {
    name: &'static str,
    label: &'static str,
    initial: &'static str,
    about: &'static str,
    g: fn(&Row<'_>) -> Option<Complex64>,
}

const PAPER: Route = Route {
    name: "paper",
    initial: "p",
    label: "paper",
    about: "the paper's inverse (eqs. 33-45)",
    g: |row| row.p.paper_g(),
};
const EXACT: Route = Route {
    name: "exact",
    initial: "x",
    label: "exact",
    about: "the exact sandwich inverse (Mead-Markus)",
    g: |row| row.p.exact_g(),
};
const LAYERED: Route = Route {
    name: "layered",
    initial: "l",
    label: "layer",
    about: "the layered model matched to the EMA pole",
    g: |row| row.p.layered_g(),
};
const FRF: Route = Route {
    name: "frf",
    initial: "f",
    label: "frf",
    about: "the core's law fitted to the measured FRFs through the layered model",
    g: |row| row.frf.map(|(g, _)| g),
};

/// The 95 % band of a route's G' and η at a row (`None` where the route has none).
type RouteBand = fn(&Row<'_>) -> [Option<Band>; 2];

/// G' and η of `route`, each followed by the ends of its 95 % band `band`.
fn route_columns(route: Route, band: RouteBand) -> Vec<Def> {
    let g = route.g;
    let (n, l, a) = (route.name, route.label, route.about);
    let mut defs = vec![
        number(
            &format!("g_{n}_storage_pa"),
            &format!("G'_{l}"),
            "Pa",
            &format!("the core's storage modulus G' by {a}"),
            MPA,
            move |row| storage(g(row)),
        )
        .summary(),
    ];
    let bounds = |part: usize, key: &str, unit: &'static str, what: &str| {
        [(0, "lo", "lower"), (1, "hi", "upper")].map(|(end, tag, word)| {
            let key = key.replacen("{}", tag, 1);
            let shown = if part == 0 { MPA } else { RATIO };
            number(
                &key,
                &key,
                unit,
                &format!("the {word} end of the 95 % band of {what} by {a}"),
                shown,
                move |row| band(row)[part].map(|b| b[end]),
            )
        })
    };
    defs.extend(bounds(0, &format!("g_{n}_storage_{{}}_pa"), "Pa", "G'"));
    defs.push(
        number(
            &format!("g_{n}_loss_factor"),
            &format!("eta_{l}"),
            "",
            &format!("the core's loss factor eta = G''/G' by {a}"),
            RATIO,
            move |row| loss(g(row)),
        )
        .summary(),
    );
    defs.extend(bounds(1, &format!("g_{n}_loss_factor_{{}}"), "", "eta"));
    defs
}

/// The paper's and the exact inverse's bands: the Monte Carlo's.
fn paper_band(row: &Row<'_>) -> [Option<Band>; 2] {
    [row.bands.paper_storage, row.bands.paper_loss_factor]
}

fn exact_band(row: &Row<'_>) -> [Option<Band>; 2] {
    [row.bands.exact_storage, row.bands.exact_loss_factor]
}

/// The FRF fit's band: its law's, widened by the mesh correction's uncertainty
/// ([`crate::frf_route::FrfRoute::at`]).
fn frf_band(row: &Row<'_>) -> [Option<Band>; 2] {
    [
        row.frf.map(|(_, f)| f.storage_ci95),
        row.frf.map(|(_, f)| f.loss_factor_ci95),
    ]
}

/// The layered route's band ([`LayeredColumns`]).
fn layered_band(row: &Row<'_>) -> [Option<Band>; 2] {
    [row.layered.storage, row.layered.loss]
}

/// The columns of the effective modulus and the paper's validity.
fn laminate_columns() -> Vec<Def> {
    vec![
        number(
            "f_hz",
            "f",
            "Hz",
            "the modal frequency",
            Shown {
                unit: "Hz",
                scale: 1.0,
                digits: 3,
            },
            |row| Some(row.p.freq_hz),
        )
        .summary(),
        number(
            "e_storage_pa",
            "E'",
            "Pa",
            "the laminate's effective storage modulus E' (the paper's route)",
            Shown {
                unit: "GPa",
                scale: 1e9,
                digits: 3,
            },
            |row| row.p.e_storage_pa(),
        )
        .summary(),
        number(
            "e_loss_factor",
            "eta_E",
            "",
            "the effective modulus's loss factor",
            RATIO,
            |row| row.p.e_loss_factor(),
        ),
        number(
            "phi_abs",
            "|phi|",
            "",
            "|phi| of the paper's inverse (eq. 37; above 0.1 beyond its ~1 % validity)",
            Shown {
                unit: "",
                scale: 1.0,
                digits: 4,
            },
            |row| row.p.phi(),
        )
        .summary(),
        text(
            "within_phi_limit",
            "yes where |phi| is within the paper's validity, no beyond",
            |row| {
                row.p
                    .phi()
                    .map(|x| if x <= PHI_ACCURACY_LIMIT { "yes" } else { "no" }.to_string())
            },
        ),
    ]
}

/// The layered route's convergence and band columns.
fn layered_detail_columns() -> Vec<Def> {
    let lc = |f: fn(&LayeredColumns) -> Option<f64>| move |row: &Row<'_>| f(&row.layered);
    let ratio = |key: &str, about: &str, f: fn(&LayeredColumns) -> Option<f64>| {
        number(key, key, "", about, RATIO, lc(f))
    };
    vec![
        ratio(
            "layered_freq_error_finest",
            "the finest mesh's estimated relative error of the frequency",
            |c| c.freq_error,
        ),
        ratio(
            "layered_loss_error_finest",
            "the finest mesh's estimated relative error of the loss factor",
            |c| c.loss_error,
        ),
        ratio(
            "layered_residual_freq_error",
            "the ladder's residual relative frequency error",
            |c| c.residual,
        ),
        number(
            "g_layered_coarsest_storage_pa",
            "g_layered_coarsest_storage_pa",
            "Pa",
            "G' on the coarsest mesh, uncorrected",
            MPA,
            lc(|c| storage(c.coarsest)),
        ),
        ratio(
            "g_layered_coarsest_loss_factor",
            "eta on the coarsest mesh, uncorrected",
            |c| loss(c.coarsest),
        ),
        ratio(
            "layered_discretization_half_width_storage",
            "the discretization's relative half-width of G'",
            |c| c.discretization_half_width.map(|h| h[0]),
        ),
        ratio(
            "layered_discretization_half_width_loss_factor",
            "the discretization's relative half-width of eta",
            |c| c.discretization_half_width.map(|h| h[1]),
        ),
        ratio(
            "layered_through_thickness_half_width_storage",
            "one element per layer against two: the relative half-width of G'",
            |c| c.through_thickness_half_width.map(|h| h[0]),
        ),
        ratio(
            "layered_through_thickness_half_width_loss_factor",
            "one element per layer against two: the relative half-width of eta",
            |c| c.through_thickness_half_width.map(|h| h[1]),
        ),
        text(
            "layered_band_main_source",
            "the largest source of the layered band, of G' and of eta",
            |row| row.layered.dominant.clone(),
        ),
    ]
}

/// The truth's G* at a row.
fn truth_g(row: &Row<'_>) -> Option<Complex64> {
    row.r.truth.as_ref().and_then(|t| t.at(row.p.freq_hz))
}

/// The truth's columns.
fn truth_columns() -> Vec<Def> {
    vec![
        number(
            "g_true_storage_pa",
            "G'_true",
            "Pa",
            "the truth's G' (a virtual test)",
            MPA,
            |row| storage(truth_g(row)),
        )
        .summary(),
        number(
            "g_true_loss_factor",
            "eta_true",
            "",
            "the truth's eta (a virtual test)",
            RATIO,
            |row| loss(truth_g(row)),
        )
        .summary(),
    ]
}

/// A route's errors against the truth, recovered/true − 1.
fn error_columns(route: Route) -> [Def; 2] {
    let (g, n, a) = (route.g, route.name, route.about);
    let initial = route.initial;
    [
        number(
            &format!("err_g_{n}_storage"),
            &format!("err G'_{initial}"),
            "",
            &format!("the relative error of G' by {a} against the truth"),
            PERCENT,
            move |row| rel_err(storage(g(row)), storage(truth_g(row))),
        )
        .summary(),
        number(
            &format!("err_g_{n}_loss_factor"),
            &format!("err eta_{initial}"),
            "",
            &format!("the relative error of eta by {a} against the truth"),
            PERCENT,
            move |row| rel_err(loss(g(row)), loss(truth_g(row))),
        )
        .summary(),
    ]
}

/// Every column of the groups `groups`, in order: the laminate, the three inverses with their
/// bands, the layered route's detail, then the truth and the errors, then the FRF fit.
fn definitions(groups: Groups) -> Vec<Def> {
    let mut defs = laminate_columns();
    defs.extend(route_columns(PAPER, paper_band));
    defs.extend(route_columns(EXACT, exact_band));
    defs.extend(route_columns(LAYERED, layered_band));
    defs.extend(layered_detail_columns());
    if groups.truth {
        defs.extend(truth_columns());
        for route in [PAPER, EXACT, LAYERED] {
            defs.extend(error_columns(route));
        }
    }
    if groups.frf {
        defs.extend(route_columns(FRF, frf_band));
        if groups.truth {
            defs.extend(error_columns(FRF));
        }
    }
    defs
}

/// The columns of a table with the groups `groups` (without computing any value).
pub fn core_columns(groups: Groups) -> Vec<CoreColumn> {
    definitions(groups).into_iter().map(|d| d.column).collect()
}

/// The core table of `r` with the groups `groups` (a group `r` lacks: its columns empty).
pub fn core_table_with(r: &ChainResult, groups: Groups) -> CoreTable {
    let defs = definitions(groups);
    let rows = r
        .modal
        .iter()
        .map(|p| {
            let row = Row::of(r, p);
            defs.iter().map(|d| (d.value)(&row)).collect()
        })
        .collect();
    CoreTable {
        columns: defs.into_iter().map(|d| d.column).collect(),
        rows,
    }
}

/// The core table of `r` with the groups it has values for ([`Groups::of`]).
pub fn core_table(r: &ChainResult) -> CoreTable {
    core_table_with(r, Groups::of(r))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Keys are unique and say their unit; every group's columns follow the base ones.
    #[test]
    fn keys_are_unique_and_name_their_unit() {
        let all = core_columns(Groups::ALL);
        let mut keys: Vec<&str> = all.iter().map(|c| c.key.as_str()).collect();
        let n = keys.len();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), n, "a key is defined twice");
        for c in &all {
            assert_eq!(c.key.ends_with("_pa"), c.unit == "Pa", "{}", c.key);
            assert_eq!(c.key.ends_with("_hz"), c.unit == "Hz", "{}", c.key);
        }
        let base = core_columns(Groups {
            truth: false,
            frf: false,
        });
        assert_eq!(all[..base.len()], base[..]);
        assert!(all.iter().any(|c| c.key == "err_g_frf_loss_factor"));
    }
}
