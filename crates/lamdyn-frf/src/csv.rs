//! A plain CSV layout for FRF sets, for data that does not come as UFF.
//!
//! **Channels file** (`name,role,x_m,y_m,z_m,dx,dy,dz`): one line per response or reference
//! channel, `role` = `response` or `reference`, position in m and direction in the global frame.
//!
//! **FRF file**: a line `# quantity = accelerance` (or `receptance`, `mobility`) before the
//! header — required: a file without it is refused, since reading accelerance as receptance
//! gives loss factors wrong by orders of magnitude without any other sign —, then a header
//! `f_hz,R@F:re,R@F:im,...` with one pair of columns per response `R` and reference `F` named in
//! the channels file, then one line per frequency (Hz, increasing). Every response × reference pair
//! must appear once.
//!
//! **Time file** (one per hammer hit): a line `# quantity = accelerance` (what the responses
//! are: `receptance` = displacement in m, `mobility` = velocity in m/s, `accelerance` =
//! acceleration in m/s²; required, as for FRF files), then a header `t_s,NAME,...` naming the
//! reference (the force, N) and every response of the channels file, then one line per sample
//! at a uniform time step: each step within 1 % of the mean step (the least-squares slope of t
//! against the sample index), which
//! absorbs the rounding of a time column printed to a few digits and still refuses a missing
//! or repeated sample.
//!
//! Lines starting with `#` are comments. Fields are separated by commas, or by semicolons or
//! tabs with decimal commas allowed (detected from the header; [`crate::text`]); files may be
//! UTF-8 (with a byte-order mark), UTF-16 or Latin-1 ([`crate::text::read_text`]).

use crate::text::{Dialect, data_lines, quoted, short};
use crate::{Channel, FrfError, FrfSet, Quantity};
use num_complex::Complex64;
use std::collections::HashMap;
use std::fmt::Write as _;

fn err(path: &str, line: usize, reason: String) -> FrfError {
    FrfError::File {
        path: path.into(),
        line,
        reason,
    }
}

/// The dialect of a CSV text (from its header line) and its data lines split into fields:
/// (1-based line number, fields), comments and blank lines skipped.
fn lines(text: &str) -> (Dialect, impl Iterator<Item = (usize, Vec<&str>)>) {
    let dialect = data_lines(text)
        .next()
        .map_or_else(Dialect::default, |(_, header)| Dialect::detect(header));
    (
        dialect,
        data_lines(text).map(move |(i, l)| (i, dialect.split(l))),
    )
}

fn number(d: Dialect, path: &str, line: usize, column: &str, s: &str) -> Result<f64, FrfError> {
    d.number(s).ok_or_else(|| {
        err(
            path,
            line,
            if d.separator == ',' {
                format!(
                    "column '{column}': '{s}' is not a finite number",
                    column = quoted(column),
                    s = quoted(s)
                )
            } else {
                format!(
                    "column '{column}': '{s}' is not a finite number (read as {})",
                    d.describe(),
                    column = quoted(column),
                    s = quoted(s)
                )
            },
        )
    })
}

/// The `# quantity = ...` line of an FRF or time file (required: module docs).
fn declared_quantity(path: &str, text: &str) -> Result<Quantity, FrfError> {
    let found = text.lines().enumerate().find_map(|(i, l)| {
        l.trim()
            .strip_prefix('#')
            .and_then(|r| r.trim().strip_prefix("quantity"))
            .map(|r| (i + 1, r.trim().trim_start_matches('=').trim()))
    });
    match found {
        Some((_, "receptance")) => Ok(Quantity::Receptance),
        Some((_, "mobility")) => Ok(Quantity::Mobility),
        Some((_, "accelerance")) => Ok(Quantity::Accelerance),
        Some((line, other)) => Err(err(
            path,
            line,
            format!(
                "quantity '{other}' must be receptance, mobility or \
                 accelerance",
                other = quoted(other)
            ),
        )),
        None => Err(err(
            path,
            1,
            "no '# quantity = ...' line: say what the responses are, in a line before the header: \
             `# quantity = accelerance` (m/s^2), `mobility` (m/s) or `receptance` (m); lamdyn does \
             not guess, since a wrong quantity gives loss factors wrong by orders of \
             magnitude"
                .into(),
        )),
    }
}

