//! `lamdyn fit`: the built-in recovery case, the job-file route on the same data, the chain into
//! `lamdyn core`, atomic outputs, and bad inputs.

use super::common::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The paper-plate example written once as a job folder (job.toml, model.toml, channels.csv,
/// frf.csv), shared by the tests that read or corrupt it.
fn example_job() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        // Shared by every test of this file, so it outlives each of them: it lives in cargo's
        // folder for integration-test files (target/tmp), not in the system's temp folder.
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("lamdyn-fit-example-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let (code, _, err) = lamdyn(&[
            "fit",
            "--example",
            "paper-plate",
            "--write-example",
            dir.to_str().unwrap(),
            "--csv",
        ]);
        assert_eq!(code, 0, "{err}");
        dir
    })
}

/// A job in `dir` using the example's files, except those given in `replace` (name → contents),
/// with `extra` appended to the job text.
fn job_with(dir: &Path, replace: &[(&str, String)], extra: &str) -> String {
    let base = example_job();
    let path_of = |name: &str| {
        if replace.iter().any(|(n, _)| *n == name) {
            dir.join(name)
        } else {
            base.join(name)
        }
    };
    for (name, text) in replace {
        std::fs::write(dir.join(name), text).unwrap();
    }
    let job = format!(
        "model = {:?}\n{extra}\n[measurement]\nchannels = {:?}\nfrf = {:?}\ntolerance_m = 1e-6\n",
        path_of("model.toml"),
        path_of("channels.csv"),
        path_of("frf.csv"),
    );
    let p = dir.join("job.toml");
    std::fs::write(&p, job).unwrap();
    p.to_str().unwrap().to_string()
}

/// The recovery claims of the issue, through the CLI: E' within 0.5 % and η within 5 % of the
/// truth at every resonance (the truth columns of the main table).
#[test]
fn example_recovers_the_paper_law() {
    let (code, out, err) = lamdyn(&["fit", "--example", "paper-plate", "--csv"]);
    assert_eq!(code, 0, "{err}");
    let rows = csv_rows(&out);
    assert!(rows.len() >= 6, "{out}");
    for r in &rows {
        assert!(num(r, "truth_e_storage_error").abs() < 5e-3, "{r:?}");
        assert!(num(r, "truth_loss_factor_error").abs() < 5e-2, "{r:?}");
        assert!(num(r, "e_storage_sd_pa") > 0.0);
    }
}

#[test]
fn text_report_has_every_table() {
    let (code, out, err) = lamdyn(&["fit", "--example", "paper-plate-zener"]);
    assert_eq!(code, 0, "{err}");
    for needle in [
        "Parameters",
        "g_inf_pa",
        "inside",
        "Levenberg-Marquardt starts",
        "Table 3",
        "Mode-wise",
        "converged",
        "misfit evaluations",
        "[GPa]",
    ] {
        assert!(out.contains(needle), "missing {needle:?} in\n{out}");
    }
}

/// The job route on the written example reads back the same data: the same result to the last
/// digit (CSV numbers are written in shortest round-trip form).
#[test]
fn job_file_gives_the_example_result() {
    let job = example_job().join("job.toml");
    let (code, from_job, err) = lamdyn(&["fit", job.to_str().unwrap(), "--csv"]);
    assert_eq!(code, 0, "{err}");
    let (_, from_example, _) = lamdyn(&["fit", "--example", "paper-plate", "--csv"]);
    let (a, b) = (csv_rows(&from_job), csv_rows(&from_example));
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        for key in ["f_hz", "e_storage_pa", "loss_factor"] {
            assert_eq!(num(x, key), num(y, key), "{key}");
        }
    }
}

/// The fit's CSV is a `lamdyn core --table` input.
#[test]
fn fit_output_feeds_the_core_inverse() {
    let dir = temp_dir("fit-core");
    let (code, out, err) = lamdyn(&["fit", "--example", "paper-plate", "--csv"]);
    assert_eq!(code, 0, "{err}");
    let table = dir.join("e.csv");
    std::fs::write(&table, &out).unwrap();
    let (code, core, err) = lamdyn(&[
        "core",
        "--stack",
        &example("roof-stack.toml"),
        "--table",
        table.to_str().unwrap(),
        "--csv",
    ]);
    assert!(code <= 1, "{err}");
    let rows = csv_rows(&core);
    assert_eq!(rows.len(), csv_rows(&out).len());
    // The paper's case: a core of a few MPa (paper Fig. 7 order of magnitude).
    for r in &rows {
        let g = num(r, "g_exact_storage_pa");
        assert!((1e6..2e7).contains(&g), "{r:?}");
    }
}

