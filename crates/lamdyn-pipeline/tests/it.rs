//! The chain as a library, on a small virtual laminate (the test bench's 0.6 x 0.5 m plate,
//! free, 5 x 5 sensors, noise-free FRFs to 240 Hz): the report's figures exist and are all
//! referenced, the recovered core is compared with the truth, a re-run takes the model, the
//! EMA and the layered model from the cache, bad job files name the field, and a failed stage
//! is named and leaves the earlier report alone.

use lamdyn_pipeline::chain::NoSandwichInverse;
use lamdyn_pipeline::demo::{DemoSampling, run_demo};
use lamdyn_pipeline::error::chain_text;
use lamdyn_pipeline::{
    ChainResult, Job, NoLayered, OutputDir, RunOptions, Silent, report, run_job,
};
use lamdyn_testbench::description::Description;
use lamdyn_testkit::TempDir;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The bench's small laminate with a 5 x 5 grid, hammer along -z, FRFs to 240 Hz (no hits),
/// on an 18 x 18 mesh graded towards the edges: a truth finer than the layered ladder's
/// coarsest meshes (its 6 x 6 mesh is so coarse that the converged identification finds its
/// core 6 % stiffer and 29 % lossier at 78 Hz than the law it was built with).
fn small() -> Description {
    let laminate = include_str!("../../lamdyn-testbench/tests/data/small_laminate.toml").replace(
        "elements = [6, 6]",
        "elements = [18, 18]\nedge_grading = 0.2",
    );
    let text = format!(
        "{laminate}\n[test]\ngrid = [5, 5]\nhammer_xy_fraction = [0.3, 0.35]\nhammer_direction = \
         [0.0, 0.0, -1.0]\nmax_hz = 240.0\nstep_hz = 0.5\n"
    );
    Description::parse("small.toml", &text).unwrap()
}

/// The demo on the small laminate into `dir/input`, the report into `dir/report`; the result
/// and the job's path.
fn demo(dir: &Path, samples: usize) -> (ChainResult, PathBuf) {
    let input = OutputDir::prepare(&dir.join("input"), &[], false).unwrap();
    let options = RunOptions {
        cache_dir: Some(dir.join("input/.lamdyn-cache")),
    };
    let sampling = DemoSampling {
        samples,
        seed: 1,
        temperature_k: None,
    };
    let (result, job, _) = run_demo(&small(), &input, sampling, &options, &Silent).unwrap();
    let out = OutputDir::prepare(&dir.join("report"), &[], false).unwrap();
    out.write(&report::build(&result).unwrap()).unwrap();
    (result, job)
}

/// The demo's modal points (at least three) with their layered bands, after checking that the
/// layered G* lies within 2 % (G') and 3 % (eta) of the truth and inside its band.
fn layered_recovers_the_truth(
    result: &ChainResult,
) -> Vec<(
    &lamdyn_pipeline::CorePoint,
    &lamdyn_pipeline::band::LayeredBand,
)> {
    let truth = result
        .truth
        .as_ref()
        .expect("the demo's job names its truth");
    assert!(
        result.modal.len() >= 3,
        "{} modal points",
        result.modal.len()
    );
    let mut out = Vec::new();
    for p in &result.modal {
        let (g, t) = (
            p.layered_g().expect("a layered G*"),
            truth.at(p.freq_hz).unwrap(),
        );
        let (eg, ee) = (g.re / t.re - 1.0, (g.im / g.re) / (t.im / t.re) - 1.0);
        eprintln!("{:.2} Hz: G' {eg:+.4}, eta {ee:+.4}", p.freq_hz);
        assert!(
            eg.abs() < 0.02 && ee.abs() < 0.03,
            "layered inverse off at {:.2} Hz: G' {eg:+.3}, eta {ee:+.3}",
            p.freq_hz
        );
        let band = p.layered_band.as_ref().expect("a band").as_ref().unwrap();
        assert!(
            eg.ln_1p().abs() < band.half_width.storage && ee.ln_1p().abs() < band.half_width.loss,
            "truth outside the band at {:.2} Hz: {eg:+.3} / {ee:+.3} against {:?}",
            p.freq_hz,
            band.half_width
        );
        out.push((p, band));
    }
    out
}

/// Every `href`/`src` of the HTML that names a file.
fn linked_files(html: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for attr in ["href=\"", "src=\""] {
        for part in html.split(attr).skip(1) {
            let target = &part[..part.find('"').unwrap()];
            if !target.starts_with('#') && !target.contains("://") {
                out.insert(target.to_string());
            }
        }
    }
    out
}

/// A copy of the demo's report where `LAMDYN_KEEP_REPORT` names a folder: `.ci/run` opens it
/// in a browser (tools/report/check.py) instead of running the demo once more.
fn keep_report(report: &Path) {
    let Some(keep) = std::env::var_os("LAMDYN_KEEP_REPORT") else {
        return;
    };
    let keep = PathBuf::from(keep);
    let _ = std::fs::remove_dir_all(&keep);
    for entry in std::fs::read_dir(report)
        .unwrap()
        .chain(std::fs::read_dir(report.join("figures")).unwrap())
    {
        let from = entry.unwrap().path();
        if from.is_file() {
            let to = keep.join(from.strip_prefix(report).unwrap());
            std::fs::create_dir_all(to.parent().unwrap()).unwrap();
            std::fs::copy(&from, &to).unwrap();
        }
    }
}