/// The least-squares slope of t against the sample index: the time step with the printing
/// errors of the stamps averaged out (their effect on the step falls as n^(-3/2)).
fn mean_step(t: &[f64]) -> f64 {
    let n = t.len() as f64;
    let k_mean = (n - 1.0) / 2.0;
    let t_mean = t.iter().sum::<f64>() / n;
    let (num, den) = t.iter().enumerate().fold((0.0, 0.0), |(a, b), (k, tk)| {
        let dk = k as f64 - k_mean;
        (a + dk * (tk - t_mean), b + dk * dk)
    });
    num / den
}

/// Largest deviation of a time step from the mean step, as a fraction of it (module docs).
pub const TIME_STEP_TOLERANCE: f64 = 0.01;

/// The time step of a sampled time axis: the least-squares step, every step within
/// [`TIME_STEP_TOLERANCE`] of it (printing precision of the stamps).
///
/// # Errors
/// `(k, message)`: the step from sample k to k + 1 is not positive, is a gap or is uneven.
pub fn uniform_step(t: &[f64]) -> Result<f64, (usize, String)> {
    // Each step is judged against the median step, which a gap or a repeated stamp does not
    // move; the step returned is the least-squares one (printing errors averaged out).
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    let typical = steps.get(steps.len() / 2).copied().unwrap_or(f64::NAN);
    match t.windows(2).position(|w| {
        !(w[1] - w[0] > 0.0 && ((w[1] - w[0]) - typical).abs() <= TIME_STEP_TOLERANCE * typical)
    }) {
        None => Ok(mean_step(t)),
        Some(k) => {
            let step = t[k + 1] - t[k];
            let why = if step <= 0.0 {
                "the time must increase (a repeated or reversed time stamp)"
            } else if step > typical {
                "a gap (a missing sample?)"
            } else {
                "the sampling must be uniform"
            };
            Err((
                k,
                format!(
                    "time step {} s after {} s, the usual step is {} s: {why}",
                    short(step),
                    short(t[k]),
                    short(typical)
                ),
            ))
        }
    }
}

/// One hammer hit read from a time file: the force and the responses sampled at `rate_hz`.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeRecord {
    /// Sampling rate, Hz.
    pub rate_hz: f64,
    /// What the responses are (their SI unit follows).
    pub quantity: Quantity,
    /// Force, N.
    pub force: Vec<f64>,
    /// Responses in the order of the channels file.
    pub responses: Vec<Vec<f64>>,
}

/// Parses a time file (module docs) against the channels file's `responses` and single
/// `reference` (the hammer).
///
/// # Errors
/// [`FrfError::File`] naming the line: missing or unknown columns, bad numbers, fewer than two
/// samples, a non-uniform or non-increasing time step.
pub fn parse_time(
    path: &str,
    text: &str,
    responses: &[Channel],
    reference: &Channel,
) -> Result<TimeRecord, FrfError> {
    parse_time_as(path, text, responses, reference, None)
}

