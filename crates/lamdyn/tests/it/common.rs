use std::path::{Path, PathBuf};

/// (exit code, stdout, stderr) of `lamdyn args...`.
pub fn lamdyn(args: &[&str]) -> (u8, String, String) {
    let (mut out, mut err) = (Vec::new(), Vec::new());
    let code = lamdyn::run(
        std::iter::once("lamdyn").chain(args.iter().copied()),
        &mut out,
        &mut err,
    );
    (
        code,
        String::from_utf8(out).unwrap(),
        String::from_utf8(err).unwrap(),
    )
}

/// A path in the repository's examples folder.
pub fn example(rel: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(rel);
    p.to_str().unwrap().to_string()
}

/// A UFF conformance file among lamdyn-uff's test fixtures.
pub fn uff_fixture(rel: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../lamdyn-uff/tests/fixtures")
        .join(rel);
    p.to_str().unwrap().to_string()
}

/// A fresh temporary folder for one test, removed when dropped (also when the test fails).
pub fn temp_dir(name: &str) -> lamdyn_testkit::TempDir {
    lamdyn_testkit::TempDir::new(name)
}

/// Rows of a CSV output as maps from column to value.
pub fn csv_rows(text: &str) -> Vec<std::collections::BTreeMap<String, String>> {
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(String::from))
                .collect()
        })
        .collect()
}

/// A CSV cell as a number.
pub fn num(row: &std::collections::BTreeMap<String, String>, key: &str) -> f64 {
    row[key]
        .parse()
        .unwrap_or_else(|_| panic!("{key} = {:?} is not a number", row[key]))
}

/// The bench's small laminate, free, 5 x 5 sensors, FRFs to 240 Hz (no hits: quick).
pub fn small_description(dir: &Path) -> PathBuf {
    let laminate = include_str!("../../../lamdyn-testbench/tests/data/small_laminate.toml");
    let text = format!(
        "{laminate}\n[test]\ngrid = [5, 5]\nhammer_xy_fraction = [0.3, 0.35]\nhammer_direction = \
         [0.0, 0.0, -1.0]\nmax_hz = 240.0\nstep_hz = 0.5\n"
    );
    let p = dir.join("small.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// The small demo (FRFs, no hits) into `dir/demo`, without Monte Carlo; its job file.
pub fn small_demo(dir: &Path) -> std::path::PathBuf {
    let desc = small_description(dir);
    let out = dir.join("demo");
    let (code, _, err) = lamdyn(&[
        "demo",
        "--description",
        desc.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--samples",
        "0",
    ]);
    assert_eq!(code, 0, "{err}");
    out.join("input/job.toml")
}

/// `lamdyn run JOB --out OUT --samples 0 EXTRA...` (no Monte Carlo).
pub fn run_into(job: &Path, out: &Path, extra: &[&str]) -> (u8, String, String) {
    let mut args = vec![
        "run",
        job.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--samples",
        "0",
    ];
    args.extend_from_slice(extra);
    lamdyn(&args)
}
