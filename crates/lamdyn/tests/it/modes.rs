use super::common::*;
use lamdyn_testkit::rel_err_f64;

#[test]
fn paper_plate_example_gives_the_flat_plate_modes() {
    let (code, out, err) = lamdyn(&[
        "modes",
        "--example",
        "paper-plate",
        "--elements",
        "20x20",
        "--modes",
        "9",
        "--csv",
    ]);
    assert_eq!(code, 0, "{err}");
    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 9);
    assert!(rows[..6].iter().all(|r| r["rigid"] == "yes"));
    // 20 x 20 MITC4 against the Reissner-Mindlin reference 16.06997 Hz: within 0.5 %.
    assert!(
        rel_err_f64(num(&rows[6], "freq_hz"), 16.06997) < 5e-3,
        "{}",
        rows[6]["freq_hz"]
    );
    assert!(rows.iter().all(|r| num(r, "residual") < 1e-12));
}

#[test]
fn text_output_reports_the_checks() {
    let (code, out, _) = lamdyn(&[
        "modes",
        "--example",
        "paper-roof-curved",
        "--elements",
        "16x16",
        "--modes",
        "10",
    ]);
    assert_eq!(code, 0);
    for needle in [
        "Sturm check",
        "none missed",
        "MITC4",
        "modal mass",
        "[Hz]",
        "total mass",
    ] {
        assert!(out.contains(needle), "missing {needle:?} in\n{out}");
    }
}

