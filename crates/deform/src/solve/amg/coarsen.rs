//! One coarsening step of the multigrid set-up: greedy aggregation, the smoothed
//! prolongator, its transpose and the Galerkin coarse matrix.

use std::time::Instant;

use rayon::prelude::*;
use sparse::csr::build_rows;
use sparse::vec3::CHUNK;
use sparse::{Entry, SymMatrix};

use super::galerkin::galerkin;
use super::transfer::Transfer;
use super::{AmgOptions, Level, LevelSetup};

/// One coarsening step of the set-up (level `depth` → `depth + 1`): aggregation, smoothed
/// prolongator, restriction and Galerkin product. `None` when the coarsening stalls.
///
/// `mask`: per node of `cur`, the components it is held in (bit c; see
/// [`super::Amg::new_held`]), or None. With a mask, an aggregate holds nodes of one mask
/// only, and the prolongator's smoothing lumps a coupling between two masks onto the
/// row's own aggregate (as if the coupling were dropped from A, its row sum kept): a row of
/// P then reaches only aggregates of its own mask, so a component held at some nodes is
/// zero at their aggregates, level after level. Also returns the coarse nodes' masks.
pub(super) fn coarsen<T: Entry>(
    cur: &SymMatrix<T>,
    opts: &AmgOptions,
    depth: usize,
    mask: Option<&[u8]>,
) -> Option<(Level, SymMatrix, Option<Vec<u8>>)> {
    // The threshold halves on each coarser level (coarse operators have more, weaker
    // connections per row).
    let theta = opts.strength * 0.5f64.powi(depth as i32);
    let t0 = Instant::now();
    let (agg, nagg) = aggregate(cur, theta, mask);
    let t_agg = t0.elapsed().as_secs_f64();
    if nagg == 0 || nagg * 10 > cur.n() * 9 {
        // Coarsening stalled: stop here.
        return None;
    }
    let rho = gershgorin(cur);
    let omega = opts.smoother_damping / rho;
    // The prolongator is stored in single precision; the coarse matrix is the Galerkin
    // product of the rounded P, so the cycle stays a symmetric positive definite
    // preconditioner (every vector stays f64).
    let p = smoothed_prolongator(cur, &agg, nagg, opts.prolongator_damping / rho, mask);
    let t_p = t0.elapsed().as_secs_f64();
    let r = p.transpose();
    let t_r = t0.elapsed().as_secs_f64();
    let ac = galerkin(cur, &p, &r);
    let setup = LevelSetup {
        prolongator_entries: p.entries.len(),
        aggregate: t_agg,
        prolongator: t_p - t_agg,
        transpose: t_r - t_p,
        galerkin: t0.elapsed().as_secs_f64() - t_r,
    };
    let coarse_mask = mask.map(|m| {
        let mut mc = vec![0u8; nagg];
        for (i, &g) in agg.iter().enumerate() {
            mc[g as usize] = m[i];
        }
        mc
    });
    let level = Level {
        p,
        omega,
        setup,
        held: held_rows(mask),
    };
    Some((level, ac, coarse_mask))
}

/// Gershgorin bound of ρ(D⁻¹A).
pub(super) fn gershgorin<T: Entry>(a: &SymMatrix<T>) -> f64 {
    (0..a.n())
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|i| {
            let s: f64 = a.vals[a.offsets[i]..a.offsets[i + 1]]
                .iter()
                .map(|v| v.get().abs())
                .sum();
            1.0 + s / a.diag[i]
        })
        .reduce(|| 0.0, f64::max)
}

/// The rows of a level held in some component, with their components (empty without a
/// mask).
pub(super) fn held_rows(mask: Option<&[u8]>) -> Vec<(u32, u8)> {
    mask.map_or_else(Vec::new, |m| {
        m.iter()
            .enumerate()
            .filter(|(_, b)| **b != 0)
            .map(|(i, &b)| (i as u32, b))
            .collect()
    })
}

