//! A rank's share of the deformation problem ([`Local`]): its validated [`Partition`] and
//! the roles of its nodes (moving, fixed, sliding, free), with the skin elements and rigid
//! motions they need. Made either by each rank from its own part ([`Local::given`]), or on
//! rank 0 from the whole grid ([`Local::from_root`]): rank 0 classifies every node as the
//! serial deformation does, cuts the grid by METIS or coordinate bisection
//! ([`super::metis::cut`]), and sends each rank its part.

use mesh::{ElementKind, Mesh};
use mpi::datatype::PartitionMut;
use mpi::traits::*;
use rayon::prelude::*;
use sparse::order;

use super::comm::{Comm, agree, offsets};
use super::cores::{broadcast_idle, on_pool, root_pool};
use super::metis::{Partitioner, cut_in, work_weights};
use super::partition::{LocalGrid, Partition};
use super::rcb::parts_in;
use crate::bc::{
    BoundaryConditions, Classified, MarkerRole, NodeRole, RigidMotion, all_displaced, classify,
    push_displaced_skin,
};
use crate::error::{Error, Result};
use crate::options::DeformOptions;
use crate::solve::Constraint;
use crate::support::{SupNode, Supports};

/// A rank's share of the problem.
pub(crate) struct Local {
    pub part: Partition,
    /// Roles of the local nodes; `Displaced(k)` indexes `disp`.
    pub cls: Classified,
    /// The prescribed displacements of the local nodes that have one.
    pub disp: Vec<[f64; 3]>,
    /// How many displacements the set-up was given: rank 0's whole-grid list for a part
    /// made there (0 on the other ranks), the rank's own list for a given part.
    pub n_bc: usize,
    /// For a part made on rank 0: the index in rank 0's list of displacements of each
    /// entry of `disp` ([`Local::displacements`] takes new values through it); empty for a
    /// given part, whose first `n_bc` entries of `disp` are its own list, in order.
    pub disp_src: Vec<u32>,
    /// How the parts were made: `given`, `metis`, `rcb`, or `rcb (METIS failed)`.
    pub made_by: &'static str,
    /// The threads rank 0 made the parts with (on rank 0; 0 elsewhere and for a given part).
    pub partition_threads: usize,
    /// On rank 0, the nodes sliding on geometry supports as the serial classification
    /// finds them (whole-grid numbering); empty elsewhere. Their roles are sent as free:
    /// `super::slide` hands each owner its own.
    pub root_supports: Vec<SupNode>,
    /// The moving boundary of the serial deformation (`crate::deformer::moving_boundary`)
    /// among the local nodes, what the reach of R and the far-field report measure from: on
    /// a part made on rank 0, found there on the whole grid and broadcast; on a given part,
    /// each owner flags its owned nodes from its own boundary elements (it has every
    /// boundary element of its nodes) and the ghosts take their owners' flags.
    pub boundary: Vec<bool>,
    /// For a part given by the caller: the renumbering of its nodes into this share's
    /// (`perm[caller's local node] = local node`; the owned nodes in the serial solver's
    /// order for locality, the ghosts kept in place). None for a part made on rank 0,
    /// whose numbering is the library's own.
    pub caller: Option<Vec<u32>>,
    /// Seconds this rank spent on its own part once it had it: decoding it, its checks,
    /// adjacency, ordering and halo ([`Partition`]), its nodes' roles and the moving
    /// boundary's flags.
    pub own_seconds: f64,
}

/// The ways rank 0 made the parts, as it broadcasts them (index + 1; 0: it failed).
const MADE_BY: [&str; 3] = ["metis", "rcb", "rcb (METIS failed)"];

