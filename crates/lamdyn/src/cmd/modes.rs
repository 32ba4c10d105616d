//! `lamdyn modes`: natural frequencies and mode shapes of a shell model, with the solver's
//! checks (residuals, Sturm count), modal masses, and VTK/JSON/MAC outputs.

use crate::Outcome;
use crate::cli::{ModelExample, ModesArgs};
use crate::progress::Spinner;
use crate::table::{Cell, Column, Fmt, Report};
use anyhow::{Context, Result, bail};
use faer::Mat;
use lamdyn_fem::assembly::{Assembly, NodeSpring};
use lamdyn_fem::convergence::{ConvergeParams, converge_modes};
use lamdyn_fem::eigen::{ModalParams, ModalSolution, Shift, solve_modes};
use lamdyn_fem::element::ShellMaterial;
use lamdyn_fem::mesh::Mesh;
use lamdyn_fem::mesh::structured::RectangleSpec;
use lamdyn_fem::model::{MeshSpec, ModelSpec, SolverSpec};
use lamdyn_fem::output::{mac, vtu_text};
use lamdyn_pipeline::AsProgress;
use lamdyn_pipeline::io::read_toml;
use lamdyn_pipeline::output::{check_file_target, write_file};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The shapes file written by `--shapes-json` and read by `--compare`.
#[derive(Debug, Serialize, Deserialize)]
struct ShapesFile {
    lamdyn: String,
    /// Node positions, m.
    nodes: Vec<[f64; 3]>,
    modes: Vec<ShapeEntry>,
}

#[derive(Debug, Serialize, Deserialize)]
struct ShapeEntry {
    freq_hz: f64,
    eigenvalue_rad2_s2: f64,
    rigid: bool,
    /// 6 dofs per node (u_x, u_y, u_z in m, θ_x, θ_y, θ_z in rad), mass-normalised.
    shape: Vec<f64>,
}

fn example(e: ModelExample) -> ModelSpec {
    let rect = |lx: f64, ly: f64, rx: f64, ry: f64| {
        MeshSpec::Rectangle(RectangleSpec::flat(lx, ly, 40, 40).curved(rx, ry))
    };
    let glass = ShellMaterial {
        young_pa: 67.45e9,
        poisson: 0.22,
        density_kg_m3: 2702.0,
        thickness_m: 0.00385,
    };
    let solver = SolverSpec::default();
    match e {
        ModelExample::PaperPlate => ModelSpec {
            mesh: rect(0.923, 0.8632, f64::INFINITY, f64::INFINITY),
            material: glass,
            supports: vec![],
            solver,
        },
        ModelExample::PaperRoofCurved => ModelSpec {
            mesh: rect(0.923, 0.8632, 3.0, 5.0),
            material: glass,
            supports: vec![],
            solver,
        },
        ModelExample::NafemsFv12 => ModelSpec {
            mesh: rect(10.0, 10.0, f64::INFINITY, f64::INFINITY),
            material: ShellMaterial {
                young_pa: 200e9,
                poisson: 0.3,
                density_kg_m3: 8000.0,
                thickness_m: 0.05,
            },
            supports: vec![],
            solver,
        },
    }
}

