//! Uniform cubic B-spline basis (SN08 / thesis eq. 4.9–4.12), used by the height pyramid's
//! synthesis filter (Sigg & Hadwiger 2005), by eq. 17's `ω_max` search and by `M_bspl`.

/// The four uniform cubic B-spline weights for fractional position `t ∈ [0, 1]`, applied to
/// samples `i−1, i, i+1, i+2` where `t` is measured from sample `i`.
pub fn weights(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [
        s * s * s / 6.0,
        (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
        (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
        t * t * t / 6.0,
    ]
}

/// Weights at a knot (`t = 0`): `{1/6, 2/3, 1/6, 0}`.
pub const KNOT: [f64; 4] = [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0, 0.0];
/// Weights at a mid-point (`t = 1/2`): `{1/48, 23/48, 23/48, 1/48}`.
pub const MIDPOINT: [f64; 4] = [1.0 / 48.0, 23.0 / 48.0, 23.0 / 48.0, 1.0 / 48.0];

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn partition_of_unity_and_constants() {
        for k in 0..=10 {
            let w = weights(k as f64 / 10.0);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        }
        for (a, b) in weights(0.0).iter().zip(KNOT) {
            assert!((a - b).abs() < 1e-15);
        }
        for (a, b) in weights(0.5).iter().zip(MIDPOINT) {
            assert!((a - b).abs() < 1e-15);
        }
    }
}