impl Local {
    /// From each rank's own part: the roles come from its own markers (the boundary
    /// elements of its nodes) and `bc` (node displacements in local numbering), the ghosts'
    /// from their owners (a ghost's boundary elements need not all be on this rank). Sliding
    /// planes need the whole marker for their fit and are refused here. The owned nodes are
    /// renumbered for locality ([`Local::caller`]): a solver's own order can be scattered
    /// (a Gmsh grid's is), and at 1M nodes on 2 ranks a part in Gmsh's order took 8.7 s
    /// against 7.4 s in Morton order (docs/perf-log/2026-12-03-mpi-adef2.md).
    pub fn given(
        comm: &Comm,
        grid: LocalGrid,
        bc: &BoundaryConditions,
        opts: &DeformOptions,
    ) -> Result<Self> {
        let t = std::time::Instant::now();
        let (part, perm) = Partition::ordered(comm, grid)?;
        let bc = &BoundaryConditions {
            markers: bc.markers.clone(),
            displacements: bc
                .displacements
                .iter()
                .map(|&(i, d)| (perm.get(i as usize).copied().unwrap_or(i), d))
                .collect(),
        };
        let cls = (|| {
            if let Some((name, _)) = bc
                .markers
                .iter()
                .find(|m| m.1 != MarkerRole::Fixed && !matches!(m.1, MarkerRole::Rigid(_)))
            {
                return Err(Error::Distributed {
                    rank: comm.rank(),
                    reason: format!(
                        "marker {name}: only rigid and fixed markers are supported on a given partition \
                         (a sliding plane is fitted to the whole marker: use the partition made on rank 0)"
                    ),
                });
            }
            classify(&part.grid.mesh, bc, opts.plane_rel_tol, None)
        })();
        let mut cls = agree(comm, cls)?;
        let mut disp = bc.displacements.iter().map(|d| d.1).collect();
        let before = cls.roles.clone();
        owners_roles(comm, &part, &mut cls, &mut disp);
        displaced_skin(&part.grid.mesh, bc, &before, &mut cls);
        let boundary = owners_flags(
            comm,
            &part,
            crate::deformer::moving_boundary(&part.grid.mesh, bc, &cls),
        );
        Ok(Self {
            part,
            cls,
            disp,
            n_bc: bc.displacements.len(),
            disp_src: Vec::new(),
            made_by: "given",
            partition_threads: 0,
            root_supports: Vec::new(),
            boundary,
            caller: Some(perm),
            own_seconds: t.elapsed().as_secs_f64(),
        })
    }

    /// From the whole grid on rank 0 (`whole` is read on rank 0 only; the other ranks pass
    /// None): classification as the serial deformation (with the supports `sup` of the
    /// nodes sliding on the geometry, read on rank 0), cut into `comm.size()` parts by
    /// `by` (METIS falls back on coordinate bisection), each part sent to its rank.
    pub fn from_root(
        comm: &Comm,
        whole: Option<(&Mesh, &BoundaryConditions)>,
        sup: Option<&Supports>,
        opts: &DeformOptions,
        by: Partitioner,
    ) -> Result<Self> {
        let root = comm.process_at_rank(0);
        let p = comm.size() as usize;
        let mut root_supports = Vec::new();
        let mut root_boundary = Vec::new();
        let n_bc = whole.map_or(0, |(_, bc)| bc.displacements.len());
        // Rank 0 cuts on the cores of the ranks waiting for it.
        let pool = root_pool(comm);
        let partition_threads = match (&pool, comm.rank()) {
            (_, r) if r != 0 => 0,
            (Some(p), _) => p.current_num_threads(),
            (None, _) => rayon::current_num_threads(),
        };
        let mine: Result<Option<(Piece, u64)>> = if comm.rank() == 0 {
            let made = on_pool(pool.as_ref(), || {
                let (m, bc) = whole.ok_or_else(|| Error::Distributed {
                    rank: 0,
                    reason: "rank 0 was given no grid".into(),
                })?;
                let mut cls = classify(m, bc, opts.plane_rel_tol, sup)?;
                root_supports = std::mem::take(&mut cls.supports);
                root_boundary = crate::deformer::moving_boundary(m, bc, &cls);
                // The nodes along a Morton curve: METIS's graph and each part are built
                // in that order (from nearby memory; a Gmsh grid's order is scattered).
                let morton = order::morton_order(&m.coords);
                let c = cut_in(m, p, by, &morton, &work_weights(&cls.roles));
                let grids = parts_in(m, &c.part, p, &order::inverse(&morton));
                let of = Origin {
                    part: &c.part,
                    boundary: &root_boundary,
                };
                let pieces: Vec<Piece> =
                    grids.par_iter().map(|g| encode(g, &cls, bc, &of)).collect();
                let how: u64 = match (c.by, c.fallback) {
                    (Partitioner::Metis, _) => 1,
                    (Partitioner::Rcb, None) => 2,
                    (Partitioner::Rcb, Some(_)) => 3,
                };
                Ok((pieces, how))
            });
            drop(pool);
            // The others wait for their part only when rank 0 has made them.
            let mut ok = made.as_ref().map_or(0, |m| m.1);
            broadcast_idle(comm, &mut ok);
            made.map(|(mut pieces, how)| {
                for (r, piece) in pieces.iter().enumerate().skip(1) {
                    piece.send(comm.process_at_rank(r as i32));
                }
                Some((pieces.swap_remove(0), how))
            })
        } else {
            let mut ok = 0u64;
            broadcast_idle(comm, &mut ok);
            if ok > 0 {
                Ok(Some((Piece::receive(root), ok)))
            } else {
                Ok(None)
            }
        };
        let (piece, how) = agree(comm, mine)?.ok_or_else(|| Error::Distributed {
            rank: 0,
            reason: "no part received".into(),
        })?;
        let t = std::time::Instant::now();
        let got = agree(comm, decode(&piece, comm.size(), comm.rank()))?;
        drop(piece);
        let Decoded {
            grid,
            mut cls,
            disp,
            disp_src,
            ghost_owner,
            boundary: flags,
        } = got;
        // The part's numbering is ours: its owned nodes take the serial solver's order.
        let (part, perm) = Partition::made(comm, grid, &ghost_owner)?;
        let mut roles = cls.roles.clone();
        let mut boundary = vec![false; flags.len()];
        for (i, &p) in perm.iter().enumerate() {
            roles[p as usize] = cls.roles[i];
            boundary[p as usize] = flags[i];
        }
        cls.roles = roles;
        for e in &mut cls.skin {
            for v in e.iter_mut() {
                *v = perm[*v as usize];
            }
        }
        Ok(Self {
            part,
            cls,
            disp,
            n_bc: if comm.rank() == 0 { n_bc } else { 0 },
            disp_src,
            partition_threads,
            made_by: MADE_BY.get(how as usize - 1).copied().unwrap_or("?"),
            root_supports,
            boundary,
            caller: None,
            own_seconds: t.elapsed().as_secs_f64(),
        })
    }
}

