//! Lamdyn never destroys what it did not write, checks its outputs and inputs before
//! the work, and trusts no cache entry blindly. Each test failed on the main of 2026-11-23.

use super::common::{lamdyn, run_into, small_demo, temp_dir};
use std::collections::BTreeMap;
use std::path::Path;

/// Every file under `dir` with its bytes (lamdyn's dot-entries left out).
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let name = p.strip_prefix(dir).unwrap().display().to_string();
            if name.starts_with(".lamdyn") || name.contains("/.lamdyn") {
                continue;
            }
            if p.is_dir() {
                stack.push(p);
            } else {
                out.insert(name, std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

/// `lamdyn run job/job.toml --out job` refused at once and deleted nothing (it deleted the job
/// file and the hit files before).
#[test]
fn run_into_the_jobs_own_folder_is_refused_and_deletes_nothing() {
    let dir = temp_dir("safety-jobdir");
    let job = small_demo(&dir);
    let input = job.parent().unwrap();
    let before = snapshot(input);
    for force in [false, true] {
        let force_flag: &[&str] = if force { &["--force"] } else { &[] };
        let (code, _, err) = run_into(&job, input, force_flag);
        if force {
            // Written beside the inputs, none of them touched.
            assert_eq!(code, 0, "{err}");
            assert!(input.join("report.html").is_file());
        } else {
            assert_eq!(code, 2, "{err}");
            assert!(err.contains("holds an input of this run"), "{err}");
            assert!(!err.contains("stage"), "refused only after work: {err}");
        }
        let after = snapshot(input);
        for (name, bytes) in &before {
            assert!(
                after.get(name) == Some(bytes),
                "'{name}' changed or vanished"
            );
        }
    }
}

/// A plain `lamdyn run job.toml` with a `report/` folder holding a user's document: refused;
/// with --force the document stays, and a re-run without --force is still refused.
#[test]
fn a_report_folder_with_a_users_file_is_kept() {
    let dir = temp_dir("safety-report");
    let job = small_demo(&dir);
    let report = job.parent().unwrap().join("report");
    std::fs::create_dir_all(&report).unwrap();
    std::fs::write(report.join("my notes.docx"), b"mine").unwrap();
    let run = |force: bool| {
        let mut a = vec!["run", job.to_str().unwrap(), "--samples", "0"];
        if force {
            a.push("--force");
        }
        lamdyn(&a)
    };
    let (code, _, err) = run(false);
    assert_eq!(code, 2);
    assert!(
        err.contains("holds 1 file(s) lamdyn did not write ('my notes.docx')"),
        "{err}"
    );
    let (code, _, err) = run(true);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        std::fs::read(report.join("my notes.docx")).unwrap(),
        b"mine"
    );
    assert!(report.join("report.html").is_file());
    assert_eq!(run(false).0, 2);
}

/// A re-run into lamdyn's own results folder replaces its files without --force.
#[test]
fn a_rerun_replaces_its_own_results() {
    let dir = temp_dir("safety-rerun");
    let job = small_demo(&dir);
    let out = dir.join("results");
    for _ in 0..2 {
        let (code, _, err) = run_into(&job, &out, &[]);
        assert_eq!(code, 0, "{err}");
    }
    let manifest = std::fs::read_to_string(out.join(".lamdyn-manifest")).unwrap();
    assert!(manifest.lines().any(|l| l == "report.html"), "{manifest}");
}

/// `fit --out`, `ema --out` and `uff convert --to csv` into a folder with a foreign file:
/// refused, the file intact.
#[test]
fn other_commands_keep_foreign_files() {
    let dir = temp_dir("safety-cmds");
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("keep.txt"), b"keep").unwrap();
    let uff = super::common::uff_fixture("ufffiles-jl/dataset58_FRF.unv");
    let o = out.to_str().unwrap();
    let runs: [Vec<&str>; 3] = [
        vec!["fit", "--example", "paper-plate", "--out", o],
        vec!["ema", "--uff", &uff, "--out", o, "--band-hz", "10,400"],
        vec!["uff", "convert", &uff, o, "--to", "csv"],
    ];
    for args in runs {
        let (code, _, err) = lamdyn(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.contains("lamdyn did not write ('keep.txt')"),
            "{args:?}: {err}"
        );
        assert_eq!(std::fs::read(out.join("keep.txt")).unwrap(), b"keep");
    }
}

