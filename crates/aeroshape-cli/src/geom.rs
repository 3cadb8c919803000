//! `aeroshape geom`: inspect and check geometric databases stored as RON (`geom-db`).

use std::io::BufReader;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::{Args, Subcommand};
use geom_db::{CheckOptions, GeomDb};

/// Geometric database commands.
#[derive(Debug, Subcommand)]
pub enum GeomCmd {
    /// Print counts, bounding box, tolerances and topology of a geometric database
    /// (validating it first; an invalid file exits 1 naming the entity at fault).
    Info(InfoArgs),
    /// Validate a geometric database and check its topology (closed/open, free and
    /// non-manifold edges, loop orientation) and C0 gaps between components; exit 1 when a
    /// problem is found.
    Check(CheckArgs),
    /// Convert an IGES file into a geometric database: curves and surfaces to power-basis
    /// arcs and patches (exact or within a tolerance), trimmed faces to surface components,
    /// coincident boundary curves sewn into shared curve components.
    Import(super::geom_import::ImportArgs),
}

/// Arguments of `aeroshape geom info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The geometric database (.ron).
    pub geom: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `aeroshape geom check`.
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// The geometric database (.ron).
    pub geom: PathBuf,
    /// Print the report as one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Largest acceptable gap, as a fraction of the bounding-box diagonal.
    #[arg(long, default_value_t = 1e-6, value_name = "REL")]
    pub gap_rel: f64,
}

/// Runs a `geom` subcommand.
pub fn run(cmd: GeomCmd) -> anyhow::Result<()> {
    match cmd {
        GeomCmd::Info(a) => info(&a),
        GeomCmd::Check(a) => check(&a),
        GeomCmd::Import(a) => super::geom_import::run(&a),
    }
}

/// Loads and validates a database; errors name the file and the entity.
pub fn load(path: &Path) -> anyhow::Result<GeomDb> {
    let shown = path.display().to_string();
    let file = std::fs::File::open(path).with_context(|| format!("cannot open {shown}"))?;
    Ok(GeomDb::read_ron(BufReader::new(file), &shown)?)
}