impl Local {
    /// The displacements of the local displaced nodes (as `disp`) for new values of the
    /// set-up's prescribed displacements, in the order the set-up was given them
    /// (collective): for a part made on rank 0, rank 0's `values` (the whole grid's list;
    /// the other ranks' are ignored) broadcast and each entry taken from its index; for a
    /// given part, each rank its own list, and its ghosts' from their owners. A list of
    /// another length, or a value that is not finite, fails on every rank.
    pub fn displacements(&self, comm: &Comm, values: &[[f64; 3]]) -> Result<Vec<[f64; 3]>> {
        let made = self.caller.is_none();
        let checked = if made && comm.rank() != 0 {
            Ok(())
        } else if values.len() != self.n_bc {
            Err(format!(
                "{} displacements given for the {} nodes of the set-up",
                values.len(),
                self.n_bc
            ))
        } else if let Some(k) = values.iter().position(|d| !d.iter().all(|x| x.is_finite())) {
            Err(format!("displacement {k} ({:?}) is not finite", values[k]))
        } else {
            Ok(())
        };
        agree(
            comm,
            checked.map_err(|reason| Error::Distributed {
                rank: comm.rank(),
                reason,
            }),
        )?;
        if made {
            let flat: Vec<f64> = if comm.rank() == 0 {
                values.iter().flatten().copied().collect()
            } else {
                Vec::new()
            };
            let all = super::comm::broadcast_vec(comm, 0, flat);
            return Ok(self
                .disp_src
                .iter()
                .map(|&s| {
                    let s = 3 * s as usize;
                    [all[s], all[s + 1], all[s + 2]]
                })
                .collect());
        }
        let mut disp = self.disp.clone();
        disp[..self.n_bc].copy_from_slice(values);
        // Every local node's displacement, the ghosts' from their owners.
        let mut at = vec![[0.0; 3]; self.cls.roles.len()];
        for (i, role) in self.cls.roles.iter().enumerate() {
            if let NodeRole::Displaced(k) = *role {
                at[i] = disp[k];
            }
        }
        self.part.halo.exchange(comm, &mut at);
        for (i, role) in self
            .cls
            .roles
            .iter()
            .enumerate()
            .skip(self.part.grid.n_owned)
        {
            if let NodeRole::Displaced(k) = *role {
                disp[k] = at[i];
            }
        }
        Ok(disp)
    }
}

const FREE: u64 = 0;
const FIXED: u64 = 1;
const RIGID: u64 = 2;
const DISPLACED: u64 = 3;
const PLANE: u64 = 4;
const LINE: u64 = 5;