/// Runs `lamdyn modes`.
pub fn run(args: &ModesArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let (mut spec, base, source) = match (&args.model, args.example) {
        (Some(path), _) => {
            let spec: ModelSpec = read_toml(path)?;
            let base = path
                .parent()
                .map(Path::to_path_buf)
                .unwrap_or_else(|| PathBuf::from("."));
            (spec, base, format!("'{}'", path.display()))
        }
        (None, Some(e)) => (example(e), PathBuf::from("."), format!("built-in {e:?}")),
        (None, None) => bail!("give a model file or --example"),
    };
    if let Some(n) = args.modes {
        spec.solver.modes = n as usize;
    }
    if args.elements.is_some() || args.element.is_some() || args.edge_layers.is_some() {
        match &mut spec.mesh {
            MeshSpec::Rectangle(r) => {
                if let Some((nx, ny)) = args.elements {
                    (r.elements_x, r.elements_y) = (nx, ny);
                }
                if let Some(e) = args.element {
                    r.order = e.into();
                }
                if let Some(n) = args.edge_layers {
                    r.edge_layers = n;
                    r.edge_layer_m = 0.0;
                    r.grading = 0.0;
                }
            }
            MeshSpec::Gmsh { .. } => bail!(
                "--elements, --element and --edge-layers apply to rectangle models; this model \
                 reads a mesh file (its element order is the file's)"
            ),
        }
    }
    let compare = match &args.compare {
        Some(p) => Some(read_shapes(p)?),
        None => None,
    };
    // Outputs are checked before the solve: a wrong path fails at once.
    let inputs: Vec<PathBuf> = args.model.iter().chain(&args.compare).cloned().collect();
    for path in args.vtu.iter().chain(&args.shapes_json) {
        check_file_target(path, &inputs)?;
    }
    let (mesh, springs) = spec
        .build(&base)
        .with_context(|| format!("invalid model {source}"))?;
    let mut params = ModalParams::lowest(spec.solver.modes);
    if let Some(f) = spec.solver.shift_hz {
        if !(f.is_finite() && f > 0.0) {
            bail!("invalid model {source}: solver.shift_hz = {f} must be a positive frequency");
        }
        params = params.with_shift(Shift::BelowHz(f));
    }
    // --converge assembles each of its meshes itself.
    if let Some(tolerance) = args.converge {
        return converge(args, &spec, &source, &mesh, &springs, tolerance, out, err);
    }
    let asm = Assembly::new(&mesh, &spec.material, &springs)
        .with_context(|| format!("invalid model {source}"))?;
    let progress = Spinner::new();
    let sol = solve_modes(&asm, &params, &AsProgress(&progress))?;
    progress.finish();

    let report = build_report(&source, &mesh, &spec, &asm, &sol, compare.as_ref())?;
    if let Some(path) = &args.vtu {
        let shapes: Vec<Vec<f64>> = (0..sol.shapes.ncols())
            .map(|j| sol.shapes.col(j).iter().copied().collect())
            .collect();
        let freqs: Vec<f64> = sol.modes.iter().map(|m| m.freq_hz).collect();
        write_file(path, vtu_text(&mesh, &freqs, &shapes).as_bytes(), &inputs)?;
    }
    if let Some(path) = &args.shapes_json {
        write_file(path, &shapes_json(&mesh, &sol)?, &inputs)?;
    }
    report.write(args.output.format(), out, err)?;
    Ok(Outcome::Done)
}

/// The columns of `lamdyn modes --converge`.
fn converge_columns() -> Vec<Column> {
    vec![
        Column::new("mode", "mode", "", Fmt::Fixed(0)),
        Column::new("freq_hz", "f", "Hz", Fmt::Fixed(5)),
        Column::new("rigid", "rigid", "", Fmt::Fixed(0)),
        Column::new("extrapolated_hz", "f extrapolated", "Hz", Fmt::Fixed(5)),
        Column::new("error_estimate", "est. error", "", Fmt::Sci(2)),
        Column::new("order", "order", "", Fmt::Fixed(2)),
    ]
}

