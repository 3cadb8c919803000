//! Gauss–Legendre quadrature on [0, 1], shared by the import's face integrals and the
//! integral constraints of `aeroshape` (volume, area).

/// The m-point Gauss–Legendre rule on [0, 1]: (node, weight) pairs, nodes ascending. The
/// nodes are the roots of the Legendre polynomial P_m, found by Newton's method from
/// Tricomi's estimate cos(π (i + 3/4) / (m + 1/2)); exact for polynomials of degree 2m − 1.
///
/// ```
/// let rule = geom_db::quadrature::gauss_legendre(3);
/// let q: f64 = rule.iter().map(|&(x, w)| w * x.powi(5)).sum();
/// assert!((q - 1.0 / 6.0).abs() < 1e-15);
/// ```
pub fn gauss_legendre(m: usize) -> Vec<(f64, f64)> {
    (0..m)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (m as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                // P_m(x) and P_{m-1}(x) by the three-term recurrence.
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=m {
                    let k = k as f64;
                    (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
                }
                dp = m as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() <= 1e-15 {
                    break;
                }
            }
            ((1.0 - x) / 2.0, 1.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::gauss_legendre;

    #[test]
    fn gauss_legendre_integrates_its_degree_exactly_and_no_more() {
        for m in 1..=20 {
            let rule = gauss_legendre(m);
            assert!(rule.windows(2).all(|w| w[0].0 < w[1].0), "m = {m}");
            // ∫_0^1 x^k dx = 1 / (k + 1) for k ≤ 2m − 1.
            for k in 0..2 * m {
                let q: f64 = rule.iter().map(|&(x, w)| w * x.powi(k as i32)).sum();
                assert!(
                    (q - 1.0 / (k as f64 + 1.0)).abs() < 1e-14,
                    "m = {m}, x^{k}: {q}"
                );
            }
            // Degree 2m is not exact: the rule is Gauss's, not a wider one (its error
            // falls below round-off beyond m = 8).
            let k = 2 * m as i32;
            let q: f64 = rule.iter().map(|&(x, w)| w * x.powi(k)).sum();
            assert!(
                m > 8 || (q - 1.0 / (k as f64 + 1.0)).abs() > 1e-12,
                "m = {m}"
            );
        }
    }
}