#[test]
fn report_has_every_figure_and_the_layered_route_recovers_the_core() {
    let dir = TempDir::new("pipeline-demo");
    let (result, _) = demo(&dir, 100);
    let report = dir.join("report");
    keep_report(&report);
    let html = std::fs::read_to_string(report.join("report.html")).unwrap();
    // Every linked file exists, every figure file is linked, every figure is inline too.
    let linked = linked_files(&html);
    for f in &linked {
        assert!(
            report.join(f).is_file(),
            "report links '{f}', which is missing"
        );
    }
    let on_disk: BTreeSet<String> = std::fs::read_dir(report.join("figures"))
        .unwrap()
        .map(|e| format!("figures/{}", e.unwrap().file_name().to_string_lossy()))
        .collect();
    assert_eq!(on_disk, linked, "figure files and links differ");
    for name in [
        "answer_storage",
        "answer_loss",
        "rms_frf",
        "stabilization",
        "cmif",
        "mode1",
        "laminate_storage",
        "laminate_loss",
        "core_storage",
        "core_loss",
    ] {
        assert!(
            linked.contains(&format!("figures/{name}.svg")),
            "{name} missing"
        );
        assert!(
            html.contains(&format!("<figure id=\"fig-{name}\">\n<svg")),
            "{name} not inline"
        );
    }
    assert_eq!(html.matches("<figure").count() * 2, on_disk.len());
    for text in [
        "Table 3",
        "Causality",
        "Monte Carlo: 100 samples, seed 1",
        "err G&#39;_paper [%]",
        "valid (|phi|&lt;=0.1)",
    ] {
        assert!(html.contains(text), "'{text}' missing from the report");
    }
    // The first screen is the answer: one sentence (the law over all modes, its bands, the
    // run's verdict and the error against the truth), then the answer's figures.
    let body = &html[html.find("</h1>").unwrap() + 6..];
    assert!(
        body.starts_with("<p class=\"answer\">The core&#39;s shear storage modulus G&#39; is ")
            && body.contains("law fitted to the layered inverse&#39;s cores at")
            && body.contains("Every identified mode has a core.")
            && body.contains("Against the virtual test&#39;s truth: within "),
        "{body:.600}"
    );
    let after_answer = &body[body.find("</p>").unwrap() + 5..];
    assert!(
        after_answer.starts_with("<figure id=\"fig-answer_storage\">"),
        "{after_answer:.80}"
    );
    // Captions of at most two lines (240 characters at the page's 1180 px).
    for caption in html
        .split("<caption>")
        .skip(1)
        .chain(html.split("<figcaption>").skip(1))
    {
        let text = &caption[..caption.find("</").unwrap()];
        let text = text.split(" (<a href").next().unwrap_or_default();
        assert!(
            text.chars().count() <= 240,
            "{} characters: {text}",
            text.chars().count()
        );
    }
    // Then the core at each mode (the layered inverse), before the warnings and the
    // reference methods, and no table is as wide as the old 23 columns.
    let first_heading = html.split("<h2>").nth(1).unwrap_or("");
    assert!(
        first_heading.starts_with("The core: lamdyn&#39;s answer</h2>"),
        "{first_heading:.80}"
    );
    let lead = &html[html.find("<table>").unwrap()..html.find("</table>").unwrap()];
    assert!(lead.contains("G&#39;_layered [MPa]"), "{lead:.300}");
    for table in html.split("<table>").skip(1) {
        let header = &table[..table.find("</tr>").unwrap()];
        assert!(header.matches("<th>").count() <= 12, "{header}");
    }
    // The core at each modal frequency against the truth, within 2 % (G') and 3 %
    // (eta); measured 0.54 % and 2.2 %. The layered inverse is converged over its mesh ladder,
    // its points moved from their poles' complex frequencies to the real axis, and the truth is
    // a finer graded mesh, so what is left is the identification's error and the truth's own
    // discretization error.
    let truth = result
        .truth
        .as_ref()
        .expect("the demo's job names its truth");
    for (p, band) in layered_recovers_the_truth(&result) {
        assert!(p.paper_g().is_some() && p.exact_g().is_some());
        // Its band holds every source it names: the faces' priors (1 % modulus, 0.01 mm,
        // 0.5 % density), their second order and what lies beyond it, the pole's scatter and
        // the discretization. The
        // faces dominate a stiff core (sensitivities of -10 to -60), to first order or, where
        // the mode's G' is far from linear in them (the 103 Hz mode: -5.4 to first order, a
        // second difference of 11 % at 1 sd of the face modulus), beyond it.
        let names: Vec<&str> = band.sources.iter().map(|s| s.0.label()).collect();
        for n in [
            "face modulus",
            "face thickness",
            "core thickness",
            "inputs beyond first order",
            "inputs beyond second order",
            "discretization",
        ] {
            assert!(names.contains(&n), "{names:?}");
        }
        let dominant = band.dominant_label(lamdyn_pipeline::band::ModulusPart::Storage);
        assert!(
            dominant.starts_with("face") || dominant.starts_with("inputs beyond"),
            "{band:?}"
        );
    }
    // The fractional Zener law fitted to all modes at once with the inputs shared.
    // Against the truth (a finer, graded mesh) between the first and the last mode: G' within
    // 2 %, eta within 3 % (measured: 0.55 % and 1.7 %, with the per-mode points 1.1 % and 2.2 %
    // off; the points scatter 2.9x beyond their stated noise, and before that excess was given
    // to the data rather than to the inputs' priors the law followed a +1.8 % core thickness
    // to 2.02 % in G'). Its bands hold the truth at every mode, in G' and in eta (since the
    // points are compared with the law at their poles' complex frequencies: before, eta was
    // 2-4 % high and its band missed).
    let law = result
        .core_law
        .as_ref()
        .expect("a core law")
        .as_ref()
        .unwrap();
    assert_eq!(law.at_modes.len(), result.modal.len());
    for p in law.curve(30) {
        let t = truth.at(p.freq_hz).unwrap();
        let (eg, ee) = (
            p.storage_pa / t.re - 1.0,
            p.loss_factor / (t.im / t.re) - 1.0,
        );
        assert!(
            eg.abs() < 0.02 && ee.abs() < 0.03,
            "law off at {:.2} Hz: G' {eg:+.4}, eta {ee:+.4}",
            p.freq_hz
        );
    }
    for p in &law.at_modes {
        let t = truth.at(p.freq_hz).unwrap();
        let eta = t.im / t.re;
        assert!(
            p.storage_ci95[0] <= t.re && t.re <= p.storage_ci95[1],
            "{p:?} vs {t}"
        );
        assert!(
            p.loss_factor_ci95[0] <= eta && eta <= p.loss_factor_ci95[1],
            "{p:?} vs eta {eta}"
        );
    }
    assert!(html.contains("The core&#39;s law over all modes"));
    let law_csv = std::fs::read_to_string(report.join("core_law.csv")).unwrap();
    assert_eq!(law_csv.lines().count(), 61);
    // The report states the band widths (the law's median half-width over its 60
    // lines, recomputed here from core_law.csv) and what would narrow the widest band.
    let widths = result.band_widths().expect("band widths");
    let mut halves: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
    for line in law_csv.lines().skip(1) {
        let v: Vec<f64> = line
            .split(',')
            .take(7)
            .map(|x| x.parse().unwrap())
            .collect();
        halves[0].push(0.5 * (v[3] / v[2]).ln());
        halves[1].push(0.5 * (v[6] / v[5]).ln());
    }
    for (c, h) in halves.iter_mut().enumerate() {
        h.sort_by(f64::total_cmp);
        let median = h[h.len() / 2];
        let stated = widths.law_median.unwrap()[c];
        assert!((stated / median - 1.0).abs() < 1e-4, "{stated} vs {median}");
        // The modes share the inputs, so the law's band is narrower than each mode's own
        // (measured: ±11 % / ±8.6 % against a factor 1.54 / 1.74 either way).
        let modes = widths.modes_median.unwrap()[c];
        assert!(stated > 0.0 && stated < modes, "{stated} vs {modes}");
    }
    assert_eq!(widths.widest.len(), 2);
    assert!(widths.undetermined.is_empty(), "{:?}", widths.undetermined);
    let stated = format!("Band widths. {}", widths.describe()).replace('\'', "&#39;");
    assert!(html.contains(&stated), "{stated}");
    assert!(html.contains("what would narrow it: ") || html.contains("what would narrow them: "));
    // The modal table as CSV, with the validity mark.
    let csv = std::fs::read_to_string(report.join("core_modal.csv")).unwrap();
    assert!(csv.lines().next().unwrap().contains("within_phi_limit"));
    assert_eq!(csv.lines().count(), result.modal.len() + 1);
}

