//! `lamdyn core`: from the laminate's effective modulus E*(f) to the core's shear modulus, by the
//! paper's inverse (eqs. 33–45, options selectable) and by the exact Mead–Markus inverse, with φ,
//! the paper model's validity and a Kramers–Kronig causality verdict per line.

use super::{kinematics, kinematics_label};
use crate::Outcome;
use crate::cli::{BendingArg, CoreArgs, CoreFormulaArg, ExampleArg, GlassShearArg};
use crate::examples;
use crate::grid;
use crate::table::{Cell, Column, Fmt, Report};
use anyhow::{Context, Result, bail};
use lamdyn_material::MaterialError;
use lamdyn_material::causality::{CausalityParams, CausalityVerdict, verdicts_where_known};
use lamdyn_material::laminate::{
    CoreEstimate, CoreShearFormula, FaceBending, FaceShear, PHI_ACCURACY_LIMIT,
    PaperInverseOptions, SandwichStack, StackSpec, paper_inverse,
};
use lamdyn_material::law::{PaperEq7Law, ViscoelasticLaw};
use lamdyn_material::sandwich::{ExactCoreEstimate, exact_inverse};
use lamdyn_pipeline::io::{CsvTable, read_toml};
use num_complex::Complex64;
use serde::Serialize;
use std::f64::consts::PI;
use std::io::Write;

/// What `lamdyn core` works on once its arguments are checked.
struct CoreConfig {
    source: String,
    stack_label: String,
    stack: SandwichStack,
    /// (f in Hz, E* in Pa) per line.
    lines: Vec<(f64, Complex64)>,
    options: PaperInverseOptions,
    kk: CausalityParams,
}

/// One line of the result.
#[derive(Debug, Clone)]
struct CoreLine {
    freq_hz: f64,
    e_eff_pa: Complex64,
    paper: Result<CoreEstimate, MaterialError>,
    exact: Result<ExactCoreEstimate, MaterialError>,
    paper_causality: Option<CausalityVerdict>,
    exact_causality: Option<CausalityVerdict>,
}

/// The JSON form of a line (complex numbers as [re, im], SI units).
#[derive(Debug, Serialize)]
struct CoreLineJson<'a> {
    freq_hz: f64,
    e_eff_pa: Complex64,
    paper: Option<&'a CoreEstimate>,
    paper_error: Option<String>,
    paper_causality: Option<CausalityVerdict>,
    exact: Option<&'a ExactCoreEstimate>,
    exact_error: Option<String>,
    exact_causality: Option<CausalityVerdict>,
}

impl CoreLine {
    fn json(&self) -> CoreLineJson<'_> {
        CoreLineJson {
            freq_hz: self.freq_hz,
            e_eff_pa: self.e_eff_pa,
            paper: self.paper.as_ref().ok(),
            paper_error: self.paper.as_ref().err().map(MaterialError::to_string),
            paper_causality: self.paper_causality,
            exact: self.exact.as_ref().ok(),
            exact_error: self.exact.as_ref().err().map(MaterialError::to_string),
            exact_causality: self.exact_causality,
        }
    }
}

/// Runs `lamdyn core`.
pub fn run(args: &CoreArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let config = validate(args)?;
    let mut lines: Vec<CoreLine> = config
        .lines
        .iter()
        .map(|&(f, e)| {
            let w = 2.0 * PI * f;
            CoreLine {
                freq_hz: f,
                e_eff_pa: e,
                paper: paper_inverse(&config.stack, w, e, &config.options),
                exact: exact_inverse(&config.stack, w, e, config.options.kinematics),
                paper_causality: None,
                exact_causality: None,
            }
        })
        .collect();
    let paper_kk = causality(
        &lines,
        |l| l.paper.as_ref().ok().map(|c| c.core_shear_pa),
        config.kk,
    )?;
    let exact_kk = causality(
        &lines,
        |l| l.exact.as_ref().ok().map(|c| c.core_shear_pa),
        config.kk,
    )?;
    for (i, line) in lines.iter_mut().enumerate() {
        line.paper_causality = paper_kk[i];
        line.exact_causality = exact_kk[i];
    }
    let report = build_report(&config, &lines)?;
    report.write(args.output.format(), out, err)?;
    let failed = lines.iter().any(|l| l.paper.is_err() || l.exact.is_err());
    Ok(if failed {
        Outcome::ChecksFailed
    } else {
        Outcome::Done
    })
}

