//! Three-vectors as `[f64; 3]`, with the few operations the elements need.

/// A point or vector in 3D, m or dimensionless.
pub type V3 = [f64; 3];

/// a + b.
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
/// a − b.
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
/// s · a.
pub fn scale(s: f64, a: V3) -> V3 {
    [s * a[0], s * a[1], s * a[2]]
}
/// a · b.
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
/// a × b.
pub fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
/// |a|.
pub fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}
/// a/|a| (a must be non-zero).
pub fn unit(a: V3) -> V3 {
    scale(1.0 / norm(a), a)
}

/// An orthonormal pair (V1, V2) completing the unit director Vn to a right-handed triad
/// (V1 × V2 = Vn): V1 = a × Vn / |a × Vn| with a the global axis least aligned with Vn.
pub fn tangent_pair(vn: V3) -> (V3, V3) {
    let k = (0..3)
        .min_by(|&i, &j| vn[i].abs().total_cmp(&vn[j].abs()))
        .unwrap_or(0);
    let mut a = [0.0; 3];
    a[k] = 1.0;
    let v1 = unit(cross(a, vn));
    let v2 = cross(vn, v1);
    (v1, v2)
}

/// Inverse of the 3×3 matrix with columns c0, c1, c2, returned as its rows (the contravariant
/// base vectors when the columns are the covariant ones), and the determinant.
pub fn inverse_columns(c0: V3, c1: V3, c2: V3) -> ([V3; 3], f64) {
    let det = dot(c0, cross(c1, c2));
    let r0 = scale(1.0 / det, cross(c1, c2));
    let r1 = scale(1.0 / det, cross(c2, c0));
    let r2 = scale(1.0 / det, cross(c0, c1));
    ([r0, r1, r2], det)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triads_are_right_handed_and_orthonormal() {
        for vn in [
            [0.0, 0.0, 1.0],
            [0.0, 1.0, 0.0],
            unit([0.3, -0.2, 0.9]),
            unit([1.0, 1.0, 1.0]),
        ] {
            let (v1, v2) = tangent_pair(vn);
            assert!((dot(v1, v2)).abs() < 1e-15 && (norm(v1) - 1.0).abs() < 1e-15);
            let n = cross(v1, v2);
            assert!(norm(sub(n, vn)) < 1e-15);
        }
    }

    #[test]
    fn inverse_gives_contravariant_basis() {
        let (c0, c1, c2) = ([2.0, 0.1, 0.0], [0.3, 1.5, 0.2], [0.0, 0.1, 1.0]);
        let (rows, det) = inverse_columns(c0, c1, c2);
        assert!(det > 0.0);
        for (i, r) in rows.iter().enumerate() {
            for (j, c) in [c0, c1, c2].iter().enumerate() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((dot(*r, *c) - want).abs() < 1e-13);
            }
        }
    }
}
