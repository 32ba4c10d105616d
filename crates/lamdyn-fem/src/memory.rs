//! Memory a modal solve needs, estimated before anything large is allocated.
//!
//! A mesh inside the documented size range can still need more memory than the machine has
//! (`lamdyn modes --elements 2000x2000` is 24 million dofs); without a check the process is
//! killed by the allocator mid-way. [`check_modal_memory`] refuses such a model up front with
//! the figures.

use crate::error::FemError;

/// Peak memory of assembly, factorization and Lanczos per dof, bytes: measured as the peak
/// resident size of `lamdyn modes --example paper-plate` (20 modes) at 100 × 100, 200 × 200
/// and 400 × 400 elements: 8.5, 8.8 and 8.8 kB per dof (61 k, 242 k and 966 k dofs, 2 cores),
/// rounded up.
pub const MODAL_BYTES_PER_DOF: f64 = 9.5e3;

/// Estimated peak memory of a modal solve with `n_dofs` dofs, bytes.
pub fn modal_memory_bytes(n_dofs: usize) -> f64 {
    MODAL_BYTES_PER_DOF * n_dofs as f64
}

/// Memory available to this process, bytes: `MemAvailable` of `/proc/meminfo` (Linux), or
/// `None` where it cannot be read.
pub fn available_bytes() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0)
}

/// Refuses a model whose estimated modal-solve memory exceeds what is available.
///
/// # Errors
/// [`FemError::InvalidParameter`] with the estimate and the available memory in GB.
pub fn check_modal_memory(n_dofs: usize) -> Result<(), FemError> {
    let need = modal_memory_bytes(n_dofs);
    match available_bytes() {
        Some(have) if need > have => Err(FemError::InvalidParameter {
            context: "mesh".into(),
            field: "size".into(),
            value: format!("{n_dofs} dofs"),
            requirement: format!(
                "needs about {:.1} GB for a modal solve, more than the {:.1} GB available: use \
                 fewer elements",
                need / 1e9,
                have / 1e9
            ),
        }),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_model_fits_and_an_absurd_one_does_not() {
        assert!(check_modal_memory(6 * 100).is_ok());
        if available_bytes().is_some() {
            let e = check_modal_memory(usize::MAX / 1_000_000)
                .unwrap_err()
                .to_string();
            assert!(e.contains("GB for a modal solve"), "{e}");
        }
    }
}
