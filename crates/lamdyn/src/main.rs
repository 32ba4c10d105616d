//! The `lamdyn` binary: a thin shell around [`lamdyn::run`].
//!
//! Neither stdout nor stderr is locked for the whole program: progress is drawn on stderr from
//! worker threads (rayon), and a lock held by the main thread while it waits for those workers
//! would deadlock them (`lamdyn demo` hung in a terminal). Each write takes the lock
//! for its own duration only.

use std::process::ExitCode;

fn main() -> ExitCode {
    let mut stdout = std::io::stdout();
    let mut stderr = std::io::stderr();
    ExitCode::from(lamdyn::run(std::env::args_os(), &mut stdout, &mut stderr))
}
