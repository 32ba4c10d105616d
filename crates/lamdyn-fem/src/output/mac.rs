//! Modal assurance criterion [Allemang & Brown 1982]:
//! MAC(φ, ψ) = |φᵀψ|² / ((φᵀφ)(ψᵀψ)), 1 for parallel shapes, 0 for orthogonal ones.

/// MAC of two shape vectors of equal length.
///
/// # Panics
/// If the lengths differ (a programming error).
pub fn mac(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "expected shapes of equal length");
    let ab: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let aa: f64 = a.iter().map(|x| x * x).sum();
    let bb: f64 = b.iter().map(|x| x * x).sum();
    if aa == 0.0 || bb == 0.0 {
        0.0
    } else {
        ab * ab / (aa * bb)
    }
}

/// MAC between every shape of `a` and every shape of `b` (rows: a, columns: b).
pub fn mac_matrix(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    a.iter()
        .map(|x| b.iter().map(|y| mac(x, y)).collect())
        .collect()
}
