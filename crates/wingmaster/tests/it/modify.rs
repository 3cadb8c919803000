//! Eq. (40): zero deviation is the identity; thickness and camber deviations move the points
//! as the B-spline deviations say.

use testkit::assert_close;
use wingmaster::modify::SectionModifier;
use wingmaster::{FitOptions, fit};

use crate::load;

#[test]
fn zero_deviation_is_identity_bit_for_bit() {
    for name in ["naca2412.dat", "sc20714.dat", "mh112.dat"] {
        let f = fit(&load(name), &FitOptions::default()).unwrap();
        let m = SectionModifier::from_fit(&f).unwrap();
        let zero = vec![[0.0, 0.0]; f.params.camber.len()];
        let q = m.apply(&f.params.thickness, &zero).unwrap();
        assert_eq!(q.len(), f.points.len());
        for (a, b) in q.iter().zip(&f.points) {
            assert_eq!(a[0].to_bits(), b[0].to_bits());
            assert_eq!(a[1].to_bits(), b[1].to_bits());
        }
    }
}

#[test]
fn thickness_and_camber_deviations() {
    let f = fit(&load("naca0012.dat"), &FitOptions::default()).unwrap();
    let m = SectionModifier::from_fit(&f).unwrap();
    let nc = f.params.camber.len();
    // +0.01 maximum thickness: at the maximum-thickness station each surface moves 0.005.
    let mut t = f.params.thickness.clone();
    t.tmax += 0.01;
    let q = m.apply(&t, &vec![[0.0, 0.0]; nc]).unwrap();
    let xt = f.params.thickness.xtmax;
    let (i, _) = f
        .points
        .iter()
        .enumerate()
        .filter(|(k, _)| f.sigma[*k] > 0.0)
        .min_by(|a, b| (a.1[0] - xt).abs().total_cmp(&(b.1[0] - xt).abs()))
        .unwrap();
    assert_close!(q[i][1] - f.points[i][1], 0.005, rel = 0.05);
    // Symmetric change: the lower surface moves down by the same amount.
    let (j, _) = f
        .points
        .iter()
        .enumerate()
        .filter(|(k, _)| f.sigma[*k] < 0.0)
        .min_by(|a, b| (a.1[0] - xt).abs().total_cmp(&(b.1[0] - xt).abs()))
        .unwrap();
    assert_close!(q[j][1] - f.points[j][1], -0.005, rel = 0.05);
    // A uniform camber deviation Σ ΔQ_j B_j = const (partition of unity) shifts every point.
    let q = m
        .apply(&f.params.thickness, &vec![[0.0, 0.003]; nc])
        .unwrap();
    for (a, b) in q.iter().zip(&f.points) {
        assert_close!(a[1] - b[1], 0.003, rel = 1e-12);
        assert_eq!(a[0], b[0]);
    }
    // Mismatched sizes are errors, not panics.
    assert!(m.apply(&f.params.thickness, &[[0.0, 0.0]]).is_err());
}
