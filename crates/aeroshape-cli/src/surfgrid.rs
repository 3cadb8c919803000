//! `aeroshape surfgrid`: surface grids tied to the geometry (generation by advancing front in
//! each surface component's parametric plane, classification of an imported grid).

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use geom_db::SurfCompId;
use mesh::io::Format;
use surfgrid::{ClassifyOptions, GenerateOptions, SizeField};

/// Surface grid commands.
#[derive(Debug, Subcommand)]
pub enum SurfgridCmd {
    /// Generate a surface grid on a geometric database: curves discretised to the size,
    /// then advancing-front triangles in each surface component's parametric plane; nodes
    /// classified (corner / curve + t / surface + (u, v)). Write .msh (parametric nodes),
    /// .su2 or .vtu; prints quality figures.
    Generate(GenerateArgs),
    /// Classify an imported grid on a geometric database by projection and write it with
    /// its parameters (.msh) and print the distances. A surface grid: its markers named
    /// after the surface components. A volume grid: the wall markers (--wall, or every
    /// marker within the tolerance of the geometry) split by surface component by geometry
    /// alone; the whole grid is written, cells and markers kept.
    Classify(ClassifyArgs),
}

/// Arguments of `aeroshape surfgrid generate`.
#[derive(Debug, Args)]
pub struct GenerateArgs {
    /// The geometric database (.ron).
    pub geom: PathBuf,
    /// Output grid (.msh, .su2 or .vtu).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Uniform element size (length units of the database).
    #[arg(long, value_name = "H")]
    pub size: f64,
    /// Mesh only these surface components (by index; repeatable). Default: all.
    #[arg(long = "component", value_name = "K")]
    pub components: Vec<u32>,
    /// A line source refining the size near a segment (repeatable): nine comma-separated
    /// numbers x0,y0,z0,x1,y1,z1,H0,R0,R — size H0 within R0 of the segment, growing to the
    /// uniform size over R further (smoothstep). E.g. along a wing's leading edge.
    #[arg(long = "line-source", value_name = "X0,Y0,Z0,X1,Y1,Z1,H0,R0,R")]
    pub line_sources: Vec<String>,
}

/// Parses `--line-source` text: nine comma-separated numbers.
fn line_source(text: &str) -> anyhow::Result<surfgrid::spacing::LineSource> {
    let v: Vec<f64> = text
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--line-source {text:?}: not a list of numbers"))?;
    if v.len() != 9 {
        bail!(
            "--line-source {text:?}: expected 9 numbers (x0,y0,z0,x1,y1,z1,h0,r0,r), got {}",
            v.len()
        );
    }
    Ok(surfgrid::spacing::LineSource {
        a: geom_db::prelude::Point3::new(v[0], v[1], v[2]),
        b: geom_db::prelude::Point3::new(v[3], v[4], v[5]),
        h0: v[6],
        r0: v[7],
        growth: surfgrid::spacing::Growth::Smoothstep { radius: v[8] },
    })
}

/// Arguments of `aeroshape surfgrid classify`.
#[derive(Debug, Args)]
pub struct ClassifyArgs {
    /// The geometric database (.ron).
    pub geom: PathBuf,
    /// The grid to classify (.su2, .msh or .vtu).
    pub grid: PathBuf,
    /// Output grid with classification (.msh recommended: SU2 cannot store it).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Largest node distance accepted, relative to the model's reference length.
    #[arg(long, default_value_t = 1e-6, value_name = "REL")]
    pub rel_tol: f64,
    /// A volume grid's marker that lies on the geometry (repeatable). Default: every marker
    /// whose nodes are all within the tolerance of the geometry.
    #[arg(long, value_name = "MARKER")]
    pub wall: Vec<String>,
}

/// Runs a `surfgrid` subcommand.
pub fn run(cmd: SurfgridCmd) -> anyhow::Result<()> {
    match cmd {
        SurfgridCmd::Generate(a) => generate(&a),
        SurfgridCmd::Classify(a) => classify(&a),
    }
}