fn validate(args: &CoreArgs) -> Result<CoreConfig> {
    if !(0.0..1.0).contains(&args.kk_tolerance) {
        bail!("--kk-tolerance = {} must lie in [0, 1)", args.kk_tolerance);
    }
    let mut kk = CausalityParams::default();
    kk.tolerance = args.kk_tolerance;
    let grid = || {
        grid::build(
            args.grid.freq_hz.as_deref(),
            args.grid.f_min_hz,
            args.grid.f_max_hz,
            args.grid.f_step_hz,
        )
    };
    let (source, stack_label, stack, lines) = match (args.example, &args.stack) {
        (Some(ExampleArg::PaperRoof), _) => {
            let (stack, law) = examples::paper_roof();
            let lines = sample(&law, &grid()?);
            let source = format!("built-in paper-roof: {}", law.describe());
            (
                source,
                "built-in paper-roof (Table 1; glass 70 GPa, nu 0.22; PVB nu 0.49; 10.40 \
                 kg/m^2 measured)"
                    .to_string(),
                stack,
                lines,
            )
        }
        (None, Some(path)) => {
            let spec: StackSpec = read_toml(path)?;
            let stack = spec
                .to_sandwich()
                .with_context(|| format!("invalid stack '{}'", path.display()))?;
            let (source, lines) = match (&args.eq7, &args.table) {
                (Some(p), _) => {
                    let [e0, mu, t0, c] = p.0;
                    let law = PaperEq7Law::new(e0, mu, t0, c).context("invalid --eq7")?;
                    (law.describe(), sample(&law, &grid()?))
                }
                (None, Some(table)) => (
                    format!("table '{}'", table.display()),
                    read_modulus_table(&CsvTable::read(table)?)?,
                ),
                (None, None) => bail!("--stack needs the laminate's modulus: --eq7 or --table"),
            };
            (source, format!("'{}'", path.display()), stack, lines)
        }
        (None, None) => bail!("give --example paper-roof, or --stack FILE with --eq7 or --table"),
    };
    let kin = kinematics(args.kinematics, stack.bottom().poisson);
    let options = PaperInverseOptions::new(
        match args.core_formula {
            CoreFormulaArg::Eq41 => CoreShearFormula::Eq41,
            CoreFormulaArg::Eq43 => CoreShearFormula::Eq43,
            CoreFormulaArg::Eq26 => CoreShearFormula::Eq26,
        },
        match args.glass_shear {
            GlassShearArg::Neglect => FaceShear::Neglected,
            GlassShearArg::Include => FaceShear::Included,
        },
        match args.bending {
            BendingArg::Faces => FaceBending::CoreNeglected,
            BendingArg::Full => FaceBending::FullStack,
        },
        kin,
    );
    Ok(CoreConfig {
        source,
        stack_label,
        stack,
        lines,
        options,
        kk,
    })
}

/// E*(ω = 2πf) of `law` on the grid.
fn sample(law: &dyn ViscoelasticLaw, freqs: &[f64]) -> Vec<(f64, Complex64)> {
    freqs
        .iter()
        .map(|f| (*f, law.modulus(2.0 * PI * f)))
        .collect()
}

