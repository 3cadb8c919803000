//! `aeroshape case init`: a ready case from the user's own CAD and grid
//! (`aeroshape::init`): markers by shape, the wall tied to the geometry, the default design
//! space with bounds checked by the study.

use std::io::BufReader;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use geom_db::GeomDb;

use aeroshape::init::{InitOptions, Tolerance, init_case};

/// `aeroshape case` subcommands.
#[derive(Debug, Subcommand)]
pub enum CaseCmd {
    /// Make a case from a CAD file (.igs, .iges or .ron) and a volume grid (.su2 or .msh):
    /// the far field fixed, planes sliding, markers on the geometry wall (by shape, not by
    /// name); writes DIR/case.ron, DIR/geometry.ron and DIR/grid.msh (parametric wall
    /// nodes) and prints the design variables with their checked bounds.
    Init(InitArgs),
}

/// Arguments of `case init`.
#[derive(Debug, Args)]
pub struct InitArgs {
    /// The CAD: IGES (.igs, .iges: imported) or a geometric database (.ron).
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
}

/// Runs a `case` subcommand.
pub fn run(cmd: CaseCmd) -> anyhow::Result<()> {
    match cmd {
        CaseCmd::Init(a) => init(&a),
    }
}

/// The geometry of `cad` and the tolerance figures its import measured.
fn load_cad(cad: &Path) -> anyhow::Result<(GeomDb, Vec<Tolerance>)> {
    let ext = cad
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("ron") => Ok((super::geom::load(cad)?, Vec::new())),
        Some("igs" | "iges") => {
            let shown = cad.display().to_string();
            let file = std::fs::File::open(cad).with_context(|| format!("cannot open {shown}"))?;
            let iges = iges::read(BufReader::new(file), &shown)?;
            let (db, report) = geom_db::import::import(&iges, &Default::default())?;
            let tolerances = vec![
                Tolerance {
                    source: format!("{shown}: conversion tolerance of the import"),
                    value: report.tolerance,
                },
                Tolerance {
                    source: format!("{shown}: largest sewing gap measured at import, × 2"),
                    value: 2.0 * report.max_sew_gap,
                },
            ];
            Ok((db, tolerances))
        }
        _ => bail!(
            "{}: unknown CAD format (use .igs, .iges or .ron; a STEP file: import it with another tool to IGES for now)",
            cad.display()
        ),
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
    let (db, cad) = load_cad(&a.cad)?;
    let grid = mesh::io::read_path(&a.grid)?;
    if grid.cells.is_empty() {
        bail!("{}: not a volume grid (no cells)", a.grid.display());
    }
    std::fs::create_dir_all(&a.output)
        .with_context(|| format!("cannot create {}", a.output.display()))?;
    let opts = InitOptions {
        rel_tol: a.rel_tol,
        ..InitOptions::default()
    };
    let r = init_case(&db, &grid, &cad, &a.output, &opts)
        .with_context(|| format!("{} with {}", a.cad.display(), a.grid.display()))?;
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
    outln!(
        "design variables ({}), each alone at either bound keeps every cell valid:",
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
    for n in &r.notes {
        outln!("note: {n}");
    }
    for f in ["case.ron", "geometry.ron", "grid.msh"] {
        outln!("wrote {}", a.output.join(f).display());
    }
    Ok(())
}
