//! Command-line definitions (clap derive). Every numeric flag states its unit and default;
//! numbers are parsed as finite values here, and physics checks happen in the commands.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

/// lamdyn: the viscoelastic core of a laminated plate, measured on the finished part.
///
/// Units are SI unless a flag's name says otherwise (frequencies on the command line are in Hz;
/// laws use the angular frequency omega = 2 pi f in rad/s).
#[derive(Debug, Parser)]
#[command(name = "lamdyn", version, about, long_about = None, propagate_version = true)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands, one per pipeline stage.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Homogenize a layer stack: B_eq, K_eq, phi and the effective modulus E_eff against frequency.
    Laminate(LaminateArgs),
    /// Recover the core's shear modulus G'(f) and loss factor from the laminate's E*(f).
    Core(CoreArgs),
    /// ASTM E756-05 beam method: resonances of a beam test -> modulus and loss factor per mode.
    E756(E756Args),
    /// Free (or supported) vibration modes of a shell model: MITC4 or MITC9 FE, shift-invert
    /// Lanczos.
    Modes(ModesArgs),
    /// Fit the laminate's effective modulus law E*(f) to measured FRFs through the FE model.
    Fit(FitArgs),
    /// Universal File Format (UFF/UNV) files: list contents, convert.
    #[command(subcommand)]
    Uff(UffCommand),
    /// Experimental modal analysis of measured FRFs or hammer-test time data: poles (LSCF or
    /// PolyMAX), stabilization diagram, modes, CMIF; charts with --out.
    Ema(EmaArgs),
    /// Virtual impact test on a layered 20-node-hexahedron model with a frequency-dependent core
    /// (a TOML description, or the built-in roof): FRFs, hammer-hit time signals, the true core.
    Simulate(SimulateArgs),
    /// The whole chain from a job file: measurement -> EMA -> fit of E*(f) -> G*(f) of the core
    /// by both inverses, Monte Carlo bands -> an HTML report with figures and CSV/JSON tables.
    Run(RunArgs),
    /// The demo: simulate the virtual roof's impact test, run the whole chain on it, and compare
    /// the recovered core with the truth (report in DIR/report/report.html).
    Demo(DemoArgs),
}

/// `lamdyn run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The job file (TOML; `lamdyn demo` writes one in DIR/input/job.toml).
    #[arg(value_name = "JOB")]
    pub job: PathBuf,
    /// Folder of the report [default: `report` beside the job file]. lamdyn writes only its own
    /// files there (listed in DIR/.lamdyn-manifest), only when every stage worked, and refuses
    /// a folder holding the job's inputs or other files (see --force).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Write into a results folder that holds files lamdyn did not write: beside them, never
    /// over them (one named like an output is refused, as is a link), nor over an input.
    #[arg(long)]
    pub force: bool,
    /// Cache folder for the FE model and the EMA [default: `.lamdyn-cache` beside the job].
    #[arg(long, value_name = "DIR", conflicts_with = "no_cache")]
    pub cache: Option<PathBuf>,
    /// Compute everything again and store nothing.
    #[arg(long)]
    pub no_cache: bool,
    /// Monte Carlo samples [default: the job's uncertainty.samples].
    #[arg(long, value_name = "N")]
    pub samples: Option<usize>,
    /// Monte Carlo seed [default: the job's uncertainty.seed].
    #[arg(long, value_name = "SEED")]
    pub seed: Option<u64>,
    /// Output format of the summary.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `lamdyn demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Results folder: DIR/input (the simulated test and its job) and DIR/report.
    #[arg(long, value_name = "DIR", default_value = "lamdyn-demo")]
    pub out: PathBuf,
    /// Write into a results folder that holds files lamdyn did not write: beside them, never
    /// over them (one named like an output is refused, as is a link), nor over an input.
    #[arg(long)]
    pub force: bool,
    /// A test-bench description (TOML, as `lamdyn simulate`) instead of the built-in roof.
    #[arg(long, value_name = "FILE")]
    pub description: Option<PathBuf>,
    /// Monte Carlo samples [default: 400].
    #[arg(long, value_name = "N")]
    pub samples: Option<usize>,
    /// Monte Carlo seed [default: 1].
    #[arg(long, value_name = "SEED")]
    pub seed: Option<u64>,
    /// Output format of the summary.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `lamdyn simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// The test's description (TOML; see `lamdyn simulate --example roof --print-description`).
    #[arg(
        value_name = "FILE",
        required_unless_present = "example",
        conflicts_with = "example"
    )]
    pub description: Option<PathBuf>,
    /// A built-in description: `roof` (the paper's roof, doubly curved, PVB-like core).
    #[arg(long, value_name = "NAME")]
    pub example: Option<String>,
    /// Print the description (TOML) and stop.
    #[arg(long)]
    pub print_description: bool,
    /// Folder for the results: frf.csv + channels.csv (sensor frames), frf_global.uff (global
    /// frame, UFF 58), hit1.csv... (time signals), truth.csv (the core's law at each line),
    /// description.toml, summary.json; written only when everything worked, never over files
    /// lamdyn did not write (see --force).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Write into a results folder that holds files lamdyn did not write: beside them, never
    /// over them (one named like an output is refused, as is a link), nor over an input.
    #[arg(long)]
    pub force: bool,
    /// Skip the time signals even if the description has a `[hits]` section.
    #[arg(long)]
    pub no_hits: bool,
    /// Output format of the summary.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// `lamdyn ema`.
