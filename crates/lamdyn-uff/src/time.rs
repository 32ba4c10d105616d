//! UFF time records (datasets 58 of function type 1) → a [`TimeRecord`] for `lamdyn ema --time`.
//!
//! **Which datasets.** Every dataset 58 of function type 1 (time response) with real ordinates.
//! Each is one channel, named as in [`crate::frf`] (`node+dir`, e.g. `12+Z`, or the entity of a
//! scalar DOF) from its *response* DOF; the channels table picks the force (its `reference`
//! row) and the responses by those names. Other datasets (geometry, FRFs, units) are ignored.
//!
//! **Time axis.** Even abscissas give the step directly; uneven ones must be uniform within
//! [`TIME_STEP_TOLERANCE`] of the mean step (printing precision), as in time CSVs. Every
//! channel must have the same step and the same number of samples; records starting at
//! different times are refused (they were not sampled together).
//!
//! **Units.** The responses' quantity comes from the ordinate's specific data type (record 9:
//! 8 displacement, 11 velocity, 12 acceleration) or, when it is 0, from the units label (`m`,
//! `mm`, `m/s`, `m/s^2`, `g`, ...); the force's from data type 13 or the label `N`, `kN`,
//! `lbf`. Values are converted to SI by the unit exponents of record 9 and the file's last
//! dataset 164, or by the label when the exponents are all zero. A file that does not say what
//! its responses are needs the quantity from the caller (`--quantity`), and a file that says
//! another quantity than the caller's is refused.

use crate::UffFile;
use crate::d58::{Abscissa, Function58, Ordinate};
use crate::error::UffError;
use crate::frf::{channel_name, quantity_from_label};
use crate::meta::Units164;
use lamdyn_frf::csv::{TIME_STEP_TOLERANCE, TimeRecord, uniform_step};
use lamdyn_frf::{Channel, Quantity};

fn convert(reason: String) -> UffError {
    UffError::Convert(reason)
}

/// The time record of a file's time responses for the channels given (module docs).
///
/// # Errors
/// [`UffError::Convert`]: no time response in the file, a channel of the table missing from
/// it or present twice, complex ordinates, channels of different steps, lengths or start
/// times, a non-uniform time axis, a force that is not a force, a quantity that cannot be told
/// or that disagrees with `quantity`.
pub fn time_record(
    file: &UffFile,
    responses: &[Channel],
    reference: &Channel,
    quantity: Option<Quantity>,
) -> Result<TimeRecord, UffError> {
    let units = file.units().cloned().unwrap_or_else(Units164::si);
    let records: Vec<&Function58> = file.functions().filter(|f| f.function_type == 1).collect();
    if records.is_empty() {
        return Err(convert(
            "no time response (dataset 58 of function type 1) in the file".into(),
        ));
    }
    let find = |c: &Channel| -> Result<&Function58, UffError> {
        let mut hits = records
            .iter()
            .filter(|f| channel_name(&f.response) == c.name);
        match (hits.next(), hits.next()) {
            (Some(f), None) => Ok(f),
            (Some(_), Some(_)) => Err(convert(format!(
                "channel '{}' has two time responses in the file",
                c.name
            ))),
            (None, _) => Err(convert(format!(
                "no time response for channel '{}'; the file's are {}",
                c.name,
                records
                    .iter()
                    .map(|f| channel_name(&f.response))
                    .collect::<Vec<_>>()
                    .join(", ")
            ))),
        }
    };
    let force_fn = find(reference)?;
    let dt = time_step(force_fn)?;
    let scale = force_scale(force_fn, &units).ok_or_else(|| not_a_force(force_fn))?;
    let force = values(force_fn)?.into_iter().map(|v| v * scale).collect();
    let mut quantity = quantity;
    let mut out = Vec::with_capacity(responses.len());
    for c in responses {
        let f = find(c)?;
        same_axis(force_fn, f, dt)?;
        let (q, scale) = response_quantity(f, &units, quantity)?;
        quantity = Some(q);
        out.push(values(f)?.into_iter().map(|v| v * scale).collect());
    }
    let quantity = quantity.ok_or_else(|| convert("no response channel".into()))?;
    Ok(TimeRecord {
        rate_hz: 1.0 / dt,
        quantity,
        force,
        responses: out,
    })
}

fn values(f: &Function58) -> Result<Vec<f64>, UffError> {
    match &f.data {
        Ordinate::Real(v) => Ok(v.clone()),
        Ordinate::Complex(_) => Err(convert(format!(
            "time response {} has complex values",
            channel_name(&f.response)
        ))),
    }
}