/// A role as five floats: its tag, its index, its payload (a displacement or a constraint
/// direction).
fn role_code(role: NodeRole, disp: &[[f64; 3]]) -> [f64; 5] {
    let (tag, index, pay) = match role {
        NodeRole::Free | NodeRole::OnSupport(_) => (FREE, 0, [0.0; 3]),
        NodeRole::Fixed => (FIXED, 0, [0.0; 3]),
        NodeRole::Rigid(m) => (RIGID, m, [0.0; 3]),
        NodeRole::Displaced(k) => (DISPLACED, 0, disp[k]),
        NodeRole::Sliding(Constraint::Plane(v)) => (PLANE, 0, v),
        NodeRole::Sliding(Constraint::Line(v)) => (LINE, 0, v),
    };
    [tag as f64, index as f64, pay[0], pay[1], pay[2]]
}

/// Completes the skin of the prescribed displacements of a given part once the ghosts have
/// their owners' roles: the elements of the markers that are not rigid whose nodes are all
/// displaced now, and were not before (a ghost displaced by its owner, not by this rank's
/// list), as the serial classification takes them. Without them a wall moved by node
/// displacements lost its skin elements across the partition's boundary, and R there: 5.3e-4
/// of the displacement from the serial grid on the wing-body fixture grid, 9.4e-10 with
/// them (tests/mpi_deform.py of the Python package).
fn displaced_skin(mesh: &Mesh, bc: &BoundaryConditions, before: &[NodeRole], cls: &mut Classified) {
    let rigid = |k: usize| {
        let name = &mesh.markers[k].name;
        bc.markers
            .iter()
            .any(|(n, r)| n == name && matches!(r, MarkerRole::Rigid(_)))
    };
    let new = |e: &[u32]| !all_displaced(before, e);
    push_displaced_skin(mesh, rigid, &cls.roles, new, &mut cls.skin);
}

/// The local nodes' `flags` with the ghosts' replaced by their owners' (collective).
fn owners_flags(comm: &Comm, part: &Partition, flags: Vec<bool>) -> Vec<bool> {
    let mut v: Vec<[f64; 1]> = flags.iter().map(|&f| [f64::from(u8::from(f))]).collect();
    part.halo.exchange(comm, &mut v);
    v.iter().map(|f| f[0] != 0.0).collect()
}

/// The ghosts' roles as their owners classified them (collective): a ghost's own
/// classification sees only the boundary elements whose nodes are all on this rank, and
/// may take a node of a rigid marker for a free one. A displaced ghost's displacement is
/// appended to `disp`.
fn owners_roles(comm: &Comm, part: &Partition, cls: &mut Classified, disp: &mut Vec<[f64; 3]>) {
    let mut v: Vec<[f64; 5]> = cls.roles.iter().map(|&r| role_code(r, disp)).collect();
    part.halo.exchange(comm, &mut v);
    for (i, c) in v.iter().enumerate().skip(part.grid.n_owned) {
        let pay = [c[2], c[3], c[4]];
        cls.roles[i] = match c[0] as u64 {
            FIXED => NodeRole::Fixed,
            RIGID => NodeRole::Rigid(c[1] as usize),
            DISPLACED => {
                disp.push(pay);
                NodeRole::Displaced(disp.len() - 1)
            }
            PLANE => NodeRole::Sliding(Constraint::Plane(pay)),
            LINE => NodeRole::Sliding(Constraint::Line(pay)),
            _ => NodeRole::Free,
        };
    }
}

/// What rank 0 sends a rank: counts, global ids and roles as integers; the node lists of the
/// cells, the skin and the markers' elements; coordinates and payloads as floats.
struct Piece {
    ints: Vec<u64>,
    nodes: Vec<u32>,
    floats: Vec<f64>,
}

impl Piece {
    /// Sends the piece to `dest` (its lengths first).
    fn send(&self, dest: mpi::topology::Process<'_>) {
        let len = [self.ints.len(), self.nodes.len(), self.floats.len()].map(|l| l as u64);
        dest.send(&len[..]);
        dest.send(&self.ints[..]);
        dest.send(&self.nodes[..]);
        dest.send(&self.floats[..]);
    }

    /// Receives a piece sent by [`Piece::send`] from `src`.
    fn receive(src: mpi::topology::Process<'_>) -> Self {
        let mut len = [0u64; 3];
        src.receive_into(&mut len[..]);
        let mut p = Self {
            ints: vec![0; len[0] as usize],
            nodes: vec![0; len[1] as usize],
            floats: vec![0.0; len[2] as usize],
        };
        src.receive_into(&mut p.ints[..]);
        src.receive_into(&mut p.nodes[..]);
        src.receive_into(&mut p.floats[..]);
        p
    }
}

