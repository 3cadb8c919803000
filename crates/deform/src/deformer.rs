//! The deformation set-up and its use: [`Deformer`] (built once per grid and
//! boundary-condition roles, then run for any prescribed values), its result [`Deformed`],
//! and the free functions [`deform`], [`deform_on_supports`] and their `_with_progress`
//! forms (set-up, then one run).

use std::time::Instant;

use mesh::quality::Summary;
use mesh::quality::summary;
use mesh::{Adjacency, Mesh};
use sparse::{V3, order};

use crate::assembly::{System, build_system};
use crate::bc::{BoundaryConditions, Classified, NodeRole, classify};
use crate::error::{Error, Result};
use crate::guard::{self, cell_quality};
use crate::operator::Operator;
use crate::options::{DeformOptions, reach_weight};
use crate::report::{DeformReport, FarField, PhaseTimes, StepTime, Steps};
use crate::stiffness::Stiffness;
use crate::support::{Support, Supports};
use crate::wall_distance::edge_distance;

/// The deformed coordinates (same numbering as the input) and the report.
#[derive(Debug, Clone)]
pub struct Deformed {
    /// New node coordinates.
    pub coords: Vec<[f64; 3]>,
    /// Final supports and parameters of the nodes that slid on geometry supports (input
    /// numbering; empty without [`crate::MarkerRole::SlideOnSupport`]).
    pub supports: Vec<(u32, Support)>,
    /// Signed quality of every cell at `coords` ([`cell_quality`], canonical order): the
    /// field the guard checked.
    pub cell_quality: Vec<f64>,
    /// What was done.
    pub report: DeformReport,
    /// The solver state of this result, the warm start of a later [`Deformer::deform`].
    pub(crate) state: SolverState,
}

/// The unknowns of a solved deformation in the set-up's own numbering: what a warm start
/// (see [`Deformer::deform`]) begins from.
#[derive(Debug, Clone, Default)]
pub(crate) struct SolverState {
    /// Nodes and unknowns of the set-up that produced it (a check on reuse).
    pub shape: (usize, usize),
    /// Δx of Eq. 21 per unknown (empty when nothing was solved).
    pub dx: Vec<V3>,
    /// The Eq. 26 solution per unknown: the quaternion's vector part as solved (before the
    /// clamp to |u| ≤ 1; empty without R). The scalar part is derived from it.
    pub qv: Vec<V3>,
    /// Parameters of the nodes sliding on supports (classification order).
    pub params: Vec<[f64; 2]>,
    /// The prescribed displacements of the call (set-up order), and the positions when the
    /// call gave positions: what [`Deformer::linearise`] re-reads.
    pub values: Vec<[f64; 3]>,
    pub exact: Option<Vec<[f64; 3]>>,
}

/// Deforms the volume grid for the boundary conditions `bc` (Eqs. 14–26 and 34), with the
/// quality guard; returns the new coordinates (input numbering) and a report.
pub fn deform(mesh: &Mesh, bc: &BoundaryConditions, opts: &DeformOptions) -> Result<Deformed> {
    deform_with_progress(mesh, bc, opts, &mut |_, _, _| {})
}

/// Renumbers the set-up's grid, boundary conditions and support nodes: node `i` becomes
/// `perm[i]` (support entries of nodes outside the grid are dropped: classification has
/// refused them wherever supports are used).
fn renumber_set_up(
    m: &mut Mesh,
    bc: &mut BoundaryConditions,
    sup: &mut Option<Supports>,
    perm: &[u32],
) -> Result<()> {
    m.renumber_nodes(perm).map_err(|e| Error::BadGraph {
        reason: e.to_string(),
    })?;
    for (v, _) in &mut bc.displacements {
        *v = perm[*v as usize];
    }
    if let Some(sp) = sup {
        sp.nodes.retain(|(v, _)| (*v as usize) < perm.len());
        for (v, _) in &mut sp.nodes {
            *v = perm[*v as usize];
        }
    }
    Ok(())
}

