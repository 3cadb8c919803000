//! `aeroshape deform`: deform a volume grid from prescribed boundary motion (paper §4).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::Args;
use deform::{RigidMotion, SolverKind, Stiffness};
use serde::Serialize;

use crate::NameParser;

/// Deform a volume mesh from prescribed boundary motion: rigid motion of markers (Eq. 34) or
/// per-node displacements, with fixed and sliding markers (spring analogy with adaptation
/// matrices R, Eqs. 14–26). Markers not named move nothing.
#[derive(Debug, Args)]
pub struct DeformArgs {
    /// Input grid (.su2, .msh or .vtu).
    pub mesh: PathBuf,
    /// Output grid (.su2, .msh or .vtu, by extension); same connectivity, markers and node
    /// numbering as the input.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Marker moved rigidly by --rotate-deg/--axis-point/--axis-dir/--translate (repeatable:
    /// all named markers share the motion).
    #[arg(long, value_name = "MARKER")]
    pub rigid: Vec<String>,
    /// Rotation angle in degrees, right-hand rule about --axis-dir (Eq. 34).
    #[arg(
        long,
        value_name = "A",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub rotate_deg: f64,
    /// A point of the rotation axis.
    #[arg(long, value_name = "x,y,z", value_parser = parse_vec3, default_value = "0,0,0", allow_negative_numbers = true)]
    pub axis_point: [f64; 3],
    /// Direction of the rotation axis.
    #[arg(long, value_name = "x,y,z", value_parser = parse_vec3, default_value = "0,0,1", allow_negative_numbers = true)]
    pub axis_dir: [f64; 3],
    /// Translation applied after the rotation.
    #[arg(long, value_name = "dx,dy,dz", value_parser = parse_vec3, default_value = "0,0,0", allow_negative_numbers = true)]
    pub translate: [f64; 3],
    /// Per-node displacements: CSV with a header line, then `node,dx,dy,dz` (node index as in
    /// the mesh file, 0-based).
    #[arg(long, value_name = "FILE.csv")]
    pub displacements: Option<PathBuf>,
    /// Marker whose nodes slide (repeatable): on the support curves and surfaces of
    /// --geometry when every node of the marker is classified on a corner, curve or surface
    /// (MSH 4.1 grid with parametric nodes), otherwise on the marker's plane (the marker must
    /// then be planar).
    #[arg(long, value_name = "MARKER")]
    pub slide: Vec<String>,
    /// Geometry (GEOM.ron) the grid's classified nodes lie on: --slide markers slide on its
    /// support curves and surfaces (paper Eqs. 27–33; node classification as written by
    /// `aeroshape mesh`: entity tag = component id + 1), corners frozen.
    #[arg(long, value_name = "GEOM.ron")]
    pub geometry: Option<PathBuf>,
    /// Marker held fixed (the default for markers not named; repeatable).
    #[arg(long, value_name = "MARKER")]
    pub fixed: Vec<String>,
    /// Find the symmetry planes by shape: a marker not named that is a plane touching the
    /// moving markers slides on it instead of being held fixed.
    #[arg(long)]
    pub find_planes: bool,
    /// Linear solver: `pcg` (conjugate gradients with multigrid), `jacobi` (the paper's
    /// point iteration, Eq. 22), `pcg-jacobi` (conjugate gradients, Jacobi preconditioner).
    #[arg(long, default_value_t = SolverKind::PcgMultigrid,
          value_parser = NameParser::<SolverKind>::new(SolverKind::ALL.map(SolverKind::name)))]
    pub solver: SolverKind,
    /// Spring stiffness K_ij: `inverse-length` (1/l), `inverse-length2` (1/l²), `volume`
    /// (1/l² × mean cell volume / local cell volume), `wall-distance` (1/l² × (1 + (ℓ/d)²),
    /// d the distance to the moving boundary, ℓ = 0.2 × its size: a stiff layer around moving
    /// bodies).
    #[arg(long, default_value_t = Stiffness::InverseLengthSquared,
          value_parser = NameParser::<Stiffness>::new(Stiffness::ALL.map(Stiffness::name)))]
    pub stiffness: Stiffness,
    /// Disable the adaptation matrices R (plain spring analogy).
    #[arg(long)]
    pub no_rotation: bool,
    /// How far R reaches: blended to the identity with the distance d from the moving
    /// markers (along grid edges), fully at d = L (grid units; 0: no R at all). Without it R
    /// reaches everywhere (the paper's, the best cells near the wall).
    #[arg(long, value_name = "L", value_parser = parse_reach, conflicts_with = "no_rotation")]
    pub rotation_reach: Option<f64>,
    /// Relative residual at which the linear solves stop.
    #[arg(long, default_value_t = 1e-8)]
    pub tolerance: f64,
    /// Write a JSON report (counts, iterations, residual, time per phase, quality).
    #[arg(long, value_name = "REPORT.json")]
    pub report: Option<PathBuf>,
    /// Write the grid even if cells are inverted after the incremental retries.
    #[arg(long)]
    pub allow_inverted: bool,
    /// Under mpirun: the least aggregates per rank of the coarse-grid correction of the
    /// distributed preconditioner (more when they would hold over 500 unknowns; 0: the
    /// per-rank multigrid blocks alone; docs/mpi.md).
    #[cfg(feature = "mpi")]
    #[arg(long, value_name = "N", default_value_t = deform::distributed::COARSE_PARTS)]
    pub coarse_parts: usize,
    /// Under mpirun: how rank 0 cuts the grid into one part per rank: `metis` (METIS k-way
    /// on the node graph; coordinate bisection if METIS fails) or `rcb` (recursive coordinate
    /// bisection; docs/mpi.md).
    #[cfg(feature = "mpi")]
    #[arg(long, default_value_t = deform::distributed::Partitioner::Metis,
          value_parser = NameParser::<deform::distributed::Partitioner>::new(
              deform::distributed::Partitioner::ALL.map(deform::distributed::Partitioner::name)))]
    pub partition: deform::distributed::Partitioner,
}