#[derive(Debug, Args)]
pub struct EmaArgs {
    /// FRFs in a UFF file (complex datasets 58/58b; nodes 15/2411 for the channel positions).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["channels", "frf", "time"], required_unless_present_any = ["frf", "time"])]
    pub uff: Option<PathBuf>,
    /// Channels table (CSV: name,role,x_m,y_m,z_m,dx,dy,dz), with --frf or --time.
    #[arg(long, value_name = "FILE")]
    pub channels: Option<PathBuf>,
    /// FRF table (CSV: f_hz,R@F:re,R@F:im,...), with --channels.
    #[arg(
        long,
        value_name = "FILE",
        requires = "channels",
        conflicts_with = "time"
    )]
    pub frf: Option<PathBuf>,
    /// Time data, one file per hammer hit or per record of continuous excitation: a CSV
    /// (t_s,FORCE,RESPONSE,...; a line `# quantity = accelerance` before the header, or
    /// --quantity) or a universal file of UFF 58 time responses (one per channel, named
    /// node+dir, e.g. 12+Z), with --channels naming one reference (the force). Several files
    /// after one --time (or --time repeated) are averaged.
    #[arg(long, value_name = "FILE", requires = "channels", num_args = 1..)]
    pub time: Vec<PathBuf>,
    /// How the time data were excited: impact (hammer hits: trigger, force window, exponential
    /// window), or continuous, estimated by Welch averaging over segments of every file with
    /// no force window: random, burst (burst random), periodic (periodic chirp, multisine) or
    /// sweep (swept sine).
    #[arg(long, value_enum, default_value_t = ExcitationArg::Impact)]
    pub excitation: ExcitationArg,
    /// Window of each Welch segment [default: hann for random; rect for burst, periodic and
    /// sweep, whose signal starts and ends inside the segment or repeats whole in it].
    #[arg(long, value_enum)]
    pub window: Option<WindowArg>,
    /// Welch segment length, s [default: each record whole with the rectangular window; else
    /// the power of two of samples nearest 1/8 of the shortest record].
    #[arg(long, value_name = "S", value_parser = finite)]
    pub segment_s: Option<f64>,
    /// Overlap of consecutive Welch segments, fraction of a segment [default: 0.5 with a
    /// window, 0 with the rectangular window].
    #[arg(long, value_parser = finite)]
    pub overlap: Option<f64>,
    /// What the responses of time files are, for files without a `# quantity` line (an
    /// instrument's export): receptance (m), mobility (m/s) or accelerance (m/s^2).
    #[arg(long, value_enum)]
    pub quantity: Option<QuantityArg>,
    /// FRF estimator for time data.
    #[arg(long, value_enum, default_value_t = Estimator::H1)]
    pub estimator: Estimator,
    /// Trigger level for time data, fraction of each hit's peak force.
    #[arg(long, default_value_t = 0.05, value_parser = finite)]
    pub trigger: f64,
    /// Time kept before the trigger, s.
    #[arg(long, default_value_t = 0.001, value_parser = finite)]
    pub pretrigger_s: f64,
    /// Impact only: force window after the record start, s. The force is kept unchanged
    /// inside it, tapered by a half cosine over the window's last 10 % and zero after it; the
    /// responses are not windowed by it. Continuous excitation never applies it.
    #[arg(long, default_value_t = 0.05, value_parser = finite)]
    pub force_window_s: f64,
    /// Record length, s [default: the longest every hit holds].
    #[arg(long, value_name = "S", value_parser = finite)]
    pub record_s: Option<f64>,
    /// With several references, one LSCF over every curve instead of PolyMAX (sdypy-EMA's
    /// formulation): on damped modes better in f at isolated modes, worse in damping, and
    /// blind to close pairs that PolyMAX resolves (docs/ema.md, "Damped poles").
    #[arg(long)]
    pub single_reference: bool,
    /// Folder for the results: modes.csv, diagram.csv, result.json and the stabilization
    /// diagram and CMIF charts (SVG and PNG); written only when everything worked, never over
    /// files lamdyn did not write (see --force).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Write into a results folder that holds files lamdyn did not write: beside them, never
    /// over them (one named like an output is refused, as is a link), nor over an input.
    #[arg(long)]
    pub force: bool,
    /// Band LO,HI in Hz [default: all lines above 0 Hz].
    #[arg(long, value_name = "LO,HI", value_delimiter = ',', value_parser = finite)]
    pub band_hz: Option<Vec<f64>>,
    /// Highest model order of the stabilization diagram.
    #[arg(long, default_value_t = 60, value_parser = clap::value_parser!(u32).range(2..=400))]
    pub max_order: u32,
    /// Lowest model order.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=400))]
    pub min_order: u32,
    /// Order step.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=50))]
    pub order_step: u32,
    /// Pick the stable pole nearest each of these frequencies (Hz) instead of the automatic
    /// selection.
    #[arg(long, value_name = "HZ,..", value_delimiter = ',', value_parser = finite)]
    pub near_hz: Option<Vec<f64>>,
    /// Reject the modes near these frequencies (support resonances): kept in the modal model,
    /// reported apart.
    #[arg(long, value_name = "HZ,..", value_delimiter = ',', value_parser = finite)]
    pub reject_hz: Option<Vec<f64>>,
    /// Window around each --near-hz and --reject-hz frequency, Hz.
    #[arg(long, default_value_t = 1.0, value_parser = finite)]
    pub window_hz: f64,
    /// Name of the driving-point response (mass-normalised shapes).
    #[arg(long, value_name = "NAME")]
    pub driving: Option<String>,
    /// Time constant of the exponential window applied to the data, s (its damping is removed);
    /// with --time the window is applied to the records here.
    #[arg(long, value_name = "S", value_parser = finite, allow_negative_numbers = true)]
    pub exp_tau_s: Option<f64>,
    /// Skip the refinement of the poles (LSFD on the diagram's poles only; as --poles diagram).
    #[arg(long)]
    pub no_refine: bool,
    /// The poles reported: the diagram's, the refined ones, each refined pole checked in the
    /// LSCF model's context (kept where it fits the curves significantly better than the
    /// diagram's; docs/ema.md, "Damped poles"), or the joint fit with rank-one residues,
    /// beside the modes the selection left out that the curves need (the checked poles with one
    /// response; docs/ema.md, "What the free residues cost at a close pair").
    #[arg(long, value_enum, default_value_t = PolesArg::RankOne)]
    pub poles: PolesArg,
    /// CMIF peaks listed: those standing at least this factor above the lower of their two
    /// bases (topographic prominence within the band; 2 = 6 dB).
    #[arg(long, default_value_t = 2.0, value_parser = finite)]
    pub cmif_prominence: f64,
    /// Output format (JSON adds the diagram, shapes and auto-MAC).
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Which poles `lamdyn ema` reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PolesArg {
    /// The stabilization diagram's poles.
    Diagram,
    /// The refined poles (output error beside real residual terms), unchecked.
    Refined,
    /// Each refined pole where it fits significantly better in the LSCF model's context.
    Checked,
    /// With several responses: the poles and participation factors fitted jointly with
    /// rank-one residues (shape times participation; free over the responses with one
    /// reference); with one response as `checked`.
    RankOne,
}

