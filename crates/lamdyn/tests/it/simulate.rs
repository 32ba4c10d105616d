//! `lamdyn simulate`: a small virtual test written to a folder, read back by `lamdyn ema` from its
//! UFF file and from its hammer-hit time files; bad descriptions name the field and leave an
//! earlier results folder alone.

use super::common::{lamdyn, temp_dir};
use std::path::Path;

/// The test bench's small laminate (0.6 x 0.5 m, 6 x 6 elements) on three damped supports,
/// 3 x 3 sensors, hits.
fn small() -> String {
    let laminate = include_str!("../../../lamdyn-testbench/tests/data/small_laminate.toml");
    format!("{laminate}\n{SECTIONS}")
}

const SECTIONS: &str = r#"
[supports]
points = [
  { xy_fraction = [0.2, 0.2], stiffness_n_m = [500.0, 500.0, 2000.0], damping_n_s_m = [60.0, 60.0, 120.0] },
  { xy_fraction = [0.8, 0.2], stiffness_n_m = [500.0, 500.0, 2000.0], damping_n_s_m = [60.0, 60.0, 120.0] },
  { xy_fraction = [0.5, 0.8], stiffness_n_m = [500.0, 500.0, 2000.0], damping_n_s_m = [60.0, 60.0, 120.0] },
]

[test]
grid = [3, 3]
hammer_xy_fraction = [0.3, 0.35]
hammer_direction = [0.0, 0.0, -1.0]
max_hz = 200.0

[hits]
count = 2
rate_hz = 1024.0
pulse_s = 0.003
peak_force_n = 100.0
"#;

fn freqs(doc: &serde_json::Value) -> Vec<f64> {
    doc["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["freq_hz"].as_f64().unwrap())
        .collect()
}

fn ema_json(args: &[&str]) -> serde_json::Value {
    let mut a = vec!["ema", "--band-hz", "20,200", "--json"];
    a.extend_from_slice(args);
    let (code, text, err) = lamdyn(&a);
    assert!(code <= 1, "{err}");
    serde_json::from_str(&text).unwrap()
}

fn path(dir: &Path, name: &str) -> String {
    dir.join(name).to_str().unwrap().to_string()
}

#[test]
fn simulated_test_reads_back_through_ema() {
    let dir = temp_dir("simulate");
    let desc = dir.join("small.toml");
    std::fs::write(&desc, small()).unwrap();
    let out = dir.join("results");
    let (code, text, err) = lamdyn(&[
        "simulate",
        desc.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert!(
        doc["inputs"]["mesh"].as_str().unwrap().contains("dofs"),
        "{text}"
    );
    for f in [
        "channels.csv",
        "frf.csv",
        "frf_global.uff",
        "hit1.csv",
        "hit2.csv",
        "truth.csv",
        "description.toml",
        "summary.json",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    // The UFF file (global frame) and the hits (sensor frames, H1) give the same modes.
    let from_uff = freqs(&ema_json(&["--uff", &path(&out, "frf_global.uff")]));
    let from_hits = freqs(&ema_json(&[
        "--channels",
        &path(&out, "channels.csv"),
        "--time",
        &path(&out, "hit1.csv"),
        "--time",
        &path(&out, "hit2.csv"),
        "--record-s",
        "4",
        "--force-window-s",
        "0.1",
    ]));
    eprintln!("modes from UFF {from_uff:?} Hz, from the hits {from_hits:?} Hz");
    assert!(from_uff.len() >= 2);
    assert_eq!(
        from_uff.len(),
        from_hits.len(),
        "{from_uff:?} vs {from_hits:?}"
    );
    for (a, b) in from_uff.iter().zip(&from_hits) {
        assert!(
            (a - b).abs() < 1e-4 * a,
            "{a} vs {b}: {from_uff:?} vs {from_hits:?}"
        );
    }
    // The truth table states the core's law at every line.
    let truth = std::fs::read_to_string(out.join("truth.csv")).unwrap();
    assert_eq!(truth.lines().filter(|l| !l.starts_with('#')).count(), 801);

    // A bad description: an error naming the key, and the earlier results stay.
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, small().replace("fractional_zener", "fractional_zenr")).unwrap();
    let (code, _, err) = lamdyn(&[
        "simulate",
        bad.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(
        err.contains("bad.toml") && err.contains("unknown variant `fractional_zenr`"),
        "{err}"
    );
    assert!(out.join("hit1.csv").exists());
}

#[test]
fn roof_example_prints_its_description() {
    let (code, text, err) = lamdyn(&["simulate", "--example", "roof", "--print-description"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(text, lamdyn_testbench::description::ROOF_TOML);
    let (code, _, err) = lamdyn(&["simulate", "--example", "attic"]);
    assert_eq!(code, 2);
    assert!(err.contains("unknown example 'attic'"), "{err}");
}