/// `lamdyn modes --converge TOL`: the per-mode error estimate over refined meshes.
#[allow(clippy::too_many_arguments)]
fn converge(
    args: &ModesArgs,
    spec: &ModelSpec,
    source: &str,
    mesh: &Mesh,
    springs: &[NodeSpring],
    tolerance: f64,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<Outcome> {
    let mut params = ConvergeParams::new(spec.solver.modes, tolerance);
    if let Some(n) = args.max_dofs {
        params.max_dofs = n;
    }
    let surface = spec.surface();
    let progress = Spinner::new();
    let result = converge_modes(
        mesh,
        surface.as_deref(),
        &spec.material,
        springs,
        &params,
        &AsProgress(&progress),
    )
    .with_context(|| format!("--converge on {source}"))?;
    progress.finish();
    let mut report = Report::new("modes", converge_columns());
    report.input("model", source.to_string());
    report.input(
        "mesh",
        format!(
            "{} {} elements, each split m x m for m = 1..={}",
            mesh.n_elements(),
            mesh.order().name(),
            result.levels.last().map_or(1, |l| l.subdivisions)
        ),
    );
    for level in &result.levels {
        report.input(
            &format!("level {}x{}", level.subdivisions, level.subdivisions),
            format!("{} dofs, {:.3} s", level.n_dofs, level.seconds),
        );
    }
    report.input("tolerance", format!("{tolerance:e} (relative frequency)"));
    report.input("stopped", result.stopped.clone());
    for (j, m) in result.modes.iter().enumerate() {
        let (extrapolated, error, order): (Cell, Cell, Cell) = if m.rigid {
            (Cell::Empty, Cell::Empty, Cell::Empty)
        } else {
            (
                m.extrapolated_hz.into(),
                m.error.into(),
                m.order.map_or(Cell::Empty, Cell::from),
            )
        };
        report.row(vec![
            ((j + 1) as f64).into(),
            m.freq_hz.into(),
            if m.rigid { "yes" } else { "" }.into(),
            extrapolated,
            error,
            order,
        ]);
    }
    report.notes.push(
        "f: the finest mesh's frequency; est. error: its estimated relative \
         discretization error (grid convergence index: Richardson over the last \
         three meshes with the observed order, factor of safety 1.25; 3 where the \
         order is assumed); order: the observed order of convergence."
            .into(),
    );
    report.warnings.extend(result.warnings.iter().cloned());
    report.extra = Some(serde_json::to_value(&result)?);
    report.write(args.output.format(), out, err)?;
    if result.converged {
        return Ok(Outcome::Done);
    }
    let worst = result
        .worst()
        .map(|(j, e)| format!("worst mode {} at {e:.2e}", j + 1))
        .unwrap_or_else(|| "no elastic mode".into());
    let last = result.levels.last().map_or(0, |l| l.n_dofs);
    writeln!(
        err,
        "lamdyn: not converged to {tolerance:e}: {worst} after {} meshes (finest {last} dofs); \
         stopped: {}",
        result.levels.len(),
        result.stopped
    )?;
    Ok(Outcome::ChecksFailed)
}

fn read_shapes(path: &Path) -> Result<ShapesFile> {
    let text = lamdyn_pipeline::io::read_text(path)?;
    serde_json::from_str(&text)
        .with_context(|| format!("'{}' is not a lamdyn shapes file", path.display()))
}

/// The `--shapes-json` file's bytes.
fn shapes_json(mesh: &Mesh, sol: &ModalSolution) -> Result<Vec<u8>> {
    let file = ShapesFile {
        lamdyn: env!("CARGO_PKG_VERSION").into(),
        nodes: mesh.nodes().to_vec(),
        modes: sol
            .modes
            .iter()
            .enumerate()
            .map(|(j, m)| ShapeEntry {
                freq_hz: m.freq_hz,
                eigenvalue_rad2_s2: m.eigenvalue,
                rigid: m.rigid,
                shape: sol.shapes.col(j).iter().copied().collect(),
            })
            .collect(),
    };
    Ok(serde_json::to_vec(&file)?)
}

/// Translational part of a shape (u_x, u_y, u_z per node).
fn translations(shape: &[f64]) -> Vec<f64> {
    shape.chunks(6).flat_map(|c| c[..3].to_vec()).collect()
}

fn build_report(
    source: &str,
    mesh: &Mesh,
    spec: &ModelSpec,
    asm: &Assembly,
    sol: &ModalSolution,
    compare: Option<&ShapesFile>,
) -> Result<Report> {
    let mut report = Report::new("modes", mode_columns(compare.is_some()));
    add_inputs(&mut report, source, mesh, spec, asm, sol);
    // Mass projections on the z translation.
    let n = asm.n_dofs();
    let ez = Mat::from_fn(n, 1, |i, _| if i % 6 == 2 { 1.0 } else { 0.0 });
    let mut m_ez = Mat::zeros(n, 1);
    lamdyn_fem::sparse::symmetric_matmul(asm.mass.as_ref(), ez.as_ref(), m_ez.as_mut());
    let total: f64 = (0..n).map(|i| ez[(i, 0)] * m_ez[(i, 0)]).sum();
    report.input("total mass", format!("{total:.6} kg"));
    let other: Option<Vec<Vec<f64>>> = match compare {
        Some(c) => {
            if c.nodes.len() != mesh.nodes().len() {
                bail!(
                    "--compare needs the same nodes: the other run has {} nodes, this one {}",
                    c.nodes.len(),
                    mesh.nodes().len()
                );
            }
            Some(c.modes.iter().map(|e| translations(&e.shape)).collect())
        }
        None => None,
    };
    for (j, mode) in sol.modes.iter().enumerate() {
        let shape: Vec<f64> = sol.shapes.col(j).iter().copied().collect();
        let max_t = shape
            .chunks(6)
            .map(|c| (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt())
            .fold(0.0, f64::max);
        let gamma: f64 = (0..n).map(|i| shape[i] * m_ez[(i, 0)]).sum();
        let mut row: Vec<Cell> = vec![
            ((j + 1) as f64).into(),
            mode.freq_hz.into(),
            if mode.rigid { "yes" } else { "" }.into(),
            (1.0 / (max_t * max_t)).into(),
            (gamma * gamma / total).into(),
            mode.residual.into(),
        ];
        if let (Some(other), Some(c)) = (&other, compare) {
            let t = translations(&shape);
            let (best, value) = other
                .iter()
                .enumerate()
                .map(|(k, o)| (k, mac(&t, o)))
                .fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a });
            row.push(((best + 1) as f64).into());
            row.push(value.into());
            let fo = c.modes[best].freq_hz;
            row.push(if fo > 0.0 {
                (mode.freq_hz / fo - 1.0).into()
            } else {
                Cell::Empty
            });
        }
        report.row(row);
    }
    report.notes.push(
        "modal mass: generalised mass of the shape scaled to a largest translation \
         of 1 m; eff. mass z: (phi^T M e_z)^2 / total mass."
            .into(),
    );
    report.notes.push(
        "residual: |K phi - lambda M phi|_2 / (|K|_1 |phi|_2); shapes are \
         mass-normalised (phi^T M phi = 1)."
            .into(),
    );
    report.extra =
        Some(serde_json::json!({ "sturm": sol.sturm, "info": sol.info, "modes": sol.modes }));
    Ok(report)
}