/// [`parse_time`] for a file that may lack the `# quantity` line, the caller stating the
/// quantity (`lamdyn ema --quantity`: an instrument's export has no such line). A file that
/// states another quantity than `quantity` is refused.
///
/// # Errors
/// As [`parse_time`], and the disagreement.
pub fn parse_time_as(
    path: &str,
    text: &str,
    responses: &[Channel],
    reference: &Channel,
    quantity: Option<Quantity>,
) -> Result<TimeRecord, FrfError> {
    let quantity = match (declared_quantity(path, text), quantity) {
        (Ok(q), None) => q,
        (Ok(q), Some(given)) if q == given => q,
        (Ok(q), Some(given)) => {
            return Err(err(
                path,
                1,
                format!(
                    "the file says quantity = {}, but {} was given",
                    q.name(),
                    given.name()
                ),
            ));
        }
        (Err(_), Some(given)) => given,
        (Err(e), None) => return Err(e),
    };
    let (d, mut it) = lines(text);
    let Some((hl, header)) = it.next() else {
        return Err(err(path, 0, "empty: expected a header t_s,NAME,...".into()));
    };
    if header.first() != Some(&"t_s") {
        return Err(err(path, hl, "the first column must be t_s".into()));
    }
    let column = |name: &str| {
        header[1..]
            .iter()
            .position(|h| *h == name)
            .map(|c| c + 1)
            .ok_or_else(|| {
                err(
                    path,
                    hl,
                    format!("no column for channel '{name}'", name = quoted(name)),
                )
            })
    };
    let force_col = column(&reference.name)?;
    let resp_cols: Vec<usize> = responses
        .iter()
        .map(|c| column(&c.name))
        .collect::<Result<_, _>>()?;
    let (mut t, mut force, mut line_of) = (Vec::new(), Vec::new(), Vec::new());
    let mut resp = vec![Vec::new(); responses.len()];
    for (line, fields) in it {
        line_of.push(line);
        if fields.len() != header.len() {
            return Err(err(
                path,
                line,
                format!("{} fields, the header has {}", fields.len(), header.len()),
            ));
        }
        t.push(number(d, path, line, "t_s", fields[0])?);
        force.push(number(d, path, line, &reference.name, fields[force_col])?);
        for (r, &c) in resp.iter_mut().zip(&resp_cols) {
            r.push(number(d, path, line, header[c], fields[c])?);
        }
    }
    if t.len() < 2 {
        return Err(err(
            path,
            hl,
            format!("{} samples: at least 2 needed", t.len()),
        ));
    }
    let dt = uniform_step(&t).map_err(|(k, why)| err(path, line_of[k + 1], why))?;
    Ok(TimeRecord {
        rate_hz: 1.0 / dt,
        quantity,
        force,
        responses: resp,
    })
}

/// Parses a channels table: (responses, references) in file order.
///
/// # Errors
/// [`FrfError::File`] naming the line: wrong field count, bad numbers, unknown role, repeated
/// names, zero directions.
pub fn parse_channels(path: &str, text: &str) -> Result<(Vec<Channel>, Vec<Channel>), FrfError> {
    let (d, mut it) = lines(text);
    let Some((hl, header)) = it.next() else {
        return Err(err(
            path,
            0,
            "empty: expected the header name,role,x_m,y_m,z_m,dx,dy,dz".into(),
        ));
    };
    let want = ["name", "role", "x_m", "y_m", "z_m", "dx", "dy", "dz"];
    if header != want {
        return Err(err(
            path,
            hl,
            format!(
                "header must be {}, got {}",
                want.join(","),
                quoted(&header.join(","))
            ),
        ));
    }
    let (mut responses, mut references) = (Vec::new(), Vec::new());
    // A name is unique within its role: a driving point has a response and a reference of the
    // same name (a UFF's node and direction, as `uff convert` writes them).
    let mut seen: HashMap<(String, String), usize> = HashMap::new();
    for (line, f) in it {
        if f.len() != 8 {
            return Err(err(path, line, format!("{} fields, expected 8", f.len())));
        }
        if let Some(prev) = seen.insert((f[0].to_string(), f[1].to_string()), line) {
            return Err(err(
                path,
                line,
                format!(
                    "{} channel '{}' was already defined on line {prev}",
                    f[1], f[0]
                ),
            ));
        }
        let v: Vec<f64> = (2..8)
            .map(|k| number(d, path, line, want[k], f[k]))
            .collect::<Result<_, _>>()?;
        let ch = Channel::new(f[0], [v[0], v[1], v[2]], [v[3], v[4], v[5]])
            .map_err(|e| err(path, line, e.to_string()))?;
        match f[1] {
            "response" => responses.push(ch),
            "reference" => references.push(ch),
            other => {
                return Err(err(
                    path,
                    line,
                    format!(
                        "role '{other}' must be response or reference",
                        other = quoted(other)
                    ),
                ));
            }
        }
    }
    if responses.is_empty() || references.is_empty() {
        return Err(err(
            path,
            0,
            format!(
                "{} responses and {} references: need at least one of each",
                responses.len(),
                references.len()
            ),
        ));
    }
    Ok((responses, references))
}

