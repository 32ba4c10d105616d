//! The UFF reader and writer against the conformance files (tests/fixtures: UFFFiles.jl and
//! pyuff collections, MIT, licences beside them), malformed variants of them, and round trips.

use lamdyn_frf::Quantity;
use lamdyn_uff::d58::{Abscissa, Function58, Ordinate};
use lamdyn_uff::frf::{from_frf_set, to_frf_set};
use lamdyn_uff::{Dataset, Encoding, ReadOptions, UffError, read, read_path, write};
use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn all_files() -> Vec<PathBuf> {
    let mut v = Vec::new();
    for dir in ["ufffiles-jl", "pyuff"] {
        for e in std::fs::read_dir(fixtures().join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.file_name().unwrap() != "LICENSE" {
                v.push(p);
            }
        }
    }
    v.sort();
    v
}

fn read_file(p: &Path) -> lamdyn_uff::UffFile {
    read_path(p, ReadOptions::default()).unwrap()
}

fn function(p: &Path) -> Function58 {
    read_file(p).functions().next().unwrap().clone()
}

/// Every conformance file reads; the one whose record 12 was cut short by hand reads in lenient
/// mode and is an error naming its line otherwise.
#[test]
fn every_conformance_file_reads() {
    let files = all_files();
    assert_eq!(files.len(), 64);
    for p in &files {
        let name = p.file_name().unwrap().to_string_lossy();
        if name == "dataset_milestone_in_header.uff" {
            let e = read_path(p, ReadOptions::default())
                .unwrap_err()
                .to_string();
            assert!(e.contains("line 20") && e.contains("2508876"), "{e}");
            let f = read_path(
                p,
                ReadOptions {
                    lenient_counts: true,
                },
            )
            .unwrap();
            assert_eq!(f.functions().next().unwrap().data.len(), 42);
            assert_eq!(f.notices.len(), 1);
            continue;
        }
        let f = read_path(p, ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert!(!f.datasets.is_empty() || !f.notices.is_empty(), "{name}");
    }
}

/// Values agree to the ASCII file's precision: E13.5 (6 significant digits, half a unit in the
/// last place is 5e-6 relative) for single, E20.12 (5e-13) for double, plus f32 rounding of the
/// binary abscissa (6e-8).
fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-300
}

#[test]
fn ascii_and_binary_pairs_agree_in_all_eight_layouts() {
    let dir = fixtures().join("ufffiles-jl");
    for case in 1..=8 {
        let a = function(&dir.join(format!("dataset58_case{case}_ascii.unv")));
        let b = function(&dir.join(format!("dataset58_case{case}_binary.unv")));
        assert_eq!(a.ordinate_type, b.ordinate_type, "case {case}");
        assert_eq!(a.data.len(), b.data.len(), "case {case}");
        assert!(a.data.len() >= 801);
        let rel = if a.ordinate_type.is_double() {
            5e-13
        } else {
            5e-6
        };
        let (xa, xb) = (a.x(), b.x());
        for (p, q) in xa.iter().zip(&xb) {
            assert!(close(*p, *q, 5e-6 + 6e-8), "case {case}: x {p} vs {q}");
        }
        let pairs: Vec<(f64, f64)> = match (&a.data, &b.data) {
            (Ordinate::Real(u), Ordinate::Real(v)) => {
                u.iter().copied().zip(v.iter().copied()).collect()
            }
            (Ordinate::Complex(u), Ordinate::Complex(v)) => u
                .iter()
                .zip(v)
                .flat_map(|(p, q)| [(p.re, q.re), (p.im, q.im)])
                .collect(),
            _ => panic!("case {case}: kinds differ"),
        };
        for (p, q) in pairs {
            assert!(close(p, q, rel), "case {case}: {p} vs {q}");
        }
        // Layout of the case: cases 2, 4, 6, 8 have an uneven abscissa.
        assert_eq!(
            matches!(a.abscissa, Abscissa::Uneven(_)),
            case % 2 == 0,
            "case {case}"
        );
    }
}

