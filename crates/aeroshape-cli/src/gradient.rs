//! `aeroshape gradient CASE.ron [--dv DV.ron] --sensitivity SENS -o grad.json|grad.csv`:
//! dJ/dx for every design variable from a flow adjoint's dJ/dX (issue 22), by the reverse
//! product of the whole chain at x (`aeroshape::study::ChainLinearisation`): one adjoint
//! deformation solve for a volume file (CSV or VTU), none for a surface file.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use serde::Serialize;

use aeroshape::case::Case;
use aeroshape::fsio::{ensure_not_input, write_atomic};
use aeroshape::sensitivity::{self, Layout};
use aeroshape::study::Study;

/// Arguments of `aeroshape gradient`.
#[derive(Debug, Args)]
pub struct GradientArgs {
    /// The case file (RON; docs/formats/case-ron.md).
    pub case: PathBuf,
    /// Design vector: a RON map {"name": value, …}; variables not named keep their initial
    /// value. Without it, the initial design vector.
    #[arg(long, value_name = "DV.ron")]
    pub dv: Option<PathBuf>,
    /// dJ/dX of the grid the case names, in SU2's layout: the volume CSV of RESTART_ASCII
    /// ("PointID", …, "Sensitivity_x", "Sensitivity_y", "Sensitivity_z"), a surface CSV
    /// ("Point", …) with the wall nodes only, or a `.vtu` with a point-data vector
    /// "Sensitivity" on every grid node (its points must be the grid's at the design vector).
    #[arg(long, value_name = "SENS.csv|SENS.vtu")]
    pub sensitivity: PathBuf,
    /// Output: JSON (`.json`) or CSV (`.csv`: variable,gradient).
    #[arg(short, long, value_name = "grad.json")]
    pub output: PathBuf,
    /// Run even if linear constraints of the parametrisation are violated.
    #[arg(long)]
    pub allow_infeasible: bool,
}

/// The file `grad.json`.
#[derive(Serialize)]
struct GradientReport<'a> {
    case: String,
    design_vector: Option<String>,
    sensitivity: String,
    layout: Layout,
    /// dJ/dx per design variable, by name, in the registry's order.
    gradient: Vec<(&'a str, f64)>,
    seconds: f64,
}

/// Runs `aeroshape gradient`.
pub fn run(a: GradientArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let csv = match a.output.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("json") => false,
        Some(e) if e.eq_ignore_ascii_case("csv") => true,
        _ => anyhow::bail!(
            "{}: the output must end in .json or .csv",
            a.output.display()
        ),
    };
    let case = Case::load(&a.case)?;
    let mut inputs: Vec<PathBuf> = vec![a.case.clone(), case.geometry_path(&a.case)];
    inputs.extend(case.grid_path(&a.case));
    inputs.extend(a.dv.clone());
    inputs.push(a.sensitivity.clone());
    let input_refs: Vec<&std::path::Path> = inputs.iter().map(PathBuf::as_path).collect();
    ensure_not_input(&a.output, &input_refs).map_err(anyhow::Error::msg)?;
    let study = Study::new(case, &a.case)?;
    let x = super::run::design_vector(&study, a.dv.as_deref())?;
    super::param::check_constraints(
        &study.case().parametrisation,
        &x,
        &a.case,
        a.allow_infeasible,
        "differentiate",
    )?;
    let sens = sensitivity::read(
        &a.sensitivity,
        study.baseline().n_nodes(),
        study.wall_nodes(),
    )?;
    let lin = study.linearise(&x)?;
    if let Some(p) = &sens.points {
        // a VTU has no point IDs: its points must be the grid's nodes at x (1e-6 of the
        // grid's size: single-precision coordinates pass, another node order does not)
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for q in lin.coords() {
            for c in 0..3 {
                lo[c] = lo[c].min(q[c]);
                hi[c] = hi[c].max(q[c]);
            }
        }
        let diag = (0..3).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt();
        sensitivity::check_points(&a.sensitivity, p, lin.coords(), 1e-6 * diag)?;
    }
    let g = match sens.layout {
        Layout::Volume => lin.vjp(&sens.values)?,
        Layout::Surface => lin.vjp_wall(&sens.values)?,
    };
    let names = study.registry().names();
    let report = GradientReport {
        case: a.case.display().to_string(),
        design_vector: a.dv.as_ref().map(|p| p.display().to_string()),
        sensitivity: a.sensitivity.display().to_string(),
        layout: sens.layout,
        gradient: names.iter().copied().zip(g.iter().copied()).collect(),
        seconds: t0.elapsed().as_secs_f64(),
    };
    write_atomic(&a.output, |w| {
        if csv {
            writeln!(w, "variable,gradient")?;
            for (n, v) in &report.gradient {
                writeln!(w, "{n},{v:e}")?;
            }
            Ok(())
        } else {
            serde_json::to_writer_pretty(&mut *w, &report).map_err(std::io::Error::other)?;
            writeln!(w)
        }
    })?;
    let width = names.iter().map(|n| n.len()).max().unwrap_or(8).max(8);
    outln!("{:<width$}  dJ/dx", "variable");
    for (n, v) in &report.gradient {
        outln!("{n:<width$}  {v:>23.15e}");
    }
    outln!(
        "{} design variables from {} {:?} sensitivities; wrote {} ({:.2} s)",
        names.len(),
        sens.rows,
        sens.layout,
        a.output.display(),
        report.seconds
    );
    Ok(())
}
