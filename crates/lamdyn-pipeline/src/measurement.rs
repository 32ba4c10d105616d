//! The measurement: FRFs from CSV (`lamdyn_frf::csv`) or UFF files, or H1/H2/Hv estimated from
//! time files (CSV or UFF time responses; hammer hits or continuous excitation), as the chain
//! and the commands read them; and the job's measurement
//! ([`read_measurement_section`]) with its coherence and the estimator's warnings.

use crate::error::{Context, Result};
pub use crate::excitation::{ContinuousOptions, Excitation, ExcitationKind};
use crate::job::{Measurement, relative};
use crate::{bail, err};
use lamdyn_ema::spectra::{Hit, Spectra, SpectraSettings, estimate};
use lamdyn_frf::csv::TimeRecord;
use lamdyn_frf::{Channel, FrfSet, Quantity};
use std::path::{Path, PathBuf};

/// FRF estimators from time data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Estimator {
    /// H1 = Gyx/Gxx: unbiased by response noise (the usual choice for hammer tests).
    H1,
    /// H2 = Gyy/Gxy: unbiased by force noise.
    H2,
    /// Hv = sqrt(H1 H2) with the phase of H1.
    Hv,
}

/// The measured data as the chain uses it.
pub struct Measured {
    /// The FRFs.
    pub set: FrfSet,
    /// Where they came from.
    pub source: String,
    /// Time data: the lowest coherence of each response in the fit band.
    pub min_coherence: Option<Vec<f64>>,
    /// Time data: the estimator's warnings (double hits, overloads).
    pub warnings: Vec<String>,
    /// Impact time data of at least [`JACKKNIFE_HITS`] files: the records read, kept for
    /// [`without_each_hit`] (the files are read once).
    records: Option<Records>,
}

impl Measured {
    /// Whether the measurement kept hammer hits that [`without_each_hit`] can leave out in
    /// turn (impact time data of at least [`JACKKNIFE_HITS`] files).
    pub fn has_hits_to_leave_out(&self) -> bool {
        self.records.is_some()
    }
}

fn read_text(p: &Path) -> Result<String> {
    crate::io::read_text(p)
}

/// One run or hit of time data: a time CSV (`lamdyn_frf::csv` module docs) or a universal file
/// of time responses (`lamdyn_uff::time`), told apart by content.
fn read_time_file(
    path: &Path,
    responses: &[Channel],
    hammer: &Channel,
    quantity: Option<Quantity>,
) -> Result<TimeRecord> {
    if crate::io::is_uff(path)? {
        let file = lamdyn_uff::read_path(path, Default::default()).map_err(|e| err!("{e}"))?;
        return lamdyn_uff::time::time_record(&file, responses, hammer, quantity)
            .map_err(|e| err!("'{}': {e}", path.display()));
    }
    Ok(lamdyn_frf::csv::parse_time_as(
        &path.display().to_string(),
        &read_text(path)?,
        responses,
        hammer,
        quantity,
    )?)
}

/// How time data become FRFs: the estimator and the record settings (rate from the files).
pub struct TimeOptions {
    /// The FRF estimator.
    pub estimator: Estimator,
    /// Hammer hits: the trigger level, a fraction of each hit's peak force.
    pub trigger: f64,
    /// Hammer hits: kept before the trigger, s.
    pub pretrigger_s: f64,
    /// Hammer hits: the force window's length, s.
    pub force_window_s: f64,
    /// Hammer hits: each record's length after its start, s (`None`: the longest record every
    /// hit holds).
    pub record_s: Option<f64>,
    /// Hammer hits: the exponential window's time constant, s (`None`: no window).
    pub exp_tau_s: Option<f64>,
    /// Hammer hits (the trigger, force and exponential windows above), or continuous
    /// excitation by Welch averaging ([`lamdyn_ema::welch`]; the hammer settings unused).
    pub excitation: Excitation,
    /// What the responses are, for files without a `# quantity` line.
    pub quantity: Option<lamdyn_frf::Quantity>,
}

/// FRFs (the chosen estimator) from hit files and the channels table, with the spectra
/// (coherence, warnings) and the number of hits.
pub fn time_frfs(
    channels: &Path,
    files: &[PathBuf],
    options: &TimeOptions,
) -> Result<(FrfSet, Spectra, usize)> {
    let records = read_records(channels, files, options)?;
    let (set, spectra) = records.frfs(&records.hits, files, options)?;
    Ok((set, spectra, records.hits.len()))
}