/// Appends the groups of `el` to a piece: their count, then each group's VTK code and
/// node count in `ints`, its nodes in `nodes`.
fn encode_elements(el: &mesh::Elements, ints: &mut Vec<u64>, nodes: &mut Vec<u32>) {
    ints.push(el.groups().len() as u64);
    for grp in el.groups() {
        ints.push(u64::from(grp.kind.vtk_code()));
        ints.push(grp.nodes.len() as u64);
        nodes.extend_from_slice(&grp.nodes);
    }
}

/// What rank 0 knows of the whole grid's nodes beside their roles: the part of each
/// (the owner of a ghost) and the moving boundary's flags.
struct Origin<'a> {
    part: &'a [u32],
    boundary: &'a [bool],
}

/// A part and its nodes' roles as a piece (what rank 0 sends): the cells, the markers'
/// elements whose nodes are all in the part (for a grid written in pieces), the skin
/// elements whose nodes are all local, in local numbering, the owners of its ghosts and
/// its nodes on the moving boundary.
fn encode(g: &LocalGrid, cls: &Classified, bc: &BoundaryConditions, of: &Origin) -> Piece {
    let n = g.mesh.n_nodes();
    let mut ints = Vec::with_capacity(3 * n + 64);
    let mut nodes = Vec::with_capacity(g.mesh.cells.groups().iter().map(|c| c.nodes.len()).sum());
    let mut floats: Vec<f64> = Vec::with_capacity(6 * n + 10 * cls.motions.len());
    ints.extend([n as u64, g.n_owned as u64, u64::from(g.mesh.dim)]);
    floats.extend(g.mesh.coords.iter().flatten());
    ints.extend(&g.global_ids);
    encode_elements(&g.mesh.cells, &mut ints, &mut nodes);
    // Roles, with a payload of three floats each; a displaced node's index is that of its
    // displacement in rank 0's list.
    for &gid in &g.global_ids {
        let (tag, index, pay) = match cls.roles[gid as usize] {
            NodeRole::Free | NodeRole::OnSupport(_) => (FREE, 0, [0.0; 3]),
            NodeRole::Fixed => (FIXED, 0, [0.0; 3]),
            NodeRole::Rigid(m) => (RIGID, m as u64, [0.0; 3]),
            NodeRole::Displaced(k) => (DISPLACED, k as u64, bc.displacements[k].1),
            NodeRole::Sliding(Constraint::Plane(v)) => (PLANE, 0, v),
            NodeRole::Sliding(Constraint::Line(v)) => (LINE, 0, v),
        };
        ints.push(tag);
        ints.push(index);
        floats.extend(pay);
    }
    ints.push(cls.motions.len() as u64);
    for m in &cls.motions {
        floats.push(m.angle_deg);
        floats.extend(m.axis_point);
        floats.extend(m.axis_dir);
        floats.extend(m.translation);
    }
    // The local number of every node of the whole grid (u32::MAX: not in the part).
    let mut local = vec![u32::MAX; cls.roles.len()];
    for (i, &gid) in g.global_ids.iter().enumerate() {
        local[gid as usize] = i as u32;
    }
    let skin: Vec<Vec<u32>> = cls
        .skin
        .iter()
        .filter_map(|e| {
            e.iter()
                .map(|&v| Some(local[v as usize]).filter(|&l| l != u32::MAX))
                .collect()
        })
        .collect();
    ints.push(skin.len() as u64);
    for e in skin {
        ints.push(e.len() as u64);
        nodes.extend(e);
    }
    ints.push(g.mesh.markers.len() as u64);
    for mk in &g.mesh.markers {
        ints.push(mk.name.len() as u64);
        ints.extend(mk.name.bytes().map(u64::from));
        ints.push(mk.tag.map_or(u64::MAX, |t| u64::from(t as u32)));
        encode_elements(&mk.elements, &mut ints, &mut nodes);
    }
    ints.extend(
        g.global_ids[g.n_owned..]
            .iter()
            .map(|&gid| u64::from(of.part[gid as usize])),
    );
    let flagged: Vec<u32> = (0..n as u32)
        .filter(|&i| of.boundary[g.global_ids[i as usize] as usize])
        .collect();
    ints.push(flagged.len() as u64);
    nodes.extend(flagged);
    Piece {
        ints,
        nodes,
        floats,
    }
}