/// The real mobility FRF and its coherence: units from the labels, SI values.
#[test]
fn measured_frf_and_coherence_read_in_si() {
    let dir = fixtures().join("ufffiles-jl");
    let frf = read_file(&dir.join("dataset58_FRF.unv"));
    let set = to_frf_set(&frf).unwrap();
    assert_eq!(set.quantity(), Quantity::Mobility);
    assert_eq!(set.n_lines(), 1600);
    assert_eq!((set.freqs_hz()[1], set.freqs_hz()[1599]), (0.5, 799.5));
    let raw = frf.functions().next().unwrap();
    assert_eq!(raw.axes[1].units, "(m/s)/N");
    let Ordinate::Complex(v) = &raw.data else {
        panic!()
    };
    assert_eq!(set.curve(0, 0)[7], v[7]);
    let coh = function(&dir.join("dataset58_coh.unv"));
    assert_eq!(coh.function_type, 6);
    let Ordinate::Real(c) = &coh.data else {
        panic!("coherence is real")
    };
    assert_eq!(c.len(), 1600);
    assert!(c.iter().all(|x| (0.0..=1.0 + 1e-6).contains(x)));
    // The UTF-8 variant holds the same numbers.
    let utf = read_file(&dir.join("dataset58_FRF_UTF.unv"));
    assert_eq!(utf.functions().next().unwrap().data, raw.data);
}

/// A dataset 164 in millimetres scales an FRF whose numerator has length exponent 1.
#[test]
fn units_164_convert_to_si() {
    let mut f = function(&fixtures().join("ufffiles-jl/dataset58_case3_ascii.unv"));
    f.axes[1] = lamdyn_uff::d58::AxisSpec {
        data_type: 12,
        length_exp: 1,
        force_exp: 0,
        temperature_exp: 0,
        label: "Acceleration".into(),
        units: "mm/s^2".into(),
    };
    f.axes[2] = lamdyn_uff::d58::AxisSpec {
        data_type: 13,
        length_exp: 0,
        force_exp: 1,
        temperature_exp: 0,
        label: "Force".into(),
        units: "N".into(),
    };
    let units = lamdyn_uff::meta::Units164 {
        code: 5,
        description: "MM".into(),
        temperature_mode: 2,
        length: 1e-3,
        force: 1.0,
        temperature: 1.0,
        temperature_offset: 0.0,
    };
    let bytes = write(
        &[
            Dataset::Units(units),
            Dataset::Function(Box::new(f.clone())),
        ],
        Encoding::Ascii,
    )
    .unwrap();
    let set = to_frf_set(&read(bytes.as_slice()).unwrap()).unwrap();
    assert_eq!(set.quantity(), Quantity::Accelerance);
    let Ordinate::Complex(v) = &f.data else {
        panic!()
    };
    assert!(close(set.curve(0, 0)[3].re, v[3].re * 1e-3, 1e-5));
}

