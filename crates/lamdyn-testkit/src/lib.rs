//! Test helpers shared by the lamdyn crates: relative errors, tolerances, frequency grids, and
//! the reader of complex columns written by Python (the free-free beam fixture).
//!
//! Tolerances come from one place: [`tol`] is c·n·ε for a computation of n rounding steps, so a
//! test states how many operations it trusts instead of a bare `1e-9`.

#![deny(missing_docs)]

pub mod functions;
pub mod modules;

use num_complex::Complex64;

/// Relative error |a − b| / |b| of two complex numbers (absolute when b = 0).
pub fn rel_err(a: Complex64, b: Complex64) -> f64 {
    let d = (a - b).norm();
    if b.norm() == 0.0 { d } else { d / b.norm() }
}

/// Relative error |a − b| / |b| of two reals (absolute when b = 0).
pub fn rel_err_f64(a: f64, b: f64) -> f64 {
    rel_err(Complex64::new(a, 0.0), Complex64::new(b, 0.0))
}

/// Tolerance c·n·ε with c = 4: what n rounding steps of double precision may cost.
pub fn tol(n: usize) -> f64 {
    4.0 * n as f64 * f64::EPSILON
}

/// `n` points from `lo` to `hi` (both > 0) spaced evenly in log scale.
pub fn log_grid(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    assert!(
        n >= 2 && lo > 0.0 && hi > lo,
        "expected n >= 2 and 0 < lo < hi"
    );
    let (a, b) = (lo.ln(), hi.ln());
    (0..n)
        .map(|i| (a + (b - a) * i as f64 / (n - 1) as f64).exp())
        .collect()
}

/// Asserts that a relative error is below a bound, printing both and a label.
#[track_caller]
pub fn assert_rel(label: &str, got: Complex64, want: Complex64, bound: f64) {
    let e = rel_err(got, want);
    assert!(
        e <= bound,
        "{label}: got {got}, want {want}, relative error {e:.3e} > {bound:.3e}"
    );
}

/// The proptest configuration of every lamdyn property test: `cases` cases from a fixed seed
/// (reproducible runs; override with `PROPTEST_RNG_SEED`), and no regression files written
/// into the source tree.
pub fn proptest_config(cases: u32) -> proptest::test_runner::Config {
    use proptest::test_runner::{Config, RngSeed};
    let seed = std::env::var("PROPTEST_RNG_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20261122);
    Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..Config::default()
    }
}

/// One complex value per line written by Python (`(-0.07+2.6e-08j)`), as in the free-free beam
/// fixture of lamdyn-ema. Panics on malformed lines (test data).
pub fn python_complex_column(text: &str) -> Vec<Complex64> {
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let t = l
                .trim()
                .trim_start_matches('(')
                .trim_end_matches(')')
                .trim_end_matches('j');
            let b = t.as_bytes();
            let cut = (1..b.len())
                .rev()
                .find(|&p| (b[p] == b'+' || b[p] == b'-') && !matches!(b[p - 1], b'e' | b'E'))
                .unwrap_or_else(|| panic!("'{l}' is not a Python complex literal"));
            let num = |s: &str| s.parse::<f64>().unwrap_or_else(|_| panic!("'{l}': '{s}'"));
            Complex64::new(num(&t[..cut]), num(&t[cut..]))
        })
        .collect()
}

/// A fresh folder for one test, removed with everything in it when dropped — also when the
/// test fails (drops run while a panic unwinds), so test runs leave nothing in the system's
/// temporary folder.
#[derive(Debug)]
pub struct TempDir(std::path::PathBuf);

impl TempDir {
    /// `lamdyn-test-PID-NAME` in the system's temporary folder, emptied if it exists.
    pub fn new(name: &str) -> Self {
        let d = std::env::temp_dir().join(format!("lamdyn-test-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("cannot create a test folder");
        Self(d)
    }

    /// The folder.
    pub fn path(&self) -> &std::path::Path {
        &self.0
    }
}

impl std::ops::Deref for TempDir {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        &self.0
    }
}

impl AsRef<std::path::Path> for TempDir {
    fn as_ref(&self) -> &std::path::Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