/// Parses an FRF file against channels.
///
/// # Errors
/// [`FrfError::File`] naming the line and column: unknown channels, missing pairs, bad numbers,
/// a non-increasing frequency axis, wrong field counts.
pub fn parse_frf(
    path: &str,
    text: &str,
    responses: Vec<Channel>,
    references: Vec<Channel>,
) -> Result<FrfSet, FrfError> {
    let quantity = declared_quantity(path, text)?;
    let (d, mut it) = lines(text);
    let Some((hl, header)) = it.next() else {
        return Err(err(
            path,
            0,
            "empty: expected a header f_hz,R@F:re,R@F:im,...".into(),
        ));
    };
    if header.first() != Some(&"f_hz") {
        return Err(err(path, hl, "the first column must be f_hz".into()));
    }
    let resp: HashMap<&str, usize> = responses
        .iter()
        .enumerate()
        .map(|(i, c)| (c.name.as_str(), i))
        .collect();
    let refs: HashMap<&str, usize> = references
        .iter()
        .enumerate()
        .map(|(i, c)| (c.name.as_str(), i))
        .collect();
    // column → (pair index, is imaginary)
    let n_pairs = responses.len() * references.len();
    let mut columns = Vec::new();
    let mut filled = vec![[false; 2]; n_pairs];
    for name in &header[1..] {
        let (i, j, im) = column_of(path, hl, name, (&resp, &refs))?;
        let p = i * references.len() + j;
        if filled[p][im as usize] {
            return Err(err(
                path,
                hl,
                format!("column '{name}' appears twice", name = quoted(name)),
            ));
        }
        filled[p][im as usize] = true;
        columns.push((p, im));
    }
    if let Some(p) = filled.iter().position(|f| !(f[0] && f[1])) {
        return Err(err(
            path,
            hl,
            format!(
                "no columns for {}@{} (:re and :im needed)",
                responses[p / references.len()].name,
                references[p % references.len()].name
            ),
        ));
    }
    let mut freqs = Vec::new();
    let mut values: Vec<Vec<Complex64>> = vec![Vec::new(); n_pairs];
    for (line, f) in it {
        if f.len() != header.len() {
            return Err(err(
                path,
                line,
                format!("{} fields, the header has {}", f.len(), header.len()),
            ));
        }
        let hz = number(d, path, line, "f_hz", f[0])?;
        if let Some(prev) = freqs.last() {
            if hz <= *prev {
                return Err(err(
                    path,
                    line,
                    format!("f_hz must increase: {hz} after {prev}"),
                ));
            }
        }
        freqs.push(hz);
        for v in values.iter_mut() {
            v.push(Complex64::new(0.0, 0.0));
        }
        for (k, &(p, im)) in columns.iter().enumerate() {
            let x = number(d, path, line, header[k + 1], f[k + 1])?;
            let slot = values[p].last_mut().expect("pushed above");
            if im {
                slot.im = x;
            } else {
                slot.re = x;
            }
        }
    }
    let data = values.into_iter().flatten().collect();
    FrfSet::new(freqs, responses, references, quantity, data)
        .map_err(|e| err(path, 0, e.to_string()))
}

/// The response's and reference's indices of an FRF file's header column `name`
/// (`RESPONSE@REFERENCE:re` or `:im`) and whether it is the imaginary part.
///
/// # Errors
/// [`FrfError::File`] naming the header's line `hl`: a malformed name, a channel not in the
/// channels file, a part other than re or im.
fn column_of(
    path: &str,
    hl: usize,
    name: &str,
    (resp, refs): (&HashMap<&str, usize>, &HashMap<&str, usize>),
) -> Result<(usize, usize, bool), FrfError> {
    let malformed = || {
        err(
            path,
            hl,
            format!(
                "column '{name}' must be RESPONSE@REFERENCE:re or :im",
                name = quoted(name)
            ),
        )
    };
    let unknown = |role: &str, channel: &str| {
        err(
            path,
            hl,
            format!(
                "column '{name}': {role} '{channel}' is not in the channels file",
                name = quoted(name),
                channel = quoted(channel)
            ),
        )
    };
    let (pair, part) = name.rsplit_once(':').ok_or_else(malformed)?;
    let (r, f) = pair.split_once('@').ok_or_else(malformed)?;
    let i = *resp.get(r).ok_or_else(|| unknown("response", r))?;
    let j = *refs.get(f).ok_or_else(|| unknown("reference", f))?;
    let im = match part {
        "re" => false,
        "im" => true,
        other => {
            return Err(err(
                path,
                hl,
                format!(
                    "column '{name}': part '{other}' must be re or im",
                    name = quoted(name),
                    other = quoted(other)
                ),
            ));
        }
    };
    Ok((i, j, im))
}

