//! UFF FRFs → [`FrfSet`] (responses × references × lines) in SI units, and back.
//!
//! **Which datasets.** The datasets 58 of function type 4 (FRF) with complex ordinates. They
//! must share one abscissa (Hz); every response × reference pair must be present once.
//!
//! **Quantity and units.** The numerator's specific data type (record 9) gives the quantity —
//! 8 displacement → receptance, 11 velocity → mobility, 12 acceleration → accelerance — and the
//! denominator must be a force (13) or unknown. When the type is unknown (0), the units label
//! decides: `m/N`, `(m/s)/N`, `m/s^2/N`, `g/N`, with `mm`, `in` and `lbf` variants. The values
//! are converted to SI by the unit exponents of records 9–10 and the factors of the file's last
//! dataset 164 (value_SI = value × L^l F^f T^t for the numerator over the same for the
//! denominator); when the exponents are all zero, by the units label.
//!
//! **Channels.** Each response and reference becomes a channel `node+dir` (e.g. `12+Z`) at the
//! node's position (datasets 15/2411 of the same file, converted to metres; the origin if the
//! file has no geometry), along its direction (±1..±3 → ±x, ±y, ±z), expressed in the global
//! frame through the node's displacement coordinate system when the file defines it (18/2420).
//! A scalar DOF (direction 0, as in test systems that name the point in the entity field, e.g.
//! `.1.Z-`) becomes a channel named by its entity with +z as a placeholder direction: the file
//! does not give one, so sensor directions must then come from elsewhere (the job file).

use crate::d58::{Abscissa, AxisSpec, Dof, Function58, Ordinate, OrdinateType};
use crate::error::UffError;
use crate::geometry::{CoordinateSystem, Node};
use crate::meta::Units164;
use crate::{Dataset, UffFile};
use lamdyn_frf::{Channel, FrfSet, Quantity};
use num_complex::Complex64;
use std::collections::HashMap;

fn convert(reason: String) -> UffError {
    UffError::Convert(reason)
}

/// (quantity, SI factor of the numerator over the denominator) from a units label such as
/// `(m/s)/N` or `g/N`.
pub fn quantity_from_label(label: &str) -> Option<(Quantity, f64)> {
    let s: String = label
        .chars()
        .filter(|c| !c.is_whitespace() && *c != '(' && *c != ')')
        .collect::<String>()
        .to_ascii_lowercase();
    let (num, den) = s.rsplit_once('/')?;
    let force = match den {
        "n" => 1.0,
        "kn" => 1e3,
        "lbf" | "lb" => 4.448_221_615_260_5,
        _ => return None,
    };
    let (q, f) = match num {
        "m" => (Quantity::Receptance, 1.0),
        "mm" => (Quantity::Receptance, 1e-3),
        "in" => (Quantity::Receptance, 0.0254),
        "m/s" => (Quantity::Mobility, 1.0),
        "mm/s" => (Quantity::Mobility, 1e-3),
        "in/s" => (Quantity::Mobility, 0.0254),
        "m/s^2" | "m/s2" | "m/s**2" => (Quantity::Accelerance, 1.0),
        "mm/s^2" | "mm/s2" => (Quantity::Accelerance, 1e-3),
        "in/s^2" | "in/s2" => (Quantity::Accelerance, 0.0254),
        "g" => (Quantity::Accelerance, 9.806_65),
        _ => return None,
    };
    Some((q, f / force))
}

fn quantity_of(f: &Function58, units: &Units164) -> Result<(Quantity, f64), UffError> {
    let [_, num, den, _] = &f.axes;
    let by_type = match num.data_type {
        8 => Some(Quantity::Receptance),
        11 => Some(Quantity::Mobility),
        12 => Some(Quantity::Accelerance),
        _ => None,
    };
    if den.data_type != 0 && den.data_type != 13 {
        return Err(convert(format!(
            "FRF {}: denominator data type {} is not a force (13)",
            dof_name(&f.response),
            den.data_type
        )));
    }
    let exps = [
        num.length_exp,
        num.force_exp,
        num.temperature_exp,
        den.length_exp,
        den.force_exp,
        den.temperature_exp,
    ];
    let by_label = quantity_from_label(&num.units)
        .or_else(|| quantity_from_label(&format!("{}/{}", num.units, den.units)));
    let factor = if exps.iter().any(|e| *e != 0) {
        Some(
            units.factor(num.length_exp, num.force_exp, num.temperature_exp)
                / units.factor(den.length_exp, den.force_exp, den.temperature_exp),
        )
    } else {
        by_label.map(|b| b.1)
    };
    match (by_type.or(by_label.map(|b| b.0)), factor) {
        (Some(q), Some(s)) => Ok((q, s)),
        (Some(q), None) => Ok((q, 1.0)),
        _ => Err(convert(format!(
            "FRF {}: neither the numerator data type ({}) nor its units label '{}' says whether it \
             is a receptance, mobility or accelerance",
            dof_name(&f.response),
            num.data_type,
            num.units
        ))),
    }
}