/// Hit files read against a channels table ([`read_records`]).
struct Records {
    responses: Vec<Channel>,
    references: Vec<Channel>,
    /// One per file, in their order.
    hits: Vec<Hit>,
    rate_hz: f64,
    quantity: Option<Quantity>,
}

/// Reads the channels table and every hit file (one sampling rate and one response quantity
/// for all).
fn read_records(channels: &Path, files: &[PathBuf], options: &TimeOptions) -> Result<Records> {
    let (responses, references) =
        lamdyn_frf::csv::parse_channels(&channels.display().to_string(), &read_text(channels)?)?;
    let [hammer] = &references[..] else {
        bail!(
            "'{}': time data needs exactly one reference channel (the hammer), the file has {}",
            channels.display(),
            references.len()
        );
    };
    let mut hits = Vec::with_capacity(files.len());
    let (mut rate, mut quantity) = (None, None);
    for f in files {
        let rec = read_time_file(f, &responses, hammer, options.quantity)?;
        let r0 = *rate.get_or_insert(rec.rate_hz);
        if (rec.rate_hz - r0).abs() > 1e-6 * r0 {
            bail!(
                "'{}': sampled at {} Hz, the first hit at {r0} Hz",
                f.display(),
                rec.rate_hz
            );
        }
        if *quantity.get_or_insert(rec.quantity) != rec.quantity {
            bail!(
                "'{}': its responses are {}, the first hit's {}",
                f.display(),
                rec.quantity.unit(),
                quantity.map_or("", |q| q.unit())
            );
        }
        hits.push(Hit {
            force: rec.force,
            responses: rec.responses,
        });
    }
    let rate_hz = rate.ok_or_else(|| err!("no time file given"))?;
    Ok(Records {
        responses,
        references,
        hits,
        rate_hz,
        quantity,
    })
}

impl Records {
    /// The FRFs and spectra of `hits` (these records' or some of them, read from `files`).
    fn frfs(
        &self,
        hits: &[Hit],
        files: &[PathBuf],
        options: &TimeOptions,
    ) -> Result<(FrfSet, Spectra)> {
        let spectra = match options.excitation {
            Excitation::Impact => impact_spectra(hits, self.rate_hz, options)?,
            Excitation::Continuous(c) => continuous_spectra(hits, self.rate_hz, &c, files)?,
        };
        let data = spectra
            .channels
            .iter()
            .flat_map(|c| match options.estimator {
                Estimator::H1 => c.h1.clone(),
                Estimator::H2 => c.h2.clone(),
                Estimator::Hv => c.hv.clone(),
            })
            .collect();
        let set = FrfSet::new(
            spectra.freqs_hz.clone(),
            self.responses.clone(),
            self.references.clone(),
            self.quantity.unwrap_or(lamdyn_frf::Quantity::Receptance),
            data,
        )?;
        Ok((set, spectra))
    }
}

/// Welch spectra of continuous-excitation records (each file one record).
fn continuous_spectra(
    hits: &[Hit],
    rate_hz: f64,
    c: &ContinuousOptions,
    files: &[PathBuf],
) -> Result<Spectra> {
    if !(c.overlap.is_finite() && (0.0..1.0).contains(&c.overlap)) {
        bail!("overlap {} must be a fraction in [0, 1)", c.overlap);
    }
    let shortest = hits.iter().map(|h| h.force.len()).min().unwrap_or(0);
    let segment = match c.segment_s {
        // Whole records for the rectangular window (bursts, sweeps, periods inside them);
        // with a window, about 8 segments per record, a power of two of samples.
        None if c.window == lamdyn_ema::welch::Window::Rectangular => 0,
        None => {
            let eighth = (shortest / 8).max(8) as f64;
            2f64.powf(eighth.log2().round()) as usize
        }
        Some(t) if t.is_finite() && t > 0.0 => (t * rate_hz).round() as usize,
        Some(t) => bail!("segment {t} s must be a positive time"),
    };
    let settings = lamdyn_ema::welch::WelchSettings {
        rate_hz,
        segment,
        overlap: (c.overlap * segment as f64).round() as usize,
        window: c.window,
        detrend: true,
        band_hz: c.band_hz,
    };
    // Messages say "record N": name the files.
    lamdyn_ema::welch::welch(hits, &settings).map_err(|e| {
        let names: Vec<String> = files
            .iter()
            .enumerate()
            .map(|(k, f)| format!("record {} = '{}'", k + 1, f.display()))
            .collect();
        err!(
            "FRF estimation from the time data failed: {e} ({})",
            names.join(", ")
        )
    })
}

