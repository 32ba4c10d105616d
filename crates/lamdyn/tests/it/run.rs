//! `lamdyn demo` and `lamdyn run` as commands: the summary table and its errors against the
//! truth, and the demo in a terminal. The chain itself (report content, recovery, cache, job
//! files) is tested in lamdyn-pipeline.

use super::common::{lamdyn, run_into, small_demo, small_description, temp_dir};

/// `lamdyn demo --json` on the small laminate: exit 0, the summary names the report and has
/// one row per mode with the three inverses' errors against the truth; `lamdyn run` on the
/// demo's job gives the same rows.
#[test]
fn demo_and_run_print_the_core_at_each_mode() {
    let dir = temp_dir("demo");
    let desc = small_description(&dir);
    let out = dir.join("out");
    let (code, text, err) = lamdyn(&[
        "demo",
        "--description",
        desc.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--samples",
        "50",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert!(
        doc["inputs"]["report"]
            .as_str()
            .unwrap()
            .ends_with("report.html")
    );
    let rows = doc["rows"].as_array().unwrap();
    assert!(rows.len() >= 3, "{rows:?}");
    for r in rows {
        for k in [
            "err_g_paper_storage",
            "err_g_exact_storage",
            "err_g_layered_storage",
            "err_g_layered_loss_factor",
        ] {
            assert!(r[k].is_number(), "{k} missing in {r}");
        }
    }
    let job = out.join("input/job.toml");
    let report = dir.join("again");
    let (code, text, err) = lamdyn(&[
        "run",
        job.to_str().unwrap(),
        "--out",
        report.to_str().unwrap(),
        "--samples",
        "50",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let again: serde_json::Value = serde_json::from_str(&text).unwrap();
    // Equal to 1e-6: this checks the report round trip, not the bits (the thread-count test
    // in lamdyn-pipeline checks those).
    let again = again["rows"].as_array().unwrap();
    assert_eq!(again.len(), rows.len());
    for (a, b) in again.iter().zip(rows) {
        for (k, v) in b.as_object().unwrap() {
            let (x, y) = (a[k].as_f64(), v.as_f64());
            if let (Some(x), Some(y)) = (x, y) {
                assert!((x - y).abs() <= 1e-6 * y.abs().max(1e-3), "{k}: {x} vs {y}");
            }
        }
    }
}

/// `lamdyn demo` hung at stage 'uncertainty' when stderr was a terminal (the main
/// thread held stderr's lock while rayon workers drew the spinner). The demo runs here under
/// `script`, which gives it a pseudo-terminal, and must end; the spinner must have drawn.
#[test]
fn demo_finishes_with_stderr_on_a_terminal() {
    let dir = temp_dir("pty");
    let desc = small_description(&dir);
    let out = dir.join("out");
    let log = dir.join("terminal.log");
    let command = format!(
        "'{}' demo --description '{}' --out '{}' --samples 200",
        env!("CARGO_BIN_EXE_lamdyn"),
        desc.display(),
        out.display()
    );
    // `timeout` ends a hang as a failure (124) instead of blocking the test suite.
    let status = std::process::Command::new("timeout")
        .args(["120", "script", "-q", "-e", "-c", &command])
        .arg(&log)
        .env("LAMDYN_PROGRESS", "")
        .stdin(std::process::Stdio::null())
        .status()
        .expect("`timeout` and `script` (util-linux) are needed for this test");
    let text = String::from_utf8_lossy(&std::fs::read(&log).unwrap_or_default()).to_string();
    assert_eq!(status.code(), Some(0), "demo in a terminal: {text}");
    assert!(out.join("report/report.html").is_file());
    assert!(
        text.contains("stage 'uncertainty'"),
        "no spinner drawn on the terminal: {text}"
    );
}

/// A run where no inverse finds a core at some mode (here faces written ten times
/// too stiff) used to exit 0; it exits 1 and names the modes. The FRF fit, which the rule would
/// call for at a mode without a core, is switched off: this is the pole routes' verdict.
#[test]
fn run_exits_1_when_no_inverse_has_a_core_at_a_mode() {
    let dir = temp_dir("no-core");
    let job = small_demo(&dir);
    let text = std::fs::read_to_string(&job).unwrap();
    let at = text.find("[[stack.layers]]").unwrap();
    let stiff = format!(
        "{}{}",
        &text[..at],
        text[at..].replace("young_pa = 70000000000.0", "young_pa = 700000000000.0")
    )
    .replace("[inverse]\n", "[inverse]\nfrf_fit = \"never\"\n");
    assert!(stiff.contains("frf_fit = \"never\""), "{stiff}");
    std::fs::write(&job, stiff).unwrap();
    let report = dir.join("stiff");
    let (code, _, err) = run_into(&job, &report, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("no core at 78.04"), "{err}");
    assert!(report.join("report.html").is_file());
}
