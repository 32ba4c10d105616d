use super::common::*;
use lamdyn_material::laminate::{PaperInverseOptions, SandwichStack, paper_inverse};
use lamdyn_material::law::{PaperEq7Law, ViscoelasticLaw};
use lamdyn_material::sandwich::exact_inverse;
use lamdyn_testkit::rel_err_f64;
use std::f64::consts::PI;

#[test]
fn paper_roof_example_runs_and_matches_the_library() {
    let (code, out, err) = lamdyn(&["core", "--example", "paper-roof", "--csv"]);
    assert_eq!(code, 0, "{err}");
    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 16, "5..80 Hz by 5 Hz");
    let stack = SandwichStack::paper_roof();
    let law = PaperEq7Law::paper_table2();
    for r in &rows {
        let f = num(r, "f_hz");
        let w = 2.0 * PI * f;
        let e = law.modulus(w);
        let paper = paper_inverse(&stack, w, e, &PaperInverseOptions::default()).unwrap();
        let exact = exact_inverse(&stack, w, e, Default::default()).unwrap();
        // CSV numbers are printed in their shortest round-trip form: equality is exact.
        assert_eq!(num(r, "g_paper_storage_pa"), paper.storage_pa());
        assert_eq!(num(r, "g_exact_storage_pa"), exact.storage_pa());
        assert_eq!(num(r, "phi_abs"), paper.phi.norm());
        assert_eq!(
            r["within_phi_limit"],
            if paper.phi.norm() <= 0.1 { "yes" } else { "no" }
        );
    }
    assert!(err.contains("|phi| > 0.1 at 9 of 16 lines"), "{err}");
    assert!(err.contains("fails the Kramers-Kronig check"), "{err}");
}

#[test]
fn text_output_states_conventions() {
    let (code, out, _) = lamdyn(&["core", "--example", "paper-roof"]);
    assert_eq!(code, 0);
    for needle in [
        "omega = 2 pi f in rad/s",
        "paper inverse (eqs. 35, 40, 41)",
        "G'_exact",
        "[MPa]",
        "KK_paper",
    ] {
        assert!(out.contains(needle), "missing {needle:?} in\n{out}");
    }
}

#[test]
fn json_output_parses_and_carries_details() {
    let (code, out, _) = lamdyn(&[
        "core",
        "--example",
        "paper-roof",
        "--json",
        "--freq-hz",
        "15.75,24.75,42.5",
    ]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["command"], "core");
    assert_eq!(v["rows"].as_array().unwrap().len(), 3);
    assert_eq!(v["details"][0]["freq_hz"], 15.75);
    assert!(
        v["details"][2]["paper"]["core_shear_pa"]
            .as_array()
            .unwrap()
            .len()
            == 2
    );
    assert!(v["details"][0]["paper_error"].is_null());
}

/// A CSV table of E*(f) gives the same cores as the same law given as --eq7.
#[test]
fn table_input_equals_eq7_input() {
    let dir = temp_dir("core-table");
    let law = PaperEq7Law::paper_table2();
    let mut csv = String::from("# the paper's Table 2 law sampled\nf_hz,e_storage_pa,e_loss_pa\n");
    for f in [10.0, 20.0, 30.0] {
        let e = law.modulus(2.0 * PI * f);
        csv += &format!("{f},{},{}\n", e.re, e.im);
    }
    let table = dir.join("e.csv");
    std::fs::write(&table, csv).unwrap();
    let stack = example("roof-stack.toml");
    let (c1, a, e1) = lamdyn(&[
        "core",
        "--stack",
        &stack,
        "--table",
        table.to_str().unwrap(),
        "--csv",
    ]);
    let (c2, b, _) = lamdyn(&[
        "core",
        "--stack",
        &stack,
        "--eq7",
        "67.45e9,0.686e-3,4.295e-3,1.617e6",
        "--freq-hz",
        "10,20,30",
        "--csv",
    ]);
    assert_eq!((c1, c2), (0, 0), "{e1}");
    let (a, b) = (csv_rows(&a), csv_rows(&b));
    for (x, y) in a.iter().zip(&b) {
        for key in [
            "g_paper_storage_pa",
            "g_exact_storage_pa",
            "g_exact_loss_factor",
        ] {
            assert!(rel_err_f64(num(x, key), num(y, key)) < 1e-14, "{key}");
        }
    }
}

#[test]
fn every_paper_option_is_reachable() {
    let stack = example("roof-stack.toml");
    for (flag, value, label) in [
        ("--core-formula", "eq43", "eqs. 35, 40, 43"),
        ("--core-formula", "eq26", "eqs. 35, 40, 26"),
        ("--glass-shear", "include", "eqs. 35, 39, 41"),
        ("--bending", "full", "eqs. 14, 40, 41"),
        ("--kinematics", "plate", "eqs. 35, 40, 41, plate"),
    ] {
        let (code, out, err) = lamdyn(&[
            "core",
            "--stack",
            &stack,
            "--eq7",
            "67.45e9,0.686e-3,4.295e-3,1.617e6",
            flag,
            value,
        ]);
        assert_eq!(code, 0, "{flag} {value}: {err}");
        assert!(out.contains(label), "{flag} {value}: no {label:?}");
    }
}

