//! `aeroshape run CASE.ron [--dv DV.ron] -o OUTDIR`: the whole chain of the paper's Figure 5
//! for a case (see [`aeroshape::study`]), with its output files.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use geom_db::{GeomDb, SurfaceId};
use mesh::io::Format;
use mesh::msh::Encoding;
use serde::Serialize;

use aeroshape::case::{Case, load_design_values};
use aeroshape::fsio::{ensure_not_input, write_atomic};
use aeroshape::study::{Report, SetupReport, Study};

/// Arguments of `aeroshape run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The case file (RON; docs/formats/case-ron.md).
    pub case: PathBuf,
    /// Design vector: a RON map {"name": value, …}; variables not named keep their initial
    /// value. Without it, the initial design vector (the baseline shape and grid).
    #[arg(long, value_name = "DV.ron")]
    pub dv: Option<PathBuf>,
    /// Output folder (created if missing): deformed.su2, deformed.msh, deformed.vtu,
    /// baseline.su2, geometry.ron, report.json and PNG pictures.
    #[arg(short, long, value_name = "OUTDIR")]
    pub output: PathBuf,
    /// Run even if linear constraints of the parametrisation are violated.
    #[arg(long)]
    pub allow_infeasible: bool,
    /// Do not draw the PNG pictures.
    #[arg(long)]
    pub no_pictures: bool,
    /// How far R reaches (the case's `deform.rotation_reach`, overridden): blended to the
    /// identity with the distance d from the wall (along grid edges), fully at d = L (grid
    /// units; 0: no R at all).
    #[arg(long, value_name = "L", value_parser = super::deform::parse_reach)]
    pub rotation_reach: Option<f64>,
}

/// The file `report.json`.
#[derive(Serialize)]
struct RunReport<'a> {
    case: String,
    design_vector: Option<String>,
    setup: &'a SetupReport,
    evaluation: &'a Report,
    outputs: Vec<String>,
}

/// Components whose name starts with "wing" (the wing and its tip cap): their support
/// surfaces are drawn in the planform and section pictures.
pub(crate) fn wing_surfaces(db: &GeomDb) -> Vec<SurfaceId> {
    let mut v: Vec<SurfaceId> = db
        .surface_components
        .iter()
        .filter(|c| c.name.to_ascii_lowercase().starts_with("wing"))
        .map(|c| c.surface)
        .collect();
    v.sort_unstable_by_key(|s| s.index());
    v.dedup();
    v
}

/// Runs `aeroshape run`.
pub fn run(a: RunArgs) -> anyhow::Result<()> {
    #[cfg(feature = "mpi")]
    if crate::deform_mpi::launched() {
        return crate::run_mpi::run(a);
    }
    let t0 = Instant::now();
    let case = load_case(&a)?;
    std::fs::create_dir_all(&a.output)
        .with_context(|| format!("{}: cannot create the output folder", a.output.display()))?;
    let out = |name: &str| a.output.join(name);
    eprintln!("[run] building the study from {}", a.case.display());
    let study = Study::new(case, &a.case)?;
    let s = study.setup_report();
    eprintln!(
        "[run]   grid {} nodes, {} cells, {} wall nodes (classified, max distance {:.2e}); set-up {:.2} s",
        s.nodes,
        s.cells,
        s.wall_nodes,
        s.classify_max_distance,
        s.read + s.param + s.model + s.classify
    );
    let x = design_vector(&study, a.dv.as_deref())?;
    super::param::check_constraints(
        &study.case().parametrisation,
        &x,
        &a.case,
        a.allow_infeasible,
        "run",
    )?;
    let ev = match study.evaluate_with_progress(&x, &mut |p| eprintln!("[run] {p}")) {
        Ok(ev) => ev,
        Err(e @ aeroshape::study::StudyError::Deform(deform::Error::Inverted { .. })) => {
            return Err(match write_failed(&study, &x, &a.output) {
                Ok(f) => anyhow::Error::new(e).context(format!(
                    "{}: the design inverts cells; wrote {f}",
                    a.case.display()
                )),
                Err(w) => anyhow::Error::new(e).context(format!("(and {w:#})")),
            });
        }
        Err(e) => return Err(e.into()),
    };
    let r = &ev.report;
    let mut written = write_outputs(
        &a.output,
        r.seconds,
        (study.baseline(), study.geometry(), study.baseline_quality()),
        (&ev.grid, &ev.geometry, &ev.cell_quality),
        !a.no_pictures,
    )?;
    let report_path = out("report.json");
    written.push(report_path.display().to_string());
    let rr = RunReport {
        case: a.case.display().to_string(),
        design_vector: a.dv.as_ref().map(|p| p.display().to_string()),
        setup: study.setup_report(),
        evaluation: r,
        outputs: written.clone(),
    };
    write_atomic(&report_path, |w| {
        serde_json::to_writer_pretty(&mut *w, &rr).map_err(std::io::Error::other)?;
        writeln!(w)
    })?;
    outln!(
        "param {:.3} s ({} control nodes moved, max {:.3e}); model update {:.3} s (control-point residual {:.2e}, {:.2e} relative); surface grid {:.3} s ({} nodes moved); deform {:.3} s ({} iterations, residual {:.1e})",
        r.param.seconds,
        r.param.nodes_moved,
        r.param.max_move,
        r.model.seconds,
        r.model.junction_residual,
        r.model.junction_residual_rel,
        r.surface.seconds,
        r.surface.moved_nodes,
        r.deform.seconds,
        r.deform.iterations(),
        r.deform.report.as_ref().map_or(0.0, |d| d.residual)
    );
    outln!("{}", r.model.junction_summary());
    outln!(
        "quality min {:.4} → {:.4}, mean {:.4} → {:.4}, 1st percentile {:.4} → {:.4}, inverted {} → {}",
        r.quality_before.min,
        r.quality_after.min,
        r.quality_before.mean,
        r.quality_after.mean,
        r.quality_before.p1,
        r.quality_after.p1,
        r.quality_before.inverted,
        r.quality_after.inverted
    );
    if let Some(f) = r.deform.report.as_ref().map(|d| d.far_field) {
        outln!(
            "far field (≥ {:.3e} from the wall, {} nodes): largest displacement {:.3e}; wall {:.3e}",
            f.distance,
            f.nodes,
            f.max_displacement,
            f.wall_max_displacement
        );
    }
    if let Some(l) = r
        .deform
        .report
        .as_ref()
        .and_then(|d| d.first_layer.as_ref())
    {
        outln!("{}", crate::deform::first_layer_line(l));
    }
    for w in &written {
        outln!("wrote {w}");
    }
    eprintln!("[run] done in {:.2} s", t0.elapsed().as_secs_f64());
    Ok(())
}

