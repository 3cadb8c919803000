//! How far the rotation reaches (issue 20, item 7): the displacement of the volume nodes
//! against their distance from the moving wall, on the Gmsh-made wing grids of
//! `fixtures/grids` (OpenCASCADE split wing and wing-body, ONERA M6), the body pitched 5°
//! about a spanwise axis through its quarter chord, the symmetry plane sliding and the far
//! field fixed; without R, with the full R (the paper's, the default) and with R blended to
//! the identity at the reach L (`--rotation-reach`, `DeformOptions::rotation_reach`) of
//! 2, 1, ½ and ¼ far-field distances D (D: the moving nodes' bounding-box diagonal, as in
//! the far-field report).
//!
//! ```text
//! cargo run --release -p deform --example rotation_reach [-- OUTDIR]
//! ```
//!
//! Writes (default OUTDIR `docs/figures`): `rotation-reach.csv` (per grid, mode and distance
//! band: nodes, largest and mean displacement relative to the wall's largest),
//! `rotation-reach-summary.csv` (per grid and mode: cell quality, minimum over all cells and
//! over the cells touching the wall, inverted cells, the far-field report) and
//! `rotation-reach.png` (the largest displacement per band against d / D, one panel per
//! grid). The distance d of a node is its Euclidean distance to the nearest wall node.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use plotters::prelude::*;

static FONT: &[u8] = include_bytes!("../../aeroshape-cli/assets/DejaVuSans.ttf");

/// The distance bands: edges from 10⁻² D to 10 D, log-spaced.
const BANDS: usize = 18;

/// One deformation of one grid.
struct Run {
    mode: String,
    /// (band lower edge / D, band upper edge / D, nodes, max, mean displacement / wall max).
    bands: Vec<(f64, f64, usize, f64, f64)>,
    q_min: f64,
    q_min_wall: f64,
    inverted: usize,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let out = std::env::args()
        .nth(1)
        .map_or_else(|| root.join("docs/figures"), PathBuf::from);
    std::fs::create_dir_all(&out)?;
    let grids: [(&str, &[&str]); 3] = [
        ("split_wing", &["wing"]),
        ("wing_body", &["wing", "fuselage"]),
        ("oneram6", &["wing"]),
    ];
    let mut csv =
        String::from("grid,mode,d_lo_over_D,d_hi_over_D,nodes,max_disp_rel,mean_disp_rel\n");
    let mut sum = String::from(
        "grid,mode,reach,q_min_before,q_min,q_min_wall_before,q_min_wall,inverted,far_distance,far_nodes,far_max_disp,wall_max_disp\n",
    );
    let mut panels = Vec::new();
    for (name, moving) in grids {
        let path = root.join(format!("fixtures/grids/{name}.su2"));
        let m = mesh::io::read_path(&path)?;
        let moving: Vec<String> = moving.iter().map(|s| s.to_string()).collect();
        let (dist, wall_cell, axis) = geometry(&m, &moving);
        let sym = m.marker("symmetry").expect("symmetry").elements.node_set();
        let held: Vec<u32> = m
            .marker("farfield")
            .expect("farfield")
            .elements
            .node_set()
            .into_iter()
            .filter(|v| sym.binary_search(v).is_ok())
            .collect();
        let q0 = deform::cell_quality(&m, &m.coords);
        let q_min0 = q0.iter().copied().fold(f64::INFINITY, f64::min);
        let q_wall0 = min_where(&q0, &wall_cell);
        let modes: [(&str, bool, Option<f64>); 6] = [
            ("no R", false, None),
            ("full R", true, None),
            ("reach 2D", true, Some(2.0)),
            ("reach D", true, Some(1.0)),
            ("reach D/2", true, Some(0.5)),
            ("reach D/4", true, Some(0.25)),
        ];
        let mut runs = Vec::new();
        let mut big_d = 0.0;
        for (mode, rot, reach) in modes {
            let mut req = deform::Request {
                rigid: moving.clone(),
                motion: deform::RigidMotion {
                    angle_deg: 5.0,
                    axis_point: axis,
                    axis_dir: [0.0, 1.0, 0.0],
                    translation: [0.0; 3],
                },
                slide: vec!["symmetry".into()],
                fixed: vec!["farfield".into()],
                adapt_rotation: rot,
                rotation_reach: reach.map(|f| f * big_d),
                ..deform::Request::default()
            };
            // As `aeroshape deform`: the far field's nodes on the symmetry plane are held.
            req.displacements = held.iter().map(|&v| (v, [0.0; 3])).collect();
            let d = req.run(&m, None, &mut |_, _, _| {})?;
            let far = d.report.far_field;
            if big_d == 0.0 {
                big_d = far.distance;
            }
            let disp: Vec<f64> = m
                .coords
                .iter()
                .zip(&d.coords)
                .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt())
                .collect();
            let wall = far.wall_max_displacement;
            let mut bands = Vec::new();
            for b in 0..BANDS {
                let edge = |k: usize| 10f64.powf(-2.0 + 3.0 * k as f64 / BANDS as f64);
                let (lo, hi) = (edge(b), edge(b + 1));
                let sel: Vec<f64> = (0..m.n_nodes())
                    .filter(|&i| dist[i] / big_d >= lo && dist[i] / big_d < hi)
                    .map(|i| disp[i] / wall)
                    .collect();
                if !sel.is_empty() {
                    let max = sel.iter().copied().fold(0.0, f64::max);
                    let mean = sel.iter().sum::<f64>() / sel.len() as f64;
                    bands.push((lo, hi, sel.len(), max, mean));
                }
            }
            let q = &d.cell_quality;
            let run = Run {
                mode: mode.to_string(),
                bands,
                q_min: q.iter().copied().fold(f64::INFINITY, f64::min),
                q_min_wall: min_where(q, &wall_cell),
                inverted: q.iter().filter(|v| **v <= 0.0).count(),
            };
            for b in &run.bands {
                writeln!(
                    csv,
                    "{name},{mode},{:.4e},{:.4e},{},{:.5e},{:.5e}",
                    b.0, b.1, b.2, b.3, b.4
                )?;
            }
            writeln!(
                sum,
                "{name},{mode},{},{q_min0:.5},{:.5},{q_wall0:.5},{:.5},{},{:.4e},{},{:.5e},{:.5e}",
                reach.map_or("none".to_string(), |f| format!("{:.4e}", f * big_d)),
                run.q_min,
                run.q_min_wall,
                run.inverted,
                far.distance,
                far.nodes,
                far.max_displacement,
                far.wall_max_displacement
            )?;
            println!(
                "{name:<10} {mode:<9} q min {:.4} (wall {:.4}; before {q_min0:.4}, wall {q_wall0:.4}), inverted {}, far field ≥ {:.3}: max {:.4e} (wall {:.4e}, ratio {:.3})",
                run.q_min,
                run.q_min_wall,
                run.inverted,
                far.distance,
                far.max_displacement,
                wall,
                far.max_displacement / wall
            );
            runs.push(run);
        }
        panels.push((name, runs));
    }
    std::fs::write(out.join("rotation-reach.csv"), csv)?;
    std::fs::write(out.join("rotation-reach-summary.csv"), sum)?;
    plot(&out.join("rotation-reach.png"), &panels)?;
    println!("wrote {}", out.display());
    Ok(())
}