/// The small laminate as five layers, glass 2 mm / PVB 0.5 mm / glass 2 mm / PVB 0.5 mm /
/// glass 2 mm, the two interlayers of one material (the law of [`small`]).
fn five_layers() -> Description {
    let mut d = small();
    let (glass, pvb) = (d.layers[0].clone(), d.layers[1].clone());
    let glass = lamdyn_material::laminate::LayerSpec {
        thickness_m: 2e-3,
        ..glass
    };
    let pvb = lamdyn_material::laminate::LayerSpec {
        thickness_m: 0.5e-3,
        ..pvb
    };
    d.layers = vec![glass.clone(), pvb.clone(), glass.clone(), pvb, glass];
    d
}

/// A stack of five layers, two of them viscoelastic with one law, goes the layered
/// route alone: the paper's and the exact inverse say why they have no answer, the Monte
/// Carlo of the paper's route is skipped with a warning, and the layered inverse recovers the
/// core at every mode within 2 % (G') and 3 % (eta) of the truth (a finer graded mesh),
/// inside its band. Measured at five modes, 79–216 Hz: G' −1.2 … +0.1 %, eta +0.6 … +1.3 %;
/// before the start from the homogenized stack, a fixed 10 MPa start matched the 156 Hz pole
/// to the wrong mode (G' −80 %, inside a 7 % band).
#[test]
fn a_five_layer_laminate_goes_the_layered_route_alone() {
    let dir = TempDir::new("pipeline-five-layers");
    let input = OutputDir::prepare(&dir.join("input"), &[], false).unwrap();
    let options = RunOptions {
        cache_dir: Some(dir.join("input/.lamdyn-cache")),
    };
    let sampling = DemoSampling {
        samples: 50,
        seed: 1,
        temperature_k: None,
    };
    let (result, _, _) = run_demo(&five_layers(), &input, sampling, &options, &Silent).unwrap();
    let out = OutputDir::prepare(&dir.join("report"), &[], false).unwrap();
    out.write(&report::build(&result).unwrap()).unwrap();
    assert!(result.stack.is_none() && result.uncertainty.is_none());
    assert!(
        result
            .warnings
            .iter()
            .any(|w| w.contains("Monte Carlo of the paper's route skipped")),
        "{:?}",
        result.warnings
    );
    for (p, _) in layered_recovers_the_truth(&result) {
        let why = p.paper.as_ref().expect_err("no paper inverse");
        assert_eq!(*why, NoSandwichInverse::NotASandwich);
        assert!(
            why.to_string().contains("not a three-layer sandwich"),
            "{why}"
        );
        assert!(p.exact_g().is_none());
    }
    let html = std::fs::read_to_string(dir.join("report/report.html")).unwrap();
    assert!(html.contains("The core&#39;s law over all modes"));
}

