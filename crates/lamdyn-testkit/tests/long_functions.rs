//! No function outside tests is longer than 100 lines but those listed here, each with the
//! reason it stays whole (docs/architecture.md): a new long function fails here with its
//! file and line, and a listed one that got shorter must leave the list.

use lamdyn_testkit::functions::longer_than;
use lamdyn_testkit::modules::read_crate;
use std::path::Path;

/// The longest a function may be, in lines from its `fn` to its closing brace.
const MAX_LINES: usize = 100;

/// The functions allowed to be longer, as (file below `crates/`, name, why).
const ALLOWED: [(&str, &str, &str); 4] = [
    (
        "lamdyn-fem/src/eigen/lanczos.rs",
        "lanczos",
        "one thick-restart Lanczos iteration: the basis, the tridiagonal matrix, the restart and \
         the convergence test share their state and invariants, which split functions would pass \
         around in pieces",
    ),
    (
        "lamdyn-fem/src/eigen/mod.rs",
        "solve_modes",
        "the eigensolver's driver, one step after another (shift, factorization, Lanczos, Sturm \
         count, residuals) with each step's time and error in one place",
    ),
    (
        "lamdyn-fit/src/joint.rs",
        "fit_core_law_shifted",
        "the joint law fit's one least-squares problem: the rows of the modes, the priors and the \
         shared remainder are built together so their scales and order stay aligned with the \
         covariance read from them",
    ),
    (
        "lamdyn-report/src/chart.rs",
        "draw",
        "one chart drawn by plotters in painting order (axes, bands, lines, marks, legend); the \
         drawing backend's borrow spans it",
    ),
];

#[test]
fn no_function_is_longer_than_a_screen_but_the_listed_ones() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .canonicalize()
        .expect("crates folder");
    let mut long = Vec::new();
    for entry in std::fs::read_dir(&crates).expect("crates folder") {
        let src = entry.expect("crate folder").path().join("src");
        if src.is_dir() {
            long.extend(longer_than(
                &read_crate(&src).expect("crate sources"),
                MAX_LINES,
            ));
        }
    }
    let relative = |file: &str| {
        Path::new(file)
            .strip_prefix(&crates)
            .map_or(file.to_string(), |p| p.display().to_string())
    };
    let unlisted: Vec<String> = long
        .iter()
        .filter(|f| {
            !ALLOWED
                .iter()
                .any(|(file, name, _)| relative(&f.file) == *file && f.name == *name)
        })
        .map(|f| {
            format!(
                "{}:{} fn {} ({} lines)",
                relative(&f.file),
                f.line,
                f.name,
                f.lines
            )
        })
        .collect();
    assert!(
        unlisted.is_empty(),
        "functions over {MAX_LINES} lines (split them into steps that return values):\n{}",
        unlisted.join("\n")
    );
    let shorter: Vec<&str> = ALLOWED
        .iter()
        .filter(|(file, name, _)| {
            !long
                .iter()
                .any(|f| relative(&f.file) == *file && f.name == *name)
        })
        .map(|(_, name, _)| *name)
        .collect();
    assert!(
        shorter.is_empty(),
        "listed as long but no longer over {MAX_LINES} lines (take them off ALLOWED): {shorter:?}"
    );
}
