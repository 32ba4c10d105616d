use lamdyn_material::laminate::*;
use lamdyn_material::law::{FractionalZener, ViscoelasticLaw};
use lamdyn_testkit::assert_rel;
use std::f64::consts::PI;

const ROOF: &str = r#"
surface_density_kg_m2 = 10.40

[[layers]]
name = "glass"
thickness_m = 1.715e-3
density_kg_m3 = 2500.0
poisson = 0.22
young_pa = 70e9

[[layers]]
name = "PVB"
thickness_m = 0.42e-3
density_kg_m3 = 1070.0
poisson = 0.49
shear_law = { kind = "fractional_zener", g0_pa = 3.504e5, g_inf_pa = 3.062e9, tau_s = 8.23e-9, alpha = 0.675 }

[[layers]]
name = "glass"
thickness_m = 1.715e-3
density_kg_m3 = 2500.0
poisson = 0.22
young_pa = 70e9
"#;

fn parse(text: &str) -> StackSpec {
    toml::from_str(text).unwrap()
}

fn err_of(text: &str) -> String {
    parse(text).to_layer_stack().unwrap_err().to_string()
}

#[test]
fn roof_toml_builds_the_same_stack_as_the_builder() {
    let spec = parse(ROOF);
    let stack = spec.to_layer_stack().unwrap();
    let sandwich = spec.to_sandwich().unwrap();
    assert_eq!(sandwich, SandwichStack::paper_roof());
    let built = SandwichStack::paper_roof()
        .with_core_law(std::sync::Arc::new(
            FractionalZener::sandwich_benchmark_core(),
        ))
        .unwrap();
    let w = 2.0 * PI * 25.0;
    let a = stack.homogenize(w, Kinematics::Beam).unwrap();
    let b = built.homogenize(w, Kinematics::Beam).unwrap();
    assert_rel("E_eff", a.e_eff, b.e_eff, 0.0);
    assert_eq!(
        stack.layers()[1].moduli(w).1,
        FractionalZener::sandwich_benchmark_core().modulus(w)
    );
}

#[test]
fn errors_name_the_layer_and_the_field() {
    let zero = ROOF.replacen("thickness_m = 0.42e-3", "thickness_m = 0.0", 1);
    assert_eq!(
        err_of(&zero),
        "layers[1] ('PVB'): thickness_m = 0 must be positive"
    );
    let no_modulus = ROOF.replacen("young_pa = 70e9\n", "", 1);
    assert_eq!(
        err_of(&no_modulus),
        "layers[0] ('glass'): no modulus: give young_pa, shear_pa, young_law or shear_law"
    );
    let two = ROOF.replacen("young_pa = 70e9\n", "young_pa = 70e9\nshear_pa = 30e9\n", 1);
    assert_eq!(
        err_of(&two),
        "layers[0] ('glass'): give one modulus, got young_pa and shear_pa"
    );
    let negative = ROOF.replacen("young_pa = 70e9", "young_pa = -70e9", 1);
    assert_eq!(
        err_of(&negative),
        "layers[0] ('glass'): young_pa = -70000000000 must be positive"
    );
    let nu = ROOF.replacen("poisson = 0.49", "poisson = 0.5", 1);
    assert_eq!(
        err_of(&nu),
        "layers[1] ('PVB'): poisson = 0.5 must lie in (-1, 0.5)"
    );
    let alpha = ROOF.replacen("alpha = 0.675", "alpha = 1.5", 1);
    assert_eq!(
        err_of(&alpha),
        "layers[1] ('PVB').shear_law: fractional Zener law: alpha = 1.5 must lie in (0, 1)"
    );
    let rho = ROOF.replacen(
        "surface_density_kg_m2 = 10.40",
        "surface_density_kg_m2 = -1",
        1,
    );
    assert_eq!(
        err_of(&rho),
        "stack: surface_density_kg_m2 = -1 must be positive"
    );
}

/// A given surface density that contradicts the layers (here the roof's 10.40 kg/m² written
/// over layers that weigh 5.2 times as much, or in g/m²) is refused by the layered stack and by
/// the sandwich, naming both values; the paper's own 10.40 over 9.02 kg/m² of nominal layers
/// (1.15 times) is accepted.
#[test]
fn a_surface_density_that_contradicts_the_layers_is_refused() {
    assert!(parse(ROOF).to_layer_stack().is_ok());
    assert!(parse(ROOF).to_sandwich().is_ok());
    let thick = ROOF.replace("thickness_m = 1.715e-3", "thickness_m = 10.0e-3");
    for e in [
        err_of(&thick),
        parse(&thick).to_sandwich().unwrap_err().to_string(),
    ] {
        assert!(
            e.contains("surface_density_kg_m2 = 10.4 contradicts the layers")
                && e.contains("sum to 50.4494 kg/m^2 (0.21 times that"),
            "{e}"
        );
    }
    let grams = ROOF.replace(
        "surface_density_kg_m2 = 10.40",
        "surface_density_kg_m2 = 10400",
    );
    assert!(err_of(&grams).contains("check its unit (kg/m^2)"));
}

