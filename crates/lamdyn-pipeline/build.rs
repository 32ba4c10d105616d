//! Sets `LAMDYN_SOURCE_HASH`: the FNV-1a 64 hash of the sources of every crate whose results
//! `lamdyn run` caches (src/cache.rs), path and bytes of each file in order. The cache's keys
//! hold it, so an entry written by other code (a build from another commit with the same
//! version number) is never read back as if this code had computed it.

use std::path::{Path, PathBuf};

/// The crates whose code decides a cached result: the EMA, the models, the fits, and this one.
const CACHED_BY: [&str; 8] = [
    "lamdyn-ema",
    "lamdyn-fem",
    "lamdyn-fit",
    "lamdyn-frf",
    "lamdyn-layered",
    "lamdyn-material",
    "lamdyn-uff",
    "lamdyn-pipeline",
];

fn main() {
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let crates = Path::new(&manifest).join("..");
    let mut files = Vec::new();
    for name in CACHED_BY {
        let src = crates.join(name).join("src");
        println!("cargo:rerun-if-changed={}", src.display());
        rust_files(&src, &mut files);
    }
    files.sort();
    let mut hash = Fnv::new();
    for file in &files {
        hash.add(
            file.strip_prefix(&crates)
                .unwrap_or(file)
                .to_string_lossy()
                .as_bytes(),
        );
        hash.add(&std::fs::read(file).unwrap_or_default());
    }
    println!("cargo:rustc-env=LAMDYN_SOURCE_HASH={:016x}", hash.0);
}

/// Every `.rs` file under `dir` (none where it is missing: a packaged crate alone).
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for path in entries.flatten().map(|e| e.path()) {
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// FNV-1a 64 with each piece's length first (as src/cache.rs's keys).
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    fn add(&mut self, data: &[u8]) {
        for b in (data.len() as u64).to_le_bytes().iter().chain(data) {
            self.0 ^= u64::from(*b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}