/// A decoded part.
struct Decoded {
    grid: LocalGrid,
    /// Its nodes' roles.
    cls: Classified,
    /// The displacements of its displaced nodes.
    disp: Vec<[f64; 3]>,
    /// The index of each in rank 0's list.
    disp_src: Vec<u32>,
    /// The owner of each ghost.
    ghost_owner: Vec<i32>,
    /// The moving boundary's flag of each node.
    boundary: Vec<bool>,
}

/// The reader of a [`Piece`]: integers, node lists and floats in the order [`encode`] put
/// them; every node index checked against the part's `n` nodes.
struct Reader<'a> {
    ints: std::slice::Iter<'a, u64>,
    nodes: &'a [u32],
    floats: std::slice::Iter<'a, f64>,
    n: usize,
}

/// The error of a piece that does not read as [`encode`] wrote it.
fn malformed() -> Error {
    Error::Distributed {
        rank: -1,
        reason: "malformed part received from rank 0".into(),
    }
}

impl<'a> Reader<'a> {
    fn int(&mut self) -> Result<u64> {
        self.ints.next().copied().ok_or_else(malformed)
    }

    fn float(&mut self) -> Result<f64> {
        self.floats.next().copied().ok_or_else(malformed)
    }

    fn floats<const K: usize>(&mut self) -> Result<[f64; K]> {
        let mut v = [0.0; K];
        for x in &mut v {
            *x = self.float()?;
        }
        Ok(v)
    }

    /// The next `len` node indices.
    fn nodes(&mut self, len: usize) -> Result<&'a [u32]> {
        if len > self.nodes.len() {
            return Err(malformed());
        }
        let (e, rest) = self.nodes.split_at(len);
        self.nodes = rest;
        if e.iter().any(|&v| v as usize >= self.n) {
            return Err(malformed());
        }
        Ok(e)
    }

    /// Element groups written by [`encode_elements`].
    fn elements(&mut self) -> Result<mesh::Elements> {
        let mut el = mesh::Elements::new();
        for _ in 0..self.int()? {
            let kind = ElementKind::from_vtk_code(self.int()? as i64).ok_or_else(malformed)?;
            let len = self.int()? as usize;
            if !len.is_multiple_of(kind.n_nodes()) {
                return Err(malformed());
            }
            let nodes = self.nodes(len)?;
            el.group_mut(kind).nodes.extend_from_slice(nodes);
        }
        el.prune();
        Ok(el)
    }
}

