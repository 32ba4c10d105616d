//! `lamdyn e756`: ASTM E756-05 reductions per mode, and the forward models that produce test
//! data from material data (`--forward`).

use crate::Outcome;
use crate::cli::{E756Args, E756Config};
use crate::table::{Column, Fmt, Report};
use anyhow::{Context, Result, bail};
use lamdyn_material::e756::{OberstBeam, ReducedModulus, Resonance, SandwichBeam, UniformBeam};
use lamdyn_pipeline::io::{CsvTable, read_toml};
use serde::Deserialize;
use std::io::Write;

/// The beam file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BeamSpec {
    /// Free (clamped-free) length, m.
    length_m: f64,
    /// Base beam thickness H, m.
    thickness_m: f64,
    /// Base beam density, kg/m³.
    density_kg_m3: f64,
    /// Base beam Young's modulus, Pa (oberst/sandwich: taken per mode from f_base_hz if absent).
    young_pa: Option<f64>,
    /// Damping layer (oberst) or core (sandwich).
    layer: Option<LayerSpec>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LayerSpec {
    thickness_m: f64,
    density_kg_m3: f64,
}

/// Runs `lamdyn e756`.
pub fn run(args: &E756Args, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let spec: BeamSpec = read_toml(&args.beam)?;
    let beam_file = args.beam.display().to_string();
    let base = UniformBeam::new(spec.length_m, spec.thickness_m, spec.density_kg_m3)
        .with_context(|| format!("invalid beam '{beam_file}'"))?;
    let layer = || -> Result<&LayerSpec> {
        spec.layer.as_ref().with_context(|| {
            format!(
                "'{beam_file}': the {:?} configuration needs a [layer] table (thickness_m, \
                 density_kg_m3)",
                args.configuration
            )
            .to_lowercase()
        })
    };
    let report = if args.forward {
        forward(args, &spec, base, &beam_file)?
    } else {
        let path = args.data.as_ref().context("--data is required")?;
        let data = CsvTable::read(path)?;
        match args.configuration {
            E756Config::Uniform => uniform(&data, base)?,
            E756Config::Oberst => {
                two_frequency(args, &data, &spec, base, layer()?, "f_composite_hz")?
            }
            E756Config::Sandwich => {
                two_frequency(args, &data, &spec, base, layer()?, "f_sandwich_hz")?
            }
        }
    };
    let mut report = report;
    report.inputs.insert(0, ("beam".into(), beam_file));
    report.write(args.output.format(), out, err)?;
    Ok(Outcome::Done)
}

/// Mode number and loss factor (or half-power bandwidth) columns common to all layouts.
struct Common {
    mode: usize,
    loss: usize,
    bandwidth: bool,
}

fn common(data: &CsvTable) -> Result<Common> {
    let mode = data.require_any(&["mode"])?;
    let loss = data.require_any(&["loss_factor", "half_power_bandwidth_hz"])?;
    Ok(Common {
        mode,
        loss,
        bandwidth: data.find("loss_factor") != Some(loss),
    })
}

/// Reads the mode number of a row: a whole number from 1 to 50.
fn mode_of(data: &CsvTable, line: usize, v: f64) -> Result<usize> {
    if v.fract() != 0.0 || !(1.0..=50.0).contains(&v) {
        bail!(
            "'{}' line {line}: mode = {v} must be a whole number from 1 to 50",
            data.path()
        );
    }
    Ok(v as usize)
}

/// Loss factor of a row: the column itself or bandwidth / frequency.
fn loss_of(c: &Common, v: &[f64], f: f64) -> f64 {
    if c.bandwidth {
        v[c.loss] / f
    } else {
        v[c.loss]
    }
}

fn uniform(data: &CsvTable, base: UniformBeam) -> Result<Report> {
    let f = data.require_any(&["f_hz"])?;
    let c = common(data)?;
    let mut report = Report::new(
        "e756 uniform",
        vec![
            Column::new("mode", "mode", "", Fmt::Fixed(0)),
            Column::new("f_hz", "f", "Hz", Fmt::Fixed(3)),
            Column::new("young_storage_pa", "E", "GPa", Fmt::Fixed(4)).scaled(1e9),
            Column::new("loss_factor", "eta", "", Fmt::Sci(4)),
        ],
    );
    for (line, v) in data.rows() {
        let mode = mode_of(data, *line, v[c.mode])?;
        let r = base
            .reduce(mode, v[f], loss_of(&c, v, v[f]))
            .with_context(|| format!("'{}' line {line}", data.path()))?;
        report.row(vec![
            (mode as f64).into(),
            v[f].into(),
            r.storage_pa.into(),
            r.loss_factor.into(),
        ]);
    }
    report.notes.push(
        "E = 12 rho l^4 f^2 / (H^2 C_n^2), eta = measured modal loss factor (ASTM E756-05).".into(),
    );
    Ok(report)
}