#[test]
fn unknown_and_missing_keys_are_toml_errors() {
    let unknown = ROOF.replacen("poisson = 0.22", "poisson = 0.22\nyoung_gpa = 70", 1);
    let e = toml::from_str::<StackSpec>(&unknown)
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown field `young_gpa`"), "{e}");
    let missing = ROOF.replacen("density_kg_m3 = 1070.0\n", "", 1);
    let e = toml::from_str::<StackSpec>(&missing)
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing field `density_kg_m3`"), "{e}");
}

#[test]
fn sandwich_spec_errors() {
    let two_layers = parse(ROOF.rsplit_once("[[layers]]").unwrap().0);
    assert_eq!(
        two_layers.to_sandwich().unwrap_err().to_string(),
        "stack: the core inverse needs three layers (face, core, face), got 2"
    );
    let law_face = ROOF.replacen(
        "young_pa = 70e9",
        "young_law = { kind = \"constant\", storage_pa = 70e9 }",
        1,
    );
    assert_eq!(
        parse(&law_face).to_sandwich().unwrap_err().to_string(),
        "layers[0] ('glass'): a face of the inverse must be elastic: give young_pa (and \
         loss_factor)"
    );
    let core_rho = ROOF.replacen("density_kg_m3 = 1070.0", "density_kg_m3 = 0", 1);
    assert_eq!(
        parse(&core_rho).to_sandwich().unwrap_err().to_string(),
        "layers[1] ('PVB'): density_kg_m3 = 0 must be positive"
    );
    // The core's law is the unknown of the inverse and may be omitted.
    let no_core_law = ROOF.replacen(
        "shear_law = \
         { kind = \"fractional_zener\", g0_pa = 3.504e5, g_inf_pa = 3.062e9, tau_s = 8.23e-9, \
         alpha = 0.675 }\n",
        "",
        1,
    );
    assert!(parse(&no_core_law).to_sandwich().is_ok());
}

/// Mm, MPa and g/cm³ written into SI fields are refused with the unit meant.
#[test]
fn units_other_than_si_are_refused() {
    let mm = ROOF.replacen("thickness_m = 0.42e-3", "thickness_m = 0.42", 1);
    assert!(
        err_of(&mm).contains("thicknesses are in m"),
        "{}",
        err_of(&mm)
    );
    let gcm3 = ROOF.replacen("density_kg_m3 = 1070.0", "density_kg_m3 = 1.07", 1);
    assert!(err_of(&gcm3).contains("g/cm^3"), "{}", err_of(&gcm3));
    let gpa = ROOF.replacen("young_pa = 70e9", "young_pa = 70", 1);
    assert!(err_of(&gpa).contains("70 GPa is 70e9"), "{}", err_of(&gpa));
    assert!(parse(&gpa).to_sandwich().is_err());
}

/// The layered inverse's core layers: the middle of three (its modulus ignored), else the
/// layers without `young_pa`; faces and cores checked for SI units with the layer named.
#[test]
fn layered_cores_of_three_and_five_layers() {
    assert_eq!(parse(ROOF).layered_cores().unwrap(), vec![1]);
    let glass =
        "[[layers]]\nthickness_m = 2e-3\ndensity_kg_m3 = 2500.0\npoisson = 0.22\nyoung_pa = 70e9\n";
    let pvb = "[[layers]]\nname = \"PVB\"\nthickness_m = 0.38e-3\ndensity_kg_m3 = 1070.0\npoisson \
               = 0.49\n";
    let five = [glass, pvb, glass, pvb, glass].concat();
    assert_eq!(parse(&five).layered_cores().unwrap(), vec![1, 3]);
    // No core, or no face.
    let faces = [glass, glass, glass, glass].concat();
    let e = parse(&faces).layered_cores().unwrap_err().to_string();
    assert!(
        e.contains("at least one core") && e.contains("4 layers, 0"),
        "{e}"
    );
    let cores = [pvb, pvb].concat();
    let e = parse(&cores).layered_cores().unwrap_err().to_string();
    assert!(e.contains("2 layers, 2 without"), "{e}");
    // A core's thickness in mm, a face's modulus in GPa: the layer and the field named.
    let mm = five.replacen("thickness_m = 0.38e-3", "thickness_m = 0.38", 1);
    let e = parse(&mm).layered_cores().unwrap_err().to_string();
    assert!(
        e.contains("layers[1] ('PVB')") && e.contains("thickness_m"),
        "{e}"
    );
    let gpa = five.replacen("young_pa = 70e9", "young_pa = 70", 1);
    let e = parse(&gpa).layered_cores().unwrap_err().to_string();
    assert!(e.contains("layers[0]") && e.contains("young_pa"), "{e}");
}