/// The sampling step of one record, s.
fn time_step(f: &Function58) -> Result<f64, UffError> {
    let name = channel_name(&f.response);
    if f.data.len() < 2 {
        return Err(convert(format!(
            "time response {name} has {} samples: at least 2 needed",
            f.data.len()
        )));
    }
    let dt = match &f.abscissa {
        Abscissa::Even { step, .. } => *step,
        Abscissa::Uneven(t) => {
            uniform_step(t).map_err(|(_, why)| convert(format!("time response {name}: {why}")))?
        }
    };
    if !(dt.is_finite() && dt > 0.0) {
        return Err(convert(format!(
            "time response {name}: time step {dt} s is not positive"
        )));
    }
    Ok(dt)
}

/// A response sampled with the force: same step, length and start.
fn same_axis(force: &Function58, f: &Function58, dt: f64) -> Result<(), UffError> {
    let (a, b) = (channel_name(&force.response), channel_name(&f.response));
    let step = time_step(f)?;
    if (step - dt).abs() > TIME_STEP_TOLERANCE * dt {
        return Err(convert(format!(
            "time response {b} is sampled every {step} s, the force {a} every {dt} s"
        )));
    }
    if f.data.len() != force.data.len() {
        return Err(convert(format!(
            "time response {b} has {} samples, the force {a} {}: records of one run must have the \
             same length",
            f.data.len(),
            force.data.len()
        )));
    }
    let start = |f: &Function58| match &f.abscissa {
        Abscissa::Even { start, .. } => *start,
        Abscissa::Uneven(t) => t[0],
    };
    let (t0, t1) = (start(force), start(f));
    if (t1 - t0).abs() > 0.5 * dt {
        return Err(convert(format!(
            "time response {b} starts at {t1} s, the force {a} at {t0} s: they were not sampled \
             together"
        )));
    }
    Ok(())
}

fn not_a_force(f: &Function58) -> UffError {
    let num = &f.axes[1];
    convert(format!(
        "the reference channel {} is not a force: its data type is {} and its units '{}' (expected \
         13 or N, kN, lbf)",
        channel_name(&f.response),
        num.data_type,
        num.units
    ))
}

/// SI factor of a force record, or None when the record is not a force.
fn force_scale(f: &Function58, units: &Units164) -> Option<f64> {
    let num = &f.axes[1];
    let label = match num.units.trim().to_ascii_lowercase().as_str() {
        "n" => Some(1.0),
        "kn" => Some(1e3),
        "lbf" | "lb" => Some(4.448_221_615_260_5),
        _ => None,
    };
    if num.data_type != 13 && !(num.data_type == 0 && label.is_some()) {
        return None;
    }
    if num.length_exp != 0 || num.force_exp != 0 || num.temperature_exp != 0 {
        Some(units.factor(num.length_exp, num.force_exp, num.temperature_exp))
    } else {
        Some(label.unwrap_or(1.0))
    }
}