#[test]
fn geometry_modal_and_units_datasets() {
    let dir = fixtures().join("ufffiles-jl");
    let f = read_file(&dir.join("dataset151_164_58_55.unv"));
    assert_eq!(f.datasets.len(), 4);
    let Dataset::NodalData(m) = &read_file(&dir.join("dataset55.unv")).datasets[0].dataset else {
        panic!()
    };
    assert!(m.complex && m.analysis_type == 3 && m.values_per_node == 3 && m.nodes.len() == 7);
    assert!((m.frequency_hz().unwrap() - 25.0964 / (2.0 * std::f64::consts::PI)).abs() < 1e-3);
    let Dataset::Units(u) = &read_file(&dir.join("dataset151&164.unv")).datasets[1].dataset else {
        panic!()
    };
    assert_eq!(
        (u.length, u.force, u.temperature_offset),
        (1e3, 1e3, 273.15)
    );
    let Dataset::Elements(e) = &read_file(&dir.join("dataset2412.unv")).datasets[0].dataset else {
        panic!()
    };
    assert_eq!(
        (e[0].nodes.as_slice(), e[2].nodes.len()),
        (&[1, 10, 11, 2][..], 3)
    );
    let Dataset::CoordinateSystems(cs) = &read_file(&dir.join("dataset18.unv")).datasets[0].dataset
    else {
        panic!()
    };
    // SYS1: origin (-2.4, -0.95, 0), x axis towards (-3.4, -0.95, 0) = -x.
    assert_eq!(cs[0].origin, [-2.4, -0.95, 0.0]);
    assert!((cs[0].axes[0][0] + 1.0).abs() < 1e-9);
    let Dataset::TraceLine(t) = &read_file(&dir.join("dataset82.unv")).datasets[0].dataset else {
        panic!()
    };
    assert_eq!(t.nodes.len(), 75);
    let tl = read_file(&fixtures().join("pyuff/TestLab 161 164 18 15 82.uff"));
    assert!(tl.datasets.len() >= 7);
}

/// Malformed files: each error names the line.
#[test]
fn malformed_files_name_the_line() {
    let good = std::fs::read(fixtures().join("ufffiles-jl/dataset58_case1_ascii.unv")).unwrap();
    let text = String::from_utf8(good.clone()).unwrap();
    let check = |bytes: &[u8], needle: &str| {
        let e = read(bytes).unwrap_err();
        assert!(matches!(e, UffError::Syntax { .. }), "{e}");
        assert!(e.to_string().contains(needle), "expected {needle:?} in {e}");
    };
    // Truncated in the middle of record 12.
    check(&good[..good.len() / 2], "truncated");
    // Wrong count in record 7.
    check(
        text.replacen("      1602         1", "      1603         1", 1)
            .as_bytes(),
        "announces 1603 points",
    );
    // A bad number on line 15.
    let mut lines: Vec<&str> = text.lines().collect();
    lines[14] = "  1.73331e-04  1.2.3e-01 -5.45225e-07 -1.32963e-05 -1.37127e-06 -6.95395e-06";
    check(
        lines.join("\n").as_bytes(),
        "line 15: '1.2.3e-01' is not a finite number",
    );
    // A bad ordinate type.
    check(
        text.replacen("         2      1602", "         3      1602", 1)
            .as_bytes(),
        "line 9: record 7: ordinate data type 3",
    );
    // Wrong byte count in a 58b header, both ways.
    let bin = std::fs::read(fixtures().join("ufffiles-jl/dataset58_case1_binary.unv")).unwrap();
    let header = String::from_utf8_lossy(&bin[..200]).to_string();
    let n: String = header
        .lines()
        .nth(1)
        .unwrap()
        .split_whitespace()
        .nth(4)
        .unwrap()
        .into();
    for wrong in [
        n.parse::<usize>().unwrap() - 8,
        n.parse::<usize>().unwrap() + 8,
    ] {
        let mut b = bin.clone();
        let pos = header.find(&format!(" {n} ")).unwrap() + 1;
        let w = format!("{wrong:>width$}", width = n.len());
        b.splice(pos..pos + n.len(), w.bytes());
        let e = read(b.as_slice()).unwrap_err().to_string();
        assert!(e.contains("byte count") || e.contains("file ends"), "{e}");
        assert!(e.starts_with("line "), "{e}");
    }
}