impl From<PolesArg> for lamdyn_ema::identify::PoleEstimator {
    fn from(p: PolesArg) -> Self {
        match p {
            PolesArg::Diagram => Self::Diagram,
            PolesArg::Refined => Self::Refined,
            PolesArg::Checked => Self::Checked,
            PolesArg::RankOne => Self::RankOne,
        }
    }
}

/// How time data were excited.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ExcitationArg {
    /// Hammer hits.
    Impact,
    /// Random noise (Hann window, overlapping segments).
    Random,
    /// Burst random: each burst dies out inside its segment.
    Burst,
    /// Periodic chirp or multisine: whole periods in a segment.
    Periodic,
    /// Swept sine starting and ending inside the record.
    Sweep,
}

/// Welch windows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum WindowArg {
    /// Hann.
    Hann,
    /// Flat-top (five terms).
    Flattop,
    /// Rectangular (none).
    Rect,
}

/// What responses are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum QuantityArg {
    /// Displacement, m.
    Receptance,
    /// Velocity, m/s.
    Mobility,
    /// Acceleration, m/s^2.
    Accelerance,
}

/// FRF estimators from time data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Estimator {
    /// H1 = Gyx/Gxx: unbiased by response noise (the usual choice for hammer tests).
    H1,
    /// H2 = Gyy/Gxy: unbiased by force noise.
    H2,
    /// Hv = sqrt(H1 H2) with the phase of H1.
    Hv,
}