/// A `--rotation-reach` value: a length ≥ 0.
pub(crate) fn parse_reach(s: &str) -> Result<f64, String> {
    s.parse::<f64>()
        .ok()
        .filter(|x| *x >= 0.0)
        .ok_or_else(|| format!("{s:?} is not a length ≥ 0"))
}

fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!("expected three comma-separated numbers, got {s:?}"));
    }
    let mut v = [0.0; 3];
    for (k, p) in parts.iter().enumerate() {
        v[k] = p
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{p:?} is not a finite number"))?;
    }
    Ok(v)
}

/// Reads `node,dx,dy,dz` lines after a header.
fn read_displacements(path: &Path, n_nodes: usize) -> anyhow::Result<Vec<(u32, [f64; 3])>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    let mut out = Vec::new();
    let mut seen = std::collections::HashMap::new();
    for (ln, line) in text.lines().enumerate().skip(1) {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let bad = |what: &str| anyhow::anyhow!("{}: line {}: {what}", path.display(), ln + 1);
        if f.len() != 4 {
            return Err(bad("expected node,dx,dy,dz"));
        }
        let node: usize = f[0]
            .parse()
            .map_err(|_| bad(&format!("bad node index {:?}", f[0])))?;
        if node >= n_nodes {
            return Err(bad(&format!(
                "node {node} does not exist (the grid has {n_nodes} nodes)"
            )));
        }
        let mut d = [0.0; 3];
        for k in 0..3 {
            d[k] = f[k + 1]
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| bad(&format!("bad displacement {:?}", f[k + 1])))?;
        }
        if let Some(prev) = seen.insert(node, ln + 1) {
            return Err(bad(&format!("node {node} already given on line {prev}")));
        }
        out.push((node as u32, d));
    }
    Ok(out)
}

#[derive(Serialize)]
struct Seconds {
    read: f64,
    setup: f64,
    assemble: f64,
    precond: f64,
    rotation: f64,
    solve: f64,
    quality: f64,
    write: f64,
    total: f64,
}

#[derive(Serialize)]
struct Report<'a> {
    input: String,
    output: String,
    nodes: usize,
    cells: usize,
    iterations: usize,
    rotation_iterations: usize,
    residual: f64,
    increments: usize,
    seconds: Seconds,
    quality_before: mesh::quality::Summary,
    quality_after: mesh::quality::Summary,
    /// The largest displacement far from the moving markers (`deform::FarField`).
    far_field: deform::FarField,
    deform: &'a deform::DeformReport,
}