#[test]
fn lines_without_solution_exit_1_and_say_why() {
    let dir = temp_dir("core-nosol");
    let table = dir.join("e.csv");
    std::fs::write(
        &table,
        "f_hz,e_storage_pa,loss_factor\n10,60e9,0.003\n20,75e9,0.003\n30,59e9,0.003\n",
    )
    .unwrap();
    let (code, out, err) = lamdyn(&[
        "core",
        "--stack",
        &example("roof-stack.toml"),
        "--table",
        table.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("no core modulus at 20.0000 Hz"), "{err}");
    assert!(
        out.lines()
            .any(|l| l.trim_start().starts_with("20.00") && l.contains(" - ")),
        "{out}"
    );
}

#[test]
fn bad_inputs_name_what_is_wrong() {
    let stack = example("roof-stack.toml");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["core"],
            "give --example paper-roof, or --stack FILE with --eq7 or --table",
        ),
        (
            vec!["core", "--stack", "/nonexistent/s.toml", "--eq7", "1,2,3,4"],
            "cannot read '/nonexistent/s.toml'",
        ),
        (
            vec!["core", "--stack", &stack, "--eq7", "67e9,2e-3,1e-3,1e6"],
            "invalid --eq7: paper eq. 7 law: t0_s = 0.001 must exceed mu_s = 0.002",
        ),
        (
            vec!["core", "--stack", &stack, "--eq7", "-67e9,1e-3,2e-3,1e6"],
            "e0_pa = -67000000000 must be positive",
        ),
        (
            vec!["core", "--example", "paper-roof", "--f-min-hz", "0"],
            "--f-min-hz = 0 must be positive",
        ),
        (
            vec!["core", "--example", "paper-roof", "--f-max-hz", "1"],
            "--f-max-hz = 1 must not be below --f-min-hz = 5",
        ),
        (
            vec!["core", "--example", "paper-roof", "--f-step-hz", "-1"],
            "--f-step-hz = -1 must be positive",
        ),
        (
            vec!["core", "--example", "paper-roof", "--f-step-hz", "1e-9"],
            "at most 1000000",
        ),
        (
            vec!["core", "--example", "paper-roof", "--freq-hz", "20,10"],
            "--freq-hz: frequencies must increase, got 20 then 10",
        ),
        (
            vec!["core", "--example", "paper-roof", "--kk-tolerance", "2"],
            "--kk-tolerance = 2 must lie in [0, 1)",
        ),
        (
            vec!["core", "--example", "paper-roof", "--f-min-hz", "NaN"],
            "'NaN' is not a finite number",
        ),
        (
            vec!["core", "--eq7", "1,2,3"],
            "expected four numbers E0_PA,MU_S,T0_S,C_PA_S, got 3",
        ),
    ];
    for (args, want) in cases {
        let (code, _, err) = lamdyn(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: want {want:?} in {err:?}");
    }
}

#[test]
fn bad_files_name_file_line_and_field() {
    let dir = temp_dir("core-badfiles");
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let roof = std::fs::read_to_string(example("roof-stack.toml")).unwrap();
    let eq7 = "67.45e9,0.686e-3,4.295e-3,1.617e6";
    let cases: Vec<(Vec<String>, String)> = vec![
        (
            vec![
                write(
                    "unknown.toml",
                    &roof.replacen("poisson = 0.22", "poisson = 0.22\nyoung_gpa = 70", 1),
                ),
                eq7.into(),
            ],
            "unknown field `young_gpa`".into(),
        ),
        (
            vec![
                write(
                    "zero.toml",
                    &roof.replacen("thickness_m = 0.42e-3", "thickness_m = 0.0", 1),
                ),
                eq7.into(),
            ],
            "layers[1] ('PVB'): thickness_m = 0 must be positive".into(),
        ),
        (
            vec![
                write("two.toml", roof.rsplit_once("[[layers]]").unwrap().0),
                eq7.into(),
            ],
            "the core inverse needs three layers (face, core, face), got 2".into(),
        ),
        (
            vec![write("broken.toml", "[[layers]\n"), eq7.into()],
            "error in '".into(),
        ),
    ];
    for (args, want) in cases {
        let (code, _, err) = lamdyn(&["core", "--stack", &args[0], "--eq7", &args[1]]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(&want), "want {want:?} in {err:?}");
    }
    let stack = example("roof-stack.toml");
    let tables = [
        (
            "nan.csv",
            "f_hz,e_storage_pa,loss_factor\n10,60e9,nan\n",
            "line 2: column 'loss_factor': 'nan' is not a finite number",
        ),
        (
            "order.csv",
            "f_hz,e_storage_pa,loss_factor\n10,60e9,0.01\n5,60e9,0.01\n",
            "line 3: column 'f_hz' must increase (5 after 10)",
        ),
        (
            "cols.csv",
            "f_hz,e_storage\n10,60e9\n",
            "no column 'e_storage_pa'; the header has: f_hz,e_storage",
        ),
        (
            "neg.csv",
            "f_hz,e_storage_pa,loss_factor\n10,-60e9,0.01\n",
            "line 2: e_storage_pa = -60000000000 must be positive",
        ),
    ];
    for (name, text, want) in tables {
        let (code, _, err) = lamdyn(&["core", "--stack", &stack, "--table", &write(name, text)]);
        assert_eq!(code, 2, "{name}: {err}");
        assert!(err.contains(want), "{name}: want {want:?} in {err:?}");
    }
}
