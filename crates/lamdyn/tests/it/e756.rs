use super::common::*;
use lamdyn_testkit::rel_err_f64;

/// The example data were made by the forward models (first line of each file); the reductions
/// recover the material to rounding (the sandwich and --exact Oberst reductions are exact
/// inverses; the standard Oberst loss formula is first order).
#[test]
fn example_data_recover_their_material() {
    let cases = [
        ("uniform", vec![], "young_storage_pa", 200e9, 0.001, 1e-12),
        ("sandwich", vec![], "core_shear_storage_pa", 2e6, 0.6, 1e-10),
        (
            "oberst",
            vec!["--exact"],
            "layer_young_storage_pa",
            2e9,
            0.3,
            1e-10,
        ),
    ];
    for (config, extra, key, modulus, eta, tol) in cases {
        let beam = example(&format!("e756/{config}-beam.toml"));
        let data = example(&format!("e756/{config}-data.csv"));
        let mut args = vec!["e756", config, "--beam", &beam, "--data", &data, "--csv"];
        args.extend(extra.iter().copied());
        let (code, out, err) = lamdyn(&args);
        assert_eq!(code, 0, "{config}: {err}");
        let rows = csv_rows(&out);
        assert_eq!(rows.len(), 5);
        for r in rows {
            assert!(
                rel_err_f64(num(&r, key), modulus) < tol,
                "{config}: {}",
                r[key]
            );
            assert!(
                rel_err_f64(num(&r, "loss_factor"), eta) < tol,
                "{config}: {}",
                r["loss_factor"]
            );
        }
    }
}

#[test]
fn standard_oberst_reduction_is_first_order_in_the_loss() {
    let (code, out, _) = lamdyn(&[
        "e756",
        "oberst",
        "--beam",
        &example("e756/oberst-beam.toml"),
        "--data",
        &example("e756/oberst-data.csv"),
        "--csv",
    ]);
    assert_eq!(code, 0);
    for r in csv_rows(&out) {
        let e_err = rel_err_f64(num(&r, "layer_young_storage_pa"), 2e9);
        // eta1 = 0.3: the standard neglects terms of order eta1^2 ~ 0.09 of the loss's effect
        assert!(e_err > 1e-4 && e_err < 0.09 * 0.3, "{e_err}");
    }
}

#[test]
fn bandwidth_column_replaces_loss_factor_and_base_modulus_may_come_from_f_base() {
    let dir = temp_dir("e756-bw");
    let beam = dir.join("beam.toml");
    std::fs::write(
        &beam,
        "length_m = 0.180\nthickness_m = 1.5e-3\ndensity_kg_m3 = \
         7850.0\n[layer]\nthickness_m = 0.25e-3\ndensity_kg_m3 = \
         1100.0\n",
    )
    .unwrap();
    let data = std::fs::read_to_string(example("e756/sandwich-data.csv")).unwrap();
    let rows = csv_rows(&data);
    let mut bw = String::from("mode,f_base_hz,f_sandwich_hz,half_power_bandwidth_hz\n");
    for r in &rows {
        bw += &format!(
            "{},{},{},{}\n",
            r["mode"],
            r["f_base_hz"],
            r["f_sandwich_hz"],
            num(r, "loss_factor") * num(r, "f_sandwich_hz")
        );
    }
    let csv = dir.join("bw.csv");
    std::fs::write(&csv, bw).unwrap();
    let (code, out, err) = lamdyn(&[
        "e756",
        "sandwich",
        "--beam",
        beam.to_str().unwrap(),
        "--data",
        csv.to_str().unwrap(),
        "--csv",
    ]);
    assert_eq!(code, 0, "{err}");
    for r in csv_rows(&out) {
        // E from f_base by the uniform-beam formula equals the 200 GPa of the forward model.
        assert!(rel_err_f64(num(&r, "base_young_pa"), 200e9) < 1e-12);
        assert!(rel_err_f64(num(&r, "core_shear_storage_pa"), 2e6) < 1e-10);
    }
}

#[test]
fn e756_errors() {
    let dir = temp_dir("e756-err");
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let no_layer = write(
        "nolayer.toml",
        "length_m = 0.18\nthickness_m = 1.5e-3\ndensity_kg_m3 = 7850.0\nyoung_pa = 200e9\n",
    );
    let data = example("e756/sandwich-data.csv");
    let (code, _, err) = lamdyn(&["e756", "sandwich", "--beam", &no_layer, "--data", &data]);
    assert_eq!(code, 2);
    assert!(
        err.contains("the sandwich configuration needs a [layer] table"),
        "{err}"
    );
    let frac = write(
        "frac.csv",
        "mode,f_base_hz,f_sandwich_hz,loss_factor\n1.5,37,58,0.2\n",
    );
    let (code, _, err) = lamdyn(&[
        "e756",
        "sandwich",
        "--beam",
        &example("e756/sandwich-beam.toml"),
        "--data",
        &frac,
    ]);
    assert_eq!(code, 2);
    assert!(
        err.contains("line 2: mode = 1.5 must be a whole number from 1 to 50"),
        "{err}"
    );
    let neg = write("neg.csv", "mode,f_hz,loss_factor\n1,-37,0.2\n");
    let (code, _, err) = lamdyn(&[
        "e756",
        "uniform",
        "--beam",
        &example("e756/uniform-beam.toml"),
        "--data",
        &neg,
    ]);
    assert_eq!(code, 2);
    assert!(
        err.contains("line 2: uniform beam: f_hz = -37 must be positive"),
        "{err}"
    );
    let unknown = write(
        "unknown.toml",
        "length_m = 0.18\nthickness_m = 1.5e-3\ndensity_kg_m3 = 7850.0\nlength_mm = 3\n",
    );
    let (code, _, err) = lamdyn(&["e756", "uniform", "--beam", &unknown, "--data", &neg]);
    assert_eq!(code, 2);
    assert!(err.contains("unknown field `length_mm`"), "{err}");
    let zero = write(
        "zero.toml",
        "length_m = 0\nthickness_m = 1.5e-3\ndensity_kg_m3 = 7850.0\n",
    );
    let (code, _, err) = lamdyn(&["e756", "uniform", "--beam", &zero, "--data", &neg]);
    assert_eq!(code, 2);
    assert!(
        err.contains("uniform beam: length_m = 0 must be positive"),
        "{err}"
    );
    let soft = write(
        "soft.csv",
        "mode,f_base_hz,f_sandwich_hz,loss_factor\n1,37.7,20,0.1\n",
    );
    let (code, _, err) = lamdyn(&[
        "e756",
        "sandwich",
        "--beam",
        &example("e756/sandwich-beam.toml"),
        "--data",
        &soft,
    ]);
    assert_eq!(code, 2);
    assert!(
        err.contains("line 2: sandwich reduction, mode 1: A = "),
        "{err}"
    );
}
