//! Fits every airfoil of a folder with the section parametrisation (several settings) and a
//! Kulfan CST fit with the same number of design variables; prints the share of airfoils
//! within 1e-3, 5e-4 and 1e-4 chords (max normal distance) and fit times.
//!
//! `cargo run --release -p wingmaster --example fit_survey -- [DIR] [--verbose] [--only CP:EX]
//! [--tol REL] [--rounds N] [--exclude DIR2] [--cst-rounds N]`
//!
//! DIR defaults to `../shared/data/airfoils`; `--exclude DIR2` skips every file of DIR whose
//! name (case-insensitive) is also in DIR2, e.g. the UIUC database held out from
//! `../shared/data/airfoils`. `--rounds N` sets the section fit's minimax rounds
//! (`FitOptions::minimax_rounds`, default [`wingmaster::fit::DEFAULT_MINIMAX_ROUNDS`]);
//! `--cst-rounds N` gives CST the same Lawson reweighting (default 0: least squares, the
//! reference of the earlier surveys). `--verbose` prints each fit's errors and where its
//! largest distance is.
//!
//! CST (Kulfan): z(x) = C(x) Σ_{i=0}^{n} A_i K_i x^i (1 − x)^{n−i} + x Δz_te per surface with
//! class function C(x) = x^0.5 (1 − x) and Bernstein order n, 2(n + 1) design variables;
//! Δz_te from the data. Fitted by linear least squares on the ordinates, then refined by
//! Gauss–Newton on the normal distances (feet re-projected each step), in the same local
//! frame as the section fit (the data's leading-edge point at the origin).

use std::path::PathBuf;
use std::time::Instant;