/// `lamdyn uff ...`.
#[derive(Debug, Subcommand)]
pub enum UffCommand {
    /// List the datasets of a file (streams it: data is not loaded).
    Info(UffInfoArgs),
    /// Convert a file: to CSV (FRF set: channels.csv + frf.csv), JSON, VTK (mesh and mode
    /// shapes), or between ASCII and binary 58b (other datasets copied verbatim).
    Convert(UffConvertArgs),
}

/// `lamdyn uff info`.
#[derive(Debug, Args)]
pub struct UffInfoArgs {
    /// The UFF file.
    pub file: PathBuf,
    /// Output format.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Targets of `lamdyn uff convert`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum UffTarget {
    /// UFF with every dataset in ASCII.
    Ascii,
    /// UFF with datasets 58 as binary 58b (little endian unless --big-endian).
    Binary,
    /// The FRFs as an FRF set: OUT is a folder receiving channels.csv and frf.csv (SI units).
    Csv,
    /// Every dataset as JSON.
    Json,
    /// Mesh (15/2411, 2412, 82) and mode shapes (55) as a VTK .vtu file for ParaView.
    Vtu,
}

/// `lamdyn uff convert`.
#[derive(Debug, Args)]
pub struct UffConvertArgs {
    /// The UFF file to read.
    pub input: PathBuf,
    /// The file (or folder, for csv) to write; written whole or not at all.
    pub output: PathBuf,
    /// What to write.
    #[arg(long, value_enum)]
    pub to: UffTarget,
    /// Binary 58b in big-endian byte order.
    #[arg(long)]
    pub big_endian: bool,
    /// Accept datasets 58 whose data holds fewer points than announced (keeps those found).
    #[arg(long)]
    pub lenient: bool,
    /// Write into a results folder that holds files lamdyn did not write: beside them, never
    /// over them (one named like an output is refused, as is a link), nor over an input.
    #[arg(long)]
    pub force: bool,
}

/// `lamdyn fit`.
#[derive(Debug, Args)]
pub struct FitArgs {
    /// Fit job (TOML, SI units): model file, measurement CSV files, law and misfit (docs/fit.md;
    /// `--example paper-plate --write-example DIR` writes a complete one).
    #[arg(conflicts_with = "example", required_unless_present = "example")]
    pub job: Option<PathBuf>,
    /// A built-in synthetic case instead of a job: the paper's plate with FRFs from a known law.
    #[arg(long, value_enum)]
    pub example: Option<FitExample>,
    /// Noise seed of the example.
    #[arg(long, default_value_t = 1, requires = "example")]
    pub seed: u64,
    /// Relative complex noise of the example (fraction).
    #[arg(long, default_value_t = 0.01, value_parser = finite, requires = "example", value_name = "FRACTION")]
    pub noise: f64,
    /// Law to fit (overrides the job's fit.law).
    #[arg(long, value_enum)]
    pub law: Option<LawArg>,
    /// Misfit (overrides the job's fit.misfit.kind).
    #[arg(long, value_enum)]
    pub misfit: Option<MisfitArg>,
    /// Covariance estimator (overrides the job's fit.covariance).
    #[arg(long, value_enum)]
    pub covariance: Option<CovarianceArg>,
    /// Identified poles for the starts, peak matching and mode-wise estimate instead of the
    /// RMS FRF's peaks: a CSV with freq_hz and damping_ratio columns, as `lamdyn ema --out DIR`
    /// writes in DIR/modes.csv (overrides the job's fit.poles).
    #[arg(long, value_name = "modes.csv")]
    pub poles: Option<PathBuf>,
    /// Write report.json, one CSV per table and the RMS curves into this folder once everything
    /// is computed (never over files lamdyn did not write; see --force).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Write into a results folder that holds files lamdyn did not write: beside them, never
    /// over them (one named like an output is refused, as is a link), nor over an input.
    #[arg(long)]
    pub force: bool,
    /// Write the example as a job folder (job.toml, model.toml, channels.csv, frf.csv).
    #[arg(long, value_name = "DIR", requires = "example")]
    pub write_example: Option<PathBuf>,
    /// Output format (CSV: the modulus at the resonances, a `lamdyn core --table` input).
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Built-in fit cases.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FitExample {
    /// Paper's plate, FRFs from the Table 2 eq. 7 law; fitted with eq. 7.
    PaperPlate,
    /// Paper's plate, FRFs from a fractional Zener law; fitted with the fractional Zener.
    PaperPlateZener,
}

/// Laws of `lamdyn fit`, spelled as in the job file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LawArg {
    /// Paper eq. 7 (E0, mu, t0, c).
    #[value(name = "paper_eq7")]
    PaperEq7,
    /// Fractional-derivative Zener (G0, G_inf, tau, alpha).
    #[value(name = "fractional_zener")]
    FractionalZener,
    /// Free E' and eta at each measured resonance, splined between.
    #[value(name = "per_mode")]
    PerMode,
    /// Old spelling of paper_eq7 (deprecated).
    #[value(name = "eq7", hide = true)]
    Eq7,
    /// Old spelling of fractional_zener (deprecated).
    #[value(name = "zener", hide = true)]
    Zener,
    /// Old spelling of per_mode (deprecated).
    #[value(name = "per-mode", hide = true)]
    PerModeKebab,
}

