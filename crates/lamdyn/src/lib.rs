//! # lamdyn (command-line interface)
//!
//! Glue only: parse arguments ([`cli`]), validate them into a run configuration, call the
//! library crates, render tables ([`table`]). Subcommands, one per pipeline stage:
//!
//! | command | what | module |
//! |---|---|---|
//! | `lamdyn laminate` | stack → B_eq, K_eq, φ, E_eff against frequency | [`cmd::laminate`] |
//! | `lamdyn core` | E_eff*(f) + stack → core G'(f), η(f) by two inverses | [`cmd::core`] |
//! | `lamdyn e756` | beam resonances → modulus and loss factor per mode | [`cmd::e756`] |
//! | `lamdyn modes` | shell model → natural frequencies, shapes, Sturm check | [`cmd::modes`] |
//! | `lamdyn fit` | measured FRFs + FE model → E*(f) law with intervals, Table 3 | [`cmd::fit`] |
//! | `lamdyn ema` | measured FRFs → stabilization diagram, modes, damping, shapes | [`cmd::ema`] |
//! | `lamdyn simulate` | virtual impact test on the layered model → FRFs, hits, true core | [`cmd::simulate`] |
//! | `lamdyn run` | job file → EMA → fit → both inverses → Monte Carlo → HTML report | [`cmd::run`], [`lamdyn_pipeline`] |
//! | `lamdyn demo` | virtual roof → simulated impact test → `lamdyn run` → errors against the truth | [`cmd::demo`], [`lamdyn_pipeline::demo`] |
//! | `lamdyn uff info\|convert` | list a UFF file; convert to CSV/JSON or ASCII ↔ binary | [`cmd::uff`] |
//!
//! Exit codes: 0 done; 1 done but a check failed (lines without a solution); 2 error. Errors
//! print as `lamdyn: {error}` with their causes; a closed pipe on stdout exits 0.

pub mod cli;
pub mod cmd;
mod examples;
mod grid;
mod progress;
pub mod table;

use clap::Parser;
use std::ffi::OsString;
use std::io::Write;

/// How a finished command went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Everything computed.
    Done,
    /// Finished, but some check failed (reported on stderr); exit code 1.
    ChecksFailed,
}

/// Runs the CLI on `args` (program name first), writing results to `out` and messages to `err`.
/// Returns the process exit code. Never panics on user input.
///
/// Every command gives the same bits on any thread count: faer's global parallelism is set to
/// sequential here, at each call and not only in `main`, so that commands run in one process
/// (the integration tests run many at once) all see the same setting
/// ([`lamdyn_pipeline::same_bits_on_any_thread_count`]). The CI once saw `lamdyn fit` differ
/// in its last digit between two in-process calls because a `run` command beside it had
/// switched faer to sequential between them.
pub fn run<I, T>(args: I, out: &mut dyn Write, err: &mut dyn Write) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    lamdyn_pipeline::same_bits_on_any_thread_count();
    let cli = match cli::Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            let text = e.render().to_string();
            let code = e.exit_code();
            let sink: &mut dyn Write = if code == 0 { out } else { err };
            let _ = write!(sink, "{text}");
            return if code == 0 { 0 } else { 2 };
        }
    };
    match cmd::dispatch(cli, out, err) {
        Ok(Outcome::Done) => 0,
        Ok(Outcome::ChecksFailed) => 1,
        Err(e) if is_broken_pipe(&e) => 0,
        Err(e) => {
            let _ = writeln!(err, "lamdyn: {e:#}");
            2
        }
    }
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