use nalgebra::{DMatrix, DVector};
use wingmaster::{Airfoil, FitOptions, NormalisedAirfoil, fit};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let verbose = args.iter().any(|a| a == "--verbose");
    const VALUED: [&str; 5] = ["--only", "--tol", "--rounds", "--exclude", "--cst-rounds"];
    let value = |flag: &str| {
        args.iter().position(|a| a == flag).map(|i| {
            args.get(i + 1)
                .unwrap_or_else(|| panic!("{flag} needs a value"))
        })
    };
    let dir = args
        .iter()
        .enumerate()
        .find(|(i, a)| !a.starts_with("--") && (*i == 0 || !VALUED.contains(&args[i - 1].as_str())))
        .map(|(_, a)| a)
        .cloned()
        .unwrap_or_else(|| "/work/shared/data/airfoils".into());
    let list = |d: &str| -> Vec<PathBuf> {
        std::fs::read_dir(d)
            .unwrap_or_else(|e| panic!("{d}: {e}"))
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "dat"))
            .collect()
    };
    let lower = |p: &PathBuf| p.file_name().unwrap().to_string_lossy().to_lowercase();
    let excluded: std::collections::HashSet<String> = value("--exclude")
        .map(|d| list(d).iter().map(lower).collect())
        .unwrap_or_default();
    let mut files: Vec<PathBuf> = list(&dir)
        .into_iter()
        .filter(|p| !excluded.contains(&lower(p)))
        .collect();
    let rounds: usize = value("--rounds")
        .map(|v| v.parse().expect("--rounds value"))
        .unwrap_or(wingmaster::fit::DEFAULT_MINIMAX_ROUNDS);
    let cst_rounds: usize = value("--cst-rounds")
        .map(|v| v.parse().expect("--cst-rounds value"))
        .unwrap_or(0);
    println!(
        "{} files in {dir} ({} excluded by name)",
        files.len(),
        excluded.len()
    );
    files.sort();
    let mut foils = Vec::new();
    for f in &files {
        let file = std::fs::File::open(f).expect("open");
        match Airfoil::parse(std::io::BufReader::new(file), &f.display().to_string()) {
            Ok(a) => foils.push((f.file_name().unwrap().to_string_lossy().into_owned(), a)),
            Err(e) => println!("skip: {e}"),
        }
    }
    let mut settings = vec![(8usize, 0usize), (6, 1), (4, 2), (6, 0), (10, 0), (8, 2)];
    if let Some(v) = value("--only") {
        let v: Vec<usize> = v
            .split(':')
            .map(|t| t.parse().expect("--only CP:EX"))
            .collect();
        settings = vec![(v[0], v[1])];
    }
    let mut best_ms = f64::INFINITY;
    let tol: f64 = value("--tol")
        .map(|v| v.parse().expect("--tol value"))
        .unwrap_or(FitOptions::default().tolerance);
    for &(cp, ex) in &settings {
        let opts = FitOptions::default()
            .with_camber_points(cp)
            .with_thickness_extra(ex)
            .with_tolerance(tol)
            .with_minimax_rounds(rounds);
        let mut errs = Vec::new();
        let t0 = Instant::now();
        for (name, a) in &foils {
            match fit(a, &opts) {
                Ok(f) => {
                    if verbose {
                        let (k, _) = f.distances.iter().enumerate().fold((0, 0.0), |b, (k, d)| {
                            if d.abs() > b.1 { (k, d.abs()) } else { b }
                        });
                        println!(
                            "  {name:24} max {:.2e} rms {:.2e} it {} at x {:.4} z {:.4} n {}",
                            f.max_error,
                            f.rms_error,
                            f.iterations,
                            f.points[k][0],
                            f.points[k][1],
                            f.points.len()
                        );
                    }
                    errs.push(f.max_error)
                }
                Err(e) => {
                    println!("  {name}: {e}");
                    errs.push(f64::INFINITY)
                }
            }
        }
        let dt = t0.elapsed().as_secs_f64() / foils.len() as f64;
        best_ms = best_ms.min(dt * 1e3);
        let share = |tol: f64| errs.iter().filter(|&&e| e <= tol).count();
        println!(
            "section cp={cp} extra={ex} tol={tol:.0e} rounds={rounds} dv={} : <=1e-3 {} <=5e-4 {} <=1e-4 {} of {}  ({:.2} ms/fit)",
            opts.n_design_variables(),
            share(1e-3),
            share(5e-4),
            share(1e-4),
            errs.len(),
            dt * 1e3
        );
    }
    // CST at the same design-variable counts.
    let mut counts: Vec<usize> = settings
        .iter()
        .map(|&(cp, ex)| {
            FitOptions::default()
                .with_camber_points(cp)
                .with_thickness_extra(ex)
                .n_design_variables()
        })
        .collect();
    counts.sort();
    counts.dedup();
    for dv in counts {
        if dv % 2 != 0 {
            continue;
        }
        let n = dv / 2 - 1;
        let t0 = Instant::now();
        let mut errs = Vec::new();
        for (name, a) in &foils {
            let e = a
                .normalise()
                .map(|na| cst_fit(&na, n, cst_rounds))
                .unwrap_or(f64::INFINITY);
            if verbose {
                println!("  {name:24} CST max {e:.2e}");
            }
            errs.push(e);
        }
        let dt = t0.elapsed().as_secs_f64() / foils.len() as f64;
        let share = |tol: f64| errs.iter().filter(|&&e| e <= tol).count();
        println!(
            "CST     order={n} rounds={cst_rounds} dv={dv} : <=1e-3 {} <=5e-4 {} <=1e-4 {} of {}  ({:.2} ms/fit)",
            share(1e-3),
            share(5e-4),
            share(1e-4),
            errs.len(),
            dt * 1e3
        );
    }
    let _ = best_ms;
}

/// CST basis values at x for order n: C(x) K_i x^i (1 − x)^(n − i).
fn cst_basis(n: usize, x: f64, out: &mut [f64]) {
    let x = x.clamp(0.0, 1.0);
    let c = x.sqrt() * (1.0 - x);
    for (i, o) in out.iter_mut().enumerate().take(n + 1) {
        *o = c * geom_db::bspline::bernstein(n, i, x);
    }
}

/// One CST surface: z(ψ) with x = ψ², returns (x, z) and d/dψ.
fn cst_eval(a: &[f64], dz: f64, psi: f64) -> ([f64; 2], [f64; 2]) {
    let n = a.len() - 1;
    let mut b = vec![0.0; n + 1];
    let z = |p: f64, b: &mut [f64]| {
        let x = p * p;
        cst_basis(n, x, b);
        b.iter().zip(a).map(|(u, v)| u * v).sum::<f64>() + x * dz
    };
    let h = 1e-7;
    let p = psi.clamp(0.0, 1.0);
    let (lo, hi) = ((p - h).max(0.0), (p + h).min(1.0));
    let d = (z(hi, &mut b) - z(lo, &mut b)) / (hi - lo);
    ([p * p, z(p, &mut b)], [2.0 * p, d])
}

