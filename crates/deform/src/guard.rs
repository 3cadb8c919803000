//! The quality guard (incremental deformation): the motion is done in 1, 2, 4, … increments
//! until no cell is inverted (beyond those of the baseline) and the minimum quality stays
//! above `min_quality_ratio` × the initial minimum; the report and the result of the last
//! attempt.

use std::time::Instant;

use mesh::Mesh;
use mesh::quality::summary;

use crate::bc::{BoundaryConditions, NodeRole};
use crate::deformer::{Deformed, Deformer, SolverState};
use crate::error::{Error, Result};
use crate::increment::{Attempt, Context, Increment};
use crate::report::{DeformReport, FarField, PhaseTimes};
use crate::support::{SupKind, Support};

/// Quality of every cell ([`mesh::quality::element_quality`]: every kind, `q ≤ 0` for a flat
/// or inverted cell; canonical order) for the grid's connectivity at coordinates `x`.
pub fn cell_quality(mesh: &Mesh, x: &[[f64; 3]]) -> Vec<f64> {
    mesh::quality::cell_quality_at(mesh, x)
}

/// The `k` worst cells as "cell id (kind, q = …)".
fn worst_cells(mesh: &Mesh, q: &[f64], k: usize) -> String {
    mesh::quality::worst_cells(&mesh.cells, q, k)
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The attempts of the guard for the set-up `d` and the call's boundary conditions `bc` (solver
/// numbering); `warm`: the state of an earlier result, `exact`: the prescribed nodes' final
/// positions when the call gave positions; `keep_inverted`: return an inverted grid as
/// `allow_inverted` does.
pub(crate) fn run(
    d: &Deformer,
    bc: &BoundaryConditions,
    warm: Option<&SolverState>,
    exact: Option<&[[f64; 3]]>,
    keep_inverted: bool,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<Deformed> {
    let ctx = Context {
        mesh: &d.mesh,
        cls: &d.cls,
        bc,
        sys: &d.sys,
        adj: &d.adj,
        opts: &d.opts,
        sup: d.sup.as_ref(),
        exact,
        reach: &d.reach,
    };
    let (mesh, cls, sys, opts) = (ctx.mesh, ctx.cls, ctx.sys, ctx.opts);
    let before = d.before;
    let mut times = PhaseTimes::default();
    let mut attempts = Vec::new();
    let mut notes = Vec::new();
    let mut inc = 1usize;
    loop {
        attempts.push(inc);
        let mut st = Attempt {
            cur: mesh.coords.clone(),
            params: match warm {
                Some(w) if inc == 1 && w.params.len() == cls.supports.len() => w.params.clone(),
                _ => cls.supports.iter().map(|s| s.param).collect(),
            },
        };
        let mut state = SolverState {
            shape: (mesh.n_nodes(), sys.node_of.len()),
            ..SolverState::default()
        };
        let mut slide_iterations = 0;
        let mut slide_update = 0.0f64;
        let mut iterations = 0;
        let mut rot_iterations = 0;
        let mut residual = 0.0f64;
        let mut amg = None;
        for m in 1..=inc {
            progress("solve", m - 1, inc);
            let step = Increment {
                s: if m == inc { 1.0 } else { m as f64 / inc as f64 },
                // The first increment starts from the baseline: its A is the set-up's.
                op: if m == 1 { d.op.as_ref() } else { None },
                warm: if inc == 1 { warm } else { None },
            };
            let o = step.run(&ctx, &mut st, &mut times)?;
            slide_iterations += o.slide_iterations;
            slide_update = slide_update.max(o.slide_update);
            iterations += o.iterations;
            rot_iterations += o.rot_iterations;
            residual = residual.max(o.residual);
            if o.amg.is_some() {
                amg = o.amg;
            }
            if inc == 1 {
                // The solutions from the baseline (later increments start elsewhere).
                (state.dx, state.qv) = (o.dx, o.qv);
            }
        }
        progress("quality", inc, inc);
        let t = Instant::now();
        let q1 = cell_quality(mesh, &st.cur);
        let after = summary(&q1);
        times.quality += t.elapsed().as_secs_f64();
        let low = after.min < opts.min_quality_ratio * before.min;
        let bad = after.n_nonpositive > before.n_nonpositive || low;
        if bad && inc < opts.max_increments {
            notes.push(format!(
                "{inc} increment(s): {} inverted cells, min quality {:.4} (initial {:.4}); retrying with {}",
                after.n_nonpositive,
                after.min,
                before.min,
                inc * 2
            ));
            inc *= 2;
            continue;
        }
        if after.n_nonpositive > before.n_nonpositive {
            let worst = worst_cells(mesh, &q1, 5);
            if !(opts.allow_inverted || keep_inverted) {
                return Err(Error::Inverted {
                    count: after.n_nonpositive,
                    increments: inc,
                    worst,
                });
            }
            notes.push(format!(
                "{} inverted cells kept (allowed); worst: {worst}",
                after.n_nonpositive
            ));
        } else if low {
            notes.push(format!(
                "minimum quality {:.4} is below {} × initial {:.4} after {inc} increments",
                after.min, opts.min_quality_ratio, before.min
            ));
        }
        let nmov = cls
            .roles
            .iter()
            .filter(|r| matches!(r, NodeRole::Rigid(_) | NodeRole::Displaced(_)))
            .count();
        let report = DeformReport {
            nodes: mesh.n_nodes(),
            cells: mesh.cells.len(),
            unknowns: sys.node_of.len(),
            sliding: sys.cons.items.len(),
            sliding_on_supports: cls.supports.len(),
            slide_iterations,
            slide_update,
            moving: nmov,
            planes: cls.planes.clone(),
            increments: inc,
            attempts,
            iterations,
            rotation_iterations: rot_iterations,
            residual,
            solver: opts.solver,
            multigrid: amg,
            quality_before: before,
            quality_after: after,
            seconds: times,
            setup_steps: Vec::new(),
            notes,
            far_field: FarField::default(),
            first_layer: None,
        };
        let Attempt { cur, params } = st;
        let supports = cls
            .supports
            .iter()
            .zip(&params)
            .map(|(sn, p)| {
                let s = match sn.kind {
                    SupKind::Curve(curve) => Support::Curve { curve, t: p[0] },
                    SupKind::Surface(surface) => Support::Surface { surface, uv: *p },
                };
                (sn.node, s)
            })
            .collect();
        state.params = params;
        if inc > 1 {
            // Δx from the baseline of the whole motion.
            state.dx = sys
                .node_of
                .iter()
                .map(|&i| {
                    let (p, q) = (cur[i as usize], mesh.coords[i as usize]);
                    [p[0] - q[0], p[1] - q[1], p[2] - q[2]]
                })
                .collect();
        }
        return Ok(Deformed {
            coords: cur,
            supports,
            cell_quality: q1,
            report,
            state,
        });
    }
}
