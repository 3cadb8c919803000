//! The step-size study behind the tolerance of the chain's derivative tests
//! (docs/crates/aeroshape.md, "Derivatives of the whole chain"): the forward product of
//! design variables of the default case against second- and fourth-order central
//! differences of `Study::evaluate`, for steps h/h0 = 1e-2 … 1e1 where h0 moves the wall by
//! 1e-4 of the model's size, volume and wall (relative error |FD − J e| / |FD|), at the
//! case's deformation tolerance and at 1e-12.
//!
//! `cargo run --release -p aeroshape --example step_study [VARIABLE…]`

use std::path::Path;

use aeroshape::case::{Case, load_design_values};
use aeroshape::study::Study;

fn norm3(v: &[[f64; 3]]) -> f64 {
    v.iter()
        .map(|p| p[0] * p[0] + p[1] * p[1] + p[2] * p[2])
        .sum::<f64>()
        .sqrt()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/cases/default");
    let path = dir.join("case.ron");
    let mut wanted: Vec<String> = std::env::args().skip(1).collect();
    if wanted.is_empty() {
        wanted = vec!["thick_lower".into(), "waist_top".into()];
    }
    for rel_tol in [None, Some(1e-12)] {
        let mut c = Case::load(&path)?;
        let case_tol = c.deform.rel_tol;
        if let Some(t) = rel_tol {
            c.deform.rel_tol = t;
        }
        c.deform.warm_start = false;
        let s = Study::new(c, &path)?;
        let x = s.vector_from_values(&load_design_values(&dir.join("dv.ron"))?)?;
        let names: Vec<String> = s.registry().names().iter().map(|n| n.to_string()).collect();
        let lref = s.geometry().reference_length();
        let lin = s.linearise(&x)?;
        println!("deformation rel_tol {:.0e}", rel_tol.unwrap_or(case_tol));
        println!(
            "| variable | h / h0 | h | 2nd order, volume | 4th order, volume | 2nd order, wall | 4th order, wall |"
        );
        println!("|---|---|---|---|---|---|---|");
        for name in &wanted {
            let Some(l) = names.iter().position(|n| n == name) else {
                return Err(format!("no design variable {name}").into());
            };
            let mut e = vec![0.0; x.len()];
            e[l] = 1.0;
            let jv = lin.jvp(&e)?;
            let jw = lin.jvp_wall(&e)?;
            let m = jw
                .iter()
                .map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt())
                .fold(0.0, f64::max);
            let h0 = 1e-4 * lref / m;
            for f in [1e-2, 1e-1, 1.0, 1e1] {
                let h = f * h0;
                let at = |k: f64| -> Result<Vec<[f64; 3]>, Box<dyn std::error::Error>> {
                    let mut y = x.clone();
                    y[l] += k * h;
                    s.forget_warm_start();
                    Ok(s.evaluate(&y)?.grid.coords)
                };
                let (p1, m1, p2, m2) = match (at(1.0), at(-1.0), at(2.0), at(-2.0)) {
                    (Ok(a), Ok(b), Ok(c), Ok(d)) => (a, b, c, d),
                    _ => {
                        println!(
                            "| {name} | {f:.0e} | {h:.2e} | evaluation failed (step too large) | | | |"
                        );
                        continue;
                    }
                };
                let mut cols = Vec::new();
                for (prod, wall) in [(&jv, false), (&jw, true)] {
                    for fourth in [false, true] {
                        let (mut err, mut fd) = (Vec::new(), Vec::new());
                        for i in 0..p1.len() {
                            if wall && !s.wall_nodes()[i] {
                                continue;
                            }
                            let d: [f64; 3] = std::array::from_fn(|c| {
                                if fourth {
                                    (8.0 * (p1[i][c] - m1[i][c]) - (p2[i][c] - m2[i][c]))
                                        / (12.0 * h)
                                } else {
                                    (p1[i][c] - m1[i][c]) / (2.0 * h)
                                }
                            });
                            err.push(std::array::from_fn(|c| d[c] - prod[i][c]));
                            fd.push(d);
                        }
                        cols.push(norm3(&err) / norm3(&fd));
                    }
                }
                println!(
                    "| {name} | {f:.0e} | {h:.2e} | {:.1e} | {:.1e} | {:.1e} | {:.1e} |",
                    cols[0], cols[1], cols[2], cols[3]
                );
            }
        }
    }
    Ok(())
}
