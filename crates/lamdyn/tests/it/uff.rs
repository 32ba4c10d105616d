//! `lamdyn uff info|convert` on the conformance files (fixtures of lamdyn-uff).

use super::common::*;
use std::path::PathBuf;

fn fixture(rel: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../lamdyn-uff/tests/fixtures")
        .join(rel)
        .to_str()
        .unwrap()
        .to_string()
}

#[test]
fn info_lists_datasets_with_lines() {
    let (code, out, err) = lamdyn(&[
        "uff",
        "info",
        &fixture("pyuff/TestLab 161 164 18 15 82.uff"),
        "--csv",
    ]);
    assert_eq!(code, 0, "{err}");
    let rows = csv_rows(&out);
    let numbers: Vec<&str> = rows.iter().map(|r| r["dataset"].as_str()).collect();
    assert_eq!(numbers, ["151", "164", "18", "15", "82", "82", "82"]);
    assert_eq!(rows[1]["line"], "12");
    let (code, out, _) = lamdyn(&[
        "uff",
        "info",
        &fixture("ufffiles-jl/dataset58_case6_binary.unv"),
    ]);
    assert_eq!(code, 0);
    assert!(out.contains("1602 RealDouble points"), "{out}");
}

/// CSV export of the measured FRF, read back by the FRF CSV reader in SI (mobility).
#[test]
fn convert_to_csv_gives_an_frf_set() {
    let dir = temp_dir("uff-csv");
    let out = dir.join("frf");
    let (code, _, err) = lamdyn(&[
        "uff",
        "convert",
        &fixture("ufffiles-jl/dataset58_FRF.unv"),
        out.to_str().unwrap(),
        "--to",
        "csv",
    ]);
    assert_eq!(code, 0, "{err}");
    let channels = std::fs::read_to_string(out.join("channels.csv")).unwrap();
    let frf = std::fs::read_to_string(out.join("frf.csv")).unwrap();
    assert!(frf.starts_with("# quantity = mobility"));
    let (r, f) = lamdyn_frf::csv::parse_channels("channels.csv", &channels).unwrap();
    let set = lamdyn_frf::csv::parse_frf("frf.csv", &frf, r, f).unwrap();
    assert_eq!(set.n_lines(), 1600);
}

/// ASCII → binary → ASCII keeps the values of a double-precision FRF exactly (E20.12 text of
/// the same f64 values).
#[test]
fn ascii_binary_round_trip() {
    let dir = temp_dir("uff-bin");
    let (bin, asc) = (dir.join("b.uff"), dir.join("a.uff"));
    let src = fixture("ufffiles-jl/dataset58_case7_ascii.unv");
    for (from, to, kind) in [
        (src.as_str(), bin.to_str().unwrap(), "binary"),
        (bin.to_str().unwrap(), asc.to_str().unwrap(), "ascii"),
    ] {
        let (code, _, err) = lamdyn(&["uff", "convert", from, to, "--to", kind, "--big-endian"]);
        assert_eq!(code, 0, "{err}");
    }
    let read =
        |p: &str| lamdyn_uff::read_path(std::path::Path::new(p), Default::default()).unwrap();
    let (a, b, c) = (
        read(&src),
        read(bin.to_str().unwrap()),
        read(asc.to_str().unwrap()),
    );
    assert!(b.datasets[0].binary && !c.datasets[0].binary);
    let data = |f: &lamdyn_uff::UffFile| f.functions().next().unwrap().data.clone();
    assert_eq!(data(&a), data(&b));
    assert_eq!(data(&a), data(&c));
}

#[test]
fn bad_files_give_errors_naming_the_line() {
    let dir = temp_dir("uff-bad");
    let text = std::fs::read_to_string(fixture("ufffiles-jl/dataset58_case1_ascii.unv")).unwrap();
    let bad = dir.join("bad.unv");
    std::fs::write(&bad, text.replacen("  1.73331e-04", "  1.7x331e-04", 1)).unwrap();
    let out = dir.join("out.json");
    let (code, _, err) = lamdyn(&[
        "uff",
        "convert",
        bad.to_str().unwrap(),
        out.to_str().unwrap(),
        "--to",
        "json",
    ]);
    assert_eq!(code, 2);
    assert!(
        err.contains("bad.unv' line 14") && err.contains("1.7x331e-04"),
        "{err}"
    );
    assert!(!out.exists(), "no partial output");
    let (code, _, err) = lamdyn(&[
        "uff",
        "convert",
        &fixture("ufffiles-jl/dataset15.unv"),
        out.to_str().unwrap(),
        "--to",
        "csv",
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("no complex FRF"), "{err}");
    let (code, _, err) = lamdyn(&["uff", "info", dir.join("missing.uff").to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("cannot open"), "{err}");
}

#[test]
fn lenient_reads_a_record_cut_short() {
    let dir = temp_dir("uff-lenient");
    let out = dir.join("m.json");
    let f = fixture("pyuff/dataset_milestone_in_header.uff");
    let (code, _, err) = lamdyn(&["uff", "convert", &f, out.to_str().unwrap(), "--to", "json"]);
    assert_eq!(code, 2);
    assert!(err.contains("line 20"), "{err}");
    let (code, _, err) = lamdyn(&[
        "uff",
        "convert",
        &f,
        out.to_str().unwrap(),
        "--to",
        "json",
        "--lenient",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("kept 42"), "{err}");
}

/// `uff info` on a non-UFF binary file dumped its bytes to the terminal; the
/// message says it is not a universal file and shows an escaped excerpt.
#[test]
fn a_binary_file_is_named_not_dumped() {
    let dir = temp_dir("uff-binary");
    let bin = dir.join("photo.jpg");
    let bytes: Vec<u8> = (0..4000u32).map(|i| (i * 7919 % 251) as u8).collect();
    std::fs::write(&bin, bytes).unwrap();
    let (code, out, err) = lamdyn(&["uff", "info", bin.to_str().unwrap()]);
    assert_eq!(code, 2, "{out}");
    assert!(err.contains("line 1: not a universal file"), "{err}");
    assert!(
        err.chars().all(|c| c == '\n' || (' '..='~').contains(&c)),
        "{err:?}"
    );
    assert!(err.len() < 300, "{err}");
}