/// Datasets are decoded in parallel, but they are kept in the file's order, and the first
/// error in the file's order is the one reported: a bad number in the first dataset before
/// the truncation of the next.
#[test]
fn datasets_and_errors_keep_the_files_order() {
    let good = std::fs::read(fixtures().join("ufffiles-jl/dataset58_case1_ascii.unv")).unwrap();
    let text = String::from_utf8(good.clone()).unwrap();
    let lines_per_copy = text.lines().count();
    let three = [good.as_slice(), &good, &good].concat();
    let file = read(three.as_slice()).unwrap();
    let at: Vec<usize> = file.datasets.iter().map(|d| d.line).collect();
    assert_eq!(at.len(), 3);
    assert!(
        at[1] == at[0] + lines_per_copy && at[2] == at[1] + lines_per_copy,
        "{at:?}"
    );
    let mut lines: Vec<&str> = text.lines().collect();
    lines[14] = "  1.73331e-04  1.2.3e-01 -5.45225e-07 -1.32963e-05 -1.37127e-06 -6.95395e-06";
    let bad = lines.join("\n") + "\n";
    let both = [bad.as_bytes(), &good[..good.len() / 2]].concat();
    let e = read(both.as_slice()).unwrap_err().to_string();
    assert!(
        e.contains("line 15: '1.2.3e-01' is not a finite number"),
        "{e}"
    );
}

#[test]
fn every_layout_round_trips_in_both_encodings() {
    let dir = fixtures().join("ufffiles-jl");
    for case in 1..=8 {
        let f = function(&dir.join(format!("dataset58_case{case}_binary.unv")));
        for enc in [
            Encoding::Ascii,
            Encoding::Binary {
                little_endian: true,
            },
            Encoding::Binary {
                little_endian: false,
            },
        ] {
            let bytes = write(&[Dataset::Function(Box::new(f.clone()))], enc).unwrap();
            let back = read(bytes.as_slice()).unwrap();
            let g = back.functions().next().unwrap();
            assert_eq!(
                (g.ordinate_type, g.response.clone(), g.axes.clone()),
                (f.ordinate_type, f.response.clone(), f.axes.clone())
            );
            if enc == Encoding::Ascii {
                // E13.5 keeps 6 digits, E20.12 13: exact for values read from single precision
                // only to that precision.
                let rel = if f.ordinate_type.is_double() {
                    5e-13
                } else {
                    5e-6
                };
                let (a, b) = (f.x(), g.x());
                assert!(a.iter().zip(&b).all(|(p, q)| close(*p, *q, 5e-6)));
                let _ = rel;
            } else {
                assert_eq!(g.data, f.data, "case {case} {enc:?}");
                assert_eq!(g.x(), f.x());
            }
        }
    }
}

/// An FRF set goes to UFF 58 and back unchanged (binary: exact; ASCII: E20.12).
#[test]
fn frf_set_round_trip() {
    let file = read_file(&fixtures().join("ufffiles-jl/dataset58_FRF.unv"));
    let set = to_frf_set(&file).unwrap();
    let ds = from_frf_set(&set).unwrap();
    let bin = write(
        &ds,
        Encoding::Binary {
            little_endian: true,
        },
    )
    .unwrap();
    let back = to_frf_set(&read(bin.as_slice()).unwrap()).unwrap();
    assert_eq!(back.data(), set.data());
    assert_eq!(back.freqs_hz(), set.freqs_hz());
    assert_eq!(back.quantity(), set.quantity());
    let ascii = write(&ds, Encoding::Ascii).unwrap();
    let back = to_frf_set(&read(ascii.as_slice()).unwrap()).unwrap();
    for (a, b) in back.data().iter().zip(set.data()) {
        assert!(close(a.re, b.re, 5e-13) && close(a.im, b.im, 5e-13));
    }
}

#[test]
fn listing_streams_headers_only() {
    let p = fixtures().join("pyuff/MPSTD#Set001_2024_10_08_10_27_07.uff");
    let entries =
        lamdyn_uff::list(std::io::BufReader::new(std::fs::File::open(&p).unwrap())).unwrap();
    assert_eq!(entries.len(), 4);
    assert!(
        entries
            .iter()
            .all(|e| e.number == 58 && e.binary && e.supported)
    );
    assert!(
        entries[0].summary.contains("222400"),
        "{}",
        entries[0].summary
    );
    let skipped = lamdyn_uff::list(
        std::fs::read(fixtures().join("ufffiles-jl/unsupported_dataset.unv"))
            .unwrap()
            .as_slice(),
    )
    .unwrap();
    assert!(skipped.iter().any(|e| !e.supported));
}