/// Misfits of `lamdyn fit`, spelled as in the job file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MisfitArg {
    /// Paper eqs. 2 and 10: RMS of magnitudes over channels, absolute difference.
    #[value(name = "rms")]
    Rms,
    /// Log of the RMS magnitudes.
    #[value(name = "log_rms")]
    LogRms,
    /// Complex FRFs per channel.
    #[value(name = "complex")]
    Complex,
    /// Old spelling of log_rms (deprecated).
    #[value(name = "log-rms", hide = true)]
    LogRmsKebab,
}

/// Covariance estimators of `lamdyn fit`, spelled as in the job file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CovarianceArg {
    /// HC3 sandwich (robust to line-to-line changes of the noise).
    #[value(name = "robust_hc3")]
    RobustHc3,
    /// Classical s^2 (J^T J)^-1.
    #[value(name = "classical")]
    Classical,
    /// Old spelling of robust_hc3 (deprecated).
    #[value(name = "hc3", hide = true)]
    Hc3,
}

/// Built-in FE models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ModelExample {
    /// The paper's plate taken flat (0.923 x 0.8632 x 0.00385 m, E0 = 67.45 GPa), 40 x 40.
    PaperPlate,
    /// The same footprint as a shallow dome (radii 3 m and 5 m), a stand-in for the curved roof.
    PaperRoofCurved,
    /// NAFEMS FV12: free square steel plate 10 x 10 x 0.05 m, 40 x 40.
    NafemsFv12,
}

/// A shell element family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ElementArg {
    /// 4-node MITC4.
    Mitc4,
    /// 9-node MITC9.
    Mitc9,
}

impl From<ElementArg> for lamdyn_fem::element::ElementOrder {
    fn from(e: ElementArg) -> Self {
        match e {
            ElementArg::Mitc4 => Self::Linear,
            ElementArg::Mitc9 => Self::Quadratic,
        }
    }
}

/// `lamdyn modes`.
#[derive(Debug, Args)]
pub struct ModesArgs {
    /// Model description (TOML, SI units; see examples/plate-modes.toml).
    #[arg(conflicts_with = "example", required_unless_present = "example")]
    pub model: Option<PathBuf>,
    /// A built-in model instead of a file.
    #[arg(long, value_enum)]
    pub example: Option<ModelExample>,
    /// Number of lowest modes, rigid-body modes included [default: the model's, 20].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=2000))]
    pub modes: Option<u32>,
    /// Elements along x and y for a rectangle model, as NXxNY (e.g. 80x80).
    #[arg(long, value_name = "NXxNY", value_parser = parse_elements)]
    pub elements: Option<(usize, usize)>,
    /// Shell element for a rectangle model: mitc4 (the paper's, 4 nodes) or mitc9 (9 nodes,
    /// far fewer dofs for the same accuracy) [default: the model's, mitc4].
    #[arg(long, value_enum)]
    pub element: Option<ElementArg>,
    /// Geometric element layers at each free edge of a rectangle model, the outermost half the
    /// shell's thickness wide: they resolve the free edges' boundary layer (0: none).
    #[arg(long, value_name = "N")]
    pub edge_layers: Option<usize>,
    /// Refine until every elastic mode among the --modes lowest has an estimated
    /// discretization error below TOL (relative, e.g. 1e-4): each element split 2x2, 3x3, ...,
    /// each mode's error by Richardson extrapolation over the last three meshes (docs/fem.md);
    /// exit 1 with how far it got when the tolerance is not met, as soon as it is seen to be
    /// out of reach (exit 2 before any solve when the finest allowed mesh cannot resolve the
    /// free edges).
    #[arg(long, value_name = "TOL", conflicts_with_all = ["vtu", "shapes_json", "compare"])]
    pub converge: Option<f64>,
    /// With --converge: the largest mesh to solve, in dofs [default: 600000].
    #[arg(long, value_name = "N", requires = "converge")]
    pub max_dofs: Option<usize>,
    /// Write the mode shapes with the mesh as a VTK unstructured grid for ParaView.
    #[arg(long, value_name = "FILE.vtu")]
    pub vtu: Option<PathBuf>,
    /// Write the mode shapes as JSON (nodes, frequencies in Hz, mass-normalised shapes).
    #[arg(long, value_name = "FILE.json")]
    pub shapes_json: Option<PathBuf>,
    /// Compare with the shapes of another run (a --shapes-json file on the same nodes): MAC.
    #[arg(long, value_name = "FILE.json")]
    pub compare: Option<PathBuf>,
    /// Output format.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Parses `NXxNY`.
fn parse_elements(s: &str) -> Result<(usize, usize), ArgValueError> {
    let (a, b) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| ArgValueError::NotElements(s.to_string()))?;
    let n = |t: &str| {
        t.trim()
            .parse::<usize>()
            .ok()
            .filter(|n| (1..=2000).contains(n))
            .ok_or_else(|| ArgValueError::NotACount(t.to_string()))
    };
    Ok((n(a)?, n(b)?))
}

