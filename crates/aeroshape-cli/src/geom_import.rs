//! `aeroshape geom import`: an IGES or STEP file into a geometric database (RON), with an
//! optional JSON report of the conversion and sewing.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use geom_db::import::{ImportOptions, LengthUnit, import_bytes};

use aeroshape::fsio::{ensure_not_input, write_atomic};

/// Arguments of `aeroshape geom import`.
#[derive(Debug, Args)]
pub struct ImportArgs {
    /// The CAD file: IGES 5.3 (fixed 80-column ASCII form) or STEP (ISO 10303-21: AP203,
    /// AP214, AP242), told apart by the content.
    pub iges: PathBuf,
    /// The geometric database to write (.ron).
    #[arg(short = 'o', long = "output", value_name = "GEOM.ron")]
    pub output: PathBuf,
    /// Approximation tolerance in model units for entities that are not polynomial (arcs,
    /// conics, surfaces of revolution, rational B-splines) [default: 1e-7 × model size].
    #[arg(long, value_name = "T")]
    pub tolerance: Option<f64>,
    /// Sewing tolerance in model units: boundary curves and corners closer than this are
    /// merged [default: 1e-6 × model size, at least 10 × the approximation tolerance].
    #[arg(long, value_name = "T")]
    pub sew_tolerance: Option<f64>,
    /// Reverse the inward normal of every surface component (the automatic choice points
    /// normals into the volume enclosed by the largest shell and away from the others).
    #[arg(long)]
    pub flip: bool,
    /// Convert lengths to this unit (m, mm, cm, in or ft) [default: the file's unit].
    #[arg(long, value_name = "UNIT", value_parser = parse_unit)]
    pub units: Option<LengthUnit>,
    /// The unit the file's numbers are in (m, mm, cm, in or ft), overriding the unit its
    /// header declares (a header saying inches over numbers in metres) [default: the
    /// file's].
    #[arg(long, value_name = "UNIT", value_parser = parse_unit)]
    pub file_units: Option<LengthUnit>,
    /// Roles given by hand (RON map face entity → role, e.g. `{"D31": "wing", "#17":
    /// "fuselage"}`), overriding the recognition by shape.
    #[arg(long, value_name = "FILE.ron")]
    pub roles: Option<PathBuf>,
    /// Do not assign control nodes (Eq. 9) at the end of the import.
    #[arg(long)]
    pub no_control_nodes: bool,
    /// Write a JSON report: per-entity conversion error, faces, shells, sewn, free and
    /// non-manifold edges.
    #[arg(long, value_name = "REPORT.json")]
    pub report: Option<PathBuf>,
}

/// Runs `aeroshape geom import`.
pub fn run(a: &ImportArgs) -> anyhow::Result<()> {
    for (name, t) in [
        ("--tolerance", a.tolerance),
        ("--sew-tolerance", a.sew_tolerance),
    ] {
        if let Some(t) = t
            && !(t.is_finite() && t > 0.0)
        {
            anyhow::bail!("{name} must be a positive number, got {t}");
        }
    }
    let inputs = [a.iges.as_path()];
    ensure_not_input(&a.output, &inputs).map_err(anyhow::Error::msg)?;
    if let Some(r) = &a.report {
        ensure_not_input(r, &inputs).map_err(anyhow::Error::msg)?;
        if r == &a.output {
            anyhow::bail!("--report and -o name the same file {}", r.display());
        }
    }
    let shown = a.iges.display().to_string();
    let bytes = std::fs::read(&a.iges).with_context(|| format!("cannot read {shown}"))?;
    let roles = match &a.roles {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            ron::from_str(&text).map_err(|e| anyhow::anyhow!("{}:{e}", path.display()))?
        }
        None => Default::default(),
    };
    let opts = ImportOptions {
        roles,
        control_nodes: !a.no_control_nodes,
        tolerance: a.tolerance,
        sew_tolerance: a.sew_tolerance,
        flip: a.flip,
        units: a.units.clone(),
        file_units: a.file_units.clone(),
        ..ImportOptions::default()
    };
    let (db, report) = import_bytes(&bytes, &shown, &opts)?;
    write_atomic(&a.output, |w| db.write_ron(w))?;
    if let Some(r) = &a.report {
        write_atomic(r, |w| {
            serde_json::to_writer_pretty(&mut *w, &report).map_err(std::io::Error::other)?;
            writeln!(w)
        })?;
    }
    outln!(
        "{}: {} surface components, {} curve components ({} shared, {} free, {} non-manifold), {} corners, {} control nodes",
        a.output.display(),
        db.surface_components.len(),
        db.curve_components.len(),
        report.sewn_edges,
        report.free_edges.len(),
        report.non_manifold_edges.len(),
        db.corners.len(),
        db.control_nodes.len()
    );
    let re = report
        .entities
        .iter()
        .filter(|e| e.method == "reapproximated")
        .count();
    let re = if re > 0 {
        format!(" ({re} re-approximated: ill-conditioned exact conversion)")
    } else {
        String::new()
    };
    outln!(
        "  conversion: {} entities{re}, max error {:.3e} (tolerance {:.3e}); max sewing gap {:.3e} (tolerance {:.3e})",
        report.entities.len(),
        report.max_error,
        report.tolerance,
        report.max_sew_gap,
        report.sew_tolerance
    );
    for s in &report.shells {
        outln!(
            "  shell: {} faces, {}, enclosed volume {:.6e}",
            s.faces,
            if s.closed { "closed" } else { "open" },
            s.volume
        );
    }
    let mut roles: std::collections::BTreeMap<&str, usize> = Default::default();
    for f in &report.faces {
        *roles.entry(f.role.as_str()).or_default() += 1;
    }
    let roles: Vec<String> = roles.iter().map(|(r, n)| format!("{n} {r}")).collect();
    outln!("  faces: {}", roles.join(", "));
    let rebuilt: Vec<f64> = report
        .junctions
        .iter()
        .filter_map(|j| j.max_distance)
        .collect();
    let rebuilt = if rebuilt.is_empty() {
        String::new()
    } else {
        format!(
            ", {} rebuilt on their supports (max distance {:.3e})",
            rebuilt.len(),
            rebuilt.iter().copied().fold(0.0, f64::max)
        )
    };
    outln!(
        "  junctions: {} curves with two defining surfaces (re-intersected on model updates){rebuilt}",
        report.junctions.len(),
    );
    for w in &report.warnings {
        outln!("  warning: {w}");
    }
    Ok(())
}

fn parse_unit(s: &str) -> Result<LengthUnit, String> {
    LengthUnit::named(s).ok_or_else(|| format!("unknown unit {s:?} (m, mm, cm, in or ft)"))
}