/// The PNG pictures: quality histogram before/after, wing planform and key sections
/// before/after (the wing: components whose name starts with "wing"; sections at 20 %, 50 %
/// and 98 % of its span).
/// The case of `a` with the command line's overrides, once no file `run` writes into
/// `a.output` would overwrite one of its inputs (the case, its geometry and grid, the design
/// vector).
pub(crate) fn load_case(a: &RunArgs) -> anyhow::Result<Case> {
    let mut case = Case::load(&a.case)?;
    if let Some(l) = a.rotation_reach {
        case.deform.rotation_reach = Some(l);
    }
    let mut inputs: Vec<PathBuf> = vec![a.case.clone(), case.geometry_path(&a.case)];
    inputs.extend(case.grid_path(&a.case));
    inputs.extend(a.dv.clone());
    let input_refs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    for n in [
        "deformed.su2",
        "deformed.msh",
        "deformed.vtu",
        "baseline.su2",
        "geometry.ron",
        "report.json",
        "planform.png",
        "sections.png",
        "quality.png",
        "failed.vtu",
        "failed.json",
    ] {
        ensure_not_input(&a.output.join(n), &input_refs).map_err(anyhow::Error::msg)?;
    }
    Ok(case)
}

/// After an evaluation refused for inverted cells: the grid of the guard's last attempt as
/// `dir/failed.vtu` (its quality field shows the cells) and `dir/failed.json` (the design
/// vector, the inverted cells with their kind, quality, place and the variables that moved
/// them, `Study::failed_grid`), each written atomically; the worst cells are printed.
/// Returns what was written, in words.
fn write_failed(study: &Study, x: &[f64], dir: &Path) -> anyhow::Result<String> {
    eprintln!("[run] the design inverts cells: the failed grid and what moved its cells");
    let f = study.failed_grid(x, 20)?;
    let (vtu, json) = (dir.join("failed.vtu"), dir.join("failed.json"));
    write_atomic(&vtu, |w| {
        mesh::io::write(&f.grid, Format::from_path(&vtu).expect("vtu"), w)
    })?;
    #[derive(Serialize)]
    struct Failed<'a> {
        design: Vec<(&'a str, f64)>,
        inverted: usize,
        cells: &'a [aeroshape::study::failure::InvertedCell],
    }
    let names = study.registry().names();
    let rec = Failed {
        design: names.iter().copied().zip(x.iter().copied()).collect(),
        inverted: f.count,
        cells: &f.cells,
    };
    write_atomic(&json, |w| {
        serde_json::to_writer_pretty(&mut *w, &rec).map_err(std::io::Error::other)?;
        writeln!(w)
    })?;
    for c in f.cells.iter().take(5) {
        let on_wall = c.nodes.iter().filter(|n| n.1).count();
        eprintln!(
            "[run]   cell {} ({}, q {:.3e}, was {:.3e}) at ({:.4}, {:.4}, {:.4}), {} of {} nodes on the wall; moved by {}",
            c.cell,
            c.kind,
            c.quality[0],
            c.quality[1],
            c.centroid[0],
            c.centroid[1],
            c.centroid[2],
            on_wall,
            c.nodes.len(),
            c.moved_by
                .iter()
                .take(3)
                .map(|(n, s)| format!("{n} ({s:.2e})"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(format!(
        "{} and {} ({} inverted cells)",
        vtu.display(),
        json.display(),
        f.count
    ))
}

/// Writes a run's files into `dir`, each to a temporary name then renamed: the deformed grid
/// (`.su2`, `.msh`, `.vtu`), the baseline grid, the updated geometry, and unless
/// `pictures_too` is false the pictures. Returns the paths written, for `report.json`.
pub(crate) fn write_outputs(
    dir: &Path,
    seconds: f64,
    (baseline, geometry0, quality0): (&mesh::Mesh, &GeomDb, &[f64]),
    (grid, geometry, quality): (&mesh::Mesh, &GeomDb, &[f64]),
    pictures_too: bool,
) -> anyhow::Result<Vec<String>> {
    eprintln!(
        "[run] writing {} (evaluation {seconds:.2} s)",
        dir.display()
    );
    let mut written = Vec::new();
    let mut put = |name: &str, f: &dyn Fn(&mut dyn std::io::Write) -> std::io::Result<()>| {
        let p = dir.join(name);
        write_atomic(&p, |w| f(w))?;
        written.push(p.display().to_string());
        anyhow::Ok(())
    };
    put("deformed.su2", &|w| mesh::io::write(grid, Format::Su2, w))?;
    put("deformed.msh", &|w| {
        mesh::io::write(grid, Format::Msh(Encoding::Ascii), w)
    })?;
    put("deformed.vtu", &|w| {
        mesh::io::write(grid, Format::from_path(Path::new("a.vtu")).expect("vtu"), w)
    })?;
    put("baseline.su2", &|w| {
        mesh::io::write(baseline, Format::Su2, w)
    })?;
    put("geometry.ron", &|w| geometry.write_ron(w))?;
    if pictures_too {
        pictures(
            (geometry0, quality0),
            (geometry, quality),
            dir,
            &mut written,
        )?;
    }
    Ok(written)
}

pub(crate) fn pictures(
    (baseline, quality_before): (&GeomDb, &[f64]),
    (geometry, quality_after): (&GeomDb, &[f64]),
    dir: &Path,
    written: &mut Vec<String>,
) -> anyhow::Result<()> {
    let out = |name: &str| dir.join(name);
    let wings = wing_surfaces(baseline);
    crate::pictures::quality_histogram(
        &out("quality.png"),
        quality_before,
        quality_after,
        "grid quality",
    )
    .map_err(anyhow::Error::msg)?;
    written.push(out("quality.png").display().to_string());
    if !wings.is_empty() {
        crate::pictures::wing_planform(&out("planform.png"), baseline, geometry, &wings)
            .map_err(anyhow::Error::msg)?;
        written.push(out("planform.png").display().to_string());
        let (lo, hi) = span_range(baseline, &wings);
        let stations = [lo + 0.2 * (hi - lo), 0.5 * (lo + hi), hi - 0.02 * (hi - lo)];
        crate::pictures::wing_sections(&out("sections.png"), baseline, geometry, &wings, &stations)
            .map_err(anyhow::Error::msg)?;
        written.push(out("sections.png").display().to_string());
    }
    Ok(())
}

fn span_range(db: &GeomDb, wings: &[SurfaceId]) -> (f64, f64) {
    use geom_db::eval::ParamSurface;
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for &id in wings {
        let s = db.surface(id);
        let ([u0, u1], [v0, v1]) = s.domain();
        for i in 0..=8 {
            for j in 0..=8 {
                let p = s.point(
                    u0 + (u1 - u0) * i as f64 / 8.0,
                    v0 + (v1 - v0) * j as f64 / 8.0,
                );
                lo = lo.min(p.y);
                hi = hi.max(p.y);
            }
        }
    }
    (lo, hi)
}

/// The design vector of `--dv FILE` (its values by name), or the case's initial one.
pub(crate) fn design_vector(study: &Study, dv: Option<&Path>) -> anyhow::Result<Vec<f64>> {
    match dv {
        Some(p) => {
            let values = load_design_values(p)?;
            study
                .vector_from_values(&values)
                .with_context(|| p.display().to_string())
        }
        None => Ok(study.initial()),
    }
}