/// The small laminate's job with its model a Gmsh file of the plan (35
/// unstructured 9-node quadrilaterals, nodes of degree 3 to 5, coordinates in mm, written by
/// Gmsh: `lamdyn-layered/testdata/gmsh`) in place of the structured rectangle. The shell model
/// is that mesh, and the layered model extrudes it through the stack, splitting it 1, 2, 3 …
/// times up the ladder: the layered inverse recovers the core within 2 % (G') and 3 % (eta)
/// of the truth (an 18 x 18 graded structured mesh) at every mode, inside its band.
#[test]
fn a_gmsh_model_goes_the_layered_route() {
    let dir = TempDir::new("pipeline-gmsh");
    let (_, job_path) = demo(&dir, 0);
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../lamdyn-layered/testdata/gmsh/small-laminate-quad9-mm.msh");
    std::fs::copy(&fixture, dir.join("input/plan.msh")).unwrap();
    let text = std::fs::read_to_string(&job_path).unwrap();
    let (from, to) = (
        text.find("[model.spec.mesh]").unwrap(),
        text.find("[model.spec.material]").unwrap(),
    );
    let text = format!(
        "{}[model.spec.mesh]\nkind = \"gmsh\"\nfile = \"plan.msh\"\nunit = \"mm\"\nelement = \
         \"mitc9\"\n\n{}",
        &text[..from],
        &text[to..]
    );
    let gmsh_job = dir.join("input/gmsh.toml");
    std::fs::write(&gmsh_job, &text).unwrap();
    // A broken mesh is found when the job is read, before any work, naming the mesh's line.
    let broken = dir.join("input/broken.toml");
    std::fs::write(&broken, text.replace("plan.msh", "broken.msh")).unwrap();
    let mesh = std::fs::read_to_string(dir.join("input/plan.msh")).unwrap();
    let at = mesh.find("$Nodes\n").unwrap();
    let at = at + mesh[at..].find("\n-300 -250 0\n").unwrap() + 1;
    let line = mesh[..at].matches('\n').count() + 1;
    let bad = format!(
        "{}-300 oops 0{}",
        &mesh[..at],
        &mesh[at + "-300 -250 0".len()..]
    );
    std::fs::write(dir.join("input/broken.msh"), bad).unwrap();
    let e = chain_text(&Job::read(&broken).unwrap_err());
    assert!(
        e.contains("broken.msh") && e.contains(&format!("line {line}")),
        "line {line}: {e}"
    );
    let options = RunOptions {
        cache_dir: Some(dir.join("input/.lamdyn-cache")),
    };
    let result = run_job(Job::read(&gmsh_job).unwrap(), &gmsh_job, &options, &Silent).unwrap();
    let line = result.layered_line.as_deref().unwrap_or("");
    eprintln!("{line}");
    assert!(
        line.contains("mid-surface mesh of 35 9-node quadrilaterals")
            && line.contains("split 1 x 1")
            && line.contains("split 3 x 3"),
        "{line}"
    );
    layered_recovers_the_truth(&result);
}

#[test]
fn rerun_uses_the_cache_and_a_failed_stage_keeps_the_report() {
    let dir = TempDir::new("pipeline-cache");
    let (first, job_path) = demo(&dir, 0);
    let options = RunOptions {
        cache_dir: Some(dir.join("input/.lamdyn-cache")),
    };
    // The demo filled the cache beside its job: a run of the same job takes the model, the EMA
    // (of all responses, of each response group and at the other model orders) and the layered
    // model from it. Its measurement is FRFs: no hits to leave out, so stage "ema without each
    // hit" runs nothing and is no cache hit.
    let job = Job::read(&job_path).unwrap();
    let r = run_job(job, &job_path, &options, &Silent).unwrap();
    let cached: Vec<&str> = r
        .timings
        .iter()
        .filter(|t| t.cached)
        .map(|t| t.name)
        .collect();
    assert_eq!(
        cached,
        [
            "ema",
            "ema by response group",
            "ema at other model orders",
            "model",
            "layered inverse"
        ]
    );
    // The cached model is described as the built one was (mesh size, sensor placement).
    assert_eq!(r.model_line, format!("{} (cached)", first.model_line));
    assert!(
        first.model_line.contains(" nodes, ") && !first.model_line.contains("- nodes"),
        "{}",
        first.model_line
    );
    // From the cache, the same bits (the EMA's JSON floats round-trip exactly).
    let layered = |r: &ChainResult| -> Vec<Option<num_complex::Complex64>> {
        r.modal.iter().map(|p| p.layered_g()).collect()
    };
    assert_eq!(layered(&r), layered(&first));
    // A dof cap below the layered model's coarsest mesh: nothing is built, and every mode and
    // the layered line say why.
    let capped = dir.join("input/capped.toml");
    let capped_text = std::fs::read_to_string(&job_path).unwrap().replace(
        "tolerance = 1e-4\n",
        "tolerance = 1e-4\nlayered_max_dofs = 5000\n",
    );
    std::fs::write(&capped, capped_text).unwrap();
    let r = run_job(Job::read(&capped).unwrap(), &capped, &options, &Silent).unwrap();
    let line = r.layered_line.as_deref().unwrap_or("");
    assert!(
        line.starts_with("not built: the layered model's coarsest mesh (12 x 12) has")
            && line.contains("above inverse.layered_max_dofs = 5000"),
        "{line}"
    );
    // The modes without a layered core call for the FRF fit, which refuses the same cap at
    // once rather than build the model the ladder refused.
    let frf = r.frf.describe();
    assert!(
        frf.starts_with("failed") && frf.contains("above inverse.layered_max_dofs = 5000"),
        "{frf}"
    );
    for p in &r.modal {
        let why = p.layered.as_ref().and_then(|l| l.as_ref().err());
        assert!(
            why.is_some_and(|w| match w {
                NoLayered::Stage(why) => why.contains("layered_max_dofs"),
                NoLayered::NoPole { .. } => w.to_string().starts_with("no EMA pole"),
                _ => false,
            }),
            "{why:?}"
        );
    }
    // The paper's route fails: no peak of the RMS FRF stands out enough to start its fit (the
    // prominence asked for is out of reach, as on a part so damped that its peaks merge), but
    // the EMA still finds the poles. The layered route does not need the fit: it still
    // recovers the core, each mode started from the modulus its pole implies on the shell
    // model; the report says why the paper's route has no result and writes none of its files.
    let no_fit = dir.join("input/no_fit.toml");
    let text = std::fs::read_to_string(&job_path).unwrap();
    assert_eq!(text.matches("[fit]\n").count(), 1);
    std::fs::write(
        &no_fit,
        text.replace("[fit]\n", "[fit]\nprominence = 1e6\n"),
    )
    .unwrap();
    let r = run_job(Job::read(&no_fit).unwrap(), &no_fit, &options, &Silent).unwrap();
    let why = r.paper_route_error.as_deref().unwrap_or("");
    assert!(
        r.fit.is_none() && why.contains("no resonance peak"),
        "{why}"
    );
    assert!(
        r.warnings
            .iter()
            .any(|w| w.starts_with("the paper's route has no result (stage 'fit' failed")),
        "{:?}",
        r.warnings
    );
    assert!(r.curve.is_empty() && r.uncertainty.is_none());
    for p in &r.modal {
        assert!(p.e_eff_pa.is_none() && p.paper_g().is_none() && p.exact_g().is_none());
    }
    layered_recovers_the_truth(&r);
    let no_fit_report = dir.join("no-fit-report");
    let out = OutputDir::prepare(&no_fit_report, &[], false).unwrap();
    out.write(&report::build(&r).unwrap()).unwrap();
    let html = std::fs::read_to_string(no_fit_report.join("report.html")).unwrap();
    assert!(html.contains("The paper&#39;s route has no result: stage &#39;fit&#39; failed"));
    assert!(!no_fit_report.join("parameters.csv").exists());
    assert!(no_fit_report.join("core_modal.csv").exists());
    // Without the layered route the paper's is the only answer: its failure is the run's.
    let paper_only = dir.join("input/paper_only.toml");
    let text = std::fs::read_to_string(&no_fit).unwrap();
    std::fs::write(
        &paper_only,
        text.replace("[inverse]\n", "[inverse]\nlayered = false\n"),
    )
    .unwrap();
    let e = run_job(
        Job::read(&paper_only).unwrap(),
        &paper_only,
        &options,
        &Silent,
    )
    .err()
    .expect("the fit stage fails");
    assert!(
        chain_text(&e).starts_with("stage 'fit' failed: "),
        "{}",
        chain_text(&e)
    );
    let report = dir.join("report/report.html");
    let before = std::fs::read(&report).unwrap();
    // A job whose model cannot hold the channels: the model stage fails, named, and nothing
    // is written.
    let text = std::fs::read_to_string(&job_path).unwrap();
    let bad = dir.join("input/bad.toml");
    std::fs::write(&bad, text.replace("length_x_m = 0.6", "length_x_m = 0.3")).unwrap();
    let e = run_job(Job::read(&bad).unwrap(), &bad, &options, &Silent)
        .err()
        .expect("the model stage fails");
    assert!(
        chain_text(&e).starts_with("stage 'model' failed: "),
        "{}",
        chain_text(&e)
    );
    assert_eq!(std::fs::read(&report).unwrap(), before);
}