/// The modes table's columns, with the match in the other run when one is compared.
fn mode_columns(compared: bool) -> Vec<Column> {
    let mut columns = vec![
        Column::new("mode", "mode", "", Fmt::Fixed(0)),
        Column::new("freq_hz", "f", "Hz", Fmt::Fixed(4)),
        Column::new("rigid", "rigid", "", Fmt::Fixed(0)),
        Column::new("modal_mass_kg", "modal mass", "kg", Fmt::Sci(4)),
        Column::new(
            "effective_mass_z_fraction",
            "eff. mass z",
            "%",
            Fmt::Fixed(2),
        )
        .scaled(0.01),
        Column::new("residual", "residual", "", Fmt::Sci(2)),
    ];
    if compared {
        columns.push(Column::new("compare_mode", "match", "", Fmt::Fixed(0)));
        columns.push(Column::new("compare_mac", "MAC", "", Fmt::Fixed(4)));
        columns.push(Column::new("compare_freq_diff", "df", "%", Fmt::Fixed(3)).scaled(0.01));
    }
    columns
}

/// The run's inputs: the model, the mesh, the material, the supports, the solver, its times
/// and the Sturm check.
fn add_inputs(
    report: &mut Report,
    source: &str,
    mesh: &Mesh,
    spec: &ModelSpec,
    asm: &Assembly,
    sol: &ModalSolution,
) {
    let m = &spec.material;
    report.input("model", source.to_string());
    report.input(
        "mesh",
        format!(
            "{} nodes, {} {} elements, {} dofs, area {:.6} m^2",
            mesh.nodes().len(),
            mesh.n_elements(),
            mesh.order().name(),
            mesh.n_dofs(),
            mesh.area()
        ),
    );
    report.input(
        "material",
        format!(
            "E = {:.6e} Pa, nu = {}, rho = {} kg/m^3, t = {} m",
            m.young_pa, m.poisson, m.density_kg_m3, m.thickness_m
        ),
    );
    report.input(
        "supports",
        format!("{} elastic supports", asm.springs.len()),
    );
    let info = sol.info;
    report.input(
        "solver",
        format!(
            "shift {:.4e} rad^2/s^2, factor {} entries, {} operator applications, {} restarts",
            info.shift, info.factor_nnz, info.applications, info.restarts
        ),
    );
    report.input(
        "time",
        format!(
            "symbolic {:.3} s, factorization {:.3} s, Lanczos {:.3} s, Sturm check {:.3} s",
            info.seconds[0], info.seconds[1], info.seconds[2], info.seconds[3]
        ),
    );
    if let Some(s) = sol.sturm {
        report.input(
            "Sturm check",
            format!(
                "{} eigenvalues below {:.6e} rad^2/s^2, {} modes returned: {}",
                s.count,
                s.cutoff,
                s.returned,
                if s.count == s.returned {
                    "none missed"
                } else {
                    "MISMATCH"
                }
            ),
        );
    }
}
