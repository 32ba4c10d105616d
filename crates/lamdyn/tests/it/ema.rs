//! `lamdyn ema` on the measured free-free beam (fixture of lamdyn-ema, MIT licence beside it).

use super::common::*;
use std::path::PathBuf;

/// The beam FRFs written as a CSV FRF set in a fresh folder: (channels, frf) paths.
fn beam_csv(name: &str) -> (String, String) {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../lamdyn-ema/tests/fixtures/free-free-beam");
    let curves: Vec<Vec<num_complex::Complex64>> = (1..=3)
        .map(|i| {
            lamdyn_testkit::python_complex_column(
                &std::fs::read_to_string(src.join(format!("meas_point_{i}.txt"))).unwrap(),
            )
        })
        .collect();
    let freqs: Vec<f64> = (0..curves[0].len()).map(|k| k as f64).collect();
    let ch = |n: &str, x: f64| lamdyn_frf::Channel::new(n, [x, 0.0, 0.0], [0.0, 0.0, 1.0]).unwrap();
    let set = lamdyn_frf::FrfSet::new(
        freqs,
        vec![ch("1", 0.0), ch("2", 0.5), ch("3", 1.0)],
        vec![ch("hammer", 0.0)],
        lamdyn_frf::Quantity::Accelerance,
        curves.into_iter().flatten().collect(),
    )
    .unwrap();
    let dir = temp_dir(name);
    let (c, f) = (dir.join("channels.csv"), dir.join("frf.csv"));
    std::fs::write(&c, lamdyn_frf::csv::write_channels(&set)).unwrap();
    std::fs::write(&f, lamdyn_frf::csv::write_frf(&set)).unwrap();
    (c.to_str().unwrap().into(), f.to_str().unwrap().into())
}

#[test]
fn beam_modes_and_correlation() {
    let (c, f) = beam_csv("ema-beam");
    let (code, out, err) = lamdyn(&[
        "ema",
        "--channels",
        &c,
        "--frf",
        &f,
        "--band-hz",
        "10,1000",
        "--driving",
        "1",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let doc: serde_json::Value = serde_json::from_str(&out).unwrap();
    let rows = doc["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 6);
    let f1 = rows[0]["freq_hz"].as_f64().unwrap();
    assert!((f1 / 51.517 - 1.0).abs() < 1e-3, "{f1}");
    assert!(
        doc["sections"]["correlation"]
            .as_array()
            .unwrap()
            .iter()
            .all(|r| r["frac"].as_f64().unwrap() > 0.95)
    );
    assert!(doc["details"]["diagram"].as_array().unwrap().len() > 100);
    assert_eq!(
        doc["details"]["modes"][0]["shape"]
            .as_array()
            .unwrap()
            .len(),
        3
    );
    let (code, text, _) = lamdyn(&["ema", "--channels", &c, "--frf", &f, "--band-hz", "10,1000"]);
    assert_eq!(code, 0);
    for needle in ["LSCF", "MPC", "FRAC", "CMIF peaks", "[Hz]"] {
        assert!(text.contains(needle), "missing {needle} in {text}");
    }
}

#[test]
fn picks_and_bad_arguments() {
    let (c, f) = beam_csv("ema-bad");
    // A frequency with no pole: a warning and exit code 1.
    let (code, _, err) = lamdyn(&[
        "ema",
        "--channels",
        &c,
        "--frf",
        &f,
        "--band-hz",
        "10,1000",
        "--near-hz",
        "51.5,600",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("no stable pole within 1 Hz of [600.0]"),
        "{err}"
    );
    let cases: [(&[&str], &str); 4] = [
        (&["--driving", "7"], "--driving '7' is not a response"),
        (&["--band-hz", "10,20,30"], "two frequencies"),
        (
            &["--band-hz", "10,40", "--max-order", "60"],
            "order 60 needs at least 61",
        ),
        (&["--exp-tau-s", "-1"], "--exp-tau-s -1 must be a positive"),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["ema", "--channels", &c, "--frf", &f];
        args.extend_from_slice(extra);
        let (code, _, err) = lamdyn(&args);
        assert_eq!(code, 2, "{extra:?}: {err}");
        assert!(
            err.contains(needle),
            "{extra:?}: expected {needle:?} in {err}"
        );
    }
}
