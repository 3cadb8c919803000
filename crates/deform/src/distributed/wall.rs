//! The grid-wide fields of the volume and wall-distance stiffnesses over the ranks
//! ([`springs`]), defined exactly as the serial `stiffness::springs`:
//! - [`Stiffness::Volume`]: V̄ / V_i, V_i the mean volume of the cells around node i (its
//!   owner has them all), V̄ the mean cell volume (one all-reduce of the sum and the count,
//!   each cell counted by the owner of its lowest global node); the ghosts take their
//!   owners' factors through the node halo.
//! - [`Stiffness::WallDistance`]: the distance of every node from the moving nodes along
//!   grid edges, by Dijkstra on each rank's part, seeded with the current distances, and
//!   the ghosts' distances brought from their owners, repeated until no distance changes on
//!   any rank. The fixed point is the serial one: each node's distance is the smallest
//!   d_j + l_ij over its neighbours (its owner has every edge of it), the shortest path's
//!   sums in the same order, whatever the order in which nodes are settled. ℓ is 0.2 × the
//!   diagonal of the moving nodes' bounding box over the ranks.
//!
//! And the fields measured from the moving boundary on the baseline grid: its distance
//! along edges ([`edge_distance`] from `scatter::Local::boundary`, for the reach of R and
//! the far field) and the far-field report ([`far_field`]).

use mpi::traits::*;

use super::comm::{Comm, max, min, sum_n, sum_u64};
use super::partition::Partition;
use crate::bc::NodeRole;
use crate::report::FarField;
use crate::stiffness::{NodeVolumes, Springs, Stiffness, WALL_SCALE, mean_volume};
use crate::wall_distance::settle_from;

/// True when this rank counts the cell `e`: it owns the cell's node of smallest global id.
fn counted(part: &Partition, e: &[u32]) -> bool {
    let g = &part.grid;
    e.iter()
        .min_by_key(|&&v| g.global_ids[v as usize])
        .is_some_and(|&v| (v as usize) < g.n_owned)
}

/// The springs' evaluator of `kind` (volume or wall distance) at the local coordinates `x`
/// (ghosts up to date), `roles` the local nodes' roles, `scale` the springs' scale of the
/// whole grid. Collective.
pub(crate) fn springs<'a>(
    comm: &Comm,
    part: &Partition,
    roles: &[NodeRole],
    x: &'a [[f64; 3]],
    kind: Stiffness,
    scale: f64,
) -> Springs<'a> {
    match kind {
        Stiffness::Volume => {
            Springs::with_factors(x, kind, scale, volume_factors(comm, part, x), 0.0)
        }
        _ => {
            let moving: Vec<bool> = roles
                .iter()
                .map(|r| matches!(r, NodeRole::Rigid(_) | NodeRole::Displaced(_)))
                .collect();
            let n_owned = part.grid.n_owned;
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for (p, _) in x[..n_owned].iter().zip(&moving).filter(|e| *e.1) {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            let (lo, hi) = (lo.map(|v| min(comm, v)), hi.map(|v| max(comm, v)));
            let diag =
                ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2))
                    .sqrt();
            let wall_len = if diag.is_finite() {
                WALL_SCALE * diag
            } else {
                0.0
            };
            let d = edge_distance(comm, part, x, &moving);
            Springs::with_factors(x, kind, scale, d, wall_len)
        }
    }
}

/// V̄ / V_i of every local node (1 where no cell or a zero volume is around it).
fn volume_factors(comm: &Comm, part: &Partition, x: &[[f64; 3]]) -> Vec<f64> {
    let v = NodeVolumes::new(&part.grid.mesh, x, |e| counted(part, e));
    let [total, cells] = sum_n(comm, [v.total, v.cells]);
    let mut f: Vec<[f64; 1]> = v
        .factors(mean_volume(total, cells))
        .into_iter()
        .map(|f| [f])
        .collect();
    // A ghost's cells are not all on this rank: its owner's factor.
    part.halo.exchange(comm, &mut f);
    f.into_iter().map(|v| v[0]).collect()
}

/// The distance of every local node from the nodes flagged `source` (local flags, ghosts
/// included) along the whole grid's edges (∞ where no source is reached). Collective.
pub(crate) fn edge_distance(
    comm: &Comm,
    part: &Partition,
    x: &[[f64; 3]],
    source: &[bool],
) -> Vec<f64> {
    let mut d: Vec<[f64; 1]> = source
        .iter()
        .map(|&s| [if s { 0.0 } else { f64::INFINITY }])
        .collect();
    // Each round settles from the nodes the last exchange lowered (the first from all):
    // the rest of the part is settled already.
    let mut flat: Vec<f64> = d.iter().map(|v| v[0]).collect();
    let mut seeds: Vec<u32> = (0..flat.len() as u32).collect();
    loop {
        settle_from(&part.adj, x, &mut flat, &seeds);
        for (v, &f) in d.iter_mut().zip(&flat) {
            v[0] = f;
        }
        part.halo.exchange(comm, &mut d);
        seeds.clear();
        for (i, (v, f)) in d.iter().zip(&mut flat).enumerate() {
            if v[0].to_bits() != f.to_bits() {
                *f = v[0];
                seeds.push(i as u32);
            }
        }
        if sum_u64(comm, seeds.len() as u64) == 0 {
            break;
        }
    }
    flat
}

/// The far-field report of the local coordinates `cur` (as the serial
/// `Deformer::far_field`: the largest displacement among the nodes at least the moving
/// boundary's bounding-box diagonal away from it along grid edges), over the ranks, from
/// each local node's distance `wall_distance` from the moving boundary ([`edge_distance`]);
/// the node by its global id (the whole grid's number).
/// Collective.
pub(crate) fn far_field(
    comm: &Comm,
    part: &Partition,
    wall_distance: &[f64],
    cur: &[[f64; 3]],
) -> FarField {
    let n = part.grid.n_owned;
    let (x0, x, d) = (&part.grid.mesh.coords[..n], &cur[..n], &wall_distance[..n]);
    let (lo, hi, wall_max) = FarField::moving(x0, x, d);
    let (lo, hi) = (lo.map(|v| min(comm, v)), hi.map(|v| max(comm, v)));
    let distance = FarField::diagonal(lo, hi);
    let (nodes, top) = FarField::far(x0, x, d, distance);
    // The largest over the ranks; among equal ones, the smallest global id.
    let mine = top.map_or([f64::NEG_INFINITY, 0.0], |(i, u)| {
        [u, part.grid.global_ids[i] as f64]
    });
    let mut all = vec![0.0f64; 2 * comm.size() as usize];
    comm.all_gather_into(&mine[..], &mut all[..]);
    let top = all
        .chunks_exact(2)
        .filter(|p| p[0] > f64::NEG_INFINITY)
        .fold(None, |acc: Option<(f64, f64)>, p| match acc {
            Some((u, g)) if u > p[0] || (u == p[0] && g <= p[1]) => Some((u, g)),
            _ => Some((p[0], p[1])),
        });
    FarField {
        distance,
        nodes: sum_u64(comm, nodes as u64) as usize,
        max_displacement: top.map_or(0.0, |t| t.0),
        node: top.map(|t| t.1 as u32),
        wall_max_displacement: max(comm, wall_max),
    }
}
