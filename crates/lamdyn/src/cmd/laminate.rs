//! `lamdyn laminate`: a stack's homogenized stiffness against frequency.
//!
//! For each frequency: B_eq (eq. 14), K_eq (eqs. 24–27 for any number of layers), φ (eq. 31),
//! E_eff = 12 B_K/h³ with B_K from eq. 29 and its loss factor; for three-layer stacks also the
//! exact (Mead–Markus) effective modulus beside it.

use super::{kinematics, kinematics_label};
use crate::Outcome;
use crate::cli::LaminateArgs;
use crate::grid;
use crate::table::{Cell, Column, Fmt, Report};
use anyhow::{Context, Result};
use lamdyn_material::laminate::{
    ModelWarning, PAPER_LOSS_AGREEMENT, PAPER_STORAGE_AGREEMENT, StackSpec, agrees_with_exact,
};
use lamdyn_material::sandwich::MeadMarkus;
use lamdyn_pipeline::io::read_toml;
use std::f64::consts::PI;
use std::io::Write;

/// Runs `lamdyn laminate`.
pub fn run(args: &LaminateArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let spec: StackSpec = read_toml(&args.stack)?;
    let file = args.stack.display().to_string();
    let stack = spec
        .to_layer_stack()
        .with_context(|| format!("invalid stack '{file}'"))?;
    // Three-layer stacks with elastic faces also get the exact sandwich theory beside the paper's.
    let sandwich = spec.to_sandwich().ok();
    let kin = kinematics(args.kinematics, stack.layers()[0].poisson());
    let freqs = grid::build(
        args.grid.freq_hz.as_deref(),
        args.grid.f_min_hz,
        args.grid.f_max_hz,
        args.grid.f_step_hz,
    )?;

    let mut report = Report::new("laminate", columns(sandwich.is_some()));
    report.input("stack", file);
    report.input("layers", layer_summary(&stack));
    report.input("thickness", format!("{:.6e} m", stack.thickness_m()));
    report.input(
        "surface density",
        format!("{:.6} kg/m^2", stack.surface_density_kg_m2()),
    );
    report.input("kinematics", kinematics_label(kin));

    let mut details = Vec::new();
    let mut beyond = Vec::new();
    let mut disagree = Vec::new();
    for f in &freqs {
        let w = 2.0 * PI * f;
        let h = stack.homogenize(w, kin)?;
        let mut row: Vec<Cell> = vec![
            (*f).into(),
            h.b_eq.re.into(),
            h.k_eq.re.into(),
            h.phi.norm().into(),
            h.e_eff.re.into(),
            h.loss_factor().into(),
            yes_no(h.within_accuracy_limit()),
        ];
        let exact = sandwich.as_ref().map(|s| {
            let core_g = stack.layers()[1].moduli(w).1;
            MeadMarkus::new(s, kin).effective_modulus(core_g, w)
        });
        let agrees = exact.is_none_or(|e| agrees_with_exact(h.e_eff, e));
        row.push(yes_no(h.within_accuracy_limit() && agrees));
        if let Some(e) = exact {
            row.push(e.re.into());
            row.push((e.im / e.re).into());
        }
        if !agrees {
            disagree.push(*f);
        }
        if let Some(ModelWarning::PhiBeyondLimit { freq_hz, .. }) = h.warning() {
            beyond.push(freq_hz);
        }
        report.row(row);
        details.push(h);
    }
    add_warnings_and_notes(
        &mut report,
        freqs.len(),
        &beyond,
        &disagree,
        sandwich.is_some(),
    );
    report.extra = Some(serde_json::to_value(&details)?);
    report.write(args.output.format(), out, err)?;
    Ok(Outcome::Done)
}

/// The table's columns, with exact sandwich theory's for a three-layer stack.
fn columns(sandwich: bool) -> Vec<Column> {
    let mut columns = vec![
        Column::new("f_hz", "f", "Hz", Fmt::Fixed(2)),
        Column::new("b_eq_storage_n_m", "B_eq'", "N m", Fmt::Sci(4)),
        Column::new("k_eq_storage_n_per_m", "K_eq'", "N/m", Fmt::Sci(4)),
        Column::new("phi_abs", "|phi|", "", Fmt::Fixed(4)),
        Column::new("e_eff_storage_pa", "E_eff'", "GPa", Fmt::Fixed(4)).scaled(1e9),
        Column::new("e_eff_loss_factor", "eta_eff", "", Fmt::Sci(3)),
        Column::new("within_phi_limit", "phi<=0.1", "", Fmt::Fixed(0)),
        Column::new("paper_valid", "valid", "", Fmt::Fixed(0)),
    ];
    if sandwich {
        columns
            .push(Column::new("e_exact_storage_pa", "E_exact'", "GPa", Fmt::Fixed(4)).scaled(1e9));
        columns.push(Column::new(
            "e_exact_loss_factor",
            "eta_exact",
            "",
            Fmt::Sci(3),
        ));
    }
    columns
}

/// The lines beyond the paper's |φ| limit (`beyond`) and those where it disagrees with exact
/// sandwich theory (`disagree`), of `lines`, as warnings; the columns' notes.
fn add_warnings_and_notes(
    report: &mut Report,
    lines: usize,
    beyond: &[f64],
    disagree: &[f64],
    sandwich: bool,
) {
    if !beyond.is_empty() {
        report.warnings.push(format!(
            "|phi| > 0.1 at {} of {} lines ({:.2} Hz and above): the paper's homogenization is \
             beyond its ~1 % accuracy range there",
            beyond.len(),
            lines,
            beyond[0]
        ));
    }
    if let [first, .., last] | [first @ last] = disagree {
        report.warnings.push(format!(
            "the paper's homogenization disagrees with exact sandwich theory at {} of {} lines \
             ({first:.2}-{last:.2} Hz): E_eff' more than {:.0} % or its loss factor more than \
             {:.0} % from E_exact's, though |phi| may be small (a core whose own bending or \
             extension matters): the paper's model is not valid there",
            disagree.len(),
            lines,
            100.0 * PAPER_STORAGE_AGREEMENT,
            100.0 * PAPER_LOSS_AGREEMENT
        ));
    }
    report.notes.push(format!(
        "valid: |phi| <= 0.1 and, for three-layer stacks, E_eff' within {:.0} % and its loss \
         factor within {:.0} % of exact sandwich theory's.",
        100.0 * PAPER_STORAGE_AGREEMENT,
        100.0 * PAPER_LOSS_AGREEMENT
    ));
    report.notes.push(
        "B_eq' and K_eq' are real parts per unit width; E_eff = 12 B_K / h^3 (paper eqs. 29-33)."
            .into(),
    );
    if sandwich {
        report.notes.push(
            "E_exact: Mead-Markus sandwich beam at the same frequency (faces in \
             bending and extension, core in shear)."
                .into(),
        );
    }
}

/// A yes/no cell.
fn yes_no(yes: bool) -> Cell {
    if yes { "yes" } else { "no" }.into()
}

fn layer_summary(stack: &lamdyn_material::laminate::LayerStack) -> String {
    stack
        .layers()
        .iter()
        .map(|l| format!("{} {:.4} mm", l.name(), l.thickness_m() * 1e3))
        .collect::<Vec<_>>()
        .join(" / ")
}