/// Runs the subcommand.
pub fn run(args: DeformArgs) -> anyhow::Result<()> {
    let t_all = Instant::now();
    // .pvtu: a grid in pieces, one per rank (under mpirun only).
    let pieces = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pvtu"));
    let format = mesh::io::Format::from_path(&args.output);
    if format.is_none() && !pieces {
        bail!(
            "{}: unknown output format (use .su2, .msh, .vtu or an OpenFOAM case directory)",
            args.output.display()
        );
    }
    let mut inputs: Vec<&Path> = vec![&args.mesh];
    if let Some(g) = &args.geometry {
        inputs.push(g);
    }
    if let Some(d) = &args.displacements {
        inputs.push(d);
    }
    if let Some(r) = &args.report {
        inputs.push(r);
    }
    aeroshape_check(&args.output, &inputs)?;
    if let Some(r) = &args.report {
        aeroshape_check(r, &[&args.mesh])?;
    }
    if args.rigid.is_empty() && (args.rotate_deg != 0.0 || args.translate != [0.0; 3]) {
        bail!("--rotate-deg/--translate need a marker to move: give --rigid MARKER");
    }
    let mut request = request(&args);
    #[cfg(feature = "mpi")]
    if crate::deform_mpi::launched() {
        return crate::deform_mpi::run(&args, request);
    }
    let Some(format) = format else {
        bail!(
            "{}: a .pvtu output (one piece per rank) is written under mpirun by a build with the feature mpi; use .su2, .msh or .vtu",
            args.output.display()
        );
    };
    let bar = progress_bar();
    let t = Instant::now();
    bar_msg(&bar, "reading");
    let m = mesh::io::read_path(&args.mesh)?;
    let read = t.elapsed().as_secs_f64();
    let geometry = match &args.geometry {
        Some(p) => {
            let text = std::fs::read_to_string(p).with_context(|| format!("{}", p.display()))?;
            Some(geom_db::GeomDb::from_ron_str(
                &text,
                &p.display().to_string(),
            )?)
        }
        None => None,
    };
    // a node of a fixed marker (named by --fixed or by nothing) never moves, even where the
    // marker meets a sliding one
    add_displacements(&args, &m, &mut request)?;
    slide_symmetry_planes(&args, &m, &mut request)?;
    let mut progress = |phase: &str, done: usize, total: usize| {
        if let Some(b) = &bar {
            b.set_message(format!("{phase} ({done}/{total} increments)"));
        }
    };
    let d = request
        .run(&m, geometry.as_ref(), &mut progress)
        .with_context(|| format!("{}", args.mesh.display()))?;
    for note in &d.report.notes {
        eprintln!("note: {note}");
    }
    bar_msg(&bar, "writing");
    let t = Instant::now();
    let mut out = m;
    deform::request::apply(&mut out, &d);
    crate::mesh::write_grid(&out, format, &args.output)?;
    let write = t.elapsed().as_secs_f64();
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    print_summary(&d.report, &args.output)?;
    if let Some(path) = &args.report {
        let r = &d.report;
        let s = r.seconds;
        let rep = Report {
            input: args.mesh.display().to_string(),
            output: args.output.display().to_string(),
            nodes: r.nodes,
            cells: r.cells,
            iterations: r.iterations,
            rotation_iterations: r.rotation_iterations,
            residual: r.residual,
            increments: r.increments,
            seconds: Seconds {
                read,
                setup: s.setup,
                assemble: s.assemble,
                precond: s.precond,
                rotation: s.rotation,
                solve: s.solve,
                quality: s.quality,
                write,
                total: t_all.elapsed().as_secs_f64(),
            },
            quality_before: r.quality_before,
            quality_after: r.quality_after,
            far_field: r.far_field,
            deform: r,
        };
        aeroshape::fsio::write_atomic(path, |w| {
            serde_json::to_writer_pretty(&mut *w, &rep).map_err(std::io::Error::other)?;
            writeln!(w)
        })?;
    }
    Ok(())
}

/// The summary printed on success, as `aeroshape run` prints its own: sizes, solver work,
/// cell quality before and after, inverted cells.
fn print_summary(r: &deform::DeformReport, output: &Path) -> std::io::Result<()> {
    outln!(
        "{} nodes, {} cells; {} iterations ({} for R) in {} increment(s), residual {:.1e}",
        r.nodes,
        r.cells,
        r.iterations,
        r.rotation_iterations,
        r.increments,
        r.residual
    );
    print_tail(
        [&r.quality_before, &r.quality_after],
        Some(&r.far_field),
        r.first_layer.as_ref(),
        output,
    )
}

/// The line of the first layer at the moving wall (`deform::layer`).
pub(crate) fn first_layer_line(l: &deform::layer::FirstLayer) -> String {
    format!(
        "first layer ({} wall nodes): height ratio {:.6} to {:.6}{}, wall-normal edges turned at most {:.3e} rad{}",
        l.nodes,
        l.height_ratio[0],
        l.height_ratio[1],
        l.worst_height_node
            .map_or(String::new(), |v| format!(" (worst node {v})")),
        l.max_turn,
        l.worst_turn_node
            .map_or(String::new(), |v| format!(" (node {v})"))
    )
}