/// Fits CST of order n to a normalised airfoil; returns the max normal distance. With
/// `rounds` > 0, Lawson's reweighting as in the section fit (the best round is returned).
fn cst_fit(na: &NormalisedAirfoil, n: usize, rounds: usize) -> f64 {
    let le = na.le_index;
    let np = na.points.len();
    let dz_u = na.points[0][1];
    let dz_l = na.points[np - 1][1];
    let surf: Vec<(usize, [f64; 2])> = na
        .points
        .iter()
        .enumerate()
        .map(|(i, &q)| (if i <= le { 0 } else { 1 }, q))
        .collect();
    let m = n + 1;
    // Linear least squares on ordinates.
    let mut a = DMatrix::<f64>::zeros(np, 2 * m);
    let mut r = DVector::<f64>::zeros(np);
    let mut b = vec![0.0; m];
    for (k, &(s, q)) in surf.iter().enumerate() {
        cst_basis(n, q[0], &mut b);
        for i in 0..m {
            a[(k, s * m + i)] = b[i];
        }
        r[k] = q[1] - q[0].clamp(0.0, 1.0) * if s == 0 { dz_u } else { dz_l };
    }
    let ata = a.tr_mul(&a) + DMatrix::<f64>::identity(2 * m, 2 * m) * 1e-12;
    let Some(ch) = ata.cholesky() else {
        return f64::INFINITY;
    };
    let mut coef = ch.solve(&a.tr_mul(&r));
    // Gauss–Newton on normal distances.
    let mut psi: Vec<f64> = surf.iter().map(|&(_, q)| q[0].max(0.0).sqrt()).collect();
    let mut dist = vec![0.0; np];
    let mut w = vec![1.0; np];
    let mut best = f64::INFINITY;
    for round in 0..=rounds {
        if round > 0 {
            let mean = w
                .iter()
                .zip(&dist)
                .map(|(w, d): (&f64, &f64)| w * d.abs())
                .sum::<f64>()
                / np as f64;
            if mean > 0.0 {
                for (w, d) in w.iter_mut().zip(&dist) {
                    *w = (*w * d.abs() / mean).max(1e-6);
                }
            }
        }
        for it in 0..8 {
            let cu: Vec<f64> = coef.rows(0, m).iter().copied().collect();
            let cl: Vec<f64> = coef.rows(m, m).iter().copied().collect();
            let mut j = DMatrix::<f64>::zeros(np, 2 * m);
            let mut res = DVector::<f64>::zeros(np);
            for (k, &(s, q)) in surf.iter().enumerate() {
                let (c, dz) = if s == 0 { (&cu, dz_u) } else { (&cl, dz_l) };
                let mut p = psi[k];
                for _ in 0..20 {
                    let (pt, d) = cst_eval(c, dz, p);
                    let g = (pt[0] - q[0]) * d[0] + (pt[1] - q[1]) * d[1];
                    let hh = d[0] * d[0] + d[1] * d[1];
                    if hh <= 0.0 {
                        break;
                    }
                    let pn = (p - g / hh).clamp(0.0, 1.0);
                    if (pn - p).abs() < 1e-13 {
                        p = pn;
                        break;
                    }
                    p = pn;
                }
                psi[k] = p;
                let (pt, d) = cst_eval(c, dz, p);
                let len = d[0].hypot(d[1]).max(1e-300);
                let nrm = [-d[1] / len, d[0] / len];
                dist[k] = nrm[0] * (q[0] - pt[0]) + nrm[1] * (q[1] - pt[1]);
                let sw = w[k].sqrt();
                res[k] = sw * dist[k];
                cst_basis(n, pt[0], &mut b);
                for i in 0..m {
                    j[(k, s * m + i)] = -sw * nrm[1] * b[i];
                }
            }
            if it == 7 {
                break;
            }
            let jtj = j.tr_mul(&j) + DMatrix::<f64>::identity(2 * m, 2 * m) * 1e-14;
            let Some(ch) = jtj.cholesky() else { break };
            let delta = ch.solve(&(-j.tr_mul(&res)));
            coef += delta;
        }
        best = best.min(dist.iter().fold(0.0f64, |acc, d| acc.max(d.abs())));
    }
    best
}
