//! # lamdyn-pipeline: the whole chain as a library
//!
//! From an impact test of a laminated part to its core's complex shear modulus G*(f), one stage
//! after the other, as `lamdyn run` and `lamdyn demo` (and the Python package) run it:
//!
//! | stage | what | module, crate |
//! |---|---|---|
//! | job | the job resolved once: each stage's configuration, defaults applied, model file read | `config` |
//! | measurement | FRFs from CSV/UFF, or H1 from hammer-hit time files (coherence) | [`measurement`], lamdyn-frf, lamdyn-ema |
//! | ema | stabilization diagram, poles, damping, shapes, CMIF (paper §2.1) | lamdyn-ema |
//! | model | the FE model's real modes projected on the channels (paper eqs. 3–4) | lamdyn-fem, lamdyn-fit |
//! | fit | the laminate's E*(ω) so that synthesized FRFs match (eqs. 2–10) | lamdyn-fit |
//! | inverse | G*(f) of the core by the paper's inverse (eqs. 33–45) and the exact one | lamdyn-material |
//! | layered inverse | G* at each EMA pole through a layered solid model (`layered`); an overlapping pair fitted to the FRFs around it | lamdyn-layered |
//! | core law | the core's law fitted to all layered modes with the inputs shared; its band widths and what would narrow them ([`band_widths`]) | lamdyn-fit |
//! | FRF fit | the core's law fitted to the measured FRFs through the layered model, the answer where modes are damped or overlap ([`frf_route`]) | lamdyn-fit, lamdyn-layered |
//! | uncertainty | Monte Carlo over the stack and the fit's covariance ([`uncertainty`]) | here |
//! | report | HTML with figures, CSV/JSON tables ([`report`]) into a results folder ([`output`]) | lamdyn-report |
//!
//! ## The API
//!
//! ```no_run
//! use lamdyn_pipeline::{Job, RunOptions, Silent, OutputDir, run_job, report};
//! # fn main() -> Result<(), lamdyn_pipeline::PipelineError> {
//! let path = std::path::Path::new("job.toml");
//! let job = Job::read(path)?; // every field and file checked, errors name them
//! let out = OutputDir::prepare(std::path::Path::new("report"), &[path.to_path_buf()], false)?;
//! let result = run_job(job, path, &RunOptions::default(), &Silent)?;
//! out.write(&report::build(&result)?)?;
//! for p in &result.modal {
//!     println!("{:.2} Hz: G* by the layered model {:?}", p.freq_hz, p.layered_g());
//! }
//! # Ok(()) }
//! ```
//!
//! - [`Job`] ([`job`]): the job file (TOML, SI units), read and checked before any work.
//! - [`run_job`]: the chain, on the job resolved once into each stage's configuration (stage
//!   "job": the stages never read the [`Job`]); [`ChainResult`] ([`result`]) holds every stage's
//!   result, [`CorePoint`] ([`chain`]) the core found at one frequency by every route, with its
//!   band ([`band`]).
//! - [`report::build`]: the report's files; [`OutputDir`] writes them without destroying
//!   anything lamdyn did not write.
//! - [`demo`]: the virtual roof's simulated test and the chain on it.
//! - [`cache`]: the slow results (modal model, EMA, layered model) keyed by their inputs and
//!   checked on every read.
//! - [`Reporter`]: what a caller hears of long work (a spinner, log lines, nothing:
//!   [`Silent`]); the eigensolvers hear it through [`AsProgress`].
//!
//! Errors are [`PipelineError`]s: each layer says what failed, the causes are its source chain
//! ([`error::chain_text`] joins them into one line).
//!
//! `docs/architecture.md` maps the crates and this crate's modules, and says how to add a
//! stage or a band source.

#![deny(missing_docs)]

pub mod band;
pub mod band_widths;
pub mod cache;
pub mod chain;
mod config;
pub mod demo;
pub mod error;
pub mod excitation;
pub mod fit_job;
pub mod frf_route;
pub mod io;
pub mod job;
mod layered;
pub mod measurement;
pub mod output;
pub mod report;
pub mod result;
mod stages;
mod stats;
mod text;
pub mod uncertainty;
mod warnings;

pub use error::{PipelineError, Result};

/// docs/architecture.md, whose code blocks are compiled and run as this crate's doc tests so
/// that the map stays true to the code.
#[cfg(doctest)]
#[doc = include_str!("../../../docs/architecture.md")]
pub struct ArchitectureDoc;
pub use chain::{CorePoint, NoLayered, StageTime, Truth};
pub use job::Job;
pub use output::OutputDir;
pub use result::ChainResult;
pub use stages::{RunOptions, check_job_path, run_job, same_bits_on_any_thread_count};

/// Progress of a run, reported as it goes; it may be reported from worker threads (the ladder's
/// levels and the Monte Carlo run on rayon). Both methods default to doing nothing.
pub trait Reporter: Sync {
    /// A stage or step starts ("stage 'layered inverse'", "FRF fit: ...", "Lanczos").
    fn stage(&self, _name: &str) {}
    /// An eigensolver has `converged` of `wanted` modes.
    fn converged(&self, _converged: usize, _wanted: usize) {}
}

/// No progress output.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Reporter for Silent {}

/// A [`Reporter`] as the eigensolvers' progress ([`lamdyn_fem::eigen::Progress`]), for the
/// stages and commands that call one.
pub struct AsProgress<'a>(pub &'a dyn Reporter);

impl lamdyn_fem::eigen::Progress for AsProgress<'_> {
    fn stage(&self, name: &str) {
        self.0.stage(name);
    }
    fn converged(&self, converged: usize, wanted: usize) {
        self.0.converged(converged, wanted);
    }
}