/// [`deform`] calling `progress(phase, done, total)` as it goes.
///
/// With `opts.renumber`, the grid is first renumbered internally along a Morton curve (so a
/// randomly numbered input runs about as fast as a well-ordered one), then in breadth-first
/// order ([`sparse::order::level_order`]), and the unknowns keep that order; the result is returned in the
/// input numbering.
pub fn deform_with_progress(
    mesh: &Mesh,
    bc: &BoundaryConditions,
    opts: &DeformOptions,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<Deformed> {
    deform_driver(mesh, bc, None, opts, progress)
}

/// [`deform`] with nodes sliding on the support curves and surfaces of a geometry (paper
/// §4.3, Eqs. 27–33): the nodes of every [`crate::MarkerRole::SlideOnSupport`] marker slide
/// on the support `supports` gives them (corners frozen), by the precedence of
/// [`crate::bc`] (moving > sliding on a curve > sliding on a surface > fixed). The sliding
/// nodes end exactly on their supports; their final parameters are returned in
/// [`Deformed::supports`].
pub fn deform_on_supports(
    mesh: &Mesh,
    bc: &BoundaryConditions,
    supports: &Supports,
    opts: &DeformOptions,
) -> Result<Deformed> {
    deform_driver(mesh, bc, Some(supports), opts, &mut |_, _, _| {})
}

/// [`deform_on_supports`] calling `progress(phase, done, total)` as it goes.
pub fn deform_on_supports_with_progress(
    mesh: &Mesh,
    bc: &BoundaryConditions,
    supports: &Supports,
    opts: &DeformOptions,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<Deformed> {
    deform_driver(mesh, bc, Some(supports), opts, progress)
}

fn deform_driver(
    mesh: &Mesh,
    bc: &BoundaryConditions,
    sup: Option<&Supports>,
    opts: &DeformOptions,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<Deformed> {
    let d = Deformer::build(mesh, bc, sup, opts, progress)?;
    let values: Vec<[f64; 3]> = bc.displacements.iter().map(|e| e.1).collect();
    let mut out = d.run(Prescribed::Displacements(&values), None, false, progress)?;
    out.report.setup_steps = d.steps.clone();
    let s = &mut out.report.seconds;
    s.setup += d.setup.setup;
    s.assemble += d.setup.assemble;
    s.precond += d.setup.precond;
    s.quality += d.setup.quality;
    Ok(out)
}

/// The spring matrix of a [`Deformer`] ([`Deformer::stiffness_matrix`]).
#[derive(Debug, Clone, PartialEq)]
pub struct StiffnessMatrix {
    /// A (symmetric positive definite; diagonal included), unknowns in the solver's order.
    pub matrix: sprs::CsMat<f64>,
    /// The node (input numbering) of each row and column.
    pub nodes: Vec<u32>,
}

/// The moving boundary, the nodes whose distance the reach of R and the far-field report
/// measure from: the nodes of rigid markers, and the nodes with a prescribed displacement
/// that are on no fixed marker and belong to a skin element (a marker element whose nodes
/// all have one) or to no marker. So a fixed marker held by zero displacements (the far
/// field of a study, the seam of a fixed and a sliding marker) is not part of it.
pub(crate) fn moving_boundary(mesh: &Mesh, bc: &BoundaryConditions, cls: &Classified) -> Vec<bool> {
    let n = mesh.n_nodes();
    let (mut on_fixed, mut on_marker, mut in_skin) =
        (vec![false; n], vec![false; n], vec![false; n]);
    for m in &mesh.markers {
        let fixed = bc
            .markers
            .iter()
            .any(|(name, r)| *name == m.name && matches!(r, crate::MarkerRole::Fixed));
        for v in m.elements.node_set() {
            on_marker[v as usize] = true;
            on_fixed[v as usize] |= fixed;
        }
    }
    for e in &cls.skin {
        for &v in e {
            in_skin[v as usize] = true;
        }
    }
    cls.roles
        .iter()
        .enumerate()
        .map(|(i, r)| match r {
            NodeRole::Rigid(_) => true,
            NodeRole::Displaced(_) => !on_fixed[i] && (in_skin[i] || !on_marker[i]),
            _ => false,
        })
        .collect()
}

/// The prescribed values given to [`Deformer`]: displacements or new positions.
#[derive(Clone, Copy)]
enum Prescribed<'a> {
    Displacements(&'a [[f64; 3]]),
    Positions(&'a [[f64; 3]]),
}

/// A reusable deformation set-up: everything that depends only on the baseline grid and on
/// the boundary-condition roles, built once by [`Deformer::new`] — node classification and
/// sliding-plane fits, adjacency, the renumbering (Morton, then
/// [`sparse::order::level_order`]; also the unknowns' order), the spring stiffnesses at the baseline geometry, the matrix A of Eq. 21 and its
/// preconditioner (multigrid hierarchy or Jacobi diagonal), the baseline quality.
///
/// [`Deformer::deform`] then takes new values for the prescribed displacements (same nodes,
/// same order as the set-up's [`BoundaryConditions::displacements`]) and reuses all of it for
/// the first increment, which starts from the baseline grid — so the matrix there is exactly
/// the baseline one and the result is bit for bit that of the free [`deform`]. The rotation
/// field R (Eqs. 25–26) only changes the right-hand side of Eq. 21, never A, so nothing is
/// approximated. When the quality guard splits the motion into increments, the increments
/// after the first start from a deformed state and assemble their own A and preconditioner.
pub struct Deformer<'s> {
    /// The grid in solver numbering (renumbered with `opts.renumber`).
    pub(crate) mesh: Mesh,
    /// Input node → solver node (None without renumbering).
    pub(crate) perm: Option<Vec<u32>>,
    /// Solver node → input node (empty without renumbering).
    pub(crate) inv: Vec<u32>,
    /// The boundary conditions in solver numbering.
    pub(crate) bc: BoundaryConditions,
    pub(crate) sup: Option<Supports<'s>>,
    pub(crate) opts: DeformOptions,
    pub(crate) cls: Classified,
    pub(crate) adj: Adjacency,
    pub(crate) sys: System,
    /// Quality of the baseline grid.
    pub(crate) before: Summary,
    /// A and its preconditioner at the baseline (None when there is no unknown).
    pub(crate) op: Option<Operator>,
    /// Every node's distance from the moving boundary ([`moving_boundary`]) along grid
    /// edges, on the baseline grid (∞ where no moving node is reached).
    pub(crate) wall_distance: Vec<f64>,
    /// The weight φ of R per node ([`reach_weight`] of `wall_distance`); empty: 1
    /// everywhere (no reach).
    pub(crate) reach: Vec<f64>,
    setup: PhaseTimes,
    /// Seconds per step of the set-up.
    steps: Vec<StepTime>,
}

impl Deformer<'static> {
    /// Builds the set-up for `bc` on `mesh` (the displacement values of `bc` are not used;
    /// only which nodes are prescribed).
    pub fn new(mesh: &Mesh, bc: &BoundaryConditions, opts: &DeformOptions) -> Result<Self> {
        Deformer::build(mesh, bc, None, opts, &mut |_, _, _| {})
    }
}

impl<'s> Deformer<'s> {
    /// [`Deformer::new`] with nodes sliding on geometry supports (as
    /// [`deform_on_supports`]).
    pub fn on_supports(
        mesh: &Mesh,
        bc: &BoundaryConditions,
        supports: &Supports<'s>,
        opts: &DeformOptions,
    ) -> Result<Self> {
        Deformer::build(mesh, bc, Some(supports), opts, &mut |_, _, _| {})
    }

    /// Seconds spent by the set-up (classification, ordering, assembly, preconditioner,
    /// baseline quality).
    pub fn setup_times(&self) -> PhaseTimes {
        self.setup
    }

    /// Number of prescribed displacements [`Deformer::deform`] expects.
    pub fn n_displacements(&self) -> usize {
        self.bc.displacements.len()
    }

    /// Seconds per step of the set-up, in the order they ran (see [`StepTime`]).
    pub fn setup_steps(&self) -> &[StepTime] {
        &self.steps
    }

    /// The spring matrix A of Eq. 21 at the baseline grid (the matrix every
    /// [`Deformer::deform`] solves with in its first increment), exported as a
    /// [`sprs::CsMat`]: row and column k are unknown k, whose node (input numbering) is
    /// `nodes[k]`. The stiffnesses are in the set-up's dimensionless scaling (K times a
    /// power of two near 1 / diag^p, diag the grid's bounding-box diagonal, p = 1 for
    /// [`Stiffness::InverseLength`], else 2; docs/crates/deform.md, "Storage of K"), rounded
    /// to single precision, as solved. Empty when no node is unknown.
    pub fn stiffness_matrix(&self) -> Result<StiffnessMatrix> {
        let Some(op) = &self.op else {
            return Ok(StiffnessMatrix {
                matrix: sprs::CsMat::zero((0, 0)),
                nodes: Vec::new(),
            });
        };
        let matrix = op.matrix().to_csmat()?;
        let nodes = self
            .sys
            .node_of
            .iter()
            .map(|&i| match &self.perm {
                Some(_) => self.inv[i as usize],
                None => i,
            })
            .collect();
        Ok(StiffnessMatrix { matrix, nodes })
    }

    fn build(
        mesh: &Mesh,
        bc: &BoundaryConditions,
        sup: Option<&Supports<'s>>,
        opts: &DeformOptions,
        progress: &mut dyn FnMut(&str, usize, usize),
    ) -> Result<Self> {
        if let Some(l) = opts.rotation_reach
            && (l.is_nan() || l < 0.0)
        {
            return Err(Error::BadOption {
                reason: format!("the reach of R must be a length ≥ 0 (or infinite), not {l}"),
            });
        }
        let mut times = PhaseTimes::default();
        let t = Instant::now();
        progress("setup", 0, 1);
        let renumber = opts.renumber && mesh.n_nodes() >= 2;
        let mut steps = Steps::start();
        let (mut m2, mut bc2, mut sup2) = (mesh.clone(), bc.clone(), sup.cloned());
        steps.mark("copy");
        let (mut perm, moving) = if renumber {
            // Validate in the user's numbering first, so that errors name the user's nodes.
            let c1 = classify(mesh, bc, opts.plane_rel_tol, sup)?;
            steps.mark("classify (input numbering)");
            let perm = order::morton_order(&mesh.coords);
            steps.mark("morton order");
            // The moving nodes (sources of the wall distance), in Morton numbering.
            let mut moving = Vec::new();
            if opts.stiffness == Stiffness::WallDistance {
                moving = vec![false; perm.len()];
                for (r, &p) in c1.roles.iter().zip(&perm) {
                    moving[p as usize] = matches!(r, NodeRole::Rigid(_) | NodeRole::Displaced(_));
                }
            }
            renumber_set_up(&mut m2, &mut bc2, &mut sup2, &perm)?;
            steps.mark("renumber");
            (Some(perm), moving)
        } else {
            (None, Vec::new())
        };
        steps.restart();
        let mut adj = Adjacency::try_build(&m2).map_err(|e| Error::BadGraph {
            reason: e.to_string(),
        })?;
        steps.mark("adjacency");
        // The wall distance of the set-up's springs, when computed beside the level order.
        let mut distance = None;
        if let Some(perm) = perm.as_mut() {
            // Then breadth-first order (see `order::level_order`): node k → level[k]. The wall
            // distance (a sequential Dijkstra) runs beside it on the Morton-numbered grid: it
            // does not depend on the numbering (a node's distance is the smallest d + l of
            // its neighbours, the same sums in any order), so it is the one `springs` would
            // compute, permuted.
            let (d, (level, permuted)) = rayon::join(
                || (!moving.is_empty()).then(|| edge_distance(&adj, &m2.coords, &moving)),
                || {
                    let level = order::level_order(adj.n_nodes(), |i| adj.neighbours(i));
                    let g = order::permute_graph(adj.n_nodes(), |i| adj.neighbours(i), &level);
                    let permuted = Adjacency {
                        offsets: g.offsets,
                        indices: g.adj,
                    };
                    (level, permuted)
                },
            );
            drop(moving);
            renumber_set_up(&mut m2, &mut bc2, &mut sup2, &level)?;
            adj = permuted;
            distance = d.map(|d| {
                let mut out = vec![0.0; d.len()];
                for (&l, v) in level.iter().zip(d) {
                    out[l as usize] = v;
                }
                out
            });
            *perm = order::then(perm, &level);
            steps.mark("level order");
        }
        // Solver node → input node.
        let inv = perm.as_deref().map_or_else(Vec::new, order::inverse);
        let cls = classify(&m2, &bc2, opts.plane_rel_tol, sup2.as_ref())?;
        steps.mark("classify");
        let sys = build_system(&cls, &adj);
        steps.mark("unknowns");
        times.setup = t.elapsed().as_secs_f64();
        let t = Instant::now();
        // The distance from the moving boundary (of the far-field report and of the reach
        // of R) beside the baseline quality.
        let (wall_distance, q0) = rayon::join(
            || edge_distance(&adj, &m2.coords, &moving_boundary(&m2, &bc2, &cls)),
            || cell_quality(&m2, &m2.coords),
        );
        let before = summary(&q0);
        steps.mark("quality");
        times.quality += t.elapsed().as_secs_f64();
        let reach = match opts.rotation_reach.filter(|l| *l != f64::INFINITY) {
            Some(l) => wall_distance.iter().map(|&d| reach_weight(d, l)).collect(),
            None => Vec::new(),
        };
        let op = if sys.node_of.is_empty() {
            None
        } else {
            Some(
                Operator::new(
                    &m2, &cls, &sys, &adj, &m2.coords, opts, &mut times, &mut steps, distance,
                )
                .map_err(|e| e.renumbered(&inv))?,
            )
        };
        Ok(Self {
            mesh: m2,
            perm,
            inv,
            bc: bc2,
            sup: sup2,
            opts: *opts,
            cls,
            adj,
            sys,
            before,
            op,
            wall_distance,
            reach,
            setup: times,
            steps: steps.list,
        })
    }

    /// Deforms the grid for the prescribed displacements `displacements` (one per entry of
    /// the set-up's `bc.displacements`, same order), reusing the set-up. Report times exclude
    /// the set-up ([`Deformer::setup_times`]).
    ///
    /// `warm_start`: an earlier result of this set-up whose solution is the initial guess of
    /// the Eq. 26 solves (R), of the Eq. 21 solve and of the parameters of the nodes sliding
    /// on supports (single increment only). Without it every solve starts from zero (R = I,
    /// baseline parameters) and the answer is bit for bit that of [`deform`]; with it the
    /// answer agrees with that one to the solver tolerances (`rel_tol`, `slide_rel_tol`) and
    /// takes fewer iterations when the motions are close — the same motion again takes none.
    pub fn deform(
        &self,
        displacements: &[[f64; 3]],
        warm_start: Option<&Deformed>,
    ) -> Result<Deformed> {
        self.run(
            Prescribed::Displacements(displacements),
            warm_start,
            false,
            &mut |_, _, _| {},
        )
    }

    /// [`Deformer::deform`] with the prescribed nodes' new positions instead of their
    /// displacements (same order): the displacements are `positions − x⁰`, and the returned
    /// grid has these nodes exactly at `positions` (x⁰ + (p − x⁰) may differ from p by
    /// round-off), so that its cell quality is that of a grid whose boundary is exactly the
    /// caller's.
    pub fn deform_to(
        &self,
        positions: &[[f64; 3]],
        warm_start: Option<&Deformed>,
    ) -> Result<Deformed> {
        self.run(
            Prescribed::Positions(positions),
            warm_start,
            false,
            &mut |_, _, _| {},
        )
    }

    /// [`Deformer::deform_to`], but a grid that the quality guard would refuse (cells
    /// inverted beyond the baseline's after every increment) is returned rather than
    /// [`Error::Inverted`]: the last attempt's grid and its cell quality, with the count in
    /// the report's notes, whatever `allow_inverted` says. For showing what failed (`aeroshape
    /// run` writes it as `failed.vtu`), never for going on with.
    pub fn deform_to_keeping_inverted(
        &self,
        positions: &[[f64; 3]],
        warm_start: Option<&Deformed>,
    ) -> Result<Deformed> {
        self.run(
            Prescribed::Positions(positions),
            warm_start,
            true,
            &mut |_, _, _| {},
        )
    }

    /// [`Deformer::deform`] calling `progress(phase, done, total)` as it goes.
    pub fn deform_with_progress(
        &self,
        displacements: &[[f64; 3]],
        warm_start: Option<&Deformed>,
        progress: &mut dyn FnMut(&str, usize, usize),
    ) -> Result<Deformed> {
        self.run(
            Prescribed::Displacements(displacements),
            warm_start,
            false,
            progress,
        )
    }

    /// The far-field report of the grid `coords` (solver numbering): the largest
    /// displacement from the baseline among the nodes at least the moving boundary's
    /// bounding-box diagonal away from it ([`FarField`]).
    fn far_field(&self, coords: &[[f64; 3]]) -> FarField {
        let (x0, d) = (&self.mesh.coords, &self.wall_distance);
        let (lo, hi, wall_max) = FarField::moving(x0, coords, d);
        let distance = FarField::diagonal(lo, hi);
        let (nodes, top) = FarField::far(x0, coords, d, distance);
        FarField {
            distance,
            nodes,
            max_displacement: top.map_or(0.0, |t| t.1),
            node: top.map(|(i, _)| {
                if self.perm.is_some() {
                    self.inv[i]
                } else {
                    i as u32
                }
            }),
            wall_max_displacement: wall_max,
        }
    }

    /// The first layer at the moving boundary of the grid `coords` (solver numbering;
    /// [`crate::layer`]).
    fn first_layer(&self, coords: &[[f64; 3]]) -> Option<crate::layer::FirstLayer> {
        let moving: Vec<bool> = self
            .cls
            .roles
            .iter()
            .map(|r| matches!(r, NodeRole::Rigid(_) | NodeRole::Displaced(_)))
            .collect();
        let id = |v: usize| {
            if self.perm.is_some() {
                self.inv[v]
            } else {
                v as u32
            }
        };
        crate::layer::first_layer(&self.mesh, &self.adj, &moving, coords, &id)
    }

    fn run(
        &self,
        values: Prescribed,
        warm_start: Option<&Deformed>,
        keep_inverted: bool,
        progress: &mut dyn FnMut(&str, usize, usize),
    ) -> Result<Deformed> {
        // `exact`: the positions the prescribed nodes must end at, when given.
        let (given, what, exact) = match values {
            Prescribed::Displacements(d) => (d, "displacement", None),
            Prescribed::Positions(p) => (p, "position", Some(p)),
        };
        if given.len() != self.bc.displacements.len() {
            return Err(Error::BadMotion {
                reason: format!(
                    "{} {what}s given; the deformation set-up has {} prescribed nodes",
                    given.len(),
                    self.bc.displacements.len()
                ),
            });
        }
        let mut bc = self.bc.clone();
        for ((v, d), &new) in bc.displacements.iter_mut().zip(given) {
            if !new.iter().all(|x| x.is_finite()) {
                let v = self.perm.as_ref().map_or(*v, |_| self.inv[*v as usize]);
                return Err(Error::BadMotion {
                    reason: format!("node {v}: {what} {new:?} is not finite"),
                });
            }
            *d = if exact.is_some() {
                let x0 = self.mesh.coords[*v as usize];
                [new[0] - x0[0], new[1] - x0[1], new[2] - x0[2]]
            } else {
                new
            };
        }
        let shape = (self.mesh.n_nodes(), self.sys.node_of.len());
        let warm = match warm_start {
            Some(w) if w.state.shape != shape => {
                return Err(Error::BadMotion {
                    reason: format!(
                        "warm start from a deformation of {} nodes and {} unknowns; this set-up has {} and {}",
                        w.state.shape.0, w.state.shape.1, shape.0, shape.1
                    ),
                });
            }
            w => w.map(|w| &w.state),
        };
        let mut d = guard::run(self, &bc, warm, exact, keep_inverted, progress)
            .map_err(|e| e.renumbered(&self.inv))?;
        d.state.values = bc.displacements.iter().map(|e| e.1).collect();
        d.state.exact = exact.map(<[[f64; 3]]>::to_vec);
        d.report.far_field = self.far_field(&d.coords);
        d.report.first_layer = self.first_layer(&d.coords);
        if let Some(perm) = &self.perm {
            d.coords = perm.iter().map(|&p| d.coords[p as usize]).collect();
            for (v, _) in d.supports.iter_mut() {
                *v = self.inv[*v as usize];
            }
            d.supports.sort_by_key(|e| e.0);
        }
        Ok(d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permuted_adjacency_is_the_adjacency_of_the_renumbered_grid() {
        // A box grid numbered at random, then Morton- and level-ordered as the set-up does.
        let mut m = crate::generate::box_with_block(
            [12, 10, 9],
            [0.0; 3],
            [1.0, 0.9, 0.8],
            [4, 3, 3],
            [8, 7, 6],
        );
        mesh::generate::shuffle_nodes(&mut m, 11);
        m.renumber_nodes(&order::morton_order(&m.coords)).unwrap();
        let adj = Adjacency::build(&m);
        let level = order::level_order(adj.n_nodes(), |i| adj.neighbours(i));
        let g = order::permute_graph(adj.n_nodes(), |i| adj.neighbours(i), &level);
        let mut m2 = m.clone();
        m2.renumber_nodes(&level).unwrap();
        let a2 = Adjacency::build(&m2);
        assert_eq!((g.offsets, g.adj), (a2.offsets, a2.indices));
    }
}