/// Why a command-line value was refused (clap shows it after the flag's name).
#[derive(Debug, Clone, PartialEq)]
pub enum ArgValueError {
    /// The text is not a number.
    NotANumber(String),
    /// The number is NaN or infinite.
    NotFinite(String),
    /// `NXxNY` without its `x`.
    NotElements(String),
    /// An element count outside 1..=2000.
    NotACount(String),
    /// `E0,MU,T0,C` with this many numbers.
    NotFourNumbers(usize),
}

impl std::fmt::Display for ArgValueError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NotANumber(s) => write!(f, "'{s}' is not a number"),
            Self::NotFinite(s) => write!(f, "'{s}' is not a finite number"),
            Self::NotElements(s) => write!(f, "expected NXxNY such as 40x40, got '{s}'"),
            Self::NotACount(s) => write!(f, "'{s}' is not a count in 1..=2000"),
            Self::NotFourNumbers(n) => {
                write!(f, "expected four numbers E0_PA,MU_S,T0_S,C_PA_S, got {n}")
            }
        }
    }
}

impl std::error::Error for ArgValueError {}

/// Output format flags shared by the commands.
#[derive(Debug, Args, Clone, Copy)]
pub struct OutputArgs {
    /// Write JSON (SI units) instead of a text table.
    #[arg(long, conflicts_with = "csv")]
    pub json: bool,
    /// Write CSV (SI units, column names carry the unit) instead of a text table.
    #[arg(long)]
    pub csv: bool,
}

impl OutputArgs {
    /// The chosen format.
    pub fn format(&self) -> crate::table::Format {
        match (self.json, self.csv) {
            (true, _) => crate::table::Format::Json,
            (_, true) => crate::table::Format::Csv,
            _ => crate::table::Format::Text,
        }
    }
}

/// A frequency grid in Hz: a list, or min/max/step.
#[derive(Debug, Args, Clone)]
pub struct GridArgs {
    /// Frequencies in Hz, comma-separated and increasing (overrides
    /// --f-min-hz/--f-max-hz/--f-step-hz).
    #[arg(long, value_delimiter = ',', value_parser = finite, allow_hyphen_values = true, value_name = "HZ,..")]
    pub freq_hz: Option<Vec<f64>>,
    /// Lowest frequency of the grid, Hz.
    #[arg(long, value_parser = finite, allow_negative_numbers = true, default_value_t = 5.0, value_name = "HZ")]
    pub f_min_hz: f64,
    /// Highest frequency of the grid, Hz.
    #[arg(long, value_parser = finite, allow_negative_numbers = true, default_value_t = 80.0, value_name = "HZ")]
    pub f_max_hz: f64,
    /// Grid step, Hz.
    #[arg(long, value_parser = finite, allow_negative_numbers = true, default_value_t = 5.0, value_name = "HZ")]
    pub f_step_hz: f64,
}

/// Bending kinematics of the homogenization.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum KinematicsArg {
    /// A beam of unit width: the paper's equations as written.
    Beam,
    /// A plate in cylindrical bending: layers bend with E/(1-nu^2); E_eff is for a plate model
    /// with the first layer's Poisson ratio.
    Plate,
}

/// `lamdyn laminate`.
#[derive(Debug, Args)]
pub struct LaminateArgs {
    /// Stack description (TOML, SI units; see examples/roof-stack.toml).
    pub stack: PathBuf,
    /// Frequency grid.
    #[command(flatten)]
    pub grid: GridArgs,
    /// Bending kinematics.
    #[arg(long, value_enum, default_value_t = KinematicsArg::Beam)]
    pub kinematics: KinematicsArg,
    /// Output format.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The paper's eq. 7 parameters, E0 (Pa), mu (s), t0 (s), c (Pa s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Eq7Params(pub [f64; 4]);

/// Core shear formula of the paper's inverse.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CoreFormulaArg {
    /// Eq. 41, the paper's general formula (core bending neglected).
    Eq41,
    /// Eq. 43, the thin-core limit of eq. 41.
    Eq43,
    /// Eq. 26 in full, with the core's bending; solved iteratively.
    Eq26,
}

/// Treatment of the faces' shear compliance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum GlassShearArg {
    /// Eq. 40: faces rigid in shear (the paper's choice).
    Neglect,
    /// Eq. 39: subtract the faces' compliance (eqs. 25, 27).
    Include,
}

