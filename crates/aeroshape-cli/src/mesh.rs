//! `aeroshape mesh info|convert`: inspect a grid (counts, markers, quality) and convert
//! between SU2, Gmsh MSH 4.1 and VTK XML by file extension.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use mesh::io::Format;
use mesh::msh::Encoding;
use mesh::vtu::VtuEncoding;
use mesh::{ALL_KINDS, Mesh};
use serde::Serialize;

/// Grid inspection and conversion.
#[derive(Debug, Subcommand)]
pub enum MeshCmd {
    /// Print node and element counts per type, markers with their element counts, node
    /// classification and the quality summary (signed mean ratio, min dihedral angle).
    Info(InfoArgs),
    /// Convert a grid between .su2, .msh (Gmsh 4.1) and .vtu, chosen by the extensions.
    /// Markers are kept; .msh to .msh also keeps entities and parametric coordinates.
    Convert(ConvertArgs),
}

/// Arguments of `mesh info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The grid file (.su2, .msh or .vtu).
    pub mesh: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `mesh convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Input grid (.su2, .msh or .vtu).
    pub input: PathBuf,
    /// Output grid (.su2, .msh or .vtu); never the input.
    pub output: PathBuf,
    /// Write .msh output in binary (default ASCII).
    #[arg(long)]
    pub binary: bool,
    /// Write .vtu output as inline base64 (default raw appended binary).
    #[arg(long)]
    pub base64: bool,
}

/// Runs a `mesh` subcommand.
pub fn run(cmd: MeshCmd) -> anyhow::Result<()> {
    match cmd {
        MeshCmd::Info(a) => info(&a),
        MeshCmd::Convert(a) => convert(&a),
    }
}

#[derive(Serialize)]
struct MarkerInfo {
    name: String,
    elements: usize,
    kinds: BTreeMap<&'static str, usize>,
}

#[derive(Serialize)]
struct Info {
    file: String,
    dim: u8,
    nodes: usize,
    cells: usize,
    cell_kinds: BTreeMap<&'static str, usize>,
    markers: Vec<MarkerInfo>,
    classified_nodes: Option<[usize; 4]>,
    parametric: bool,
    quality: mesh::quality::Summary,
    /// The summary per cell kind (kinds present).
    quality_by_kind: BTreeMap<&'static str, mesh::quality::Summary>,
    /// The lowest-quality cells (up to 5), worst first.
    worst: Vec<mesh::quality::CellQuality>,
    min_angle_deg: Option<f64>,
    warnings: Vec<String>,
}

fn kinds(set: &mesh::Elements) -> BTreeMap<&'static str, usize> {
    ALL_KINDS
        .iter()
        .filter(|k| set.count(**k) > 0)
        .map(|k| (k.name(), set.count(*k)))
        .collect()
}

fn gather(path: &Path, m: &Mesh) -> Info {
    let q = mesh::quality::cell_quality(m);
    let angles = mesh::quality::cell_min_angle(m);
    let min_angle = angles
        .iter()
        .copied()
        .filter(|a| !a.is_nan())
        .fold(None, |acc: Option<f64>, a| {
            Some(acc.map_or(a, |b| b.min(a)))
        });
    Info {
        file: path.display().to_string(),
        dim: m.dim,
        nodes: m.n_nodes(),
        cells: m.cells.len(),
        cell_kinds: kinds(&m.cells),
        markers: m
            .markers
            .iter()
            .map(|k| MarkerInfo {
                name: k.name.clone(),
                elements: k.elements.len(),
                kinds: kinds(&k.elements),
            })
            .collect(),
        classified_nodes: m.classes.as_ref().map(|c| {
            let mut n = [0; 4];
            for x in c {
                n[usize::from(x.dim.min(3))] += 1;
            }
            n
        }),
        parametric: m.parametric,
        quality: mesh::quality::summary(&q),
        quality_by_kind: mesh::quality::summary_by_kind(&m.cells, &q)
            .into_iter()
            .map(|(k, s)| (k.name(), s))
            .collect(),
        worst: mesh::quality::worst_cells(&m.cells, &q, 5),
        min_angle_deg: min_angle,
        warnings: m.warnings.clone(),
    }
}

fn join(k: &BTreeMap<&'static str, usize>) -> String {
    k.iter()
        .map(|(n, c)| format!("{n} {c}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn info(a: &InfoArgs) -> anyhow::Result<()> {
    let m = mesh::io::read_path(&a.mesh)?;
    let i = gather(&a.mesh, &m);
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&i)?);
        return Ok(());
    }
    outln!("grid: {} ({}-D)", i.file, i.dim);
    outln!("nodes: {}", i.nodes);
    outln!("cells: {} ({})", i.cells, join(&i.cell_kinds));
    for (k, n) in &i.cell_kinds {
        outln!("  {k}: {n}");
    }
    outln!("markers: {}", i.markers.len());
    for mk in &i.markers {
        outln!("  {}: {} ({})", mk.name, mk.elements, join(&mk.kinds));
    }
    match i.classified_nodes {
        Some(c) => outln!(
            "classification: {} on corners, {} on curves, {} on surfaces, {} in volumes{}",
            c[0],
            c[1],
            c[2],
            c[3],
            if i.parametric {
                " (with parametric coordinates)"
            } else {
                ""
            }
        ),
        None => outln!("classification: none"),
    }
    let s = &i.quality;
    if s.measured > 0 {
        outln!(
            "quality ({} of {} cells; signed mean ratio of tetrahedra and triangles, scaled Jacobian of the other kinds): min {:.4}, mean {:.4}, 1st percentile {:.4}, max {:.4}, {} invalid (q <= 0)",
            s.measured,
            s.count,
            s.min,
            s.mean,
            s.p1,
            s.max,
            s.n_nonpositive
        );
        for (k, s) in &i.quality_by_kind {
            outln!(
                "  {k}: min {:.4}, mean {:.4}, 1st percentile {:.4}, {} invalid",
                s.min,
                s.mean,
                s.p1,
                s.n_nonpositive
            );
        }
        if s.n_nonpositive > 0 {
            let w: Vec<String> = i.worst.iter().map(ToString::to_string).collect();
            outln!("worst: {}", w.join(", "));
        }
    } else {
        outln!("quality: no cells to measure");
    }
    if let Some(a) = i.min_angle_deg {
        let what = if i.dim == 3 { "dihedral" } else { "corner" };
        outln!("min {what} angle: {a:.2} deg");
    }
    for w in &i.warnings {
        outln!("warning: {w}");
    }
    Ok(())
}

fn convert(a: &ConvertArgs) -> anyhow::Result<()> {
    let format = match Format::from_path(&a.output) {
        Some(Format::Msh(_)) => Format::Msh(if a.binary {
            Encoding::Binary
        } else {
            Encoding::Ascii
        }),
        Some(Format::Vtu(_)) => Format::Vtu(if a.base64 {
            VtuEncoding::Base64
        } else {
            VtuEncoding::AppendedRaw
        }),
        Some(f) => f,
        None => bail!(
            "{}: unknown output format (use .su2, .msh, .vtu or an OpenFOAM case directory)",
            a.output.display()
        ),
    };
    aeroshape::fsio::ensure_not_input(&a.output, &[&a.input]).map_err(anyhow::Error::msg)?;
    let m = mesh::io::read_path(&a.input)?;
    m.validate()
        .with_context(|| format!("{}", a.input.display()))?;
    for w in &m.warnings {
        eprintln!("warning: {w}");
    }
    if format == Format::Su2 && m.classes.is_some() {
        eprintln!(
            "note: node classification and entities are not stored in SU2 files; they are dropped"
        );
    }
    if format != Format::Su2 && !m.su2_extra.is_empty() {
        eprintln!("note: the SU2 trailing sections (e.g. FFD boxes) are only kept in .su2 output");
    }
    write_grid(&m, format, &a.output)
}

/// Writes a grid at `path` in `format`: a file through a temporary name renamed into place,
/// or an OpenFOAM case (the case the grid was read from, with its `points` replaced;
/// `mesh::foam::write`).
pub(crate) fn write_grid(m: &Mesh, format: Format, path: &Path) -> anyhow::Result<()> {
    if mesh::io::is_directory(format) {
        mesh::io::write_path(m, format, path)?;
    } else {
        aeroshape::fsio::write_atomic(path, |w| mesh::io::write(m, format, w))?;
    }
    Ok(())
}