/// Reads f_hz, e_storage_pa and loss_factor or e_loss_pa.
fn read_modulus_table(t: &CsvTable) -> Result<Vec<(f64, Complex64)>> {
    let f = t.require_any(&["f_hz"])?;
    let e = t.require_any(&["e_storage_pa"])?;
    let loss = t.require_any(&["loss_factor", "e_loss_pa"])?;
    t.require_increasing_positive(f)?;
    let is_factor = t.find("loss_factor") == Some(loss);
    t.rows()
        .iter()
        .map(|(line, v)| {
            if v[e] <= 0.0 {
                bail!(
                    "'{}' line {line}: e_storage_pa = {} must be positive",
                    t.path(),
                    v[e]
                );
            }
            let im = if is_factor { v[e] * v[loss] } else { v[loss] };
            Ok((v[f], Complex64::new(v[e], im)))
        })
        .collect()
}

/// Kramers–Kronig verdicts of the recovered G*(f) on the lines where `g` exists.
fn causality(
    lines: &[CoreLine],
    g: impl Fn(&CoreLine) -> Option<Complex64>,
    params: CausalityParams,
) -> Result<Vec<Option<CausalityVerdict>>> {
    let points: Vec<(f64, Option<Complex64>)> = lines.iter().map(|l| (l.freq_hz, g(l))).collect();
    Ok(verdicts_where_known(&points, params)?)
}

fn build_report(config: &CoreConfig, lines: &[CoreLine]) -> Result<Report> {
    let columns = vec![
        Column::new("f_hz", "f", "Hz", Fmt::Fixed(2)),
        Column::new("e_eff_storage_pa", "E_eff'", "GPa", Fmt::Fixed(4)).scaled(1e9),
        Column::new("e_eff_loss_factor", "eta_eff", "", Fmt::Sci(3)),
        Column::new("phi_abs", "|phi|", "", Fmt::Fixed(4)),
        Column::new("g_paper_storage_pa", "G'_paper", "MPa", Fmt::Fixed(4)).scaled(1e6),
        Column::new("g_paper_loss_factor", "eta_paper", "", Fmt::Fixed(4)),
        Column::new("g_exact_storage_pa", "G'_exact", "MPa", Fmt::Fixed(4)).scaled(1e6),
        Column::new("g_exact_loss_factor", "eta_exact", "", Fmt::Fixed(4)),
        Column::new("within_phi_limit", "phi<=0.1", "", Fmt::Fixed(0)),
        Column::new("causality_paper", "KK_paper", "", Fmt::Fixed(0)),
        Column::new("causality_exact", "KK_exact", "", Fmt::Fixed(0)),
    ];
    let mut report = Report::new("core", columns);
    add_inputs(&mut report, config);

    let verdict = |v: Option<CausalityVerdict>| v.map_or("n/a".into(), |v| v.label().to_string());
    let mut beyond = 0;
    let mut failures = Vec::new();
    for l in lines {
        let phi = l.paper.as_ref().ok().map(|c| c.phi.norm());
        if phi.is_some_and(|p| p > PHI_ACCURACY_LIMIT) {
            beyond += 1;
        }
        for (name, r) in [
            ("paper", l.paper.as_ref().err()),
            ("exact", l.exact.as_ref().err()),
        ] {
            if let Some(e) = r {
                failures.push(format!("{name} inverse: {e}"));
            }
        }
        let (gp, ep) = split(l.paper.as_ref().ok().map(|c| c.core_shear_pa));
        let (ge, ee) = split(l.exact.as_ref().ok().map(|c| c.core_shear_pa));
        report.row(vec![
            l.freq_hz.into(),
            l.e_eff_pa.re.into(),
            (l.e_eff_pa.im / l.e_eff_pa.re).into(),
            phi.into(),
            gp,
            ep,
            ge,
            ee,
            match phi {
                Some(p) if p <= PHI_ACCURACY_LIMIT => "yes".into(),
                Some(_) => "no".into(),
                None => Cell::Empty,
            },
            verdict(l.paper_causality).into(),
            verdict(l.exact_causality).into(),
        ]);
    }
    if beyond > 0 {
        report.warnings.push(format!(
            "|phi| > {PHI_ACCURACY_LIMIT} at {beyond} of {} lines: the paper's inverse is beyond \
             its ~1 % accuracy range there; prefer G'_exact",
            lines.len()
        ));
    }
    add_causality_warnings(&mut report, lines);
    report.warnings.extend(failures);
    report.notes.push(
        "G'_paper, eta_paper: paper eqs. 33-45; G'_exact, eta_exact: Mead-Markus \
         exact sandwich inverse."
            .into(),
    );
    report.notes.push(
        "|phi|: paper eq. 37; phi<=0.1: within the paper model's ~1 % accuracy range \
         (method-notes section 3)."
            .into(),
    );
    report.notes.push(
        "KK: local Kramers-Kronig check of the recovered G*(f) (causal | G' falls | \
         too little loss | negative loss)."
            .into(),
    );
    report.extra = Some(serde_json::to_value(
        lines.iter().map(CoreLine::json).collect::<Vec<_>>(),
    )?);
    Ok(report)
}