/// Bending stiffness B_eq of the paper's inverse.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BendingArg {
    /// Eq. 35: faces only (the paper's choice).
    Faces,
    /// Eq. 14: the full stack, core included (iterative).
    Full,
}

/// `lamdyn core`.
#[derive(Debug, Args)]
pub struct CoreArgs {
    /// Built-in case: `paper-roof` = Table 1 stack and Table 2 eq. 7 law.
    #[arg(long, value_enum, conflicts_with_all = ["stack", "eq7", "table"])]
    pub example: Option<ExampleArg>,
    /// Stack description (TOML, SI; three layers: face, core, face; the core's modulus is the
    /// unknown and may be omitted).
    #[arg(long, value_name = "FILE", requires = "source")]
    pub stack: Option<PathBuf>,
    /// The laminate's E*(omega) as eq. 7 parameters E0_PA,MU_S,T0_S,C_PA_S (Pa, s, s, Pa s);
    /// omega in rad/s.
    #[arg(long, value_name = "E0,MU,T0,C", value_parser = parse_eq7, group = "source", allow_hyphen_values = true)]
    pub eq7: Option<Eq7Params>,
    /// The laminate's E*(f) as a CSV table with columns f_hz, e_storage_pa and either
    /// loss_factor or e_loss_pa.
    #[arg(long, value_name = "FILE", group = "source")]
    pub table: Option<PathBuf>,
    /// Frequency grid for --eq7 and --example (a --table brings its own).
    #[command(flatten)]
    pub grid: GridArgs,
    /// Core shear formula of the paper's inverse.
    #[arg(long, value_enum, default_value_t = CoreFormulaArg::Eq41)]
    pub core_formula: CoreFormulaArg,
    /// Faces' shear compliance in the paper's inverse.
    #[arg(long, value_enum, default_value_t = GlassShearArg::Neglect)]
    pub glass_shear: GlassShearArg,
    /// Bending stiffness in the paper's inverse.
    #[arg(long, value_enum, default_value_t = BendingArg::Faces)]
    pub bending: BendingArg,
    /// Bending kinematics of both inverses.
    #[arg(long, value_enum, default_value_t = KinematicsArg::Beam)]
    pub kinematics: KinematicsArg,
    /// Relative margin of the Kramers-Kronig check (dimensionless).
    #[arg(long, value_parser = finite, allow_negative_numbers = true, default_value_t = 0.05, value_name = "FRACTION")]
    pub kk_tolerance: f64,
    /// Output format.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// Built-in examples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ExampleArg {
    /// The paper's laminated glass roof: Table 1 stack, Table 2 eq. 7 effective modulus.
    PaperRoof,
}

/// `lamdyn e756`.
#[derive(Debug, Args)]
pub struct E756Args {
    /// Test configuration.
    #[arg(value_enum)]
    pub configuration: E756Config,
    /// Beam description (TOML, SI): length_m, thickness_m, density_kg_m3, young_pa and, for
    /// oberst/sandwich, a `[layer]` table with thickness_m and density_kg_m3.
    #[arg(long, value_name = "FILE")]
    pub beam: PathBuf,
    /// Measured resonances (CSV). uniform: mode,f_hz,loss_factor; oberst:
    /// mode,f_base_hz,f_composite_hz,loss_factor; sandwich:
    /// mode,f_base_hz,f_sandwich_hz,loss_factor. A half_power_bandwidth_hz column may replace
    /// loss_factor.
    #[arg(long, value_name = "FILE", required_unless_present = "forward")]
    pub data: Option<PathBuf>,
    /// Oberst only: solve the standard's quadratic with the complex frequency ratio (exact)
    /// instead of its first-order loss formula.
    #[arg(long)]
    pub exact: bool,
    /// Run the forward model instead: write the resonances (in the --data CSV layout) that a
    /// material of --modulus-pa and --loss-factor gives on this beam.
    #[arg(long, conflicts_with = "data", requires_all = ["modulus_pa", "loss_factor"])]
    pub forward: bool,
    /// Forward model: the material's storage modulus, Pa (E for uniform/oberst, G for sandwich).
    #[arg(long, value_parser = finite, allow_negative_numbers = true, value_name = "PA")]
    pub modulus_pa: Option<f64>,
    /// Forward model: the material's loss factor.
    #[arg(long, value_parser = finite, allow_negative_numbers = true)]
    pub loss_factor: Option<f64>,
    /// Forward model: number of modes.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=50))]
    pub modes: u32,
    /// Output format.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// ASTM E756-05 configurations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum E756Config {
    /// Bare uniform beam: Young's modulus and loss factor of the beam material.
    Uniform,
    /// Oberst beam: damping layer on one side; its Young's modulus and loss factor.
    Oberst,
    /// Sandwich beam: core between two identical base beams; its shear modulus and loss factor.
    Sandwich,
}