/// The shell model's ρ h of a job, kg/m² (its inline `[model.spec.material]`).
fn shell_surface_density(job: &str) -> f64 {
    let v: toml::Table = toml::from_str(job).unwrap();
    let m = &v["model"]["spec"]["material"];
    m["density_kg_m3"].as_float().unwrap() * m["thickness_m"].as_float().unwrap()
}

/// A job whose inline shell model takes the stack's total thickness and Σ ρ_i h_i.
fn with_the_stacks_shell(job: &str) -> String {
    let mut v: toml::Table = toml::from_str(job).unwrap();
    let layers = v["stack"]["layers"].as_array().unwrap();
    let of = |key: &str, l: &toml::Value| l[key].as_float().unwrap();
    let h: f64 = layers.iter().map(|l| of("thickness_m", l)).sum();
    let m: f64 = layers
        .iter()
        .map(|l| of("thickness_m", l) * of("density_kg_m3", l))
        .sum();
    let material = v["model"]["spec"]["material"].as_table_mut().unwrap();
    material.insert("thickness_m".into(), h.into());
    material.insert("density_kg_m3".into(), (m / h).into());
    toml::to_string(&v).unwrap()
}

#[test]
fn bad_job_files_name_the_field() {
    let dir = TempDir::new("pipeline-jobs");
    let (_, job_path) = demo(&dir, 0);
    let input = job_path.parent().unwrap();
    let good = std::fs::read_to_string(&job_path).unwrap();
    let read = |name: &str, text: String| {
        let p = input.join(name);
        std::fs::write(&p, text).unwrap();
        Job::read(&p).map(|_| ()).map_err(|e| chain_text(&e))
    };
    let check = |name: &str, text: String, expect: &str| {
        let e = read(name, text).expect_err(name);
        assert!(e.contains(expect), "{name}: expected '{expect}' in: {e}");
    };
    // A missing section, an unknown key, a thickness in mm, a modulus in GPa.
    let start = good.find("[measurement]").unwrap();
    let end = good.find("[model]").unwrap();
    check(
        "missing.toml",
        format!("{}{}", &good[..start], &good[end..]),
        "missing field `measurement`",
    );
    check(
        "unknown.toml",
        good.replace("[fit]\n", "[fit]\nlaww = \"per_mode\"\n"),
        "unknown field `laww`",
    );
    check(
        "mm.toml",
        good.replacen("thickness_m = 0.003\n", "thickness_m = 3.0\n", 1),
        "stack.layers[0] ('glass'): thickness_m = 3 is outside [1e-6, 1e-1]: thicknesses are in m",
    );
    check(
        "gpa.toml",
        good.replacen("young_pa = 70000000000.0", "young_pa = 70.0", 1),
        "young_pa = 70 is outside [1e8, 2e12]: moduli are in Pa",
    );
    check(
        "subdivisions.toml",
        good.replace("[inverse]\n", "[inverse]\nlayered_subdivisions = 0\n"),
        "inverse.layered_subdivisions: 0 must lie in 1..=8",
    );
    // A five-layer stack: the layered route takes it, the paper's route alone
    // does not; a stack whose every layer has young_pa has no core.
    let layers_at = good.find("[[stack.layers]]").unwrap();
    let layers = &good[layers_at..];
    let pvb_at = layers[16..].find("[[stack.layers]]").unwrap() + 16;
    let glass_at = layers[pvb_at + 16..].find("[[stack.layers]]").unwrap() + pvb_at + 16;
    let (glass, pvb) = (&layers[..pvb_at], &layers[pvb_at..glass_at]);
    let five = format!(
        "{}{glass}\n{pvb}\n{glass}\n{pvb}\n{glass}\n",
        &good[..layers_at]
    );
    // The shell model describes the same part: its thickness and density follow the stack.
    let five = with_the_stacks_shell(&five);
    read("five.toml", five.clone()).expect("a five-layer job");
    check(
        "five_paper.toml",
        five.replace("[inverse]\n", "[inverse]\nlayered = false\n"),
        "stack.layers: 5 layers: the paper's route needs three (face, core, face); set \
         inverse.layered = true",
    );
    check(
        "four_faces.toml",
        format!("{}{glass}\n{glass}\n{glass}\n{glass}\n", &good[..layers_at]),
        "at least one core (without): 4 layers, 0 without young_pa",
    );
    // A stack that is not the shell model's part: 5 % thicker than the shell, or 15 % heavier
    // (a given surface density).
    check(
        "thicker.toml",
        good.replace("thickness_m = 0.003\n", "thickness_m = 0.0032\n"),
        "mm thick in all, but the shell model [model.spec] is",
    );
    check(
        "heavier.toml",
        good.replacen(
            "[[stack.layers]]",
            &format!(
                "[stack]\nsurface_density_kg_m2 = {}\n\n[[stack.layers]]",
                1.15 * shell_surface_density(&good)
            ),
            1,
        ),
        "(material.density_kg_m3 x thickness_m): one part, so they must agree within 10 %",
    );
    // A support of the layered model outside the plate.
    check(
        "support.toml",
        good.replace(
            "tolerance = 1e-4\n",
            "tolerance = 1e-4\n\n[[inverse.supports]]\nxy_fraction = [1.2, 0.5]\nstiffness_n_m = \
             [100.0, 100.0, 500.0]\n",
        ),
        "inverse.supports[0].xy_fraction = [1.2, 0.5]: the support lies outside the plate",
    );
    // The layered ladder's tolerance and levels.
    check(
        "tolerance.toml",
        good.replace("tolerance = 1e-4\n", "tolerance = 0.0\n"),
        "inverse.tolerance: 0 must be a relative frequency error in (0, 0.1)",
    );
    check(
        "levels.toml",
        good.replace(
            "tolerance = 1e-4\n",
            "tolerance = 1e-4\nlayered_levels = 2\n",
        ),
        "inverse.layered_levels: 2 must lie in 3..=6",
    );
    check(
        "max_dofs.toml",
        good.replace(
            "tolerance = 1e-4\n",
            "tolerance = 1e-4\nlayered_max_dofs = 10\n",
        ),
        "inverse.layered_max_dofs: 10 is below 1000 dofs",
    );
    // Priors of the layered band and the Monte Carlo: a negative or non-finite
    // standard deviation, each named.
    for (field, value, expect) in [
        (
            "face_modulus_rel_sd",
            "-0.01",
            "uncertainty.face_modulus_rel_sd: -0.01 must be a relative standard deviation",
        ),
        (
            "density_rel_sd",
            "-0.005",
            "uncertainty.density_rel_sd: -0.005 must be a relative standard deviation",
        ),
        (
            "thickness_sd_m",
            "-1e-5",
            "uncertainty.thickness_sd_m: -0.00001 must be in m",
        ),
        (
            "support_stiffness_rel_sd",
            "-0.2",
            "uncertainty.support_stiffness_rel_sd: -0.2 must be a relative standard deviation",
        ),
        (
            "support_damping_rel_sd",
            "nan",
            "uncertainty.support_damping_rel_sd: NaN must be a relative standard deviation",
        ),
    ] {
        check(
            &format!("{field}.toml"),
            good.replace(
                "[uncertainty]\n",
                &format!("[uncertainty]\n{field} = {value}\n"),
            ),
            expect,
        );
    }
    // A temperature in degrees Celsius: refused with the kelvin it probably meant; in K, read.
    check(
        "celsius.toml",
        format!("temperature_k = 20.0\n{good}"),
        "temperature_k: 20 is outside [150, 500]: temperatures are in K (20 °C would be 293.15 K)",
    );
    let p = input.join("kelvin.toml");
    std::fs::write(&p, format!("temperature_k = 293.15\n{good}")).unwrap();
    assert_eq!(Job::read(&p).unwrap().temperature_k, Some(293.15));
    // Channel counts: the job's count against the geometry, and an FRF table against it: these
    // are found by the measurement stage.
    let options = RunOptions::default();
    let stage_error = |name: &str, text: String| {
        let p = input.join(name);
        std::fs::write(&p, text).unwrap();
        let job = Job::read(&p).unwrap();
        chain_text(&run_job(job, &p, &options, &Silent).err().expect(name))
    };
    let e = stage_error(
        "count.toml",
        good.replace("[measurement]\n", "[measurement]\nresponses = 48\n"),
    );
    assert!(
        e.contains("measurement.responses = 48, but the geometry has 75 response channels"),
        "{e}"
    );
    let channels = std::fs::read_to_string(input.join("channels.csv")).unwrap();
    // Two response channels fewer, the hammer kept (the last line).
    let lines: Vec<&str> = channels.lines().collect();
    let mut fewer: Vec<&str> = lines[..lines.len() - 3].to_vec();
    fewer.push(lines[lines.len() - 1]);
    std::fs::write(input.join("fewer.csv"), fewer.join("\n")).unwrap();
    let e = stage_error(
        "fewer.toml",
        good.replace("channels = \"channels.csv\"", "channels = \"fewer.csv\""),
    );
    assert!(
        e.contains("measurement.frf ('") && e.contains("read against the channels of"),
        "{e}"
    );
    // A missing FRF file was reported as "does not match the geometry"; it is
    // refused when the job is read, naming the field and the file.
    let missing = input.join("missing.toml");
    std::fs::write(
        &missing,
        good.replace("frf = \"frf.csv\"", "frf = \"nothere.csv\""),
    )
    .unwrap();
    let e = chain_text(&Job::read(&missing).expect_err("missing file"));
    assert!(
        e.contains("measurement.frf: cannot read") && e.contains("nothere.csv"),
        "{e}"
    );
    assert!(!e.contains("geometry"), "{e}");
}