/// `node+X`-style channel name of a DOF.
pub fn dof_name(d: &Dof) -> String {
    let axis = ["S", "X", "Y", "Z", "RX", "RY", "RZ"];
    let a = axis
        .get(d.direction.unsigned_abs() as usize)
        .copied()
        .unwrap_or("?");
    format!("{}{}{a}", d.node, if d.direction < 0 { '-' } else { '+' })
}

/// The channel name of a DOF: [`dof_name`], or for a scalar DOF (direction 0) its entity when
/// the file names one.
pub fn channel_name(d: &Dof) -> String {
    if d.direction == 0 && !(d.entity.is_empty() || d.entity == "NONE") {
        d.entity.clone()
    } else {
        dof_name(d)
    }
}

struct Geometry<'a> {
    nodes: HashMap<i64, &'a Node>,
    systems: HashMap<i64, &'a CoordinateSystem>,
    length: f64,
}

impl Geometry<'_> {
    fn channel(&self, d: &Dof) -> Result<Channel, UffError> {
        let k = d.direction.unsigned_abs() as usize;
        if k == 0 {
            // A scalar DOF: the file says nothing about the direction.
            let name = channel_name(d);
            let point = self
                .nodes
                .get(&d.node)
                .map_or([0.0; 3], |n| n.xyz.map(|v| v * self.length));
            return Channel::new(name, point, [0.0, 0.0, 1.0]).map_err(|e| convert(e.to_string()));
        }
        if !(1..=3).contains(&k) {
            return Err(convert(format!(
                "DOF {}: direction {} is not a translation (±1, ±2, ±3)",
                dof_name(d),
                d.direction
            )));
        }
        let mut dir = [0.0; 3];
        dir[k - 1] = d.direction.signum() as f64;
        let node = self.nodes.get(&d.node);
        let point = node.map_or([0.0; 3], |n| n.xyz.map(|v| v * self.length));
        if let Some(cs) = node.and_then(|n| self.systems.get(&n.displacement_cs)) {
            dir = cs.to_global(dir);
        }
        Channel::new(dof_name(d), point, dir).map_err(|e| convert(e.to_string()))
    }
}

impl<'a> Geometry<'a> {
    /// The nodes and coordinate systems of `file`, lengths in its unit `length` (m per unit).
    fn of(file: &'a UffFile, length: f64) -> Self {
        let mut geo = Geometry {
            nodes: HashMap::new(),
            systems: HashMap::new(),
            length,
        };
        for d in &file.datasets {
            match &d.dataset {
                Dataset::Nodes(n) => geo.nodes.extend(n.nodes.iter().map(|n| (n.label, n))),
                Dataset::CoordinateSystems(c) => geo.systems.extend(c.iter().map(|c| (c.label, c))),
                _ => {}
            }
        }
        geo
    }
}

