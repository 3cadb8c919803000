//! The quality summary of the whole grid from the ranks' counted cells
//! ([`mesh::quality::Summary`] of the concatenated fields, with the serial summary's
//! minimum, maximum, counts and 1st percentile exactly; the mean summed by rank). Rank 0
//! no longer computes the whole grid's quality a second time, alone, after the gather.

use mpi::collective::SystemOperation;
use mpi::traits::*;

use mesh::quality::Summary;

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