/// The inputs: the laminate's modulus, the stack, the bonded faces' bound, the inverses, the
/// kinematics and the frequency convention.
fn add_inputs(report: &mut Report, config: &CoreConfig) {
    let stack = &config.stack;
    let h = stack.thickness_m();
    let bonded = stack
        .section(Complex64::new(1.0, 0.0), config.options.kinematics)
        .without_bending_of(1)
        .bending_stiffness()
        .re;
    report.input("laminate modulus", config.source.clone());
    report.input("stack", config.stack_label.clone());
    report.input(
        "faces / core",
        format!(
            "{:.4} mm + {:.4} mm + {:.4} mm, E_faces = {:.4e} Pa",
            stack.bottom().thickness_m * 1e3,
            stack.core().thickness_m * 1e3,
            stack.top().thickness_m * 1e3,
            stack.bottom().young_pa
        ),
    );
    report.input(
        "surface density",
        format!("{:.4} kg/m^2", stack.surface_density_kg_m2()),
    );
    report.input(
        "bonded faces",
        format!(
            "B_eq = {bonded:.6e} N m, 12 B_eq/h^3 = {:.4} GPa (E_eff' must stay below)",
            12.0 * bonded / h.powi(3) * config.options.kinematics.effective_modulus_factor() / 1e9
        ),
    );
    report.input("paper inverse", config.options.label());
    report.input(
        "exact inverse",
        "Mead-Markus sandwich beam, closed form".to_string(),
    );
    report.input("kinematics", kinematics_label(config.options.kinematics));
    report.input(
        "omega convention",
        "omega = 2 pi f in rad/s wherever a law takes a frequency".to_string(),
    );
}

/// A warning per inverse whose G*(f) fails the Kramers-Kronig check at some line.
fn add_causality_warnings(report: &mut Report, lines: &[CoreLine]) {
    let non_causal = |pick: fn(&CoreLine) -> Option<CausalityVerdict>| {
        lines
            .iter()
            .filter(|l| pick(l).is_some_and(|v| !v.is_consistent()))
            .count()
    };
    for (name, n) in [
        ("paper", non_causal(|l| l.paper_causality)),
        ("exact", non_causal(|l| l.exact_causality)),
    ] {
        if n > 0 {
            report.warnings.push(format!(
                "the {name} inverse's G*(f) fails the Kramers-Kronig check at {n} of {} lines: no \
                 causal material has this modulus",
                lines.len()
            ));
        }
    }
}

/// (G', η) cells of an optional complex modulus.
fn split(g: Option<Complex64>) -> (Cell, Cell) {
    match g {
        Some(g) => (g.re.into(), (g.im / g.re).into()),
        None => (Cell::Empty, Cell::Empty),
    }
}