fn format_of(path: &std::path::Path) -> anyhow::Result<Format> {
    match Format::from_path(path) {
        Some(f) => Ok(f),
        None => bail!(
            "{}: unknown output format (use .su2, .msh or .vtu)",
            path.display()
        ),
    }
}

fn generate(a: &GenerateArgs) -> anyhow::Result<()> {
    let format = format_of(&a.output)?;
    aeroshape::fsio::ensure_not_input(&a.output, &[&a.geom]).map_err(anyhow::Error::msg)?;
    let db = super::geom::load(&a.geom)?;
    let mut field = SizeField::uniform(a.size)?;
    for l in &a.line_sources {
        field = field.with_line(line_source(l)?)?;
    }
    let mut opts = GenerateOptions::default();
    if !a.components.is_empty() {
        opts = opts.with_components(a.components.iter().map(|&k| SurfCompId(k)).collect());
    }
    let g =
        surfgrid::generate(&db, &field, &opts).with_context(|| format!("{}", a.geom.display()))?;
    let st = surfgrid::grid_stats(&g, &field);
    outln!(
        "{} nodes, {} triangles; min angle {:.2} deg, {:.2} % of triangles >= 20 deg, {:.2} % of edges within +-30 % of the size, worst mean ratio {:.4}",
        g.n_nodes(),
        st.triangles,
        st.min_angle_deg,
        100.0 * st.frac_min_angle_ge_20,
        100.0 * st.frac_edges_within_30,
        st.worst_quality
    );
    let m = g.to_mesh(&db);
    aeroshape::fsio::write_atomic(&a.output, |w| mesh::io::write(&m, format, w))?;
    Ok(())
}

fn classify(a: &ClassifyArgs) -> anyhow::Result<()> {
    let format = format_of(&a.output)?;
    aeroshape::fsio::ensure_not_input(&a.output, &[&a.geom, &a.grid])
        .map_err(anyhow::Error::msg)?;
    let db = super::geom::load(&a.geom)?;
    let m = mesh::io::read_path(&a.grid)?;
    let opts = ClassifyOptions { rel_tol: a.rel_tol };
    let volume = !m.cells.is_empty();
    let (g, rep) = if volume {
        let wall = if a.wall.is_empty() {
            markers_on_geometry(&db, &m, a.rel_tol * db.reference_length())
                .with_context(|| format!("{}", a.grid.display()))?
        } else {
            a.wall.clone()
        };
        if wall.is_empty() {
            bail!(
                "{}: no marker lies on the geometry {} (within {:.3e}); name the wall with --wall",
                a.grid.display(),
                a.geom.display(),
                a.rel_tol * db.reference_length()
            );
        }
        outln!("wall markers: {}", wall.join(", "));
        surfgrid::classify_wall(&db, &m, &wall, &opts)
    } else {
        surfgrid::classify(&m, &db, &opts)
    }
    .with_context(|| format!("{}", a.grid.display()))?;
    outln!(
        "{} corner, {} curve and {} surface nodes; distance max {:.3e} (node {}), mean {:.3e}",
        rep.corners,
        rep.curve_nodes,
        rep.surface_nodes,
        rep.max_distance,
        rep.worst_node,
        rep.mean_distance
    );
    let out = if volume {
        g.volume_with_params(&m)
    } else {
        g.to_mesh(&db)
    };
    aeroshape::fsio::write_atomic(&a.output, |w| mesh::io::write(&out, format, w))?;
    Ok(())
}

/// The markers of `m` whose nodes all lie within `tol` of the geometry.
fn markers_on_geometry(
    db: &geom_db::GeomDb,
    m: &mesh::Mesh,
    tol: f64,
) -> anyhow::Result<Vec<String>> {
    let pr = surfgrid::classify::component_projectors(db)?;
    let mut out = Vec::new();
    for mk in &m.markers {
        if surfgrid::classify::marker_distance(&pr, m, &mk.name, tol)?.max_distance <= tol {
            out.push(mk.name.clone());
        }
    }
    Ok(out)
}