/// Writes the channels table of a set.
pub fn write_channels(set: &FrfSet) -> String {
    let mut s = String::from("name,role,x_m,y_m,z_m,dx,dy,dz\n");
    for (role, chans) in [
        ("response", set.responses()),
        ("reference", set.references()),
    ] {
        for c in chans {
            let _ = writeln!(
                s,
                "{},{role},{},{},{},{},{},{}",
                c.name,
                c.point_m[0],
                c.point_m[1],
                c.point_m[2],
                c.direction[0],
                c.direction[1],
                c.direction[2]
            );
        }
    }
    s
}

/// Writes a time file (module docs) of one hit: the force under `reference`'s name and the
/// responses under `responses`' names, t = k / rate.
///
/// # Errors
/// [`FrfError::Inconsistent`] if the record's responses and `responses` differ in count or the
/// signals differ in length.
pub fn write_time(
    record: &TimeRecord,
    responses: &[Channel],
    reference: &Channel,
) -> Result<String, FrfError> {
    let n = record.force.len();
    if record.responses.len() != responses.len() || record.responses.iter().any(|r| r.len() != n) {
        return Err(FrfError::Inconsistent {
            context: "time record".into(),
            reason: format!(
                "{} response signals for {} channels, lengths must all be {n}",
                record.responses.len(),
                responses.len()
            ),
        });
    }
    let q = quantity_name(record.quantity);
    let mut s = format!("# quantity = {q}\nt_s,{}", reference.name);
    for c in responses {
        let _ = write!(s, ",{}", c.name);
    }
    s.push('\n');
    for k in 0..n {
        let _ = write!(s, "{:e},{:e}", k as f64 / record.rate_hz, record.force[k]);
        for r in &record.responses {
            let _ = write!(s, ",{:e}", r[k]);
        }
        s.push('\n');
    }
    Ok(s)
}

fn quantity_name(q: Quantity) -> &'static str {
    match q {
        Quantity::Receptance => "receptance",
        Quantity::Mobility => "mobility",
        Quantity::Accelerance => "accelerance",
    }
}