/// H1/H2/Hv of hammer hits (triggered records, force and exponential windows).
fn impact_spectra(hits: &[Hit], rate_hz: f64, options: &TimeOptions) -> Result<Spectra> {
    for (name, v) in [
        ("trigger", options.trigger),
        ("pretrigger", options.pretrigger_s),
        ("force window", options.force_window_s),
    ] {
        if v < 0.0 {
            bail!("the {name} {v} must not be negative");
        }
    }
    let settings = SpectraSettings {
        rate_hz,
        trigger: options.trigger,
        pretrigger: (options.pretrigger_s * rate_hz).round() as usize,
        length: options
            .record_s
            .map_or(0, |t| (t * rate_hz).round() as usize),
        force_window_s: options.force_window_s,
        exp_tau_s: options.exp_tau_s,
        double_hit: 0.2,
    };
    estimate(hits, &settings).context("FRF estimation from the time data failed")
}

/// The FRF set named by the arguments.
pub fn read_frfs(
    uff: Option<&Path>,
    channels: Option<&Path>,
    frf: Option<&Path>,
) -> Result<(FrfSet, String)> {
    match (uff, channels, frf) {
        (Some(u), _, _) => {
            let file = lamdyn_uff::read_path(u, Default::default()).map_err(|e| err!("{e}"))?;
            let set =
                lamdyn_uff::frf::to_frf_set(&file).map_err(|e| err!("'{}': {e}", u.display()))?;
            Ok((set, format!("UFF '{}'", u.display())))
        }
        (None, Some(c), Some(f)) => {
            let text = |p: &Path| crate::io::read_text(p);
            let (r, q) = lamdyn_frf::csv::parse_channels(&c.display().to_string(), &text(c)?)?;
            let set = lamdyn_frf::csv::parse_frf(&f.display().to_string(), &text(f)?, r, q)?;
            Ok((
                set,
                format!("CSV '{}' with channels '{}'", f.display(), c.display()),
            ))
        }
        _ => bail!(
            "give --uff FILE, --channels FILE with --frf FILE, or --channels FILE with --time \
             FILE..."
        ),
    }
}

/// How a job's time data are turned into FRFs (H1, the job's trigger and windows).
fn time_options(m: &Measurement, band_hz: Option<[f64; 2]>) -> Result<TimeOptions> {
    Ok(TimeOptions {
        estimator: Estimator::H1,
        trigger: m.trigger,
        pretrigger_s: m.pretrigger_s,
        force_window_s: m.force_window_s,
        record_s: None,
        exp_tau_s: None,
        excitation: Excitation::new(m.excitation, m.window, m.segment_s, m.overlap, band_hz)
            .context("measurement.excitation")?,
        quantity: m.quantity,
    })
}

/// The fewest hammer hits for [`without_each_hit`]: with two, each set is one hit.
pub const JACKKNIFE_HITS: usize = 3;

/// The job's hammer-hit FRFs again without each hit in turn (the delete-one jackknife's sets,
/// [Efron & Tibshirani 1993, ch. 11]), in the order of `measurement.time`, one set without each
/// of its files (a file is one hit in the usual layout; a file of several hits is left out
/// whole, a delete-a-group jackknife), from the records `measured` kept; empty unless the
/// measurement is time data of at least [`JACKKNIFE_HITS`] files of an impact test. What the
/// hits' noise does to a pole, bias of the identification included, is read from how the pole
/// moves across these sets (`crate::layered`'s pole scatter).
///
/// # Errors
/// As [`read_measurement_section`].
pub fn without_each_hit(
    (section, band_hz): (&Measurement, Option<[f64; 2]>),
    measured: &Measured,
) -> Result<Vec<FrfSet>> {
    let Some(records) = &measured.records else {
        return Ok(Vec::new());
    };
    let options = time_options(section, band_hz)?;
    let n = records.hits.len();
    (0..n)
        .map(|left_out| {
            let hits: Vec<Hit> = (0..n)
                .filter(|&k| k != left_out)
                .map(|k| records.hits[k].clone())
                .collect();
            // Impact spectra name no file.
            records
                .frfs(&hits, &[], &options)
                .map(|r| r.0)
                .with_context(|| format!("measurement.time without hit {}", left_out + 1))
        })
        .collect()
}

