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

    /// Adds the ghost entries of `v` into their owners' entries (the reverse of
    /// [`Halo::exchange`]: each rank sends its ghosts' values to their owners, which add
    /// them in rank order); the ghost entries are left as they are.
    pub fn accumulate<const W: usize>(&self, comm: &Comm, v: &mut [[f64; W]]) {
        let packed: Vec<Vec<f64>> = self
            .recv
            .iter()
            .map(|(_, l)| l.iter().flat_map(|&e| v[e as usize]).collect())
            .collect();
        let total: usize = self.send.iter().map(|s| s.1.len() * W).sum();
        let mut rbuf = vec![0.0f64; total];
        scope(|sc| {
            let mut reqs: Vec<Request<'_, [f64], _>> = Vec::new();
            let mut rest = &mut rbuf[..];
            for (r, l) in &self.send {
                let (a, b) = rest.split_at_mut(l.len() * W);
                rest = b;
                reqs.push(comm.process_at_rank(*r).immediate_receive_into(sc, a));
            }
            for ((r, _), buf) in self.recv.iter().zip(&packed) {
                reqs.push(comm.process_at_rank(*r).immediate_send(sc, &buf[..]));
            }
            for q in reqs {
                q.wait_without_status();
            }
        });
        let mut at = 0;
        for (_, l) in &self.send {
            for &e in l {
                let dst = &mut v[e as usize];
                for (d, s) in dst.iter_mut().zip(&rbuf[at..at + W]) {
                    *d += s;
                }
                at += W;
            }
        }
    }

    /// Fills the ghost entries of `v` from their owners; `work` runs on `v` (read only)
    /// while the messages travel, so it may read the owned entries only.
    pub fn exchange_overlapped<const W: usize, F>(&self, comm: &Comm, v: &mut [[f64; W]], work: F)
    where
        F: FnOnce(&[[f64; W]]),
    {
        let packed: Vec<Vec<f64>> = self
            .send
            .iter()
            .map(|(_, l)| l.iter().flat_map(|&e| v[e as usize]).collect())
            .collect();
        let total: usize = self.recv.iter().map(|r| r.1.len() * W).sum();
        let mut rbuf = vec![0.0f64; total];
        scope(|sc| {
            let mut reqs: Vec<Request<'_, [f64], _>> = Vec::new();
            let mut rest = &mut rbuf[..];
            for (r, l) in &self.recv {
                let (a, b) = rest.split_at_mut(l.len() * W);
                rest = b;
                reqs.push(comm.process_at_rank(*r).immediate_receive_into(sc, a));
            }
            for ((r, _), buf) in self.send.iter().zip(&packed) {
                reqs.push(comm.process_at_rank(*r).immediate_send(sc, &buf[..]));
            }
            work(v);
            for q in reqs {
                q.wait_without_status();
            }
        });
        let mut at = 0;
        for (_, l) in &self.recv {
            for &e in l {
                let dst = &mut v[e as usize];
                dst.copy_from_slice(&rbuf[at..at + W]);
                at += W;
            }
        }
    }
}
