//! `cargo xtask chain`: the end-to-end default case. For now it loads the default geometry
//! (`fixtures/geom/wing_body.ron`), validates and checks it and prints a summary; later
//! issues grow it into the whole chain of the paper's Figure 5.

use std::path::Path;

use geom_db::{CheckOptions, GeomDb};

/// Runs the chain on the default case.
pub fn run(root: &Path) -> Result<(), String> {
    let path = root.join("fixtures").join("geom").join("wing_body.ron");
    let shown = path.display().to_string();
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{shown}: {e}"))?;
    let db = GeomDb::from_ron_str(&text, &shown).map_err(|e| e.to_string())?;
    let report = db.check(&CheckOptions::default());
    let c = &report.counts;
    println!("geometry: {} ({shown})", db.name);
    println!(
        "  {} corners, {} support curves ({} arcs), {} support surfaces ({} patches), {} curve components, {} surface components, {} control nodes",
        c.corners,
        c.curves,
        c.arcs,
        c.surfaces,
        c.patches,
        c.curve_components,
        c.surface_components,
        c.control_nodes
    );
    println!(
        "  bounding box [{:.4}, {:.4}, {:.4}] – [{:.4}, {:.4}, {:.4}], reference length {:.4}",
        report.bbox[0][0],
        report.bbox[0][1],
        report.bbox[0][2],
        report.bbox[1][0],
        report.bbox[1][1],
        report.bbox[1][2],
        report.reference_length
    );
    println!(
        "  topology: {}, {} free edges, {} non-manifold; max gap {:.3e} (tolerance {:.3e})",
        if report.topology.closed {
            "closed"
        } else {
            "open"
        },
        report.topology.free_edges.len(),
        report.topology.non_manifold.len(),
        report.max_gap,
        report.gap_tolerance
    );
    if report.is_ok() {
        println!("  check: ok");
        Ok(())
    } else {
        Err(format!("{shown}: {}", report.problems.join("; ")))
    }
}