/// ASCII ↔ binary re-encoding rewrites the 58s and copies every other dataset byte for byte.
#[test]
fn reencoding_keeps_other_datasets_verbatim() {
    let nx = std::fs::read(fixtures().join("pyuff/NX simulation output.uff")).unwrap();
    let (out, _) = lamdyn_uff::reencode(
        nx.as_slice(),
        Encoding::Binary {
            little_endian: true,
        },
        ReadOptions::default(),
    )
    .unwrap();
    let norm = |b: &[u8]| String::from_utf8_lossy(b).replace("\r\n", "\n");
    assert_eq!(norm(&out), norm(&nx));
    let src = std::fs::read(fixtures().join("ufffiles-jl/dataset151_164_58_55.unv")).unwrap();
    let (bin, _) = lamdyn_uff::reencode(
        src.as_slice(),
        Encoding::Binary {
            little_endian: false,
        },
        ReadOptions::default(),
    )
    .unwrap();
    let (back, _) =
        lamdyn_uff::reencode(bin.as_slice(), Encoding::Ascii, ReadOptions::default()).unwrap();
    let (a, b, c) = (
        read(src.as_slice()).unwrap(),
        read(bin.as_slice()).unwrap(),
        read(back.as_slice()).unwrap(),
    );
    assert!(b.datasets.iter().any(|d| d.binary));
    assert_eq!(a.datasets.len(), c.datasets.len());
    // Single-precision data is stored as f32 in 58b: equal after rounding to f32.
    let (fa, fb) = (a.functions().next().unwrap(), b.functions().next().unwrap());
    assert!(!fa.ordinate_type.is_double());
    let (Ordinate::Complex(u), Ordinate::Complex(v)) = (&fa.data, &fb.data) else {
        panic!()
    };
    assert!(
        u.iter()
            .zip(v)
            .all(|(p, q)| p.re as f32 == q.re as f32 && p.im as f32 == q.im as f32)
    );
}

/// Mode shapes with their mesh: a geometry file and a 55 file together give a VTU with the
/// points, cells and one vector field per mode.
#[test]
fn vtu_of_mesh_and_modes() {
    let mut bytes = std::fs::read(
        fixtures().join("pyuff/Artemis export - Geometry RPBC_setup_05_14102016_105117.uff"),
    )
    .unwrap();
    let geo = read(bytes.as_slice()).unwrap();
    let Some(Dataset::Nodes(nodes)) = geo
        .datasets
        .iter()
        .map(|d| &d.dataset)
        .find(|d| matches!(d, Dataset::Nodes(_)))
    else {
        panic!()
    };
    // A real mode on the first three nodes.
    let mode = lamdyn_uff::d55::Modal55 {
        id_lines: [
            "mode 1".into(),
            "NONE".into(),
            "NONE".into(),
            "NONE".into(),
            "NONE".into(),
        ],
        model_type: 1,
        analysis_type: 2,
        data_characteristic: 2,
        specific_data_type: 8,
        complex: false,
        values_per_node: 3,
        ints: vec![1, 1],
        reals: vec![12.5, 1.0, 0.01, 0.0],
        nodes: nodes.nodes[..3]
            .iter()
            .map(|n| lamdyn_uff::d55::NodeValues {
                node: n.label,
                values: vec![num_complex::Complex64::new(0.5, 0.0); 3],
            })
            .collect(),
    };
    bytes.extend(write(&[Dataset::NodalData(Box::new(mode))], Encoding::Ascii).unwrap());
    let vtu = lamdyn_uff::vtu::to_vtu(&read(bytes.as_slice()).unwrap()).unwrap();
    assert!(vtu.contains(&format!("NumberOfPoints=\"{}\"", nodes.nodes.len())));
    assert!(vtu.contains("Name=\"mode_01_12.500Hz\""));
    assert!(vtu.contains("5e-1 5e-1 5e-1"));
}