/// The summary's lines after its first, shared with the distributed command: the cell
/// quality before and after, the far field and the first layer (when measured) and the
/// file written.
pub(crate) fn print_tail(
    q: [&mesh::quality::Summary; 2],
    far: Option<&deform::FarField>,
    layer: Option<&deform::layer::FirstLayer>,
    output: &Path,
) -> std::io::Result<()> {
    outln!(
        "quality min {:.4} → {:.4}, mean {:.4} → {:.4}, 1st percentile {:.4} → {:.4}, inverted {} → {}",
        q[0].min,
        q[1].min,
        q[0].mean,
        q[1].mean,
        q[0].p1,
        q[1].p1,
        q[0].n_nonpositive,
        q[1].n_nonpositive
    );
    if let Some(f) = far {
        outln!(
            "far field (≥ {:.3e} from the moving markers, {} nodes): largest displacement {:.3e}{}; moving markers {:.3e}",
            f.distance,
            f.nodes,
            f.max_displacement,
            f.node.map_or(String::new(), |v| format!(" (node {v})")),
            f.wall_max_displacement
        );
    }
    if let Some(l) = layer {
        outln!("{}", first_layer_line(l));
    }
    outln!("wrote {}", output.display());
    Ok(())
}

/// The request of the flags: markers, motion, solver options. Its displacements (which need
/// the grid) are left empty; [`add_displacements`] puts them in.
pub(crate) fn request(args: &DeformArgs) -> deform::Request {
    deform::Request {
        rigid: args.rigid.clone(),
        motion: RigidMotion {
            angle_deg: args.rotate_deg,
            axis_point: args.axis_point,
            axis_dir: args.axis_dir,
            translation: args.translate,
        },
        displacements: Vec::new(),
        slide: args.slide.clone(),
        fixed: args.fixed.clone(),
        solver: args.solver,
        stiffness: args.stiffness,
        adapt_rotation: !args.no_rotation,
        rotation_reach: args.rotation_reach,
        rel_tol: args.tolerance,
        allow_inverted: args.allow_inverted,
    }
}

/// Puts into `request` the per-node displacements on `m`: those of `--displacements`, then
/// a zero displacement for every node of a fixed marker (named by `--fixed` or by nothing)
/// that meets a sliding one and that no line gives
/// ([`aeroshape::precedence::hold_fixed_nodes`]), so that such a node never moves.
pub(crate) fn add_displacements(
    args: &DeformArgs,
    m: &mesh::Mesh,
    request: &mut deform::Request,
) -> anyhow::Result<()> {
    request.displacements = match &args.displacements {
        Some(p) => read_displacements(p, m.n_nodes())?,
        None => Vec::new(),
    };
    aeroshape::precedence::hold_fixed_nodes(m, request);
    Ok(())
}

/// With `--find-planes`: the markers not named that are symmetry planes by their shape
/// (`deform::Request::symmetry_planes`) slide on their planes, each said in a note; then the
/// fixed markers' nodes where they meet them are held again (`add_displacements`).
pub(crate) fn slide_symmetry_planes(
    args: &DeformArgs,
    m: &mesh::Mesh,
    request: &mut deform::Request,
) -> anyhow::Result<()> {
    if !args.find_planes {
        return Ok(());
    }
    let planes = request.symmetry_planes(m);
    if planes.is_empty() {
        return Ok(());
    }
    for (name, dev) in &planes {
        eprintln!(
            "note: marker {name} slides on its plane (not named; a plane touching the moving \
             markers, nodes within {dev:.1e} of it, --find-planes); --fixed {name} holds it"
        );
        request.slide.push(name.clone());
    }
    add_displacements(args, m, request)
}

fn aeroshape_check(out: &Path, inputs: &[&Path]) -> anyhow::Result<()> {
    aeroshape::fsio::ensure_not_input(out, inputs).map_err(anyhow::Error::msg)
}

fn progress_bar() -> Option<indicatif::ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let b = indicatif::ProgressBar::new_spinner();
    b.enable_steady_tick(std::time::Duration::from_millis(120));
    Some(b)
}

fn bar_msg(bar: &Option<indicatif::ProgressBar>, msg: &str) {
    if let Some(b) = bar {
        b.set_message(msg.to_string());
    }
}