/// A symlink as the output is written through (the link stays); a FIFO is refused and stays.
#[test]
fn file_outputs_write_through_links_and_refuse_special_files() {
    let dir = temp_dir("safety-links");
    let uff = super::common::uff_fixture("ufffiles-jl/dataset58_FRF.unv");
    let real = dir.join("real.json");
    std::fs::write(&real, b"old").unwrap();
    let link = dir.join("link.json");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    let (code, _, err) = lamdyn(&[
        "uff",
        "convert",
        &uff,
        link.to_str().unwrap(),
        "--to",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert!(std::fs::read_to_string(&real).unwrap().starts_with('{'));
    let fifo = dir.join("fifo");
    assert!(
        std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let (code, _, err) = lamdyn(&[
        "uff",
        "convert",
        &uff,
        fifo.to_str().unwrap(),
        "--to",
        "json",
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("is not a regular file (a FIFO)"), "{err}");
    use std::os::unix::fs::FileTypeExt;
    assert!(
        std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo()
    );
    // Converting a file onto itself would destroy the input.
    let copy = dir.join("in.unv");
    std::fs::copy(&uff, &copy).unwrap();
    let c = copy.to_str().unwrap();
    let (code, _, err) = lamdyn(&["uff", "convert", c, c, "--to", "ascii"]);
    assert_eq!(code, 2);
    assert!(err.contains("is an input of this run"), "{err}");
}

/// Validation before work: a typo in the truth path, an --out under a file, and a sample count
/// beyond the job's limit fail at once, before any stage.
#[test]
fn bad_paths_and_counts_fail_before_any_stage() {
    let dir = temp_dir("safety-early");
    let job = small_demo(&dir);
    let text = std::fs::read_to_string(&job).unwrap();
    let typo = job.with_file_name("typo.toml");
    std::fs::write(&typo, text.replace("truth.csv", "truht.csv")).unwrap();
    let (code, _, err) = lamdyn(&["run", typo.to_str().unwrap(), "--samples", "0"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("truth: cannot read '") && err.contains("truht.csv"),
        "{err}"
    );
    let file = dir.join("a-file");
    std::fs::write(&file, b"").unwrap();
    let under = file.join("report");
    let (code, _, err) = lamdyn(&[
        "run",
        job.to_str().unwrap(),
        "--out",
        under.to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("is not a folder"), "{err}");
    let (code, _, err) = lamdyn(&["run", job.to_str().unwrap(), "--samples", "100000000"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("--samples: 100000000 is more than 100000"),
        "{err}"
    );
    assert!(!err.contains("stage '"), "{err}");
}

/// A bit flipped in a cached modal model is caught: the run recomputes the model, says so,
/// and gives the uncached run's numbers.
#[test]
fn a_damaged_cache_entry_is_recomputed() {
    let dir = temp_dir("safety-cache");
    let job = small_demo(&dir);
    let cache = job.parent().unwrap().join(".lamdyn-cache");
    let run = || {
        let out = dir.join("r");
        let (code, text, err) = run_into(&job, &out, &["--json"]);
        assert_eq!(code, 0, "{err}");
        (
            serde_json::from_str::<serde_json::Value>(&text).unwrap(),
            err,
        )
    };
    let (clean, _) = run();
    let model = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("model-")
        })
        .expect("a cached model");
    let mut bytes = std::fs::read(&model).unwrap();
    let k = bytes.len() / 2;
    bytes[k] ^= 0x10;
    std::fs::write(&model, bytes).unwrap();
    let (again, err) = run();
    let stages = again["inputs"]["stages"].as_str().unwrap();
    assert!(
        !stages
            .split(", ")
            .any(|s| s.starts_with("model ") && s.ends_with("(cached)")),
        "the damaged model was used: {stages}"
    );
    assert!(
        err.contains("failed its check (checksum mismatch)"),
        "{err}"
    );
    assert_eq!(clean["rows"], again["rows"]);
}