/// A job's `[measurement]` with continuous excitation: the measured plate sweep (fixture of
/// lamdyn-ema, MIT) read as `lamdyn ema --excitation sweep` reads it, its H1 equal to scipy's
/// Welch (h1_scipy.csv, tools/ema/plate_sweep_h1.py; 1e-9 as in the CLI test), and the Welch
/// settings checked by `Job::check`.
#[test]
fn a_job_measures_a_swept_sine() {
    use lamdyn_pipeline::job::Measurement;
    use lamdyn_pipeline::measurement::read_measurement_section;
    let fixture =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../lamdyn-ema/tests/fixtures/plate-sweep");
    let section = |extra: &str| -> Measurement {
        toml::from_str(&format!(
            "channels = \"channels.csv\"\ntime = [\"run1.csv\", \"run2.csv\", \"run3.csv\", \
             \"run4.csv\"]\nquantity = \"accelerance\"\n{extra}"
        ))
        .unwrap()
    };
    let m = read_measurement_section(
        &section("excitation = \"sweep\""),
        Some([60.0, 500.0]),
        &fixture,
        &fixture.join("job.toml"),
    )
    .unwrap();
    let reference = std::fs::read_to_string(fixture.join("h1_scipy.csv")).unwrap();
    let df = m.set.freqs_hz()[1];
    for row in reference.lines().skip(1) {
        let v: Vec<f64> = row.split(',').map(|x| x.parse().unwrap()).collect();
        let h = m.set.curve(0, 0)[(v[0] / df).round() as usize];
        let err = (h - num_complex::Complex64::new(v[1], v[2])).norm() / v[1].hypot(v[2]);
        assert!(err < 1e-9, "{} Hz: {err:e}", v[0]);
    }
    // Welch settings that do not fit the excitation are refused, naming the section.
    for (extra, expect) in [
        ("window = \"hann\"", "not impact"),
        ("excitation = \"random\"\noverlap = 1.5", "overlap 1.5"),
        ("excitation = \"sweep\"\nsegment_s = -1.0", "segment -1 s"),
    ] {
        let e =
            read_measurement_section(&section(extra), None, &fixture, &fixture.join("job.toml"))
                .err()
                .map(|e| chain_text(&e))
                .unwrap_or_default();
        assert!(
            e.contains("measurement.excitation") && e.contains(expect),
            "{extra}: {e}"
        );
    }
}