/// The measured FRF set of a job's `[measurement]` section (any command's job file), paths
/// relative to `base`, `path` the job file for messages; `band_hz` is where the coherence of
/// time data is judged (default: every line).
pub fn read_measurement_section(
    m: &Measurement,
    band_hz: Option<[f64; 2]>,
    base: &Path,
    path: &Path,
) -> Result<Measured> {
    let mut out = match (&m.channels, &m.frf, &m.uff) {
        (Some(c), Some(f), None) => csv_frfs(&relative(base, c), &relative(base, f))?,
        (Some(c), None, None) => {
            let files: Vec<PathBuf> = m.time.iter().map(|t| relative(base, t)).collect();
            time_records(m, &relative(base, c), &files, band_hz)?
        }
        (None, None, Some(u)) => {
            let (set, source) =
                read_frfs(Some(&relative(base, u)), None, None).context("measurement.uff")?;
            Measured {
                set,
                source,
                min_coherence: None,
                warnings: vec![],
                records: None,
            }
        }
        _ => bail!(
            "error in '{}': measurement: give channels with frf or time, or uff",
            path.display()
        ),
    };
    let texts = m.channels.iter().chain(&m.frf).chain(&m.time);
    let texts: Vec<PathBuf> = texts.map(|p| relative(base, p)).collect();
    out.warnings.extend(crate::io::encoding_notes(
        texts.iter().map(PathBuf::as_path),
    ));
    if let Some(n) = m.responses {
        let got = out.set.responses().len();
        if got != n {
            bail!("measurement.responses = {n}, but the geometry has {got} response channels",);
        }
    }
    if out.set.references().is_empty() {
        bail!("measurement: no reference (hammer) channel in the geometry");
    }
    out.source = format!(
        "{} ({} responses x {} references, {} lines {:.3}-{:.3} Hz, {})",
        out.source,
        out.set.responses().len(),
        out.set.references().len(),
        out.set.n_lines(),
        out.set.freqs_hz()[0],
        out.set.freqs_hz()[out.set.n_lines() - 1],
        out.set.quantity().unit()
    );
    Ok(out)
}

/// FRFs from the CSV files `f` with their channels `c`.
fn csv_frfs(c: &Path, f: &Path) -> Result<Measured> {
    let (responses, references) =
        lamdyn_frf::csv::parse_channels(&c.display().to_string(), &read_text(c)?)
            .context("measurement.channels")?;
    let set = lamdyn_frf::csv::parse_frf(
        &f.display().to_string(),
        &read_text(f)?,
        responses,
        references,
    )
    .with_context(|| {
        format!(
            "measurement.frf ('{}', read against the channels of '{}')",
            f.display(),
            c.display()
        )
    })?;
    Ok(Measured {
        set,
        source: format!("FRFs '{}', channels '{}'", f.display(), c.display()),
        min_coherence: None,
        warnings: vec![],
        records: None,
    })
}

/// FRFs estimated from the time files `files` with their channels `c`: their coherence's
/// minimum per channel over `band_hz`, and the hits kept for the jackknife.
fn time_records(
    m: &Measurement,
    c: &Path,
    files: &[PathBuf],
    band_hz: Option<[f64; 2]>,
) -> Result<Measured> {
    let options = time_options(m, band_hz)?;
    let context = || {
        format!(
            "measurement.time (read against the channels of '{}')",
            c.display()
        )
    };
    let records = read_records(c, files, &options).with_context(context)?;
    let (set, spectra) = records
        .frfs(&records.hits, files, &options)
        .with_context(context)?;
    let hits = records.hits.len();
    let jackknife = hits >= JACKKNIFE_HITS && m.excitation == ExcitationKind::Impact;
    let band = band_hz.unwrap_or([0.0, f64::INFINITY]);
    let min_coherence = spectra
        .channels
        .iter()
        .map(|ch| {
            spectra
                .freqs_hz
                .iter()
                .zip(&ch.coherence)
                .filter(|(f, _)| **f >= band[0] && **f <= band[1])
                .map(|(_, g)| *g)
                .fold(1.0, f64::min)
        })
        .collect();
    Ok(Measured {
        set,
        source: format!(
            "H1 from {hits} hammer hits ('{}'...), channels '{}'",
            files
                .first()
                .map_or(String::new(), |f| f.display().to_string()),
            c.display()
        ),
        min_coherence: Some(min_coherence),
        warnings: spectra.warnings.clone(),
        records: jackknife.then_some(records),
    })
}
