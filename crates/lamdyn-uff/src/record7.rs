//! Dataset 58's record 7 (ordinate type, point count, spacing) and the byte count of the
//! binary record 12 it implies: what the scanner needs to find the end of a 58b dataset, kept
//! apart from the dataset's parser ([`crate::d58`]) so that the scanner does not depend on it.

use crate::fields::cols;
use serde::Serialize;

/// Precision and kind of the ordinate (record 7, field 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum OrdinateType {
    /// Code 2.
    RealSingle,
    /// Code 4.
    RealDouble,
    /// Code 5.
    ComplexSingle,
    /// Code 6.
    ComplexDouble,
}

impl OrdinateType {
    pub(crate) fn from_code(c: i64) -> Option<Self> {
        Some(match c {
            2 => Self::RealSingle,
            4 => Self::RealDouble,
            5 => Self::ComplexSingle,
            6 => Self::ComplexDouble,
            _ => return None,
        })
    }
    /// The code of record 7.
    pub fn code(self) -> i64 {
        match self {
            Self::RealSingle => 2,
            Self::RealDouble => 4,
            Self::ComplexSingle => 5,
            Self::ComplexDouble => 6,
        }
    }
    /// Complex ordinate.
    pub fn is_complex(self) -> bool {
        matches!(self, Self::ComplexSingle | Self::ComplexDouble)
    }
    /// Double precision.
    pub fn is_double(self) -> bool {
        matches!(self, Self::RealDouble | Self::ComplexDouble)
    }
}

/// The binary size of record 12 from records 6–7 (`None` if they do not parse).
pub(crate) fn layout_bytes(lines: &[(usize, String)]) -> Option<usize> {
    let r7 = &lines.get(6)?.1;
    let t = OrdinateType::from_code(cols(r7, 0, 10).trim().parse().ok()?)?;
    let n: usize = cols(r7, 10, 20).trim().parse().ok()?;
    let even = cols(r7, 20, 30).trim() == "1";
    let size = if t.is_double() { 8 } else { 4 };
    let y_per = if t.is_complex() { 2 } else { 1 };
    n.checked_mul(y_per * size + if even { 0 } else { 4 })
}
