//! The `lamdyn` binary: a thin shell around [`lamdyn::run`].

use std::process::ExitCode;

fn main() -> ExitCode {
    let mut stdout = std::io::stdout().lock();
    let mut stderr = std::io::stderr().lock();
    ExitCode::from(lamdyn::run(std::env::args_os(), &mut stdout, &mut stderr))
}
