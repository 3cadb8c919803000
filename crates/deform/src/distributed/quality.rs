//! The quality summary of the whole grid from the ranks' counted cells
//! ([`mesh::quality::Summary`] of the concatenated fields, with the serial summary's
//! minimum, maximum, counts and 1st percentile exactly; the mean summed by rank). Rank 0
//! no longer computes the whole grid's quality a second time, alone, after the gather.

use mpi::collective::SystemOperation;
use mpi::traits::*;

use mesh::quality::Summary;
use mesh::{ALL_KINDS, Mesh};

use super::comm::{Comm, all_gather_vec, max, min, sum, sum_u64};

/// Bins of the 1st percentile's search: the bin of the rank is found from the all-reduced
/// counts, and only its values are gathered.
const BINS: usize = 4096;

/// The summary over the ranks of the quality field whose share on this rank is `q` (each
/// cell counted on one rank; NaN: not measured). Collective.
pub(crate) fn summary(comm: &Comm, q: &[f64]) -> Summary {
    let (mut lo, mut hi, mut total) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
    let (mut measured_here, mut bad) = (0u64, 0u64);
    for &x in q.iter().filter(|x| !x.is_nan()) {
        lo = lo.min(x);
        hi = hi.max(x);
        total += x;
        measured_here += 1;
        bad += u64::from(x <= 0.0);
    }
    let count = sum_u64(comm, q.len() as u64) as usize;
    let measured = sum_u64(comm, measured_here) as usize;
    let (lo, hi) = (min(comm, lo), max(comm, hi));
    let total = sum(comm, total);
    let n_nonpositive = sum_u64(comm, bad) as usize;
    if measured == 0 {
        return Summary {
            count,
            measured,
            min: f64::NAN,
            mean: f64::NAN,
            p1: f64::NAN,
            max: f64::NAN,
            n_nonpositive,
        };
    }
    // The value of rank ⌈n/100⌉ in increasing order, as the serial summary.
    let rank = ((0.01 * measured as f64).ceil() as usize).max(1) - 1;
    Summary {
        count,
        measured,
        min: lo,
        mean: total / measured as f64,
        p1: nth_smallest(comm, q, rank, lo, hi),
        max: hi,
        n_nonpositive,
    }
}

/// The value of rank `rank` among the non-NaN values of every rank's `q` (smallest `lo`,
/// largest `hi` over the ranks): the bin of equal width over [lo, hi] that holds it from
/// the counts summed over the ranks, then that bin's values gathered on every rank and
/// selected. Without a finite positive width, every value is gathered.
fn nth_smallest(comm: &Comm, q: &[f64], rank: usize, lo: f64, hi: f64) -> f64 {
    let width = hi - lo;
    let binned = width.is_finite() && width > 0.0;
    let scale = if binned { BINS as f64 / width } else { 0.0 };
    let bin = |x: f64| (((x - lo) * scale) as usize).min(BINS - 1);
    let mut local = vec![0u64; BINS];
    for &x in q.iter().filter(|x| !x.is_nan()) {
        local[bin(x)] += 1;
    }
    let mut counts = vec![0u64; BINS];
    comm.all_reduce_into(&local[..], &mut counts[..], SystemOperation::sum());
    let (mut b, mut below) = (0, 0usize);
    while below + counts[b] as usize <= rank {
        below += counts[b] as usize;
        b += 1;
    }
    let mine: Vec<f64> = q
        .iter()
        .copied()
        .filter(|&x| !x.is_nan() && bin(x) == b)
        .collect();
    let mut all = all_gather_vec(comm, &mine);
    *all.select_nth_unstable_by(rank - below, f64::total_cmp).1
}

/// The worst cell over the ranks of the counted cells `cells` at the local coordinates `x`
/// (`global`: the global id of every local node), for the guard's message: "kind with
/// nodes g₀ g₁ … at (x, y, z) (q = …)", the same on every rank (ties: the lowest rank).
/// Collective.
pub(crate) fn worst_cell(comm: &Comm, cells: &Mesh, x: &[[f64; 3]], global: &[u64]) -> String {
    let q = mesh::quality::cell_quality_at(cells, x);
    // [q, kind index, n nodes, centroid (3), global node ids (8)], NaN q when none.
    let mut rec = [f64::NAN; 14];
    if let Some(w) = mesh::quality::worst_cells(&cells.cells, &q, 1).first() {
        let nodes = cells.cells.iter().nth(w.id).map_or(&[][..], |(_, e)| e);
        rec[0] = w.quality;
        rec[1] = ALL_KINDS.iter().position(|k| *k == w.kind).unwrap_or(0) as f64;
        rec[2] = nodes.len() as f64;
        rec[3..6].fill(0.0);
        for (k, &v) in nodes.iter().enumerate() {
            for d in 0..3 {
                rec[3 + d] += x[v as usize][d] / nodes.len() as f64;
            }
            rec[6 + k] = global[v as usize] as f64;
        }
    }
    let all = all_gather_vec(comm, &rec);
    let best = all
        .chunks_exact(14)
        .filter(|r| !r[0].is_nan())
        .min_by(|a, b| a[0].total_cmp(&b[0]));
    let Some(r) = best else {
        return "no measured cell".into();
    };
    let kind = ALL_KINDS[r[1] as usize];
    let ids: Vec<String> = r[6..6 + r[2] as usize]
        .iter()
        .map(|g| format!("{}", *g as u64))
        .collect();
    format!(
        "{} with nodes {} at ({:.6e}, {:.6e}, {:.6e}) (q = {:.3e})",
        kind.name(),
        ids.join(" "),
        r[3],
        r[4],
        r[5],
        r[0]
    )
}
