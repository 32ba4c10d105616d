//! The FRF set type.

use num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use thiserror::Error;

/// Errors of FRF sets: inconsistent shapes, axes or values.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum FrfError {
    /// Shapes, axes or values that do not fit together.
    #[error("{context}: {reason}")]
    Inconsistent {
        /// Which data.
        context: String,
        /// What is wrong, with numbers and names.
        reason: String,
    },
    /// A file could not be read or parsed.
    #[error("error reading '{path}'{}: {reason}", on_line(*.line))]
    File {
        /// The file.
        path: String,
        /// 1-based line (0: not tied to a line).
        line: usize,
        /// What is wrong.
        reason: String,
    },
}

/// " line N" for a 1-based line, nothing for 0 (an error of the whole file).
fn on_line(line: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!(" line {line}")
    }
}

fn inconsistent(context: &str, reason: String) -> FrfError {
    FrfError::Inconsistent {
        context: context.into(),
        reason,
    }
}

/// What an FRF measures per unit force.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// Displacement / force, m/N.
    Receptance,
    /// Velocity / force, m/(s·N).
    Mobility,
    /// Acceleration / force, m/(s²·N).
    Accelerance,
}

impl Quantity {
    /// The factor from receptance to this quantity at ω (rad/s): 1, iω or −ω².
    pub fn from_receptance(self, omega_rad_s: f64) -> Complex64 {
        match self {
            Self::Receptance => Complex64::new(1.0, 0.0),
            Self::Mobility => Complex64::new(0.0, omega_rad_s),
            Self::Accelerance => Complex64::new(-omega_rad_s * omega_rad_s, 0.0),
        }
    }

    /// The name written in files (`receptance`, `mobility`, `accelerance`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Receptance => "receptance",
            Self::Mobility => "mobility",
            Self::Accelerance => "accelerance",
        }
    }

    /// SI unit.
    pub fn unit(self) -> &'static str {
        match self {
            Self::Receptance => "m/N",
            Self::Mobility => "m/s/N",
            Self::Accelerance => "m/s^2/N",
        }
    }
}

/// A response channel or a reference: a point (node) and a unit direction in the global frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Channel {
    /// A name for messages and reports (`"12+Z"`).
    pub name: String,
    /// Position, m (where the sensor or the hammer is).
    pub point_m: [f64; 3],
    /// Unit direction in the global frame.
    pub direction: [f64; 3],
}

impl Channel {
    /// A channel; the direction is normalised.
    ///
    /// # Errors
    /// [`FrfError::Inconsistent`] for non-finite numbers or a zero direction.
    pub fn new(
        name: impl Into<String>,
        point_m: [f64; 3],
        direction: [f64; 3],
    ) -> Result<Self, FrfError> {
        let name = name.into();
        let n = direction.iter().map(|d| d * d).sum::<f64>().sqrt();
        if !point_m.iter().chain(&direction).all(|v| v.is_finite()) {
            return Err(inconsistent(
                &format!("channel '{name}'"),
                "point and direction must be finite numbers".into(),
            ));
        }
        if n < 1e-12 {
            return Err(inconsistent(
                &format!("channel '{name}'"),
                "the direction is zero".into(),
            ));
        }
        Ok(Self {
            name,
            point_m,
            direction: direction.map(|d| d / n),
        })
    }
}

/// FRFs of `responses` × `references` channels at `freqs_hz`, stored response-major:
/// value(i, j, k) = `data[(i * n_refs + j) * n_lines + k]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrfSet {
    freqs_hz: Vec<f64>,
    responses: Vec<Channel>,
    references: Vec<Channel>,
    quantity: Quantity,
    data: Vec<Complex64>,
}

impl FrfSet {
    /// Builds a set, checking shapes, a strictly increasing positive frequency axis and finite
    /// values.
    ///
    /// # Errors
    /// [`FrfError::Inconsistent`] naming what disagrees.
    pub fn new(
        freqs_hz: Vec<f64>,
        responses: Vec<Channel>,
        references: Vec<Channel>,
        quantity: Quantity,
        data: Vec<Complex64>,
    ) -> Result<Self, FrfError> {
        let ctx = "FRF set";
        if freqs_hz.is_empty() || responses.is_empty() || references.is_empty() {
            return Err(inconsistent(
                ctx,
                format!(
                    "{} lines, {} responses, {} references: none may be empty",
                    freqs_hz.len(),
                    responses.len(),
                    references.len()
                ),
            ));
        }
        for (k, f) in freqs_hz.iter().enumerate() {
            if !(f.is_finite() && *f >= 0.0) {
                return Err(inconsistent(
                    ctx,
                    format!("frequency [{k}] = {f} Hz is not a finite non-negative number"),
                ));
            }
            if k > 0 && *f <= freqs_hz[k - 1] {
                return Err(inconsistent(
                    ctx,
                    format!(
                        "frequencies must increase: [{}] = {} Hz then [{k}] = {f} Hz",
                        k - 1,
                        freqs_hz[k - 1]
                    ),
                ));
            }
        }
        let want = responses.len() * references.len() * freqs_hz.len();
        if data.len() != want {
            return Err(inconsistent(
                ctx,
                format!(
                    "{} values for {} responses x {} references x {} lines",
                    data.len(),
                    responses.len(),
                    references.len(),
                    freqs_hz.len()
                ),
            ));
        }
        if let Some(p) = data
            .iter()
            .position(|v| !(v.re.is_finite() && v.im.is_finite()))
        {
            let (i, rest) = (
                p / (references.len() * freqs_hz.len()),
                p % (references.len() * freqs_hz.len()),
            );
            return Err(inconsistent(
                ctx,
                format!(
                    "value of response '{}' at {} Hz is not finite",
                    responses[i].name,
                    freqs_hz[rest % freqs_hz.len()]
                ),
            ));
        }
        Ok(Self {
            freqs_hz,
            responses,
            references,
            quantity,
            data,
        })
    }