fn two_frequency(
    args: &E756Args,
    data: &CsvTable,
    spec: &BeamSpec,
    base: UniformBeam,
    layer: &LayerSpec,
    composite_col: &str,
) -> Result<Report> {
    let fb = data.require_any(&["f_base_hz"])?;
    let fc = data.require_any(&[composite_col])?;
    let c = common(data)?;
    let sandwich = args.configuration == E756Config::Sandwich;
    let (key, header) = if sandwich {
        ("core_shear_storage_pa", "G1")
    } else {
        ("layer_young_storage_pa", "E1")
    };
    let mut report = Report::new(
        if sandwich {
            "e756 sandwich"
        } else {
            "e756 oberst"
        },
        vec![
            Column::new("mode", "mode", "", Fmt::Fixed(0)),
            Column::new("f_base_hz", "f_base", "Hz", Fmt::Fixed(3)),
            Column::new(
                if sandwich {
                    "f_sandwich_hz"
                } else {
                    "f_composite_hz"
                },
                if sandwich {
                    "f_sandwich"
                } else {
                    "f_composite"
                },
                "Hz",
                Fmt::Fixed(3),
            ),
            Column::new("base_young_pa", "E_base", "GPa", Fmt::Fixed(3)).scaled(1e9),
            Column::new(key, header, "MPa", Fmt::Fixed(4)).scaled(1e6),
            Column::new("loss_factor", "eta1", "", Fmt::Fixed(4)),
        ],
    );
    for (line, v) in data.rows() {
        let at = || format!("'{}' line {line}", data.path());
        let mode = mode_of(data, *line, v[c.mode])?;
        // Base modulus: given, or from the bare beam's own resonance of this mode.
        let e = match spec.young_pa {
            Some(e) => e,
            None => base.reduce(mode, v[fb], 0.0).with_context(at)?.storage_pa,
        };
        let eta = loss_of(&c, v, v[fc]);
        let r: ReducedModulus = if sandwich {
            SandwichBeam::new(base, e, layer.thickness_m, layer.density_kg_m3)
                .with_context(|| format!("invalid beam '{}'", args.beam.display()))?
                .reduce(mode, v[fb], v[fc], eta)
        } else {
            let b = OberstBeam::new(base, e, layer.thickness_m, layer.density_kg_m3)
                .with_context(|| format!("invalid beam '{}'", args.beam.display()))?;
            if args.exact {
                b.reduce_exact(mode, v[fb], v[fc], eta)
            } else {
                b.reduce(mode, v[fb], v[fc], eta)
            }
        }
        .with_context(at)?;
        report.row(vec![
            (mode as f64).into(),
            v[fb].into(),
            v[fc].into(),
            e.into(),
            r.storage_pa.into(),
            r.loss_factor.into(),
        ]);
    }
    report.notes.push(if sandwich {
        "G1, eta1: ASTM E756-05 sandwich-beam equations (the exact inverse of symmetric \
         RKU)."
            .to_string()
    } else if args.exact {
        "E1, eta1: exact complex solution of the Oberst quadratic.".to_string()
    } else {
        "E1, eta1: ASTM E756-05 Oberst equations (eta1 first order in the loss; --exact for the \
         complex solution)."
            .to_string()
    });
    Ok(report)
}

/// `--forward`: resonances of a material on this beam, in the `--data` layout.
fn forward(args: &E756Args, spec: &BeamSpec, base: UniformBeam, beam_file: &str) -> Result<Report> {
    let (m, eta) = (
        args.modulus_pa.unwrap_or_default(),
        args.loss_factor.unwrap_or_default(),
    );
    let layer = |name: &str| {
        spec.layer.as_ref().with_context(|| {
            format!(
                "'{beam_file}': the {name} configuration needs \
                 a [layer] table (thickness_m, density_kg_m3)"
            )
        })
    };
    let e_base = || {
        spec.young_pa
            .with_context(|| format!("'{beam_file}': --forward needs the base beam's young_pa"))
    };
    let mode_col = Column::new("mode", "mode", "", Fmt::Fixed(0));
    let hz = |k: &'static str, h: &'static str| Column::new(k, h, "Hz", Fmt::Fixed(6));
    let loss_col = Column::new("loss_factor", "loss_factor", "", Fmt::Sci(9));
    let mut report;
    match args.configuration {
        E756Config::Uniform => {
            report = Report::new(
                "e756 uniform forward",
                vec![mode_col, hz("f_hz", "f_hz"), loss_col],
            );
            for n in 1..=args.modes as usize {
                let r = base.resonance(n, m, eta)?;
                report.row(vec![
                    (n as f64).into(),
                    r.freq_hz.into(),
                    r.loss_factor.into(),
                ]);
            }
        }
        E756Config::Oberst | E756Config::Sandwich => {
            let sandwich = args.configuration == E756Config::Sandwich;
            let l = layer(if sandwich { "sandwich" } else { "oberst" })?;
            let e = e_base()?;
            report = Report::new(
                if sandwich {
                    "e756 sandwich forward"
                } else {
                    "e756 oberst forward"
                },
                vec![
                    mode_col,
                    hz("f_base_hz", "f_base_hz"),
                    if sandwich {
                        hz("f_sandwich_hz", "f_sandwich_hz")
                    } else {
                        hz("f_composite_hz", "f_composite_hz")
                    },
                    loss_col,
                ],
            );
            for n in 1..=args.modes as usize {
                let (b, c): (Resonance, Resonance) = if sandwich {
                    SandwichBeam::new(base, e, l.thickness_m, l.density_kg_m3)?
                        .resonances(n, m, eta)?
                } else {
                    OberstBeam::new(base, e, l.thickness_m, l.density_kg_m3)?
                        .resonances(n, m, eta)?
                };
                report.row(vec![
                    (n as f64).into(),
                    b.freq_hz.into(),
                    c.freq_hz.into(),
                    c.loss_factor.into(),
                ]);
            }
        }
    }
    report.input("material", format!("modulus {m} Pa, loss factor {eta}"));
    report.notes.push(
        "Forward model: resonance f = sqrt(Re lambda)/(2 pi), loss factor Im lambda \
         / Re lambda, clamped-free wavenumbers."
            .into(),
    );
    Ok(report)
}
