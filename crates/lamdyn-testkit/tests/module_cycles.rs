//! No crate of the workspace has modules that use each other in a circle
//! (`lamdyn_testkit::modules`; docs/architecture.md): the pipeline flows one way, and a new
//! cycle fails here naming the uses that close it.

use lamdyn_testkit::modules::{cycles, read_crate};
use std::path::Path;

#[test]
fn no_crate_has_a_module_cycle() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .canonicalize()
        .expect("crates folder");
    let mut found = Vec::new();
    let mut scanned = 0;
    for entry in std::fs::read_dir(&crates).expect("crates folder") {
        let src = entry.expect("crate folder").path().join("src");
        if !src.is_dir() {
            continue;
        }
        let files = read_crate(&src).expect("crate sources");
        scanned += files.len();
        found.extend(cycles(&files).into_iter().map(|c| c.to_string()));
    }
    assert!(
        scanned > 100,
        "only {scanned} source files found under {crates:?}"
    );
    assert!(
        found.is_empty(),
        "module cycles (move what both sides need into a leaf module):\n{}",
        found.join("\n")
    );
}
