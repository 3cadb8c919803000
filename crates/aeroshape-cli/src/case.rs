//! `aeroshape case init`: a ready case from the user's own CAD and grid (`aeroshape::init`):
//! markers by shape, the wall tied to the geometry, the default design space with bounds
//! checked by the study; and the dispatch of `case check` ([`crate::case_check`]).

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};

use aeroshape::init::{InitOptions, init_case, read_cad};

/// `aeroshape case` subcommands.
#[derive(Debug, Subcommand)]
pub enum CaseCmd {
    /// Make a case from a CAD file (.igs, .iges, .stp, .step or .ron) and a volume grid
    /// (.su2 or .msh): the far field fixed, planes sliding, markers on the geometry wall (by
    /// shape, not by name); writes DIR/case.ron, DIR/geometry.ron and DIR/grid.msh
    /// (parametric wall nodes) and prints the design variables (wing master, fuselage
    /// waist, bumps) with their checked bounds.
    Init(InitArgs),
    /// Check the design box as a whole: the corners and a Latin hypercube through the chain;
    /// where one inverts a cell or fails, the box is shrunk about the initial design until
    /// every sample passes. Prints the bounds before and after, the failing samples and the
    /// variables that fail together; optionally writes the case with the shrunk bounds, a
    /// picture of the valid fraction per pair of variables and every sample as JSON.
    Check(crate::case_check::CheckArgs),
}

/// Arguments of `case init`.
#[derive(Debug, Args)]
pub struct InitArgs {
    /// The CAD: IGES (.igs, .iges) or STEP (.stp, .step), imported as by `geom import`, or
    /// a geometric database (.ron).
    pub cad: PathBuf,
    /// The volume grid (.su2 or .msh).
    pub grid: PathBuf,
    /// The folder of the new case (created if needed).
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,
    /// Geometric tolerance relative to the model's reference length, instead of the largest
    /// of the default (1e-6) and the CAD's own figures.
    #[arg(long, value_name = "REL")]
    pub rel_tol: Option<f64>,
    /// Make control nodes (one per interpolation point of every arc and patch, shared where
    /// they coincide) when a `.ron` geometry has none; without it such a geometry is an
    /// error. An imported IGES or STEP file always gets them.
    #[arg(long)]
    pub assign_control_nodes: bool,
    /// Latin-hypercube samples of the box checked as a whole, besides up to as many corners
    /// (`case check` with its defaults does more); the bounds shrink until all pass. 0
    /// skips the check.
    #[arg(long, value_name = "N", default_value_t = 8)]
    pub box_samples: usize,
}

/// Runs a `case` subcommand.
pub fn run(cmd: CaseCmd) -> anyhow::Result<()> {
    match cmd {
        CaseCmd::Init(a) => init(&a),
        CaseCmd::Check(a) => crate::case_check::check(&a),
    }
}

fn init(a: &InitArgs) -> anyhow::Result<()> {
    if let Some(r) = a.rel_tol
        && !(r.is_finite() && r > 0.0)
    {
        bail!("--rel-tol must be a positive number, got {r}");
    }
    for f in ["case.ron", "geometry.ron", "grid.msh"] {
        aeroshape::fsio::ensure_not_input(&a.output.join(f), &[&a.cad, &a.grid])
            .map_err(anyhow::Error::msg)?;
    }
    let cad = read_cad(&a.cad)?;
    let grid = mesh::io::read_path(&a.grid)?;
    if grid.cells.is_empty() {
        bail!("{}: not a volume grid (no cells)", a.grid.display());
    }
    std::fs::create_dir_all(&a.output)
        .with_context(|| format!("cannot create {}", a.output.display()))?;
    let opts = InitOptions {
        rel_tol: a.rel_tol,
        assign_control_nodes: a.assign_control_nodes,
        box_check: (a.box_samples > 0).then(|| aeroshape::boxcheck::BoxCheckOptions {
            samples: a.box_samples,
            max_corners: a.box_samples,
            ..InitOptions::default().box_check.unwrap_or_default()
        }),
        ..InitOptions::default()
    };
    let r = init_case(&cad.db, &grid, &cad.tolerances, &a.output, &opts).map_err(|e| match e {
        // the geometry's own defect: name its file alone
        aeroshape::init::InitError::NoControlNodes { .. } => {
            anyhow::anyhow!("{}: {e}", a.cad.display())
        }
        e => {
            anyhow::Error::new(e).context(format!("{} with {}", a.cad.display(), a.grid.display()))
        }
    })?;
    if cad.control_nodes_made > 0 {
        outln!(
            "{}: {} control nodes made at import (Eq. 9: one per interpolation point, shared \
             where they coincide)",
            a.cad.display(),
            cad.control_nodes_made
        );
    }
    outln!("tolerance {:.3e}, the largest of:", r.tolerance);
    for t in &r.tolerances {
        outln!("  {:.3e}  {}", t.value, t.source);
    }
    outln!("markers:");
    for m in &r.markers {
        outln!(
            "  {:<20} {:<6} {}",
            m.marker,
            format!("{:?}", m.role).to_lowercase(),
            m.why
        );
    }
    outln!(
        "wall: {} corner, {} curve and {} surface nodes; distance max {:.3e} (node {}), mean {:.3e}",
        r.classify.corners,
        r.classify.curve_nodes,
        r.classify.surface_nodes,
        r.classify.max_distance,
        r.classify.worst_node,
        r.classify.mean_distance
    );
    if r.control_nodes_assigned > 0 {
        outln!(
            "control nodes: {} made (the geometry had none)",
            r.control_nodes_assigned
        );
    }
    outln!("design space:");
    for b in &r.built {
        outln!("  {b}");
    }
    outln!(
        "design variables ({}), each alone at either bound inverts no cell:",
        r.variables.len()
    );
    outln!(
        "  {:<32} {:>11} {:>6} {:>9} {:>9}",
        "name",
        "bound",
        "nodes",
        "q min -",
        "q min +"
    );
    for v in &r.variables {
        outln!(
            "  {:<32} {:>11.4e} {:>6} {:>9.4} {:>9.4}",
            v.name,
            v.bound,
            v.nodes_moved,
            v.min_quality[0],
            v.min_quality[1]
        );
    }
    match &r.box_check {
        Some(b) if b.scale == 1.0 => outln!(
            "together: {} of {} samples of the box (corners, Latin hypercube) valid; bounds kept",
            b.valid,
            b.samples
        ),
        Some(b) if b.scale > 0.0 => outln!(
            "together: {} of {} samples of the box valid; in the case, bounds multiplied by: {}",
            b.valid,
            b.samples,
            b.scales
                .iter()
                .filter(|(_, s)| *s < 1.0)
                .map(|(n, s)| format!("{n} {s}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        Some(b) => outln!(
            "together: {} of {} samples of the box valid, and it still fails when shrunk; see \
             the note",
            b.valid,
            b.samples
        ),
        None => {}
    }
    for n in &r.notes {
        outln!("note: {n}");
    }
    for f in ["case.ron", "geometry.ron", "grid.msh"] {
        outln!("wrote {}", a.output.join(f).display());
    }
    Ok(())
}
