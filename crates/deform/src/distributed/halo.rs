//! The halo exchange ([`Halo`]): the owners' values of the ghost entries of a per-rank
//! vector (owned entries first, ghosts after), sent with non-blocking point-to-point
//! messages while the caller works on the owned entries.

use std::collections::HashMap;

use mpi::request::{Request, scope};
use mpi::traits::*;

use super::comm::{Comm, all_to_all};
use crate::error::{Error, Result};

/// Who sends what to whom for one kind of vector (nodes, or unknowns).
pub(crate) struct Halo {
    /// Ranks this rank sends to, and per rank the owned entries it sends, in the order the
    /// receiver listed them.
    send: Vec<(i32, Vec<u32>)>,
    /// Ranks this rank receives from, and per rank the ghost entries it fills, in the order
    /// it listed them to the owner.
    recv: Vec<(i32, Vec<u32>)>,
}

impl Halo {
    /// The halo of the ghost entries `ghosts` (entry, owner rank, global id), the owned
    /// entries of this rank being found by their global id in `owned`. Collective. Fails on
    /// the owner's side when a rank asks for a global id it does not own (the caller makes
    /// the ranks agree on it).
    pub fn build(
        comm: &Comm,
        ghosts: &[(u32, i32, u64)],
        owned: &HashMap<u64, u32>,
    ) -> Result<Self> {
        let p = comm.size() as usize;
        let mut want: Vec<Vec<u64>> = vec![Vec::new(); p];
        let mut fill: Vec<Vec<u32>> = vec![Vec::new(); p];
        let mut sorted = ghosts.to_vec();
        sorted.sort_unstable_by_key(|g| (g.1, g.2));
        for &(e, r, g) in &sorted {
            want[r as usize].push(g);
            fill[r as usize].push(e);
        }
        let asked = all_to_all(comm, &want);
        let mut send = Vec::new();
        let mut bad = None;
        for (r, gids) in asked.into_iter().enumerate() {
            if gids.is_empty() {
                continue;
            }
            let mut list = Vec::with_capacity(gids.len());
            for g in gids {
                match owned.get(&g) {
                    Some(&e) => list.push(e),
                    None => {
                        bad.get_or_insert((r, g));
                    }
                }
            }
            send.push((r as i32, list));
        }
        if let Some((r, g)) = bad {
            return Err(Error::Distributed {
                rank: comm.rank(),
                reason: format!(
                    "rank {r} has node {g} (global id) as a ghost owned by rank {}, which does not own it",
                    comm.rank()
                ),
            });
        }
        let recv = fill
            .into_iter()
            .enumerate()
            .filter(|(_, l)| !l.is_empty())
            .map(|(r, l)| (r as i32, l))
            .collect();
        Ok(Self { send, recv })
    }

    /// Bytes this rank sends per exchange of `w` f64 per entry.
    pub fn bytes_sent(&self, w: usize) -> usize {
        self.send.iter().map(|s| s.1.len()).sum::<usize>() * w * 8
    }

    /// Fills the ghost entries of `v` from their owners, blocking.
    pub fn exchange<const W: usize>(&self, comm: &Comm, v: &mut [[f64; W]]) {
        self.exchange_overlapped(comm, v, |_| {});
    }

    /// Fills `ghosts` (the ghost entries of a local vector from entry `first` on) with
    /// their owners' entries `owned(e)`, blocking: [`Halo::exchange`] of a vector whose
    /// owned entries are held apart, or made on demand for the entries sent only.
    pub fn exchange_from<const W: usize>(
        &self,
        comm: &Comm,
        owned: impl Fn(usize) -> [f64; W],
        ghosts: &mut [[f64; W]],
        first: usize,
    ) {
        let rbuf = transfer(comm, &self.send, &self.recv, owned, || {});
        for (e, val) in received::<W>(&self.recv, &rbuf) {
            ghosts[e - first].copy_from_slice(val);
        }
    }

    /// Adds the ghost entries of `v` into their owners' entries (the reverse of
    /// [`Halo::exchange`]: each rank sends its ghosts' values to their owners, which add
    /// them in rank order); the ghost entries are left as they are.
    pub fn accumulate<const W: usize>(&self, comm: &Comm, v: &mut [[f64; W]]) {
        let rbuf = transfer(comm, &self.recv, &self.send, |e| v[e], || {});
        for (e, val) in received::<W>(&self.send, &rbuf) {
            for (d, s) in v[e].iter_mut().zip(val) {
                *d += s;
            }
        }
    }

    /// [`Halo::accumulate`] of a vector held in two pieces: `ghosts` (its ghost entries
    /// from entry `first` on) added into their owners' entries of `owned`.
    pub fn accumulate_into<const W: usize>(
        &self,
        comm: &Comm,
        ghosts: &[[f64; W]],
        first: usize,
        owned: &mut [[f64; W]],
    ) {
        let rbuf = transfer(comm, &self.recv, &self.send, |e| ghosts[e - first], || {});
        for (e, val) in received::<W>(&self.send, &rbuf) {
            for (d, s) in owned[e].iter_mut().zip(val) {
                *d += s;
            }
        }
    }

    /// Fills the ghost entries of `v` from their owners; `work` runs on `v` (read only)
    /// while the messages travel, so it may read the owned entries only.
    pub fn exchange_overlapped<const W: usize, F>(&self, comm: &Comm, v: &mut [[f64; W]], work: F)
    where
        F: FnOnce(&[[f64; W]]),
    {
        let rbuf = transfer(comm, &self.send, &self.recv, |e| v[e], || work(v));
        for (e, val) in received::<W>(&self.recv, &rbuf) {
            v[e].copy_from_slice(val);
        }
    }
}

/// Sends to each rank of `out` the values `value(e)` of its entries, and receives from
/// each rank of `inn` the values of its entries, in one buffer in the order of `inn`;
/// `work` runs while the messages travel.
fn transfer<const W: usize>(
    comm: &Comm,
    out: &[(i32, Vec<u32>)],
    inn: &[(i32, Vec<u32>)],
    value: impl Fn(usize) -> [f64; W],
    work: impl FnOnce(),
) -> Vec<f64> {
    let packed: Vec<Vec<f64>> = out
        .iter()
        .map(|(_, l)| l.iter().flat_map(|&e| value(e as usize)).collect())
        .collect();
    let total: usize = inn.iter().map(|r| r.1.len() * W).sum();
    let mut rbuf = vec![0.0f64; total];
    scope(|sc| {
        let mut reqs: Vec<Request<'_, [f64], _>> = Vec::new();
        let mut rest = &mut rbuf[..];
        for (r, l) in inn {
            let (a, b) = rest.split_at_mut(l.len() * W);
            rest = b;
            reqs.push(comm.process_at_rank(*r).immediate_receive_into(sc, a));
        }
        for ((r, _), buf) in out.iter().zip(&packed) {
            reqs.push(comm.process_at_rank(*r).immediate_send(sc, &buf[..]));
        }
        work();
        for q in reqs {
            q.wait_without_status();
        }
    });
    rbuf
}

/// The entries of `lists` and their values in `rbuf` (as [`transfer`] received them).
fn received<'a, const W: usize>(
    lists: &'a [(i32, Vec<u32>)],
    rbuf: &'a [f64],
) -> impl Iterator<Item = (usize, &'a [f64])> {
    lists
        .iter()
        .flat_map(|l| l.1.iter().map(|&e| e as usize))
        .zip(rbuf.chunks_exact(W))
}