/// Writes the FRF file of a set (shortest round-trip numbers).
pub fn write_frf(set: &FrfSet) -> String {
    let q = quantity_name(set.quantity());
    let mut s = format!("# quantity = {q}\nf_hz");
    for r in set.responses() {
        for f in set.references() {
            let _ = write!(s, ",{}@{}:re,{}@{}:im", r.name, f.name, r.name, f.name);
        }
    }
    s.push('\n');
    for (k, hz) in set.freqs_hz().iter().enumerate() {
        let _ = write!(s, "{hz}");
        for i in 0..set.responses().len() {
            for j in 0..set.references().len() {
                let v = set.curve(i, j)[k];
                let _ = write!(s, ",{:e},{:e}", v.re, v.im);
            }
        }
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> FrfSet {
        let r = vec![
            Channel::new("p1+Z", [0.0, 0.0, 0.0], [0.0, 0.0, 2.0]).unwrap(),
            Channel::new("p2+X", [0.1, 0.0, 0.0], [1.0, 0.0, 0.0]).unwrap(),
        ];
        let f = vec![Channel::new("hammer", [0.0, 0.1, 0.0], [0.0, 0.0, -1.0]).unwrap()];
        let data = (0..6)
            .map(|k| Complex64::new(k as f64 * 0.1, -(k as f64) * 1e-7))
            .collect();
        FrfSet::new(vec![1.0, 2.0, 3.5], r, f, Quantity::Accelerance, data).unwrap()
    }

    /// A subset of the responses keeps their curves, in the order asked; an index out of
    /// range or none at all is refused.
    #[test]
    fn a_subset_of_responses_keeps_their_curves() {
        let set = sample();
        let one = set.with_responses(&[1]).unwrap();
        assert_eq!(one.responses()[0].name, "p2+X");
        assert_eq!(one.curve(0, 0), set.curve(1, 0));
        let both = set.with_responses(&[1, 0]).unwrap();
        assert_eq!(both.curve(1, 0), set.curve(0, 0));
        let e = set.with_responses(&[2]).unwrap_err().to_string();
        assert!(e.contains("response 2 of 2"), "{e}");
        assert!(set.with_responses(&[]).is_err());
    }

    #[test]
    fn round_trip() {
        let set = sample();
        let (r, f) = parse_channels("c.csv", &write_channels(&set)).unwrap();
        let back = parse_frf("h.csv", &write_frf(&set), r, f).unwrap();
        assert_eq!(back, set);
        assert_eq!(
            set.responses()[0].direction,
            [0.0, 0.0, 1.0],
            "directions are normalised"
        );
    }

    /// The same set written with semicolons and decimal commas, with a byte-order mark or in
    /// Latin-1 with a "µ" in a comment, reads back equal.
    #[test]
    fn spreadsheet_dialects_and_encodings_read_the_same() {
        let set = sample();
        let (r, f) = parse_channels("c.csv", &write_channels(&set)).unwrap();
        let comma = write_frf(&set);
        let semi: String = comma
            .lines()
            .map(|l| {
                if l.starts_with('#') {
                    l.to_string()
                } else {
                    l.replace(',', ";").replace('.', ",")
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        let back = parse_frf("h.csv", &semi, r.clone(), f.clone()).unwrap();
        assert_eq!(back, set);
        let mut bom = b"\xEF\xBB\xBF".to_vec();
        bom.extend_from_slice(comma.as_bytes());
        let text = crate::text::decode(&bom).0;
        assert_eq!(
            parse_frf("h.csv", &text, r.clone(), f.clone()).unwrap(),
            set
        );
        let mut latin1 = b"# sensor sensitivity 10 mV/(m/s\xB2), \xB5-accelerometers\n".to_vec();
        latin1.extend_from_slice(comma.as_bytes());
        let text = crate::text::decode(&latin1).0;
        assert_eq!(parse_frf("h.csv", &text, r, f).unwrap(), set);
    }

    /// Without its quantity line a file is refused, naming the line to add.
    #[test]
    fn the_quantity_line_is_required() {
        let set = sample();
        let (r, f) = parse_channels("c.csv", &write_channels(&set)).unwrap();
        let text = write_frf(&set);
        let without: String = text.lines().skip(1).collect::<Vec<_>>().join("\n");
        let e = parse_frf("h.csv", &without, r.clone(), f.clone())
            .unwrap_err()
            .to_string();
        assert!(e.contains("no '# quantity = ...' line"), "{e}");
        let hammer = &f[0];
        let e = parse_time(
            "t.csv",
            "t_s,hammer,p1+Z,p2+X\n0,1,0,0\n1,0,0,0\n",
            &r,
            hammer,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("line 1: no '# quantity = ...' line"), "{e}");
    }

    /// A time column printed to 1 ns at 25.6 kHz (steps of 39.0625 µs printed as 39.062 or
    /// 39.063 µs) is uniform; a missing sample and a repeated stamp are refused by line.
    #[test]
    fn time_steps_within_printing_precision_are_uniform() {
        let r = vec![Channel::new("a", [0.0; 3], [0.0, 0.0, 1.0]).unwrap()];
        let f = Channel::new("F", [0.0; 3], [0.0, 0.0, -1.0]).unwrap();
        let rows = |t: &[f64]| {
            let mut s = String::from("# quantity = accelerance\nt_s,F,a\n");
            for (k, t) in t.iter().enumerate() {
                s += &format!("{t:.9},{k},0\n");
            }
            s
        };
        let t: Vec<f64> = (0..2000).map(|k| k as f64 / 25600.0).collect();
        let rec = parse_time("t.csv", &rows(&t), &r, &f).unwrap();
        assert!(
            (rec.rate_hz / 25600.0 - 1.0).abs() < 1e-9,
            "{}",
            rec.rate_hz
        );
        let mut gap = t.clone();
        gap.remove(700);
        let e = parse_time("t.csv", &rows(&gap), &r, &f)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 703: time step 7.8124e-5 s after 0.0273047 s") && e.contains("a gap"),
            "{e}"
        );
        let mut repeated = t.clone();
        repeated[900] = repeated[899];
        let e = parse_time("t.csv", &rows(&repeated), &r, &f)
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 903:") && e.contains("repeated"), "{e}");
    }

    #[test]
    fn errors_name_line_and_column() {
        let set = sample();
        let (r, f) = parse_channels("c.csv", &write_channels(&set)).unwrap();
        let text = write_frf(&set);
        let bad = text.replacen("2,", "2x,", 1);
        let e = parse_frf("h.csv", &bad, r.clone(), f.clone())
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "error reading 'h.csv' line 4: column 'f_hz': '2x' is not a finite number"
        );
        let bad = text.replacen("p2+X@hammer:im", "p3+X@hammer:im", 1);
        let e = parse_frf("h.csv", &bad, r.clone(), f.clone())
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "error reading 'h.csv' line 2: column 'p3+X@hammer:im': response 'p3+X' is not in the \
             channels file"
        );
        let bad = text.replacen("\n3.5,", "\n1.5,", 1);
        let e = parse_frf("h.csv", &bad, r.clone(), f.clone())
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "error reading 'h.csv' line 5: f_hz must increase: 1.5 after 2"
        );
        let e = parse_channels(
            "c.csv",
            "name,role,x_m,y_m,z_m,dx,dy,dz\na,response,0,0,0,0,0,0\n",
        )
        .unwrap_err()
        .to_string();
        assert_eq!(
            e,
            "error reading 'c.csv' line 2: channel 'a': the direction is zero"
        );
        let e = parse_channels(
            "c.csv",
            "name,role,x_m,y_m,z_m,dx,dy,dz\na,sensor,0,0,0,0,0,1\n",
        )
        .unwrap_err()
        .to_string();
        assert_eq!(
            e,
            "error reading 'c.csv' line 2: role 'sensor' must be response or reference"
        );
    }

    /// A huge field or header of binary bytes is quoted as at most 40 escaped characters; an
    /// error of the whole file names no line.
    #[test]
    fn errors_quote_bounded_printable_excerpts() {
        let set = sample();
        let (r, f) = parse_channels("c.csv", &write_channels(&set)).unwrap();
        let text = write_frf(&set);
        let field = format!("2{}\u{1b}[2J", "3".repeat(100_000));
        let bad = text.replacen("2,", &format!("{field},"), 1);
        let e = parse_frf("h.csv", &bad, r.clone(), f.clone())
            .unwrap_err()
            .to_string();
        assert!(e.len() < 200 && !e.contains('\u{1b}'), "{e}");
        assert!(e.ends_with(&format!("'2{}...' is not a finite number", "3".repeat(39))));
        let header = format!("name,role,\u{7}{}\n", "x".repeat(100_000));
        let e = parse_channels("c.csv", &header).unwrap_err().to_string();
        assert!(
            e.len() < 300 && !e.contains('\u{7}') && e.contains("\\u{7}"),
            "{e}"
        );
        let e = parse_time_as(
            "t.csv",
            "# only a comment\n",
            &r,
            &f[0],
            Some(set.quantity()),
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("error reading 't.csv': empty"), "{e}");
    }

    #[test]
    fn rms_and_quantity_conversion() {
        let set = sample();
        let rms = set.rms(0);
        let want = ((set.curve(0, 0)[1].norm_sqr() + set.curve(1, 0)[1].norm_sqr()) / 2.0).sqrt();
        assert!((rms[1] - want).abs() < 1e-15);
        let rec = set.to_quantity(Quantity::Receptance);
        let w = 2.0 * std::f64::consts::PI * 2.0;
        assert!((rec.curve(0, 0)[1] * (-w * w) - set.curve(0, 0)[1]).norm() < 1e-15);
    }
}
