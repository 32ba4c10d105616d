//! Small statistics shared by the stages.

/// Sample standard deviation (n − 1) of each part of `points` (n ≥ 2).
pub fn sample_sd(points: &[[f64; 2]]) -> [f64; 2] {
    let n = points.len() as f64;
    let sd = |k: usize| {
        let mean = points.iter().map(|p| p[k]).sum::<f64>() / n;
        (points.iter().map(|p| (p[k] - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    };
    [sd(0), sd(1)]
}

#[cfg(test)]
mod tests {
    #[test]
    fn sample_sd_divides_by_n_minus_one() {
        let sd = super::sample_sd(&[[1.0, 10.0], [3.0, 10.0]]);
        assert_eq!(sd, [2f64.sqrt(), 0.0]);
    }
}
