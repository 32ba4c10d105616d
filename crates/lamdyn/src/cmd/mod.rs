//! The subcommands. Each follows the same flow: validate the arguments into a configuration
//! (files read and checked, units parsed) before any computation, compute, then render a
//! [`crate::table::Report`].

pub mod core;
pub mod demo;
pub mod e756;
pub mod ema;
pub mod fit;
pub mod laminate;
pub mod modes;
pub mod run;
pub mod simulate;
pub mod uff;

use crate::Outcome;
use crate::cli::{Cli, Command, KinematicsArg};
use lamdyn_material::laminate::Kinematics;
use std::io::Write;

/// Runs the parsed command line.
pub fn dispatch(cli: Cli, out: &mut dyn Write, err: &mut dyn Write) -> anyhow::Result<Outcome> {
    match cli.command {
        Command::Laminate(args) => laminate::run(&args, out, err),
        Command::Core(args) => core::run(&args, out, err),
        Command::E756(args) => e756::run(&args, out, err),
        Command::Modes(args) => modes::run(&args, out, err),
        Command::Fit(args) => fit::run(&args, out, err),
        Command::Uff(cmd) => uff::run(&cmd, out, err),
        Command::Ema(args) => ema::run(&args, out, err),
        Command::Simulate(args) => simulate::run(&args, out, err),
        Command::Run(args) => run::run(&args, out, err),
        Command::Demo(args) => demo::run(&args, out, err),
    }
}

/// The material crate's kinematics for a CLI choice; plate kinematics take `poisson` (the faces').
fn kinematics(arg: KinematicsArg, poisson: f64) -> Kinematics {
    match arg {
        KinematicsArg::Beam => Kinematics::Beam,
        KinematicsArg::Plate => Kinematics::Plate { poisson },
    }
}

/// "beam" or "plate (nu = 0.22)".
fn kinematics_label(k: Kinematics) -> String {
    match k {
        Kinematics::Beam => "beam (paper eqs. as written, per unit width)".into(),
        Kinematics::Plate { poisson } => {
            format!("plate in cylindrical bending (E_eff for nu = {poisson})")
        }
    }
}
