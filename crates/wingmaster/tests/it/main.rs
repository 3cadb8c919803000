//! Public-API tests of `wingmaster` (one integration binary).

mod conditions;
mod fit;
mod master;
mod modify;
mod parse;
mod planform;
mod props;
mod split;

use std::path::PathBuf;

/// A file of the repository's `fixtures/airfoils/`.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/airfoils")
        .join(name)
}

/// Reads a fixture airfoil.
pub fn load(name: &str) -> wingmaster::Airfoil {
    let p = fixture(name);
    let f = std::fs::File::open(&p).unwrap();
    wingmaster::Airfoil::parse(std::io::BufReader::new(f), &p.display().to_string()).unwrap()
}

/// The analytic NACA 4-digit section (closed trailing edge variant), Selig order, with
/// `n` cosine-spaced stations per surface; thickness added normal to the camber line.
pub fn naca4(m: f64, p: f64, t: f64, n: usize) -> Vec<[f64; 2]> {
    let yt = |x: f64| {
        5.0 * t
            * (0.2969 * x.sqrt() - 0.1260 * x - 0.3516 * x * x + 0.2843 * x.powi(3)
                - 0.1036 * x.powi(4))
    };
    let yc = |x: f64| {
        if m == 0.0 {
            (0.0, 0.0)
        } else if x < p {
            (
                m / (p * p) * (2.0 * p * x - x * x),
                2.0 * m / (p * p) * (p - x),
            )
        } else {
            (
                m / ((1.0 - p) * (1.0 - p)) * (1.0 - 2.0 * p + 2.0 * p * x - x * x),
                2.0 * m / ((1.0 - p) * (1.0 - p)) * (p - x),
            )
        }
    };
    let xs: Vec<f64> = (0..=n)
        .map(|k| 0.5 * (1.0 - (std::f64::consts::PI * k as f64 / n as f64).cos()))
        .collect();
    let surf = |x: f64, s: f64| {
        let (c, dc) = yc(x);
        let th = dc.atan();
        [x - s * yt(x) * th.sin(), c + s * yt(x) * th.cos()]
    };
    let mut out: Vec<[f64; 2]> = xs.iter().rev().map(|&x| surf(x, 1.0)).collect();
    out.extend(xs[1..].iter().map(|&x| surf(x, -1.0)));
    out
}