/// Greedy aggregation; returns the aggregate of every node and the aggregate count. With a
/// `mask`, nodes of different masks are never strongly connected (see [`coarsen`]).
pub(super) fn aggregate<T: Entry>(
    a: &SymMatrix<T>,
    theta: f64,
    mask: Option<&[u8]>,
) -> (Vec<u32>, usize) {
    const NONE: u32 = u32::MAX;
    let n = a.n();
    let strong = |i: usize, p: usize| {
        let j = a.cols[p] as usize;
        a.vals[p].get().abs() >= theta * (a.diag[i] * a.diag[j]).abs().sqrt()
            && mask.is_none_or(|m| m[i] == m[j])
    };
    let mut agg = vec![NONE; n];
    let mut nagg = 0u32;
    // Pass 1: roots whose strong neighbourhood is entirely unaggregated.
    for i in 0..n {
        if agg[i] != NONE {
            continue;
        }
        let mut any_strong = false;
        let mut free = true;
        for p in a.offsets[i]..a.offsets[i + 1] {
            if strong(i, p) {
                any_strong = true;
                if agg[a.cols[p] as usize] != NONE {
                    free = false;
                    break;
                }
            }
        }
        if any_strong && free {
            agg[i] = nagg;
            for p in a.offsets[i]..a.offsets[i + 1] {
                if strong(i, p) {
                    agg[a.cols[p] as usize] = nagg;
                }
            }
            nagg += 1;
        }
    }
    // Pass 2: attach to the strongest neighbouring pass-1 aggregate.
    let snapshot = agg.clone();
    for i in 0..n {
        if agg[i] != NONE {
            continue;
        }
        let mut best = (0.0, NONE);
        for p in a.offsets[i]..a.offsets[i + 1] {
            let g = snapshot[a.cols[p] as usize];
            if g != NONE && strong(i, p) && a.vals[p].get().abs() > best.0 {
                best = (a.vals[p].get().abs(), g);
            }
        }
        agg[i] = best.1;
    }
    // Pass 3: leftovers form aggregates with their unaggregated strong neighbours.
    for i in 0..n {
        if agg[i] != NONE {
            continue;
        }
        agg[i] = nagg;
        for p in a.offsets[i]..a.offsets[i + 1] {
            let j = a.cols[p] as usize;
            if agg[j] == NONE && strong(i, p) {
                agg[j] = nagg;
            }
        }
        nagg += 1;
    }
    (agg, nagg as usize)
}

/// P = (I − ω D⁻¹ A) P₀, P₀ the aggregate indicator.
///
/// A row of P has a few distinct aggregates (~4 on the finest level): each contribution is
/// added to its aggregate's entry found by a linear search, in the row's order — the sums of
/// a stable sort by column followed by merging (`merge_row`), bit for bit — and only the
/// distinct entries are sorted.
///
/// With a `mask`, a coupling between nodes of different masks goes to the row's own
/// aggregate (see [`coarsen`]).
///
/// The values are rounded to single precision as they are stored ([`build_rows`]).
pub(super) fn smoothed_prolongator<T: Entry>(
    a: &SymMatrix<T>,
    agg: &[u32],
    nagg: usize,
    omega: f64,
    mask: Option<&[u8]>,
) -> Transfer {
    let (offsets, entries) = build_rows(
        a.n(),
        |i, buf| {
            let mut add = |c: u32, v: f64| match buf.iter_mut().find(|e| e.0 == c) {
                Some(e) => e.1 += v,
                None => buf.push((c, v)),
            };
            add(agg[i], 1.0 - omega);
            let s = omega / a.diag[i];
            for p in a.offsets[i]..a.offsets[i + 1] {
                let j = a.cols[p] as usize;
                let g = match mask {
                    Some(m) if m[i] != m[j] => agg[i],
                    _ => agg[j],
                };
                add(g, -s * a.vals[p].get());
            }
            buf.sort_unstable_by_key(|e| e.0);
        },
        |(c, v)| (c, v as f32),
    );
    Transfer {
        ncols: nagg,
        offsets,
        entries,
    }
}