#[test]
fn model_file_with_supports_vtu_json_and_compare() {
    let dir = temp_dir("modes-files");
    let model = dir.join("m.toml");
    std::fs::write(
        &model,
        "[mesh]\nkind = \"rectangle\"\nlength_x_m = 0.5\nlength_y_m = 0.4\nelements_x = \
         10\nelements_y = 8\n\n[material]\nyoung_pa = 70e9\npoisson = 0.22\ndensity_kg_m3 = \
         2500.0\nthickness_m = 0.004\n\n[[supports]]\npoint_m = [0.0, 0.0, \
         0.0]\ntranslational_n_per_m = [0.0, 0.0, 1e4]\n\n[solver]\nmodes = 8\n",
    )
    .unwrap();
    let vtu = dir.join("m.vtu");
    let shapes = dir.join("m.json");
    let (code, _, err) = lamdyn(&[
        "modes",
        model.to_str().unwrap(),
        "--vtu",
        vtu.to_str().unwrap(),
        "--shapes-json",
        shapes.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        std::fs::read_to_string(&vtu)
            .unwrap()
            .contains("NumberOfPoints=\"99\"")
    );
    let (code, out, err) = lamdyn(&[
        "modes",
        model.to_str().unwrap(),
        "--compare",
        shapes.to_str().unwrap(),
        "--csv",
    ]);
    assert_eq!(code, 0, "{err}");
    for r in csv_rows(&out).iter().filter(|r| r["rigid"] != "yes") {
        assert!(num(r, "compare_mac") > 0.999999, "{r:?}");
        assert_eq!(r["compare_mode"], r["mode"]);
    }
}

#[test]
fn gmsh_model_relative_to_the_model_file() {
    let dir = temp_dir("modes-gmsh");
    let fixture = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../lamdyn-fem/testdata/gmsh/plate-v41.msh");
    std::fs::copy(fixture, dir.join("plate.msh")).unwrap();
    let model = dir.join("m.toml");
    std::fs::write(
        &model,
        "[mesh]\nkind = \"gmsh\"\nfile = \"plate.msh\"\n\n[material]\nyoung_pa \
         = 70e9\npoisson = 0.22\ndensity_kg_m3 = 2500.0\nthickness_m = \
         0.003\n\n[solver]\nmodes = 8\n",
    )
    .unwrap();
    let (code, out, err) = lamdyn(&["modes", model.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("35 nodes, 24 MITC4 elements"), "{out}");
    // The file holds 4-node quadrilaterals: MITC9 is refused with the Gmsh setting that helps.
    std::fs::write(
        &model,
        "[mesh]\nkind = \"gmsh\"\nfile = \"plate.msh\"\nelement = \
         \"mitc9\"\n\n[material]\nyoung_pa = 70e9\npoisson = \
         0.22\ndensity_kg_m3 = 2500.0\nthickness_m = 0.003\n",
    )
    .unwrap();
    let (code, _, err) = lamdyn(&["modes", model.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("Mesh.ElementOrder = 2"), "{err}");
    let (code, _, err) = lamdyn(&["modes", model.to_str().unwrap(), "--element", "mitc9"]);
    assert_ne!(code, 0);
    assert!(err.contains("apply to rectangle models"), "{err}");
}

/// The dome on 12 × 12 MITC9 elements with 3 edge layers: 25² nodes, and its first elastic
/// modes within 1e-3 of the extrapolated reference of docs/fem.md (16.22420, 23.22042 Hz).
#[test]
fn mitc9_with_edge_layers_from_the_command_line() {
    let dome = [
        "modes",
        "--example",
        "paper-roof-curved",
        "--element",
        "mitc9",
        "--elements",
        "12x12",
    ];
    let (code, out, err) =
        lamdyn(&[&dome[..], &["--edge-layers", "3", "--modes", "8", "--csv"]].concat());
    assert_eq!(code, 0, "{err}");
    let rows = csv_rows(&out);
    let elastic: Vec<f64> = rows
        .iter()
        .filter(|r| r["rigid"] != "yes")
        .map(|r| num(r, "freq_hz"))
        .collect();
    for (f, want) in elastic.iter().zip([16.22420, 23.22042]) {
        assert!((f / want - 1.0).abs() < 1e-3, "{f} vs {want}");
    }
    let (code, text, err) = lamdyn(&dome);
    assert_eq!(code, 0, "{err}");
    assert!(text.contains("625 nodes, 144 MITC9 elements"), "{text}");
}

#[test]
fn bad_models_name_the_field() {
    let dir = temp_dir("modes-bad");
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let good = "[mesh]\nkind = \"rectangle\"\nlength_x_m = 0.5\nlength_y_m = 0.4\nelements_x = \
                10\nelements_y = 8\n\n[material]\nyoung_pa = 70e9\npoisson = 0.22\ndensity_kg_m3 = \
                2500.0\nthickness_m = 0.004\n";
    let plate = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../lamdyn-fem/testdata/gmsh/plate-v41.msh");
    std::fs::copy(plate, dir.join("plate.msh")).unwrap();
    let cases = [
        // Mm, GPa and a metre mesh read as mm are refused with the unit meant.
        (
            write(
                "mm.toml",
                &good.replace("thickness_m = 0.004", "thickness_m = 4"),
            ),
            "material: thickness_m = 4 is outside [1e-6, 1e-1]: thicknesses are in m",
        ),
        (
            write(
                "gpa.toml",
                &good.replace("young_pa = 70e9", "young_pa = 70"),
            ),
            "70 GPa is 70e9",
        ),
        (
            write(
                "span.toml",
                "[mesh]\nkind = \"gmsh\"\nfile = \"plate.msh\"\nunit = \
                 \"mm\"\n[material]\nyoung_pa = 70e9\npoisson = 0.22\ndensity_kg_m3 = \
                 2500.0\nthickness_m = 0.004\n",
            ),
            "mesh: span = 0.0003 m is outside [5e-3, 1e2]: lengths are in m",
        ),
        (
            write(
                "unknown.toml",
                &good.replace("poisson = 0.22", "poisson = 0.22\nyoungs = 1"),
            ),
            "unknown field `youngs`",
        ),
        (
            write(
                "neg.toml",
                &good.replace("thickness_m = 0.004", "thickness_m = -0.004"),
            ),
            "material: thickness_m = -0.004 must be positive",
        ),
        (
            write(
                "len.toml",
                &good.replace("length_x_m = 0.5", "length_x_m = 0"),
            ),
            "mesh: length_x_m = 0 must be positive",
        ),
        (
            write("kind.toml", &good.replace("\"rectangle\"", "\"circle\"")),
            "unknown variant `circle`",
        ),
        (
            write(
                "msh.toml",
                "[mesh]\nkind = \"gmsh\"\nfile = \"none.msh\"\n[material]\nyoung_pa = \
                 70e9\npoisson = 0.22\ndensity_kg_m3 = 2500.0\nthickness_m = 0.004\n",
            ),
            "none.msh': No such file",
        ),
        (
            write(
                "unit.toml",
                "[mesh]\nkind = \"gmsh\"\nfile = \"none.msh\"\nunit = \
                 \"inch\"\n[material]\nyoung_pa = 70e9\npoisson = 0.22\ndensity_kg_m3 = \
                 2500.0\nthickness_m = 0.004\n",
            ),
            "mesh: unit = inch must be \"m\" or \"mm\"",
        ),
        (
            write(
                "support.toml",
                &format!(
                    "{good}[[supports]]\npoint_m = [3.0, 0.0, 0.0]\ntranslational_n_per_m = [0.0, \
                     0.0, 1.0]\n"
                ),
            ),
            "supports[0]: point_m = [3, 0, 0] must lie on the mesh: nearest node",
        ),
        (
            write("modes.toml", &format!("{good}[solver]\nmodes = 0\n")),
            "modal solver: modes = 0 must lie in 1..",
        ),
    ];
    for (path, want) in cases {
        let (code, _, err) = lamdyn(&["modes", &path]);
        assert_eq!(code, 2, "{path}: {err}");
        assert!(err.contains(want), "want {want:?} in {err:?}");
    }
    let (code, _, err) = lamdyn(&["modes", "--example", "paper-plate", "--elements", "40y40"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("expected NXxNY such as 40x40, got '40y40'"),
        "{err}"
    );
}

/// `--elements 2000x2000` (inside the documented range) aborted with "memory
/// allocation of 10371456288 bytes failed" (rc 134); the memory is estimated first and the
/// model refused with the figure.
#[test]
fn a_mesh_too_large_for_memory_is_refused_with_the_figure() {
    let (code, _, err) = lamdyn(&[
        "modes",
        "--example",
        "paper-plate",
        "--elements",
        "2000x2000",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("GB for a modal solve, more than the"), "{err}");
}

/// The flat paper plate on 6 × 6 MITC9 elements with 2 edge layers.
const FLAT_MITC9_6X6: [&str; 9] = [
    "modes",
    "--example",
    "paper-plate",
    "--element",
    "mitc9",
    "--elements",
    "6x6",
    "--edge-layers",
    "2",
];

/// `--converge`: the flat paper plate on 6 × 6 MITC9 with 2 edge layers refines until its first
/// elastic modes meet 1e-4; their extrapolated frequencies are within 1e-5 of the
/// Reissner-Mindlin reference (method-notes §5) and each estimate covers its true error.
#[test]
fn converge_refines_until_the_tolerance_holds() {
    let (code, out, err) = lamdyn(
        &[
            &FLAT_MITC9_6X6[..],
            &["--modes", "10", "--converge", "1e-4", "--csv"],
        ]
        .concat(),
    );
    assert_eq!(code, 0, "{err}");
    let rows = csv_rows(&out);
    let elastic: Vec<_> = rows.iter().filter(|r| r["rigid"] != "yes").collect();
    assert_eq!(elastic.len(), 4);
    for (r, want) in elastic.iter().zip([16.06997, 22.65761, 27.80974, 39.98957]) {
        let (f, estimate) = (num(r, "freq_hz"), num(r, "error_estimate"));
        assert!(estimate <= 1e-4, "{r:?}");
        assert!((f / want - 1.0).abs() <= estimate + 1e-6, "{r:?} vs {want}");
        assert!(
            (num(r, "extrapolated_hz") / want - 1.0).abs() < 1e-5,
            "{r:?}"
        );
    }
}

/// A cap below what the tolerance needs: exit 1, how far it got; a tolerance below double
/// precision: exit 2, said so; --max-dofs alone is refused by the parser.
#[test]
fn converge_says_how_far_it_got_and_refuses_impossible_tolerances() {
    let base = [&FLAT_MITC9_6X6[..], &["--modes", "8"]].concat();
    let (code, out, err) =
        lamdyn(&[&base[..], &["--converge", "1e-7", "--max-dofs", "10000"]].concat());
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("not converged to 1e-7"), "{err}");
    assert!(err.contains("dof cap"), "{err}");
    assert!(out.contains("est. error"), "{out}");
    let (code, _, err) = lamdyn(&[&base[..], &["--converge", "1e-17"]].concat());
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("below what double precision allows"), "{err}");
    let (code, _, err) = lamdyn(&[&base[..], &["--max-dofs", "1000"]].concat());
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--converge"), "{err}");
}

/// A tolerance the limits cannot reach is said before the expensive meshes: the built-in
/// paper plate (uniform MITC4) leaves its free edges unresolved on the finest mesh the caps
/// allow, so it is refused before any solve (it used to run 6 meshes, about a minute here,
/// and exit 1); the graded MITC9 plate to 1e-9 stops after three meshes with the mode, the
/// projection and the subdivisions it would need.
#[test]
fn converge_says_up_front_when_the_tolerance_is_out_of_reach() {
    let (code, out, err) = lamdyn(&["modes", "--example", "paper-plate", "--converge", "1e-4"]);
    assert_eq!(code, 2, "{err}");
    assert!(out.is_empty(), "{out}");
    assert!(
        err.contains("cannot be met within the limits") && err.contains("edge layers"),
        "{err}"
    );
    let base = [&FLAT_MITC9_6X6[..], &["--modes", "8"]].concat();
    let (code, out, err) = lamdyn(&[&base[..], &["--converge", "1e-9"]].concat());
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("stopped: out of reach: mode"), "{err}");
    assert!(err.contains("after 3 meshes"), "{err}");
    assert!(out.contains("est. error"), "{out}");
}
