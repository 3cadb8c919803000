//! The collective operations the distributed deformation uses, over rsmpi: all-reduced sums,
//! maxima and minima, the agreement on errors that precedes every blocking exchange, the
//! broadcast of a list from one rank, the all-gather of every rank's list, and the variable
//! all-to-all of integer and float lists.

use mpi::collective::SystemOperation;
use mpi::datatype::{Equivalence, Partition, PartitionMut};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::error::{Error, Result};

/// The communicator type of [`crate::distributed`] (the world, or any communicator made
/// from it by `split` or `duplicate`).
pub type Comm = SimpleCommunicator;

/// Σ over the ranks.
pub(crate) fn sum(comm: &Comm, x: f64) -> f64 {
    let mut out = 0.0;
    comm.all_reduce_into(&x, &mut out, SystemOperation::sum());
    out
}

/// Element-wise Σ over the ranks of a short array.
pub(crate) fn sum_n<const N: usize>(comm: &Comm, x: [f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    comm.all_reduce_into(&x[..], &mut out[..], SystemOperation::sum());
    out
}

/// Σ over the ranks of a count.
pub(crate) fn sum_u64(comm: &Comm, x: u64) -> u64 {
    let mut out = 0u64;
    comm.all_reduce_into(&x, &mut out, SystemOperation::sum());
    out
}

/// max over the ranks.
pub(crate) fn max(comm: &Comm, x: f64) -> f64 {
    let mut out = 0.0;
    comm.all_reduce_into(&x, &mut out, SystemOperation::max());
    out
}

/// min over the ranks.
pub(crate) fn min(comm: &Comm, x: f64) -> f64 {
    let mut out = 0.0;
    comm.all_reduce_into(&x, &mut out, SystemOperation::min());
    out
}

/// The lowest rank whose `local` failed and its message, broadcast from it to every rank, or
/// `None` when every rank succeeded (collective: every rank calls it with its own outcome).
/// `message` renders the failing rank's error.
pub fn first_failure<T, E>(
    comm: &Comm,
    local: &std::result::Result<T, E>,
    message: impl FnOnce(&E) -> String,
) -> Option<(i32, String)> {
    let me = comm.rank();
    let mine = if local.is_err() { me } else { i32::MAX };
    let mut first = i32::MAX;
    comm.all_reduce_into(&mine, &mut first, SystemOperation::min());
    if first == i32::MAX {
        return None;
    }
    let text: Vec<u8> = match local {
        Err(e) if me == first => message(e).into_bytes(),
        _ => Vec::new(),
    };
    let text = broadcast_vec(comm, first, text);
    Some((first, String::from_utf8_lossy(&text).into_owned()))
}

/// Rank `root`'s `v`, on every rank: its length, then its entries (collective; the other
/// ranks' `v` is ignored).
pub(crate) fn broadcast_vec<T: Equivalence + Copy + Default>(
    comm: &Comm,
    root: i32,
    mut v: Vec<T>,
) -> Vec<T> {
    let from = comm.process_at_rank(root);
    let mut len = v.len() as u64;
    from.broadcast_into(&mut len);
    v.resize(len as usize, T::default());
    if len > 0 {
        from.broadcast_into(&mut v[..]);
    }
    v
}

/// The ranks agree on `local`: when any rank failed, every rank returns the error of the
/// lowest failing rank (its message broadcast from it), so that no rank goes on into an
/// exchange that the others will not join.
pub(crate) fn agree<T>(comm: &Comm, local: Result<T>) -> Result<T> {
    let failure = first_failure(comm, &local, |e| match e {
        Error::Distributed { reason, .. } => reason.clone(),
        e => e.to_string(),
    });
    match failure {
        // The rank that failed keeps its own error (its type and fields).
        Some((rank, reason)) if rank != comm.rank() => Err(Error::Distributed { rank, reason }),
        _ => local,
    }
}

/// The offsets of blocks of `counts` laid end to end (the displacements of a
/// variable-count gather or exchange).
pub(crate) fn offsets(counts: &[i32]) -> Vec<i32> {
    counts
        .iter()
        .scan(0, |a, &x| {
            let d = *a;
            *a += x;
            Some(d)
        })
        .collect()
}

/// Every rank's `v`, concatenated in rank order, on every rank (collective).
pub(crate) fn all_gather_vec<T: Equivalence + Copy + Default>(comm: &Comm, v: &[T]) -> Vec<T> {
    let mut counts = vec![0i32; comm.size() as usize];
    comm.all_gather_into(&(v.len() as i32), &mut counts[..]);
    let displs = offsets(&counts);
    let mut all = vec![T::default(); counts.iter().map(|&c| c as usize).sum()];
    comm.all_gather_varcount_into(
        v,
        &mut PartitionMut::new(&mut all[..], &counts[..], &displs[..]),
    );
    all
}

/// Sends `out[r]` to rank r and returns what each rank sent here (`in[r]` from rank r).
pub(crate) fn all_to_all<T: Equivalence + Copy + Default>(
    comm: &Comm,
    out: &[Vec<T>],
) -> Vec<Vec<T>> {
    let p = comm.size() as usize;
    let counts: Vec<i32> = out.iter().map(|v| v.len() as i32).collect();
    let mut rcounts = vec![0i32; p];
    comm.all_to_all_into(&counts[..], &mut rcounts[..]);
    let (sd, rd) = (offsets(&counts), offsets(&rcounts));
    let flat: Vec<T> = out.iter().flatten().copied().collect();
    let total: usize = rcounts.iter().map(|&c| c as usize).sum();
    let mut buf = vec![T::default(); total];
    {
        let send = Partition::new(&flat[..], &counts[..], &sd[..]);
        let mut recv = PartitionMut::new(&mut buf[..], &rcounts[..], &rd[..]);
        comm.all_to_all_varcount_into(&send, &mut recv);
    }
    (0..p)
        .map(|r| buf[rd[r] as usize..(rd[r] + rcounts[r]) as usize].to_vec())
        .collect()
}