fn info(a: &InfoArgs) -> anyhow::Result<()> {
    let db = load(&a.geom)?;
    let report = db.check(&CheckOptions {
        samples: 2,
        ..CheckOptions::default()
    });
    let tol = db.tolerances();
    if a.json {
        let comps: Vec<serde_json::Value> = db
            .surface_components
            .iter()
            .enumerate()
            .map(|(i, sc)| {
                serde_json::json!({
                    "id": i,
                    "name": sc.name,
                    "surface": sc.surface.0,
                    "loops": sc.loops.len(),
                    "inward": format!("{:?}", sc.inward),
                })
            })
            .collect();
        let v = serde_json::json!({
            "file": a.geom.display().to_string(),
            "name": db.name,
            "format_version": db.format_version,
            "units": db.units,
            "counts": report.counts,
            "bbox": report.bbox,
            "reference_length": report.reference_length,
            "tolerances": tol,
            "topology": {
                "closed": report.topology.closed,
                "free_edges": report.topology.free_edges.iter().map(|c| c.0).collect::<Vec<_>>(),
                "non_manifold": report.topology.non_manifold.iter().map(|c| c.0).collect::<Vec<_>>(),
            },
            "surface_components": comps,
        });
        outln!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    let c = &report.counts;
    outln!("{}: {}", a.geom.display(), db.name);
    outln!(
        "  format version {}, units {}",
        db.format_version,
        db.units.as_deref().unwrap_or("(unspecified)")
    );
    outln!("  corners             {}", c.corners);
    outln!(
        "  support curves      {} ({} arcs, degree ≤ {})",
        c.curves,
        c.arcs,
        c.max_curve_degree
    );
    outln!(
        "  support surfaces    {} ({} patches, degree ≤ {})",
        c.surfaces,
        c.patches,
        c.max_surface_degree
    );
    outln!("  curve components    {}", c.curve_components);
    outln!("  surface components  {}", c.surface_components);
    for (i, sc) in db.surface_components.iter().enumerate() {
        outln!(
            "    {i}: {:<16} surface {}, {} loop(s), inward {:?}",
            sc.name,
            sc.surface.0,
            sc.loops.len(),
            sc.inward
        );
    }
    outln!("  control nodes       {}", c.control_nodes);
    print_bbox(&report)?;
    outln!(
        "  tolerances          Newton {:.3e}, same point {:.3e}",
        tol.newton.abs,
        tol.same_point.abs
    );
    print_topology(&report)?;
    Ok(())
}

fn print_bbox(r: &geom_db::CheckReport) -> anyhow::Result<()> {
    let [lo, hi] = r.bbox;
    outln!(
        "  bounding box        [{:.6}, {:.6}, {:.6}] – [{:.6}, {:.6}, {:.6}], diagonal {:.6}",
        lo[0],
        lo[1],
        lo[2],
        hi[0],
        hi[1],
        hi[2],
        r.reference_length
    );
    Ok(())
}

fn print_topology(r: &geom_db::CheckReport) -> anyhow::Result<()> {
    let t = &r.topology;
    let list = |v: &[geom_db::CurveCompId]| {
        v.iter()
            .map(|c| c.0.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    outln!(
        "  topology            {}",
        if t.closed { "closed" } else { "open" }
    );
    if !t.free_edges.is_empty() {
        outln!("    free edges (curve components): {}", list(&t.free_edges));
    }
    if !t.non_manifold.is_empty() {
        outln!(
            "    non-manifold edges (curve components): {}",
            list(&t.non_manifold)
        );
    }
    if !t.unused.is_empty() {
        outln!("    unused curve components: {}", list(&t.unused));
    }
    Ok(())
}

fn check(a: &CheckArgs) -> anyhow::Result<()> {
    if !(a.gap_rel.is_finite() && a.gap_rel > 0.0) {
        anyhow::bail!("--gap-rel must be a positive number, got {}", a.gap_rel);
    }
    let db = load(&a.geom)?;
    let mut report = db.check(&CheckOptions {
        gap_rel: a.gap_rel,
        ..CheckOptions::default()
    });
    // junction accuracy: each support curve with two defining surfaces sampled (≥ 200 per
    // arc) against both, foot of the normal (Eq. 11) — the measure of the model update
    let inter = db
        .junctions_accuracy(&geom_db::check::AccuracyOptions::default())
        .with_context(|| format!("{}: junction accuracy", a.geom.display()))?;
    for r in &inter {
        if r.max() > report.gap_tolerance || r.max().is_nan() {
            report.problems.push(format!(
                "{} is {:.3e} away from its defining surfaces {} and {} (tolerance {:.3e})",
                r.label,
                r.max(),
                r.surfaces[0],
                r.surfaces[1],
                report.gap_tolerance
            ));
        }
    }
    if a.json {
        let mut v = serde_json::to_value(&report)?;
        v["file"] = a.geom.display().to_string().into();
        v["ok"] = report.is_ok().into();
        v["intersections"] = serde_json::to_value(&inter)?;
        outln!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        let c = &report.counts;
        outln!("{}: {}", a.geom.display(), db.name);
        outln!(
            "  {} corners, {} curves ({} arcs), {} surfaces ({} patches), {} curve components, {} surface components, {} control nodes",
            c.corners,
            c.curves,
            c.arcs,
            c.surfaces,
            c.patches,
            c.curve_components,
            c.surface_components,
            c.control_nodes
        );
        print_bbox(&report)?;
        print_topology(&report)?;
        let worst = report.gaps.iter().max_by(|x, y| x.max.total_cmp(&y.max));
        match worst {
            Some(g) => outln!(
                "  max gap             {:.3e} ({}), tolerance {:.3e}",
                g.max,
                g.what,
                report.gap_tolerance
            ),
            None => outln!("  max gap             none measured"),
        }
        for r in &inter {
            let d = &r.distance.surfaces;
            outln!(
                "  intersection        {}: max {:.3e} from {} (rms {:.1e}, t = {:.4}), {:.3e} from {} (rms {:.1e}, t = {:.4}) ({} samples)",
                r.label,
                d[0].max,
                r.surfaces[0],
                d[0].rms,
                d[0].at_t,
                d[1].max,
                r.surfaces[1],
                d[1].rms,
                d[1].at_t,
                r.distance.samples
            );
        }
        for p in &report.problems {
            outln!("  problem: {p}");
        }
        if report.is_ok() {
            outln!("  valid");
        }
    }
    if let Some(first) = report.problems.first() {
        anyhow::bail!(
            "{}: {first}{}",
            a.geom.display(),
            if report.problems.len() > 1 {
                format!(" (and {} more problems)", report.problems.len() - 1)
            } else {
                String::new()
            }
        );
    }
    Ok(())
}
