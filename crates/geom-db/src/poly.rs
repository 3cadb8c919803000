//! Power-basis polynomials with vector coefficients: Horner evaluation of Eq. (2)
//! r(u) = a_0 + a_1 u + … + a_n u^n and of its first two derivatives, without allocation.

use crate::prelude::{Point3, Vector3};

/// r(u) = Σ a_k u^k by Horner's rule (Eq. 2/4).
#[inline]
pub fn horner(coeffs: &[Point3], u: f64) -> Vector3 {
    let mut acc = Vector3::zeros();
    for c in coeffs.iter().rev() {
        acc = acc * u + c.coords;
    }
    acc
}

/// r(u), r'(u) and r''(u) by a simultaneous Horner scheme.
#[inline]
pub fn horner_d2(coeffs: &[Point3], u: f64) -> (Vector3, Vector3, Vector3) {
    let mut p = Vector3::zeros();
    let mut d1 = Vector3::zeros();
    let mut d2 = Vector3::zeros();
    for c in coeffs.iter().rev() {
        d2 = d2 * u + d1;
        d1 = d1 * u + p;
        p = p * u + c.coords;
    }
    (p, d1, d2 * 2.0)
}

/// Scalar Horner: Σ c_k u^k.
#[inline]
pub fn horner_f64(coeffs: &[f64], u: f64) -> f64 {
    coeffs.iter().rev().fold(0.0, |acc, &c| acc * u + c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn horner_matches_powers() {
        let c = [
            Point3::new(1.0, 2.0, 3.0),
            Point3::new(-1.0, 0.5, 0.0),
            Point3::new(0.25, 0.0, 2.0),
            Point3::new(0.0, 1.0, -1.0),
        ];
        let u: f64 = 0.3;
        let mut want = Vector3::zeros();
        let mut d1 = Vector3::zeros();
        let mut d2 = Vector3::zeros();
        for (k, a) in c.iter().enumerate() {
            want += a.coords * u.powi(k as i32);
            if k >= 1 {
                d1 += a.coords * (k as f64) * u.powi(k as i32 - 1);
            }
            if k >= 2 {
                d2 += a.coords * (k * (k - 1)) as f64 * u.powi(k as i32 - 2);
            }
        }
        let (p, q1, q2) = horner_d2(&c, u);
        assert!((p - want).norm() < 1e-15);
        assert!((horner(&c, u) - want).norm() < 1e-15);
        assert!((q1 - d1).norm() < 1e-14);
        assert!((q2 - d2).norm() < 1e-14);
    }
}
