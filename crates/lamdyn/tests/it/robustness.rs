use super::common::*;
use proptest::prelude::*;

/// Every command's --help states its units.
#[test]
fn help_states_units() {
    for (cmd, needles) in [
        ("core", vec!["Hz", "Pa", "rad/s", "E0_PA,MU_S,T0_S,C_PA_S"]),
        ("laminate", vec!["Hz", "SI"]),
        ("e756", vec!["Pa", "length_m", "half_power_bandwidth_hz"]),
        ("modes", vec!["SI", "NXxNY", "ParaView", "MAC"]),
    ] {
        let (code, out, _) = lamdyn(&[cmd, "--help"]);
        assert_eq!(code, 0);
        for n in needles {
            assert!(out.contains(n), "{cmd} --help lacks {n:?}");
        }
    }
}

fn vocabulary() -> Vec<String> {
    let mut v: Vec<String> = [
        "core",
        "laminate",
        "e756",
        "uniform",
        "oberst",
        "sandwich",
        "--example",
        "paper-roof",
        "--stack",
        "--eq7",
        "--table",
        "--freq-hz",
        "--f-min-hz",
        "--f-max-hz",
        "--f-step-hz",
        "--core-formula",
        "eq26",
        "eq43",
        "--glass-shear",
        "include",
        "--bending",
        "full",
        "--kinematics",
        "plate",
        "--kk-tolerance",
        "--json",
        "--csv",
        "--beam",
        "--data",
        "--forward",
        "--modulus-pa",
        "--loss-factor",
        "--modes",
        "--exact",
        "0",
        "-1",
        "1e308",
        "NaN",
        "inf",
        "1e-300",
        "5",
        "80",
        "1,2,3,4",
        "67.45e9,0.686e-3,4.295e-3,1.617e6",
        "0,0,0,0",
        "1e9,0,1e-300,1e9",
        "10,5",
        "",
        ",",
        "-",
        "--",
        "x",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for f in [
        "roof-stack.toml",
        "roof-stack-wlf.toml",
        "e756/sandwich-beam.toml",
        "e756/sandwich-data.csv",
        "e756/oberst-data.csv",
        "e756/uniform-beam.toml",
    ] {
        v.push(example(f));
    }
    v
}

proptest! {
    #![proptest_config(lamdyn_testkit::proptest_config(400))]

    /// No command line panics: every outcome is an exit code 0, 1 or 2.
    #[test]
    fn no_command_line_panics(picks in prop::collection::vec(0usize..1000, 0..9)) {
        let vocab = vocabulary();
        let args: Vec<&str> = picks.iter().map(|i| vocab[i % vocab.len()].as_str()).collect();
        let result = std::panic::catch_unwind(|| lamdyn(&args));
        prop_assert!(result.is_ok(), "panic on {:?}", args);
        let (code, _, _) = result.unwrap();
        prop_assert!(code <= 2);
    }
}

/// The real binary: exit codes and the error prefix.
#[test]
fn binary_exit_codes() {
    let bin = env!("CARGO_BIN_EXE_lamdyn");
    let ok = std::process::Command::new(bin)
        .args(["core", "--example", "paper-roof", "--freq-hz", "20"])
        .output()
        .unwrap();
    assert_eq!(ok.status.code(), Some(0));
    let bad = std::process::Command::new(bin)
        .args(["core", "--stack", "/nonexistent.toml", "--eq7", "1,2,3,4"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&bad.stderr).starts_with("lamdyn: cannot read '/nonexistent.toml'")
    );
    let usage = std::process::Command::new(bin)
        .args(["nonsense"])
        .output()
        .unwrap();
    assert_eq!(usage.status.code(), Some(2));
}

/// `--help` printed some defaults twice (in the doc text and by clap). Each
/// option's block of every command's help states its default at most once.
#[test]
fn help_states_each_default_once() {
    let commands: [&[&str]; 12] = [
        &["run"],
        &["demo"],
        &["simulate"],
        &["ema"],
        &["fit"],
        &["modes"],
        &["laminate"],
        &["core"],
        &["e756"],
        &["uff", "info"],
        &["uff", "convert"],
        &["uff", "write"],
    ];
    for cmd in commands {
        let mut args = cmd.to_vec();
        args.push("--help");
        let (code, out, err) = lamdyn(&args);
        if code != 0 && err.contains("unrecognized subcommand") {
            continue;
        }
        assert_eq!(code, 0, "{cmd:?}: {err}");
        let mut block = String::new();
        for line in out.lines().chain(std::iter::once("  -end")) {
            if line.trim_start().starts_with('-') && line.starts_with("  ") {
                assert!(
                    block.matches("[default:").count() <= 1,
                    "{cmd:?}: default twice in\n{block}"
                );
                block.clear();
            }
            block.push_str(line);
            block.push('\n');
        }
    }
}

/// The README says how to put `lamdyn` on the PATH, with a path that holds the
/// binary's package, and does not send readers to files the repository lacks without saying so.
#[test]
fn readme_install_command_names_the_binary_package() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let install = readme
        .lines()
        .find(|l| l.starts_with("cargo install --path "))
        .expect("an install command");
    let path = install["cargo install --path ".len()..]
        .split_whitespace()
        .next()
        .unwrap();
    let manifest = std::fs::read_to_string(root.join(path).join("Cargo.toml")).unwrap();
    assert!(manifest.contains("name = \"lamdyn\""), "{path}");
    // The README names the workplace's reference folder beside the repository; no test reads it.
    if readme.contains("shared/reference/") {
        assert!(readme.contains("not\nredistributed") || readme.contains("not redistributed"));
    }
}

/// Binary input and a huge one-line file given to every command that reads a file: exit 2
/// with a short error (an excerpt of the file at most, never the whole line) and no control
/// byte that would reach the terminal raw.
#[test]
fn binary_and_huge_inputs_get_short_printable_errors() {
    let dir = temp_dir("cli-binary-inputs");
    let mut binary: Vec<u8> = (0..20_000u32).map(|i| (i * 7919 % 251) as u8).collect();
    binary.extend_from_slice(b"\x1b[2J\x07");
    let mut huge = b"\x1b]0;title\x07".to_vec();
    huge.extend(std::iter::repeat_n(b'x', 1_000_000));
    huge.extend_from_slice(b"\x1b[31m\n");
    let channels = dir.join("channels.csv");
    std::fs::write(
        &channels,
        "name,role,x_m,y_m,z_m,dx,dy,dz\na,response,0,0,0,0,0,1\nb,reference,0,0,0,0,0,1\n",
    )
    .unwrap();
    for (name, bytes) in [("binary.dat", &binary), ("huge.txt", &huge)] {
        let file = dir.join(name);
        std::fs::write(&file, bytes).unwrap();
        let f = file.to_str().unwrap();
        let c = channels.to_str().unwrap();
        for args in [
            vec!["run", f],
            vec!["fit", f],
            vec!["modes", f],
            vec!["simulate", f],
            vec!["laminate", f],
            vec!["uff", f],
            vec!["ema", "--frf", f, "--channels", c],
            vec!["ema", "--uff", f],
            vec!["ema", "--frf", f, "--channels", f],
        ] {
            let (code, _, err) = lamdyn(&args);
            assert_eq!(code, 2, "{args:?}: {err}");
            assert!(err.len() < 600, "{args:?}: {} bytes", err.len());
            assert!(
                !err.chars().any(|c| c.is_control() && c != '\n'),
                "{args:?}: {err:?}"
            );
        }
    }
}
