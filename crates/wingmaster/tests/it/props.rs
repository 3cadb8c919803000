//! Property tests: conditions 1–6 and the Eq. (40) identity over random valid parameters.

use proptest::prelude::*;
use wingmaster::modify::SectionModifier;
use wingmaster::{CamberLine, SectionParams, ThicknessParams};

fn params() -> impl Strategy<Value = ThicknessParams> {
    (
        (
            0.004f64..0.03,
            0.3f64..0.7,
            0.75f64..0.98,
            0.2f64..0.45,
            0.06f64..0.2,
        ),
        (
            -1.2f64..-0.2,
            0.55f64..0.8,
            0.3f64..0.85,
            0.05f64..0.5,
            0.05f64..0.25,
        ),
    )
        .prop_map(|((r0, f1, f2, xtmax, tmax), (crv4, f6, g6, phi_te, d78))| {
            let h = tmax / 2.0;
            ThicknessParams {
                r0,
                z1: f1 * h,
                z2: f2 * h,
                xtmax,
                tmax,
                crv4,
                x6: xtmax + f6 * (1.0 - xtmax),
                z6: g6 * h,
                phi_te,
                d78,
                extra: vec![],
            }
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn conditions_hold(p in params()) {
        // Invalid combinations are rejected with an error, never a panic; proptest fails if
        // too many of the drawn sets are invalid.
        let r = p.polygon();
        prop_assume!(r.is_ok());
        let poly = r.unwrap();
        for t in [0.5 - 1e-7, 0.5 + 1e-7] {
            let d = poly.ders(t, 2);
            let slope = d[1][1] / d[1][0];
            let curv = (d[1][0] * d[2][1] - d[1][1] * d[2][0]) / d[1][0].powi(3);
            prop_assert!(slope.abs() < 1e-5 * (1.0 + p.crv4.abs()));
            prop_assert!((curv - p.crv4).abs() < 1e-4 * p.crv4.abs());
        }
        let d = poly.ders(0.0, 2);
        let kappa = (d[1][0] * d[2][1] - d[1][1] * d[2][0]).abs() / d[1][1].abs().powi(3);
        prop_assert!((1.0 / kappa - p.r0).abs() < 1e-10 * p.r0);
        let d = poly.ders(1.0, 1);
        prop_assert!((-2.0 * (d[1][1] / d[1][0]).atan() - p.phi_te).abs() < 1e-10);
    }

    #[test]
    fn zero_deviation_is_identity(p in params(), cz in -0.03f64..0.03) {
        let camber: Vec<[f64; 2]> = CamberLine::flat(5).unwrap().points().iter()
            .enumerate()
            .map(|(j, q)| [q[0], if j == 0 || j == 4 { 0.0 } else { cz }])
            .collect();
        let sp = SectionParams { name: String::new(), thickness: p.clone(), camber, te_thickness: 0.0 };
        let r = sp.build();
        prop_assume!(r.is_ok());
        let sec = r.unwrap();
        // Points off the curve: the sampled section shifted, with σ of the samples.
        let n = 40;
        let pts = sec.sample(n);
        let mut sigma = Vec::new();
        for k in (0..=n).rev() {
            let x = 0.5 * (1.0 - (std::f64::consts::PI * k as f64 / n as f64).cos());
            sigma.push(sec.thickness().t_at_x(x));
        }
        for k in 1..=n {
            let x = 0.5 * (1.0 - (std::f64::consts::PI * k as f64 / n as f64).cos());
            sigma.push(-sec.thickness().t_at_x(x));
        }
        let q: Vec<[f64; 2]> = pts.iter().map(|a| [a[0] + 1e-3, a[1] - 2e-4]).collect();
        let m = SectionModifier::new(sp.clone(), q.clone(), &sigma).unwrap();
        let out = m.apply(&p, &[[0.0, 0.0]; 5]).unwrap();
        for (a, b) in out.iter().zip(&q) {
            prop_assert_eq!(a[0].to_bits(), b[0].to_bits());
            prop_assert_eq!(a[1].to_bits(), b[1].to_bits());
        }
    }
}