/// Parses a finite number (no NaN, no infinity).
pub fn finite(s: &str) -> Result<f64, ArgValueError> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| ArgValueError::NotANumber(s.to_string()))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ArgValueError::NotFinite(s.to_string()))
    }
}

/// Parses `E0,MU,T0,C`.
fn parse_eq7(s: &str) -> Result<Eq7Params, ArgValueError> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 4 {
        return Err(ArgValueError::NotFourNumbers(parts.len()));
    }
    let mut p = [0.0; 4];
    for (slot, part) in p.iter_mut().zip(parts) {
        *slot = finite(part)?;
    }
    Ok(Eq7Params(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("lamdyn").chain(args.iter().copied()))
    }

    #[test]
    fn finite_refuses_nan_inf_and_words() {
        assert_eq!(finite("1e3"), Ok(1e3));
        let refused = |s: &str| finite(s).unwrap_err().to_string();
        assert_eq!(refused("NaN"), "'NaN' is not a finite number");
        assert_eq!(refused("inf"), "'inf' is not a finite number");
        assert_eq!(refused("ten"), "'ten' is not a number");
    }

    #[test]
    fn eq7_takes_four_numbers() {
        assert_eq!(parse_eq7("1,2,3,4"), Ok(Eq7Params([1.0, 2.0, 3.0, 4.0])));
        assert!(
            parse_eq7("1,2,3")
                .unwrap_err()
                .to_string()
                .contains("expected four numbers")
        );
        assert!(
            parse_eq7("1,2,x,4")
                .unwrap_err()
                .to_string()
                .contains("'x' is not a number")
        );
    }

    #[test]
    fn grid_flags_default_to_the_paper_band() {
        let Command::Core(a) = parse(&["core", "--example", "paper-roof"]).unwrap().command else {
            panic!("core expected")
        };
        assert_eq!(
            (a.grid.f_min_hz, a.grid.f_max_hz, a.grid.f_step_hz),
            (5.0, 80.0, 5.0)
        );
        assert_eq!(a.kk_tolerance, 0.05);
        assert_eq!(a.core_formula, CoreFormulaArg::Eq41);
        assert_eq!(a.glass_shear, GlassShearArg::Neglect);
        assert_eq!(a.bending, BendingArg::Faces);
        assert_eq!(a.kinematics, KinematicsArg::Beam);
    }

    #[test]
    fn freq_list_is_parsed() {
        let Command::Core(a) = parse(&["core", "--example", "paper-roof", "--freq-hz", "10,20.5"])
            .unwrap()
            .command
        else {
            panic!("core expected")
        };
        assert_eq!(a.grid.freq_hz, Some(vec![10.0, 20.5]));
        assert!(parse(&["core", "--example", "paper-roof", "--freq-hz", "10,nan"]).is_err());
    }

    #[test]
    fn conflicting_sources_are_refused() {
        assert!(parse(&["core", "--example", "paper-roof", "--eq7", "1,2,3,4"]).is_err());
        assert!(
            parse(&["core", "--stack", "s.toml"]).is_err(),
            "a stack needs --eq7 or --table"
        );
        assert!(
            parse(&[
                "core", "--stack", "s.toml", "--eq7", "1,2,3,4", "--table", "t.csv"
            ])
            .is_err()
        );
        assert!(parse(&["core", "--json", "--csv", "--example", "paper-roof"]).is_err());
    }

    #[test]
    fn e756_flags() {
        let Command::E756(a) = parse(&["e756", "sandwich", "--beam", "b.toml", "--data", "d.csv"])
            .unwrap()
            .command
        else {
            panic!("e756 expected")
        };
        assert_eq!(a.configuration, E756Config::Sandwich);
        assert_eq!(a.modes, 5);
        assert!(
            parse(&["e756", "sandwich", "--beam", "b.toml"]).is_err(),
            "needs --data or --forward"
        );
        assert!(
            parse(&[
                "e756",
                "sandwich",
                "--beam",
                "b.toml",
                "--forward",
                "--modulus-pa",
                "1e6"
            ])
            .is_err()
        );
        assert!(
            parse(&[
                "e756",
                "sandwich",
                "--beam",
                "b.toml",
                "--forward",
                "--modulus-pa",
                "1e6",
                "--loss-factor",
                "0.3",
                "--modes",
                "0"
            ])
            .is_err()
        );
    }

    #[test]
    fn laminate_flags() {
        let Command::Laminate(a) = parse(&["laminate", "s.toml", "--kinematics", "plate", "--csv"])
            .unwrap()
            .command
        else {
            panic!("laminate expected")
        };
        assert_eq!(a.kinematics, KinematicsArg::Plate);
        assert!(a.output.csv);
    }
}