/// The chain gives the same bits on one and on two threads: the law's parameters,
/// the EMA's poles, G* per mode by the layered, the paper's and the exact inverse, and the core
/// law fitted to all modes with its bands (the
/// layered inverse differed by 3e-6 in G' before faer's kernels were made sequential).
#[test]
fn same_bits_on_one_and_two_threads() {
    let dir = TempDir::new("pipeline-threads");
    let (_, job_path) = demo(&dir, 0);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let no_cache = RunOptions { cache_dir: None };
        pool.install(|| run_job(Job::read(&job_path).unwrap(), &job_path, &no_cache, &Silent))
            .unwrap()
    };
    let bits = |r: &ChainResult| -> Vec<u64> {
        let mut out: Vec<u64> = r
            .fit
            .as_ref()
            .expect("the paper's route ran")
            .parameters
            .iter()
            .map(|p| p.value.to_bits())
            .collect();
        for m in &r.ema.modes {
            out.extend([m.freq_hz.to_bits(), m.damping_ratio.to_bits()]);
        }
        for p in &r.modal {
            let g = [p.layered_g(), p.paper_g(), p.exact_g()];
            out.push(p.freq_hz.to_bits());
            out.extend(
                g.iter()
                    .flatten()
                    .flat_map(|g| [g.re.to_bits(), g.im.to_bits()]),
            );
        }
        // The core's law fitted to all modes: its parameters, the inputs it finds and its
        // bands at the modes.
        let law = r.core_law.as_ref().unwrap().as_ref().unwrap();
        out.extend(law.parameters.iter().map(|p| p.value.to_bits()));
        for p in &law.at_modes {
            out.extend(
                [p.storage_ci95, p.loss_factor_ci95]
                    .iter()
                    .flatten()
                    .map(|v| v.to_bits()),
            );
        }
        out
    };
    let (one, two) = (run(1), run(2));
    assert!(one.modal.iter().all(|p| p.layered_g().is_some()));
    assert_eq!(bits(&one), bits(&two));
}

/// The small laminate with an acoustic-PVB-like core (a Prony series, G' 1.5–8 MPa, η 1.1–1.4
/// over the band): modal damping above 5 %, neighbours overlapping.
fn damped() -> Description {
    let laminate = include_str!("../../lamdyn-testbench/tests/data/small_laminate.toml")
        .replace("elements = [6, 6]", "elements = [40, 40]\nedge_grading = 0.2")
        .replace(
            r#"shear_law = { kind = "fractional_zener", g0_pa = 0.3e6, g_inf_pa = 300e6, tau_s = 1e-4, alpha = 0.55 }"#,
            r#"shear_law = { kind = "generalized_maxwell", g_e_pa = 0.2e6, terms = [{ g_pa = 0.5e6, tau_s = 1e-1 }, { g_pa = 2.0e6, tau_s = 1e-2 }, { g_pa = 8.0e6, tau_s = 1e-3 }, { g_pa = 32e6, tau_s = 1e-4 }, { g_pa = 128e6, tau_s = 1e-5 }] }"#,
        );
    let text = format!(
        "{laminate}\n[test]\ngrid = [5, 5]\nhammer_xy_fraction = [0.3, 0.35]\nhammer_direction = \
         [0.0, 0.0, -1.0]\nmax_hz = 400.0\nstep_hz = 1.0\nfrf_snr_db = 40.0\nseed = 5\n"
    );
    Description::parse("damped.toml", &text).unwrap()
}