/// The FRF set of a file's FRFs (module docs).
///
/// # Errors
/// [`UffError::Convert`] when the file has no complex FRF, when FRFs have different abscissas,
/// a pair is missing or repeated, the quantity cannot be told, or quantities differ.
pub fn to_frf_set(file: &UffFile) -> Result<FrfSet, UffError> {
    let units = file.units().cloned().unwrap_or_else(Units164::si);
    let frfs: Vec<&Function58> = file
        .functions()
        .filter(|f| f.function_type == 4 && f.ordinate_type.is_complex())
        .collect();
    let Some(first) = frfs.first() else {
        return Err(convert(
            "no complex FRF (dataset 58 of function type 4) in the file".into(),
        ));
    };
    let x = first.x();
    let geo = Geometry::of(file, units.length);
    let mut responses: Vec<Dof> = Vec::new();
    let mut references: Vec<Dof> = Vec::new();
    let mut quantity = None;
    let mut scales = Vec::with_capacity(frfs.len());
    for f in &frfs {
        // The same abscissa record and length give the same axis; others are compared by value.
        let same_record = f.abscissa == first.abscissa && f.data.len() == first.data.len();
        if !same_record && f.x() != x {
            return Err(convert(format!(
                "FRF {} / {} has a different frequency axis from the first FRF",
                dof_name(&f.response),
                dof_name(&f.reference)
            )));
        }
        let (q, scale) = quantity_of(f, &units)?;
        scales.push(scale);
        if quantity.is_some_and(|p| p != q) {
            return Err(convert(format!(
                "FRF {} is a {q:?}, the first FRF a {:?}",
                dof_name(&f.response),
                quantity.unwrap_or(q)
            )));
        }
        quantity = Some(q);
        let key = |d: &Dof| (d.node, d.direction, d.entity.clone());
        if !responses.iter().any(|r| key(r) == key(&f.response)) {
            responses.push(f.response.clone());
        }
        if !references.iter().any(|r| key(r) == key(&f.reference)) {
            references.push(f.reference.clone());
        }
    }
    let nl = x.len();
    let (nr, nf) = (responses.len(), references.len());
    // Each (response, reference) pair's values and their scale to SI.
    let mut sources: Vec<Option<(&[Complex64], f64)>> = vec![None; nr * nf];
    let mut seen = vec![false; nr * nf];
    for (f, scale) in frfs.iter().zip(&scales) {
        let i = responses.iter().position(|r| r == &f.response).unwrap_or(0);
        let j = references
            .iter()
            .position(|r| r == &f.reference)
            .unwrap_or(0);
        if std::mem::replace(&mut seen[i * nf + j], true) {
            return Err(convert(format!(
                "FRF {} / {} appears twice",
                dof_name(&f.response),
                dof_name(&f.reference)
            )));
        }
        if let Ordinate::Complex(v) = &f.data {
            sources[i * nf + j] = Some((v, *scale));
        }
    }
    if let Some(p) = seen.iter().position(|s| !s) {
        return Err(convert(format!(
            "no FRF for response {} and reference {}",
            dof_name(&responses[p / nf]),
            dof_name(&references[p % nf])
        )));
    }
    let data = in_si(&sources, nl);
    let resp = responses
        .iter()
        .map(|d| geo.channel(d))
        .collect::<Result<Vec<_>, _>>()?;
    let refs = references
        .iter()
        .map(|d| geo.channel(d))
        .collect::<Result<Vec<_>, _>>()?;
    FrfSet::new(
        x,
        resp,
        refs,
        quantity.unwrap_or(Quantity::Receptance),
        data,
    )
    .map_err(|e| convert(e.to_string()))
}

/// The FRF set's values: each pair's `nl` values of `sources` times its scale, NaN for a pair
/// without complex values (refused by the set); the pairs in parallel, the memory touched first
/// on the threads that fill it.
fn in_si(sources: &[Option<(&[Complex64], f64)>], nl: usize) -> Vec<Complex64> {
    use rayon::prelude::*;
    let nan = Complex64::new(f64::NAN, f64::NAN);
    let mut data: Vec<Complex64> = rayon::iter::repeat_n(nan, sources.len() * nl).collect();
    data.par_chunks_mut(nl.max(1))
        .zip(sources)
        .for_each(|(out, source)| {
            if let Some((values, scale)) = source {
                out.iter_mut()
                    .zip(values.iter())
                    .for_each(|(o, h)| *o = h * scale);
            }
        });
    data
}

/// The sign and axis code (±1..±3) of a unit direction along a global axis, if it is one.
fn axis_code(d: [f64; 3]) -> Option<i64> {
    (0..3)
        .find(|&c| (d[c].abs() - 1.0).abs() < 1e-9)
        .map(|c| (c as i64 + 1) * d[c].signum() as i64)
}

/// A channel's node and direction: a name `node+X` / `node-Z` gives them; otherwise the channel's
/// index + 1 as node and its direction's axis.
fn dof_of(c: &Channel, index: usize) -> Result<Dof, UffError> {
    let parsed = c.name.find(['+', '-']).and_then(|p| {
        let node: i64 = c.name[..p].parse().ok()?;
        let sign = if &c.name[p..p + 1] == "-" { -1 } else { 1 };
        let axis = match &c.name[p + 1..] {
            "X" | "x" => 1,
            "Y" | "y" => 2,
            "Z" | "z" => 3,
            _ => return None,
        };
        Some((node, sign * axis))
    });
    let (node, direction) = match parsed {
        Some(v) => v,
        None => {
            let axis = axis_code(c.direction).ok_or_else(|| {
                convert(format!(
                    "channel '{}': its direction {:?} is not along a global axis; UFF 58 needs a \
                     node and an axis",
                    c.name, c.direction
                ))
            })?;
            (index as i64 + 1, axis)
        }
    };
    Ok(Dof {
        entity: "NONE".into(),
        node,
        direction,
    })
}