/// The inverse of [`encode`], on rank `me` of `ranks` (a ghost's owner is another rank).
fn decode(piece: &Piece, ranks: i32, me: i32) -> Result<Decoded> {
    let mut r = Reader {
        ints: piece.ints.iter(),
        nodes: &piece.nodes,
        floats: piece.floats.iter(),
        n: 0,
    };
    let n = r.int()? as usize;
    r.n = n;
    let n_owned = r.int()? as usize;
    if n_owned > n {
        return Err(malformed());
    }
    let dim = r.int()? as u8;
    let mut m = Mesh::new(dim);
    m.coords = (0..n).map(|_| r.floats::<3>()).collect::<Result<_>>()?;
    let global_ids = (0..n).map(|_| r.int()).collect::<Result<Vec<u64>>>()?;
    m.cells = r.elements()?;
    let mut roles = Vec::with_capacity(n);
    let (mut disp, mut disp_src) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let (tag, index) = (r.int()?, r.int()? as usize);
        let pay = r.floats::<3>()?;
        roles.push(match tag {
            FREE => NodeRole::Free,
            FIXED => NodeRole::Fixed,
            RIGID => NodeRole::Rigid(index),
            DISPLACED => {
                disp.push(pay);
                disp_src.push(u32::try_from(index).map_err(|_| malformed())?);
                NodeRole::Displaced(disp.len() - 1)
            }
            PLANE => NodeRole::Sliding(Constraint::Plane(pay)),
            LINE => NodeRole::Sliding(Constraint::Line(pay)),
            _ => return Err(malformed()),
        });
    }
    let motions = (0..r.int()?)
        .map(|_| {
            let v = r.floats::<10>()?;
            Ok(RigidMotion {
                angle_deg: v[0],
                axis_point: [v[1], v[2], v[3]],
                axis_dir: [v[4], v[5], v[6]],
                translation: [v[7], v[8], v[9]],
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let skin = (0..r.int()?)
        .map(|_| {
            let len = r.int()? as usize;
            Ok(r.nodes(len)?.to_vec())
        })
        .collect::<Result<Vec<_>>>()?;
    for _ in 0..r.int()? {
        let len = r.int()? as usize;
        let name = (0..len)
            .map(|_| u8::try_from(r.int()?).map_err(|_| malformed()))
            .collect::<Result<Vec<u8>>>()?;
        let name = String::from_utf8(name).map_err(|_| malformed())?;
        let tag = match r.int()? {
            u64::MAX => None,
            t => Some(u32::try_from(t).map_err(|_| malformed())? as i32),
        };
        let elements = r.elements()?;
        m.markers.push(mesh::Marker {
            name,
            tag,
            elements,
        });
    }
    let ghost_owner = (n_owned..n)
        .map(|_| {
            let o = r.int()?;
            i32::try_from(o)
                .ok()
                .filter(|&o| o < ranks && o != me)
                .ok_or_else(malformed)
        })
        .collect::<Result<Vec<i32>>>()?;
    let mut boundary = vec![false; n];
    let flagged = r.int()? as usize;
    for &i in r.nodes(flagged)? {
        boundary[i as usize] = true;
    }
    Ok(Decoded {
        grid: LocalGrid {
            mesh: m,
            global_ids,
            n_owned,
        },
        cls: Classified {
            roles,
            motions,
            planes: Vec::new(),
            skin,
            supports: Vec::new(),
        },
        disp,
        disp_src,
        ghost_owner,
        boundary,
    })
}

/// The owned nodes' coordinates `coords` of every rank, whose global ids are `gids`,
/// gathered on rank 0 in global-id order (`None` on the other ranks): the inverse of the
/// scatter, for [`super::Deformer::gather`]. Collective.
pub(crate) fn gather(comm: &Comm, gids: &[u64], coords: &[[f64; 3]]) -> Option<Vec<[f64; 3]>> {
    let no = gids.len();
    let xs: Vec<f64> = coords.iter().flatten().copied().collect();
    let root = comm.process_at_rank(0);
    let mut counts = vec![0i32; comm.size() as usize];
    if comm.rank() == 0 {
        root.gather_into_root(&(no as i32), &mut counts[..]);
    } else {
        root.gather_into(&(no as i32));
    }
    if comm.rank() != 0 {
        root.gather_varcount_into(gids);
        root.gather_varcount_into(&xs[..]);
        return None;
    }
    let displs = |w: i32| -> (Vec<i32>, Vec<i32>) {
        let c: Vec<i32> = counts.iter().map(|&c| c * w).collect();
        let d = offsets(&c);
        (c, d)
    };
    let total: usize = counts.iter().map(|&c| c as usize).sum();
    let mut all_g = vec![0u64; total];
    let mut all_x = vec![0.0f64; 3 * total];
    let (c1, d1) = displs(1);
    root.gather_varcount_into_root(
        gids,
        &mut PartitionMut::new(&mut all_g[..], &c1[..], &d1[..]),
    );
    let (c3, d3) = displs(3);
    root.gather_varcount_into_root(
        &xs[..],
        &mut PartitionMut::new(&mut all_x[..], &c3[..], &d3[..]),
    );
    let mut out = vec![[0.0; 3]; total];
    for (k, &g) in all_g.iter().enumerate() {
        out[g as usize] = [all_x[3 * k], all_x[3 * k + 1], all_x[3 * k + 2]];
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box grid cut in two by bisection, its nodes classified with one rigid marker,
    /// one displaced node and one fixed marker.
    #[allow(clippy::type_complexity)]
    fn parts_of_a_box() -> (
        Mesh,
        Vec<LocalGrid>,
        Classified,
        BoundaryConditions,
        Vec<u32>,
        Vec<bool>,
    ) {
        let m = mesh::generate::box_tets(4, 3, 3, [0.0; 3], [2.0, 1.0, 1.0]);
        let bc = BoundaryConditions {
            markers: vec![
                (
                    "x_m".into(),
                    MarkerRole::Rigid(RigidMotion {
                        angle_deg: 2.0,
                        axis_point: [0.0; 3],
                        axis_dir: [0.0, 1.0, 0.0],
                        translation: [0.0; 3],
                    }),
                ),
                ("x_p".into(), MarkerRole::Fixed),
            ],
            displacements: vec![(7, [0.0, 0.0, 0.01])],
        };
        let cls = classify(&m, &bc, 1e-6, None).unwrap();
        let part = super::super::rcb::rcb(&m.coords, 2);
        let grids = super::super::rcb::parts(&m, &part, 2);
        let boundary = crate::deformer::moving_boundary(&m, &bc, &cls);
        (m, grids, cls, bc, part, boundary)
    }

    #[test]
    fn a_part_reads_back_as_it_was_sent_markers_and_skin_included() {
        let (m, grids, cls, bc, part, boundary) = parts_of_a_box();
        let of = Origin {
            part: &part,
            boundary: &boundary,
        };
        let mut faces = vec![0usize; m.markers.len()];
        let (mut displaced, mut rigid, mut flagged) = (0, 0, 0);
        for (q, g) in grids.iter().enumerate() {
            let got = decode(&encode(g, &cls, &bc, &of), 2, q as i32).unwrap();
            let (back, roles, disp, src) = (&got.grid, &got.cls, &got.disp, &got.disp_src);
            for (k, &gid) in g.global_ids[g.n_owned..].iter().enumerate() {
                assert_eq!(got.ghost_owner[k], part[gid as usize] as i32);
            }
            for (i, &gid) in g.global_ids.iter().enumerate() {
                assert_eq!(got.boundary[i], boundary[gid as usize]);
                flagged += usize::from(got.boundary[i]);
            }
            assert_eq!(back.global_ids, g.global_ids);
            assert_eq!(back.n_owned, g.n_owned);
            assert_eq!(back.mesh.coords, g.mesh.coords);
            assert_eq!(back.mesh.cells, g.mesh.cells);
            assert_eq!(back.mesh.markers, g.mesh.markers);
            for (k, mk) in back.mesh.markers.iter().enumerate() {
                assert_eq!(mk.name, m.markers[k].name);
                // A marker's element on this part has its nodes on this part.
                faces[k] += mk.elements.len();
            }
            for (i, &gid) in g.global_ids.iter().enumerate() {
                let want = cls.roles[gid as usize];
                match (roles.roles[i], want) {
                    (NodeRole::Displaced(k), NodeRole::Displaced(j)) => {
                        assert_eq!((disp[k], src[k] as usize), (bc.displacements[j].1, j));
                        displaced += 1;
                    }
                    (NodeRole::Rigid(a), NodeRole::Rigid(b)) => {
                        assert_eq!(a, b);
                        rigid += 1;
                    }
                    (got, want) => assert_eq!(format!("{got:?}"), format!("{want:?}")),
                }
            }
            assert_eq!(roles.motions.len(), cls.motions.len());
            for e in &roles.skin {
                assert!(e.iter().all(|&v| (v as usize) < back.mesh.n_nodes()));
            }
        }
        assert!(
            displaced >= 1 && rigid >= 16,
            "{displaced} displaced, {rigid} rigid"
        );
        assert!(flagged >= 16, "{flagged} nodes on the moving boundary");
        // Every boundary element is on some part.
        for (k, mk) in m.markers.iter().enumerate() {
            assert!(faces[k] >= mk.elements.len(), "marker {}", mk.name);
        }
    }

    #[test]
    fn a_malformed_part_is_an_error_not_a_panic() {
        let (_, grids, cls, bc, part, boundary) = parts_of_a_box();
        let of = Origin {
            part: &part,
            boundary: &boundary,
        };
        let good = encode(&grids[0], &cls, &bc, &of);
        let n = grids[0].mesh.n_nodes() as u32;
        let mut wrong = Vec::new();
        // A node index beyond the part's nodes, in a cell and in the last marker element.
        let mut p = encode(&grids[0], &cls, &bc, &of);
        p.nodes[0] = n;
        wrong.push(p);
        let mut p = encode(&grids[0], &cls, &bc, &of);
        *p.nodes.last_mut().unwrap() = n + 5;
        wrong.push(p);
        // Lists cut short.
        for cut in [1, good.ints.len() / 2, good.ints.len() - 1] {
            let mut p = encode(&grids[0], &cls, &bc, &of);
            p.ints.truncate(cut);
            wrong.push(p);
        }
        let mut p = encode(&grids[0], &cls, &bc, &of);
        p.nodes.truncate(p.nodes.len() - 1);
        wrong.push(p);
        let mut p = encode(&grids[0], &cls, &bc, &of);
        p.floats.truncate(p.floats.len() / 2);
        wrong.push(p);
        for (k, p) in wrong.iter().enumerate() {
            let err = decode(p, 2, 0)
                .err()
                .unwrap_or_else(|| panic!("case {k} decoded"));
            assert!(
                err.to_string().contains("malformed part"),
                "case {k}: {err}"
            );
        }
        assert!(decode(&good, 2, 0).is_ok());
        // A ghost owned by the receiving rank, or by no rank of the job.
        assert!(decode(&good, 2, 1).is_err());
        assert!(decode(&good, 1, 0).is_err());
    }
}