/// Per node its Euclidean distance to the nearest node of the `moving` markers; per cell
/// whether it touches one; the pitch axis point (quarter chord of the moving nodes' box, at
/// its mid height, y = 0).
fn geometry(m: &mesh::Mesh, moving: &[String]) -> (Vec<f64>, Vec<bool>, [f64; 3]) {
    let mut wall: Vec<u32> = moving
        .iter()
        .flat_map(|n| m.marker(n).expect("marker").elements.node_set())
        .collect();
    wall.sort_unstable();
    wall.dedup();
    let mut on = vec![false; m.n_nodes()];
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &v in &wall {
        on[v as usize] = true;
        for k in 0..3 {
            lo[k] = lo[k].min(m.coords[v as usize][k]);
            hi[k] = hi[k].max(m.coords[v as usize][k]);
        }
    }
    let pts: Vec<[f64; 3]> = wall.iter().map(|&v| m.coords[v as usize]).collect();
    let dist = m
        .coords
        .iter()
        .map(|p| {
            pts.iter()
                .map(|q| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>())
                .fold(f64::INFINITY, f64::min)
                .sqrt()
        })
        .collect();
    assert_eq!(m.tets().len(), m.cells.len(), "a tetrahedral grid");
    let cell = m
        .tets()
        .iter()
        .map(|t| t.iter().any(|&v| on[v as usize]))
        .collect();
    let axis = [lo[0] + 0.25 * (hi[0] - lo[0]), 0.0, 0.5 * (lo[2] + hi[2])];
    (dist, cell, axis)
}

fn min_where(q: &[f64], sel: &[bool]) -> f64 {
    q.iter()
        .zip(sel)
        .filter(|(_, s)| **s)
        .map(|(v, _)| *v)
        .fold(f64::INFINITY, f64::min)
}

/// One panel per grid: the largest displacement per band (relative to the wall's) against
/// d / D, log–log, one line per mode.
fn plot(path: &Path, panels: &[(&str, Vec<Run>)]) -> Result<(), Box<dyn std::error::Error>> {
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    let root = BitMapBackend::new(path, (1200, 420)).into_drawing_area();
    root.fill(&WHITE)?;
    let areas = root.split_evenly((1, panels.len()));
    let colours = [BLACK, RED, BLUE, GREEN, MAGENTA, CYAN];
    for (area, (name, runs)) in areas.iter().zip(panels) {
        let mut chart = ChartBuilder::on(area)
            .caption(format!("{name}, pitch 5°"), ("sans-serif", 18))
            .margin(8)
            .x_label_area_size(34)
            .y_label_area_size(48)
            .build_cartesian_2d((0.01f64..10.0).log_scale(), (1e-2f64..10.0).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("d / D")
            .y_desc("max |Δx| / max |Δx| on the wall")
            .label_style(("sans-serif", 12))
            .draw()?;
        for (run, c) in runs.iter().zip(colours) {
            let pts: Vec<(f64, f64)> = run
                .bands
                .iter()
                .map(|b| ((b.0 * b.1).sqrt(), b.3.max(1e-2)))
                .collect();
            let style = ShapeStyle::from(&c).stroke_width(2);
            chart
                .draw_series(LineSeries::new(pts, style))?
                .label(run.mode.clone())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], style));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 12))
            .draw()?;
    }
    root.present()?;
    Ok(())
}