#[test]
fn out_folder_holds_every_table_and_survives_a_failed_run() {
    let dir = temp_dir("fit-out");
    let out_dir = dir.join("result");
    let o = out_dir.to_str().unwrap();
    let (code, _, err) = lamdyn(&["fit", "--example", "paper-plate", "--out", o]);
    assert_eq!(code, 0, "{err}");
    for f in [
        "report.json",
        "modulus.csv",
        "parameters.csv",
        "starts.csv",
        "table3.csv",
        "modewise.csv",
        "rms.csv",
    ] {
        assert!(out_dir.join(f).is_file(), "{f}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("report.json")).unwrap())
            .unwrap();
    assert_eq!(json["sections"]["parameters"].as_array().unwrap().len(), 4);
    let before = std::fs::read(out_dir.join("modulus.csv")).unwrap();
    // A failing run (empty band) leaves the good results as they were.
    let bad = job_with(
        &dir,
        &[],
        "[misfit]\nkind = \"log_rms\"\nband_hz = [10.0, 10.3]",
    );
    let (code, _, err) = lamdyn(&["fit", &bad, "--out", o]);
    assert_eq!(code, 2);
    assert!(err.contains("residuals for 4 parameters"), "{err}");
    assert_eq!(std::fs::read(out_dir.join("modulus.csv")).unwrap(), before);
}

/// Bad inputs: each error names the file, line, field or channel.
#[test]
fn bad_inputs_give_clear_errors() {
    let dir = temp_dir("fit-bad");
    let base = example_job();
    let frf = std::fs::read_to_string(base.join("frf.csv")).unwrap();
    let channels = std::fs::read_to_string(base.join("channels.csv")).unwrap();
    let mut cases: Vec<(String, &str)> = Vec::new();
    // NaN in the FRF file, on its 5th line.
    let mut lines: Vec<String> = frf.lines().map(String::from).collect();
    let mut fields: Vec<String> = lines[4].split(',').map(String::from).collect();
    fields[1] = "NaN".into();
    lines[4] = fields.join(",");
    let nan = lines;
    let sub = dir.join("nan");
    std::fs::create_dir_all(&sub).unwrap();
    cases.push((job_with(&sub, &[("frf.csv", nan.join("\n"))], ""), "line 5"));
    // A sensor 5 m off the plate.
    let off = channels.replacen("-0.4615,-0.4316", "5.0,-0.4316", 1);
    let sub = dir.join("off");
    std::fs::create_dir_all(&sub).unwrap();
    cases.push((
        job_with(&sub, &[("channels.csv", off)], ""),
        "channel '1+X'",
    ));
    // Too few lines for four parameters.
    let sub = dir.join("few");
    std::fs::create_dir_all(&sub).unwrap();
    cases.push((
        job_with(
            &sub,
            &[],
            "[misfit]\nkind = \"rms\"\nband_hz = [20.0, 20.6]",
        ),
        "3 residuals for 4 parameters",
    ));
    // A zero weight.
    let sub = dir.join("weight");
    std::fs::create_dir_all(&sub).unwrap();
    cases.push((
        job_with(
            &sub,
            &[],
            "[misfit]\nkind = \"rms\"\n[[misfit.weights]]\nband_hz = [1.0, 10.0]\nweight = 0.0",
        ),
        "weights[0].weight",
    ));
    // An unknown key.
    let sub = dir.join("key");
    std::fs::create_dir_all(&sub).unwrap();
    cases.push((job_with(&sub, &[], "moduls = 3"), "moduls"));
    // A model's support off the mesh.
    let spring = |point: &str| {
        std::fs::read_to_string(base.join("model.toml")).unwrap()
            + &format!(
                "\n[[supports]]\npoint_m = {point}\ntranslational_n_per_m = [0.0, 0.0, 1e4]\n"
            )
    };
    let sub = dir.join("support-off");
    std::fs::create_dir_all(&sub).unwrap();
    cases.push((
        job_with(&sub, &[("model.toml", spring("[5.0, 5.0, 0.0]"))], ""),
        "point_m",
    ));
    // Frequencies x1000 used to fit to E0 = 1.48e16 Pa with exit 0.
    let khz: Vec<String> = frf
        .lines()
        .map(|l| match l.split_once(',') {
            Some((f, rest)) if f.parse::<f64>().is_ok() => {
                format!("{},{rest}", f.parse::<f64>().unwrap() * 1000.0)
            }
            _ => l.to_string(),
        })
        .collect();
    let sub = dir.join("khz");
    std::fs::create_dir_all(&sub).unwrap();
    cases.push((
        job_with(&sub, &[("frf.csv", khz.join("\n"))], ""),
        "implausible result",
    ));
    // A reference that does not exist.
    let sub = dir.join("reference");
    std::fs::create_dir_all(&sub).unwrap();
    cases.push((
        job_with(&sub, &[], "[misfit]\nkind = \"rms\"\nreference = 3"),
        "misfit.reference",
    ));
    for (job, needle) in cases {
        let (code, out, err) = lamdyn(&["fit", &job]);
        assert_eq!(code, 2, "{job}: {out}");
        assert!(err.contains(needle), "{job}: expected {needle:?} in {err}");
    }
    // A model on a node spring is fitted with the spring coupling its modes.
    let sub = dir.join("supports");
    std::fs::create_dir_all(&sub).unwrap();
    let job = job_with(&sub, &[("model.toml", spring("[0.0, 0.0, 0.0]"))], "");
    let (code, out, err) = lamdyn(&["fit", &job]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("and 1 node springs (model file)"), "{out}");
    let (code, _, err) = lamdyn(&["fit", "--example", "paper-plate", "--noise", "NaN"]);
    assert_eq!(code, 2);
    assert!(err.contains("noise"), "{err}");
}

/// The measurement as a binary UFF file (nodes 2411 + FRFs 58b written by lamdyn-uff) gives the
/// same fit as the CSV files it was made from.
#[test]
fn uff_measurement_gives_the_csv_result() {
    let base = example_job();
    let text = |n: &str| std::fs::read_to_string(base.join(n)).unwrap();
    let (r, f) = lamdyn_frf::csv::parse_channels("channels.csv", &text("channels.csv")).unwrap();
    let set = lamdyn_frf::csv::parse_frf("frf.csv", &text("frf.csv"), r, f).unwrap();
    let datasets = lamdyn_uff::frf::from_frf_set(&set).unwrap();
    let dir = temp_dir("fit-uff");
    let uff = dir.join("test.uff");
    std::fs::write(
        &uff,
        lamdyn_uff::write(
            &datasets,
            lamdyn_uff::Encoding::Binary {
                little_endian: true,
            },
        )
        .unwrap(),
    )
    .unwrap();
    let job = dir.join("job.toml");
    std::fs::write(
        &job,
        format!(
            "model = {:?}\n[measurement]\nuff = {:?}\ntolerance_m = 1e-6\n",
            base.join("model.toml"),
            uff
        ),
    )
    .unwrap();
    let (code, from_uff, err) = lamdyn(&["fit", job.to_str().unwrap(), "--csv"]);
    assert_eq!(code, 0, "{err}");
    let (_, from_csv, _) = lamdyn(&["fit", base.join("job.toml").to_str().unwrap(), "--csv"]);
    assert_eq!(from_uff, from_csv);
    // Both sources at once is an error naming the field.
    std::fs::write(
        &job,
        format!(
            "model = {:?}\n[measurement]\nuff = {:?}\nfrf = \"x.csv\"\n",
            base.join("model.toml"),
            uff
        ),
    )
    .unwrap();
    let (code, _, err) = lamdyn(&["fit", job.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(
        err.contains("measurement: give channels with frf or time, or uff"),
        "{err}"
    );
}

/// `uff convert --to csv` wrote a channels table that `ema` and `fit` rejected
/// ("channel '1+Z' was already defined"). Round trip: the example's FRFs as UFF, converted to
/// CSV, fitted again: the same result as the CSV files they came from.
#[test]
fn uff_converted_to_csv_feeds_fit_and_ema() {
    let base = example_job();
    let text = |n: &str| std::fs::read_to_string(base.join(n)).unwrap();
    // The hammer moved onto response 41's node and direction: a driving point, whose response
    // and reference share the UFF name '41+Z'.
    let channels: Vec<String> = text("channels.csv").lines().map(String::from).collect();
    let at_41 = channels.iter().find(|l| l.starts_with("41+Z,")).unwrap();
    let driving = at_41.replacen("response", "reference", 1);
    let with_driving: Vec<String> = channels
        .iter()
        .map(|l| {
            if l.starts_with("hammer,") {
                driving.clone()
            } else {
                l.clone()
            }
        })
        .collect();
    let (r, f) = lamdyn_frf::csv::parse_channels("channels.csv", &with_driving.join("\n")).unwrap();
    let frf_text = text("frf.csv").replace("@hammer:", "@41+Z:");
    let set = lamdyn_frf::csv::parse_frf("frf.csv", &frf_text, r, f).unwrap();
    let dir = temp_dir("fit-uff-csv");
    std::fs::write(dir.join("channels.csv"), with_driving.join("\n")).unwrap();
    std::fs::write(dir.join("frf.csv"), frf_text).unwrap();
    let uff = dir.join("test.uff");
    let datasets = lamdyn_uff::frf::from_frf_set(&set).unwrap();
    std::fs::write(
        &uff,
        lamdyn_uff::write(&datasets, lamdyn_uff::Encoding::Ascii).unwrap(),
    )
    .unwrap();
    let csv = dir.join("csv");
    let (code, _, err) = lamdyn(&[
        "uff",
        "convert",
        uff.to_str().unwrap(),
        csv.to_str().unwrap(),
        "--to",
        "csv",
    ]);
    assert_eq!(code, 0, "{err}");
    let (channels, frf) = (csv.join("channels.csv"), csv.join("frf.csv"));
    let job = dir.join("job.toml");
    std::fs::write(
        &job,
        format!(
            "[measurement]\nchannels = {:?}\nfrf = {:?}\ntolerance_m = 1e-6\n[model]\nfile = \
             {:?}\n",
            channels,
            frf,
            base.join("model.toml")
        ),
    )
    .unwrap();
    let (code, from_csv_of_uff, err) = lamdyn(&["fit", job.to_str().unwrap(), "--csv"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("deprecated"), "{err}");
    let direct = dir.join("direct.toml");
    std::fs::write(
        &direct,
        format!(
            "[measurement]\nchannels = \"channels.csv\"\nfrf = \"frf.csv\"\ntolerance_m = \
             1e-6\n[model]\nfile = {:?}\n",
            base.join("model.toml")
        ),
    )
    .unwrap();
    let (code, from_csv, err) = lamdyn(&["fit", direct.to_str().unwrap(), "--csv"]);
    assert_eq!(code, 0, "{err}");
    // Equal to the ASCII UFF's 13 significant digits.
    let (a, b) = (csv_rows(&from_csv_of_uff), csv_rows(&from_csv));
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        for k in ["f_hz", "e_storage_pa", "loss_factor"] {
            let (x, y) = (num(x, k), num(y, k));
            assert!((x - y).abs() <= 1e-9 * y.abs(), "{k}: {x} vs {y}");
        }
    }
    let (code, _, err) = lamdyn(&[
        "ema",
        "--channels",
        channels.to_str().unwrap(),
        "--frf",
        frf.to_str().unwrap(),
        "--band-hz",
        "10,78",
    ]);
    assert_eq!(code, 0, "{err}");
}

/// One layout and one vocabulary. A `lamdyn run` job is a `lamdyn fit` job; the
/// old fit layout (`model` as a path, `[misfit]`) and the old flag spellings still work, each
/// with a deprecation note; the job file's spellings work on the command line without one.
#[test]
fn run_jobs_and_old_spellings_are_read_by_fit() {
    let dir = temp_dir("fit-vocabulary");
    let run_job = small_demo(&dir);
    let (code, out, err) = lamdyn(&["fit", run_job.to_str().unwrap(), "--csv"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("deprecated"), "{err}");
    assert!(csv_rows(&out).len() >= 3, "{out}");

    let old = job_with(&dir, &[], "[misfit]\nkind = \"log_rms\"");
    let (code, _, err) = lamdyn(&["fit", &old, "--csv"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("deprecated: model = "), "{err}");
    assert!(
        err.contains("deprecated: [misfit]; write [fit.misfit]"),
        "{err}"
    );
    let both = job_with(
        &dir,
        &[],
        "[misfit]\nkind = \"rms\"\n[fit.misfit]\nkind = \"rms\"",
    );
    let (code, _, err) = lamdyn(&["fit", &both]);
    assert_eq!(code, 2);
    assert!(err.contains("give [fit.misfit] only"), "{err}");

    let example = ["fit", "--example", "paper-plate", "--csv"];
    for (flags, note) in [
        (
            ["--law", "eq7"],
            Some("deprecated: --law eq7; write --law paper_eq7"),
        ),
        (["--law", "paper_eq7"], None),
        (["--misfit", "log-rms"], Some("write --misfit log_rms")),
        (["--misfit", "log_rms"], None),
        (
            ["--covariance", "hc3"],
            Some("write --covariance robust_hc3"),
        ),
        (["--covariance", "robust_hc3"], None),
    ] {
        let args: Vec<&str> = example.iter().chain(&flags).copied().collect();
        let (code, _, err) = lamdyn(&args);
        assert_eq!(code, 0, "{flags:?}: {err}");
        match note {
            Some(n) => assert!(err.contains(n), "{flags:?}: {err}"),
            None => assert!(!err.contains("deprecated"), "{flags:?}: {err}"),
        }
    }
}

/// `--poles`: the example's FRFs through `lamdyn ema`, its modes.csv into the fit.
/// The mode-wise estimate then uses the identified poles instead of the RMS FRF's peaks (which
/// sit up to 0.3 % below the poles in frequency on this plate, so E' = E_ref (f/f_FE)² came
/// out up to 0.5 % low), and η = 2ζ of each pole (the half-power bandwidth is not resolved at
/// 0.25 Hz). A pole file with a damping ratio in % is refused with its line.
#[test]
fn ema_poles_feed_the_modewise_estimate() {
    use lamdyn_material::law::{PaperEq7Law, ViscoelasticLaw};
    let base = example_job();
    let dir = temp_dir("fit-poles");
    let ema = dir.path().join("ema");
    let (code, _, err) = lamdyn(&[
        "ema",
        "--channels",
        base.join("channels.csv").to_str().unwrap(),
        "--frf",
        base.join("frf.csv").to_str().unwrap(),
        "--out",
        ema.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let job = base.join("job.toml");
    let modewise = |extra: &[&str]| {
        let (code, out, err) =
            lamdyn(&[&["fit", job.to_str().unwrap(), "--json"][..], extra].concat());
        assert_eq!(code, 0, "{err}");
        let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
        doc["sections"]["modewise"].as_array().unwrap().clone()
    };
    let truth = PaperEq7Law::paper_table2();
    // Per mode: relative errors of E' and of η against the truth at the row's frequency.
    let errors = |rows: &[serde_json::Value]| -> Vec<(f64, f64)> {
        rows.iter()
            .map(|r| {
                let f = r["f_measured_hz"].as_f64().unwrap();
                let t = truth.modulus(2.0 * std::f64::consts::PI * f);
                let e = r["e_storage_pa"].as_f64().unwrap() / t.re - 1.0;
                let eta = r["loss_factor"]
                    .as_f64()
                    .map_or(f64::INFINITY, |l| l / (t.im / t.re) - 1.0);
                (e.abs(), eta.abs())
            })
            .collect()
    };
    let peaks = errors(&modewise(&[]));
    let poles = errors(&modewise(&[
        "--poles",
        ema.join("modes.csv").to_str().unwrap(),
    ]));
    eprintln!("RMS peaks: {peaks:?}\nEMA poles: {poles:?}");
    assert_eq!(peaks.len(), 9);
    assert_eq!(poles.len(), 9);
    // RMS peaks: E' off by 2e-4 to 5e-3 at every mode, η not resolved.
    assert!(peaks.iter().all(|(e, eta)| *e > 1e-4 && eta.is_infinite()));
    // Poles: E' within 1e-4 and η within 2 % at 8 of 9 modes; the ninth (65.4 Hz, MPC 0.997,
    // beside a close FE mode) is 4e-3 off in E' by either route.
    let good = poles
        .iter()
        .filter(|(e, eta)| *e < 1e-4 && *eta < 0.02)
        .count();
    assert!(good >= 8, "{poles:?}");
    // A damping ratio written in per cent is refused with the file and line.
    let bad = dir.path().join("modes.csv");
    std::fs::write(
        &bad,
        "mode,freq_hz,damping_ratio\n1,15.57,0.16\n2,21.67,19.0\n",
    )
    .unwrap();
    let (code, _, err) = lamdyn(&[
        "fit",
        job.to_str().unwrap(),
        "--poles",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(
        err.contains("line 3") && err.contains("damping_ratio"),
        "{err}"
    );
}