/// (quantity, SI factor) of a response record, checked against the quantity already known.
fn response_quantity(
    f: &Function58,
    units: &Units164,
    known: Option<Quantity>,
) -> Result<(Quantity, f64), UffError> {
    let num = &f.axes[1];
    let name = channel_name(&f.response);
    let by_type = match num.data_type {
        8 => Some(Quantity::Receptance),
        11 => Some(Quantity::Mobility),
        12 => Some(Quantity::Accelerance),
        _ => None,
    };
    let by_label = quantity_from_label(&format!("{}/N", num.units.trim()));
    let q = by_type.or(by_label.map(|b| b.0)).or(known).ok_or_else(|| {
        convert(format!(
            "time response {name}: neither its data type ({}) nor its units '{}' say whether it is \
             a displacement, velocity or acceleration; give the quantity (--quantity)",
            num.data_type, num.units
        ))
    })?;
    if let Some(k) = known.filter(|k| *k != q) {
        return Err(convert(format!(
            "time response {name} is a {} record, but the responses are {}",
            q.name(),
            k.name()
        )));
    }
    let scale = if num.length_exp != 0 || num.force_exp != 0 || num.temperature_exp != 0 {
        units.factor(num.length_exp, num.force_exp, num.temperature_exp)
    } else {
        by_label.map_or(1.0, |b| b.1)
    };
    Ok((q, scale))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::d58::{Dof, OrdinateType};
    use crate::{Dataset, Encoding};

    const RATE: f64 = 1000.0;

    fn dof(node: i64) -> Dof {
        Dof {
            entity: "NONE".into(),
            node,
            direction: 3,
        }
    }

    /// A time response of `n` samples at node `node` (+Z) of data type `kind` and units `label`.
    fn record(node: i64, kind: i64, label: &str, values: Vec<f64>) -> Function58 {
        let mut f = Function58::complex_frf("t", node, dof(node), dof(1), 0.0, 1.0 / RATE, vec![]);
        f.function_type = 1;
        f.ordinate_type = OrdinateType::RealDouble;
        f.axes[1].data_type = kind;
        f.axes[1].units = label.into();
        f.data = Ordinate::Real(values);
        f
    }

    /// Written by lamdyn's writer and read back (ASCII, then binary 58b).
    fn file(records: Vec<Function58>) -> Vec<UffFile> {
        let ds: Vec<Dataset> = records
            .into_iter()
            .map(|f| Dataset::Function(Box::new(f)))
            .collect();
        [
            Encoding::Ascii,
            Encoding::Binary {
                little_endian: true,
            },
        ]
        .into_iter()
        .map(|e| crate::read(&crate::write(&ds, e).unwrap()[..]).unwrap())
        .collect()
    }

    fn channel(name: &str) -> Channel {
        Channel::new(name, [0.0; 3], [0.0, 0.0, 1.0]).unwrap()
    }

    fn signal(n: usize, phase: f64) -> Vec<f64> {
        (0..n).map(|k| (0.1 * k as f64 + phase).sin()).collect()
    }

    #[test]
    fn force_and_responses_in_si_units() {
        let force = signal(64, 0.0);
        let acc_g = signal(64, 1.0);
        for f in file(vec![
            record(1, 13, "N", force.clone()),
            record(2, 0, "g", acc_g.clone()),
            record(3, 12, "m/s^2", acc_g.clone()),
        ]) {
            let r =
                time_record(&f, &[channel("2+Z"), channel("3+Z")], &channel("1+Z"), None).unwrap();
            assert_eq!(r.quantity, Quantity::Accelerance);
            assert!((r.rate_hz - RATE).abs() < 1e-9 * RATE);
            // ASCII prints 13 significant digits.
            let close = |a: &[f64], b: &[f64], scale: f64| {
                a.iter().zip(b).all(|(x, y)| (x - y * scale).abs() < 1e-12)
            };
            assert!(close(&r.force, &force, 1.0));
            assert!(close(&r.responses[0], &acc_g, 9.806_65));
            assert!(close(&r.responses[1], &acc_g, 1.0));
        }
    }

    fn error(records: Vec<Function58>, quantity: Option<Quantity>) -> String {
        let f = &file(records)[0];
        time_record(f, &[channel("2+Z")], &channel("1+Z"), quantity)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn bad_time_records_are_named() {
        let ok = |node, kind, label: &str| record(node, kind, label, signal(64, 0.0));
        let e = error(vec![ok(1, 13, "N")], None);
        assert!(
            e.contains("no time response for channel '2+Z'; the file's are 1+Z"),
            "{e}"
        );
        let e = error(
            vec![ok(1, 13, "N"), record(2, 12, "", signal(60, 0.0))],
            None,
        );
        assert!(e.contains("2+Z has 60 samples, the force 1+Z 64"), "{e}");
        let mut slow = ok(2, 12, "");
        slow.abscissa = Abscissa::Even {
            start: 0.0,
            step: 2.0 / RATE,
        };
        let e = error(vec![ok(1, 13, "N"), slow], None);
        assert!(
            e.contains("2+Z is sampled every 0.002 s, the force 1+Z every 0.001 s"),
            "{e}"
        );
        let mut late = ok(2, 12, "");
        late.abscissa = Abscissa::Even {
            start: 1.0,
            step: 1.0 / RATE,
        };
        let e = error(vec![ok(1, 13, "N"), late], None);
        assert!(e.contains("starts at 1 s"), "{e}");
        let mut gap = ok(1, 13, "N");
        let mut t: Vec<f64> = (0..64).map(|k| k as f64 / RATE).collect();
        t[40..].iter_mut().for_each(|v| *v += 1.0 / RATE);
        gap.abscissa = Abscissa::Uneven(t);
        let e = error(vec![gap, ok(2, 12, "")], None);
        assert!(e.contains("a gap (a missing sample?)"), "{e}");
        let e = error(vec![ok(1, 12, "m/s^2"), ok(2, 12, "")], None);
        assert!(
            e.contains("the reference channel 1+Z is not a force"),
            "{e}"
        );
        let e = error(vec![ok(1, 13, "N"), ok(2, 0, "V")], None);
        assert!(e.contains("give the quantity (--quantity)"), "{e}");
        let e = error(
            vec![ok(1, 13, "N"), ok(2, 8, "m")],
            Some(Quantity::Accelerance),
        );
        assert!(
            e.contains("is a receptance record, but the responses are accelerance"),
            "{e}"
        );
        let e = error(vec![ok(1, 13, "N"), ok(2, 12, ""), ok(2, 12, "")], None);
        assert!(e.contains("'2+Z' has two time responses"), "{e}");
        let e = error(vec![], None);
        assert!(
            e.contains("no time response (dataset 58 of function type 1)"),
            "{e}"
        );
    }
}