    /// The set restricted to the responses `keep` (indices, in that order), every reference
    /// and line kept.
    ///
    /// # Errors
    /// [`FrfError::Inconsistent`] for no response or an index out of range.
    pub fn with_responses(&self, keep: &[usize]) -> Result<Self, FrfError> {
        let n = self.responses.len();
        if let Some(&bad) = keep.iter().find(|&&i| i >= n) {
            return Err(inconsistent(
                "FRF set",
                format!("response {bad} of {n} responses"),
            ));
        }
        let per = self.references.len() * self.freqs_hz.len();
        let data = keep
            .iter()
            .flat_map(|&i| self.data[i * per..(i + 1) * per].iter().copied())
            .collect();
        Self::new(
            self.freqs_hz.clone(),
            keep.iter().map(|&i| self.responses[i].clone()).collect(),
            self.references.clone(),
            self.quantity,
            data,
        )
    }

    /// Frequency lines, Hz.
    pub fn freqs_hz(&self) -> &[f64] {
        &self.freqs_hz
    }
    /// Response channels.
    pub fn responses(&self) -> &[Channel] {
        &self.responses
    }
    /// References (excitations).
    pub fn references(&self) -> &[Channel] {
        &self.references
    }
    /// The quantity held.
    pub fn quantity(&self) -> Quantity {
        self.quantity
    }
    /// Number of lines.
    pub fn n_lines(&self) -> usize {
        self.freqs_hz.len()
    }

    /// The FRF of response `i` to reference `j` over all lines.
    pub fn curve(&self, i: usize, j: usize) -> &[Complex64] {
        let n = self.n_lines();
        let start = (i * self.references.len() + j) * n;
        &self.data[start..start + n]
    }

    /// All values (response-major, then reference, then line).
    pub fn data(&self) -> &[Complex64] {
        &self.data
    }

    /// The same FRFs as another quantity (dividing or multiplying by iω per line). Lines at
    /// 0 Hz become 0 when dividing.
    pub fn to_quantity(&self, q: Quantity) -> Self {
        let mut data = self.data.clone();
        let n = self.n_lines();
        for (p, v) in data.iter_mut().enumerate() {
            let w = 2.0 * PI * self.freqs_hz[p % n];
            let from = self.quantity.from_receptance(w);
            let to = q.from_receptance(w);
            *v = if from.norm() == 0.0 {
                Complex64::new(0.0, 0.0)
            } else {
                *v * to / from
            };
        }
        Self {
            data,
            quantity: q,
            ..self.clone()
        }
    }

    /// The paper's RMS FRF for reference `j` (eq. 2, read as the RMS of the magnitudes):
    /// rms(ω) = √((1/N) Σ_i |H_ij(ω)|²) over the responses.
    pub fn rms(&self, j: usize) -> Vec<f64> {
        let n = self.n_lines();
        let mut acc = vec![0.0; n];
        for i in 0..self.responses.len() {
            for (a, v) in acc.iter_mut().zip(self.curve(i, j)) {
                *a += v.norm_sqr();
            }
        }
        acc.into_iter()
            .map(|a| (a / self.responses.len() as f64).sqrt())
            .collect()
    }

    /// Checks that `other` has the same axis (to 1e-9 Hz), channels and references.
    ///
    /// # Errors
    /// [`FrfError::Inconsistent`] naming the first difference.
    pub fn check_compatible(&self, other: &FrfSet) -> Result<(), FrfError> {
        let ctx = "FRF sets";
        if self.n_lines() != other.n_lines()
            || self
                .freqs_hz
                .iter()
                .zip(&other.freqs_hz)
                .any(|(a, b)| (a - b).abs() > 1e-9)
        {
            return Err(inconsistent(
                ctx,
                format!(
                    "frequency axes differ ({} lines from {} Hz against {} lines from {} Hz)",
                    self.n_lines(),
                    self.freqs_hz[0],
                    other.n_lines(),
                    other.freqs_hz[0]
                ),
            ));
        }
        if self.responses.len() != other.responses.len()
            || self.references.len() != other.references.len()
        {
            return Err(inconsistent(
                ctx,
                format!(
                    "{} x {} channels against {} x {}",
                    self.responses.len(),
                    self.references.len(),
                    other.responses.len(),
                    other.references.len()
                ),
            ));
        }
        Ok(())
    }
}