/// One node per channel's node label, at the channel's point.
///
/// # Errors
/// As [`from_frf_set`].
fn channel_nodes(set: &FrfSet) -> Result<Vec<Node>, UffError> {
    let mut nodes: Vec<Node> = Vec::new();
    for (k, c) in set.responses().iter().chain(set.references()).enumerate() {
        let d = dof_of(c, k)?;
        match nodes.iter().find(|n| n.label == d.node) {
            Some(n) if n.xyz != c.point_m => {
                return Err(convert(format!(
                    "channel '{}' puts node {} at {:?}, another channel at {:?}",
                    c.name, d.node, c.point_m, n.xyz
                )));
            }
            Some(_) => {}
            None => nodes.push(Node {
                label: d.node,
                definition_cs: 0,
                displacement_cs: 0,
                color: 1,
                xyz: c.point_m,
            }),
        }
    }
    Ok(nodes)
}

/// A dataset 58's axes for an FRF of `quantity` in SI: frequency in Hz, the ordinate, the
/// force in N.
fn frf_axes(quantity: Quantity) -> [AxisSpec; 4] {
    let (data_type, units, lexp) = match quantity {
        Quantity::Receptance => (8, "m/N", 1),
        Quantity::Mobility => (11, "m/s/N", 1),
        Quantity::Accelerance => (12, "m/s^2/N", 1),
    };
    [
        AxisSpec {
            data_type: 18,
            length_exp: 0,
            force_exp: 0,
            temperature_exp: 0,
            label: "Frequency".into(),
            units: "Hz".into(),
        },
        AxisSpec {
            data_type,
            length_exp: lexp,
            force_exp: 0,
            temperature_exp: 0,
            label: format!("{quantity:?}"),
            units: units.into(),
        },
        AxisSpec {
            data_type: 13,
            length_exp: 0,
            force_exp: 1,
            temperature_exp: 0,
            label: "Force".into(),
            units: "N".into(),
        },
        AxisSpec::none(),
    ]
}

/// lamdyn's 151 header ([`crate::meta::Header151::lamdyn`]: how lamdyn knows its own file
/// before replacing it), a dataset 2411 with the channels' nodes (metres), then datasets 58
/// (complex double, even
/// abscissa if the lines are evenly spaced) for every pair of a set, in SI units (unit exponents
/// and labels set accordingly).
///
/// # Errors
/// [`UffError::Convert`] for channels that cannot be named as node and axis, or two channels on
/// one node label at different points.
pub fn from_frf_set(set: &FrfSet) -> Result<Vec<Dataset>, UffError> {
    let f = set.freqs_hz();
    let even = f.len() > 1 && {
        let step = (f[f.len() - 1] - f[0]) / (f.len() - 1) as f64;
        f.windows(2)
            .all(|w| ((w[1] - w[0]) / step - 1.0).abs() < 1e-9)
    };
    let abscissa = if even {
        Abscissa::Even {
            start: f[0],
            step: (f[f.len() - 1] - f[0]) / (f.len() - 1) as f64,
        }
    } else {
        Abscissa::Uneven(f.to_vec())
    };
    let nodes = channel_nodes(set)?;
    let mut out = vec![
        Dataset::Header(crate::meta::Header151::lamdyn("FRFs")),
        Dataset::Nodes(crate::geometry::Nodes {
            dataset: 2411,
            nodes,
        }),
    ];
    for (i, r) in set.responses().iter().enumerate() {
        let response = dof_of(r, i)?;
        for (j, q) in set.references().iter().enumerate() {
            let reference = dof_of(q, set.responses().len() + j)?;
            out.push(Dataset::Function(Box::new(Function58 {
                id_lines: [
                    format!("FRF {} / {}", r.name, q.name),
                    "NONE".into(),
                    "NONE".into(),
                    "lamdyn".into(),
                    "NONE".into(),
                ],
                function_type: 4,
                function_id: (i * set.references().len() + j + 1) as i64,
                version: 0,
                load_case: 0,
                response: response.clone(),
                reference,
                ordinate_type: OrdinateType::ComplexDouble,
                abscissa: abscissa.clone(),
                z_value: 0.0,
                axes: frf_axes(set.quantity()),
                data: Ordinate::Complex(set.curve(i, j).to_vec()),
            })));
        }
    }
    Ok(out)
}