/// Damped, overlapping modes (modal damping 5.7–15 %, overlapping pairs, 1 % noise; the rule
/// of lamdyn_pipeline::frf_route fires, and the paper's route finds no peak): the run takes the
/// FRF fit as its answer, says why, has a core at every mode (exit 0), recovers the core within
/// 4 % in G' and in η of the truth at every pole the EMA found, inside its 95 % band, and the
/// report shows the section with the measured and model FRFs. The truth is a 40 × 40 graded
/// mesh, finer than the fit's model (the ladder's finest level, 38 × 38): on an 18 × 18 truth
/// the truth's own discretization error was the comparison's limit (G' −4.1 … −1.7 %, the core
/// thickness found at −4.2 %, three of its prior's sd). Of the EMA's seven poles from 69 to
/// 343 Hz three are smears over clusters (MPC 0.02–0.36), set aside from the inverses; at the
/// four modes left the pole route is −7.9 … −3.2 % in G' (no core at 249 Hz). Measured, FRF fit:
/// G' −2.5 … +0.8 %, η −2.9 … +0.9 % at the seven poles, the core thickness found at −1.4 %
/// (1.5 of its prior's sd); run 232 s on 2 cores.
#[test]
fn damped_modes_take_the_frf_fit() {
    let dir = TempDir::new("pipeline-damped");
    let input = OutputDir::prepare(&dir.join("input"), &[], false).unwrap();
    let options = RunOptions {
        cache_dir: Some(dir.join("input/.lamdyn-cache")),
    };
    let sampling = DemoSampling {
        samples: 0,
        seed: 1,
        temperature_k: None,
    };
    let t = std::time::Instant::now();
    let (result, _, _) = run_demo(&damped(), &input, sampling, &options, &Silent).unwrap();
    eprintln!(
        "run {:.1?}; FRF fit: {}",
        t.elapsed(),
        result.frf.describe()
    );
    let route = result.frf.answer().expect("the FRF fit is the answer");
    assert!(!route.why.is_empty());
    let truth = result.truth.as_ref().unwrap();
    let pole_route = |f: f64| {
        let p = result.modal.iter().find(|p| p.freq_hz == f)?;
        let t = truth.at(f)?;
        Some(p.layered_g().map(|g| g.re / t.re - 1.0))
    };
    let mut poles: Vec<f64> = result.modal.iter().map(|p| p.freq_hz).collect();
    poles.extend(result.ema.set_aside.iter().map(|m| m.freq_hz));
    poles.sort_by(f64::total_cmp);
    for f in poles.iter().copied() {
        let (g, t) = (route.modulus(f), truth.at(f).unwrap());
        let (eg, ee) = (g.re / t.re - 1.0, (g.im / g.re) / (t.im / t.re) - 1.0);
        let a = route.at(f);
        eprintln!(
            "{f:.2} Hz: FRF fit G' {eg:+.4} [{:.3e}, {:.3e}] vs {:.3e}, eta {ee:+.4}; pole route \
             {:?} (None: set aside)",
            a.storage_ci95[0],
            a.storage_ci95[1],
            t.re,
            pole_route(f)
        );
        assert!(
            eg.abs() < 0.04 && ee.abs() < 0.04,
            "{f:.2} Hz: G' {eg:+.3}, eta {ee:+.3}"
        );
        let eta_t = t.im / t.re;
        assert!(
            (a.storage_ci95[0]..=a.storage_ci95[1]).contains(&t.re)
                && (a.loss_factor_ci95[0]..=a.loss_factor_ci95[1]).contains(&eta_t),
            "truth outside the band at {f:.2} Hz: {a:?}"
        );
    }
    assert!(poles.len() >= 6, "{} poles", poles.len());
    assert!(result.modal.len() >= 4, "{} modes", result.modal.len());
    assert!(result.modes_without_core().is_empty());
    let out = OutputDir::prepare(&dir.join("report"), &[], false).unwrap();
    out.write(&report::build(&result).unwrap()).unwrap();
    let html = std::fs::read_to_string(dir.join("report/report.html")).unwrap();
    assert!(html.contains("The core from the FRFs (no poles)"));
    assert!(dir.join("report/figures/frf_fit_1.svg").is_file());
    // core_modal.csv carries the answer with its band at every mode.
    let csv = std::fs::read_to_string(dir.join("report/core_modal.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |key: &str| header.iter().position(|h| *h == key).expect(key);
    let keys = [
        "g_frf_storage_lo_pa",
        "g_frf_storage_pa",
        "g_frf_storage_hi_pa",
    ];
    let at = keys.map(col);
    let route = result.frf.route().expect("the FRF fit");
    for (line, p) in lines.zip(&result.modal) {
        let v: Vec<&str> = line.split(',').collect();
        let [lo, g, hi] = at.map(|k| v[k].parse::<f64>().expect("a number"));
        let want = route.at(p.freq_hz);
        assert!(lo < g && g < hi, "{line}");
        assert_eq!(
            [lo, g, hi],
            [want.storage_ci95[0], want.storage_pa, want.storage_ci95[1]]
        );
    }
    // core_frf_law.csv: the answer's law and band over the fitted band; result.json has it too.
    let law = std::fs::read_to_string(dir.join("report/core_frf_law.csv")).unwrap();
    let rows: Vec<Vec<f64>> = law
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 60);
    let [lo_hz, hi_hz] = route.fit.band_hz;
    assert!((rows[0][0] / lo_hz - 1.0).abs() < 1e-12 && (rows[59][0] / hi_hz - 1.0).abs() < 1e-12);
    for row in &rows {
        let want = route.at(row[0]);
        assert_eq!(
            row[1..],
            [
                want.storage_pa,
                want.storage_ci95[0],
                want.storage_ci95[1],
                want.loss_factor,
                want.loss_factor_ci95[0],
                want.loss_factor_ci95[1]
            ]
        );
        assert!(row[2] < row[1] && row[1] < row[3] && row[5] < row[4] && row[4] < row[6]);
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report/result.json")).unwrap())
            .unwrap();
    assert_eq!(json["frf_fit"]["the_answer"], true);
    assert_eq!(json["frf_fit"]["law"], route.fit.law.name());
    assert_eq!(json["frf_fit"]["curve"].as_array().unwrap().len(), 60);
    let inputs = json["frf_fit"]["inputs"].as_array().unwrap();
    assert!(!inputs.is_empty() && inputs.len() == route.fit.inputs.len());
    assert!(route.fit.inputs_held_step.is_some());
}
