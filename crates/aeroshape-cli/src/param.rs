//! `aeroshape param`: list a case's design variables and constraints, apply a design vector
//! to its geometry (paper §5, then the model update of §3.1–3.2).

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use geom_db::GeomDb;
use param::{MasterSources, Prepared};
use serde::Serialize;

use aeroshape::case::{Case, load_design_values};
use aeroshape::fsio::{ensure_not_input, write_atomic};

/// `aeroshape param` subcommands.
#[derive(Debug, Subcommand)]
pub enum ParamCmd {
    /// List the design variables of a case (values, bounds, scale, group, modifier) and its
    /// linear constraints; checks every modifier against the geometry.
    List(ListArgs),
    /// Apply a design vector: move the control nodes (node / line / surface / master
    /// modifiers), re-solve the surfaces, re-intersect the support curves and corners, and
    /// write the updated geometry.
    Apply(ApplyArgs),
}

/// Arguments of `param list`.
#[derive(Debug, Args)]
pub struct ListArgs {
    /// The case file (RON).
    pub case: PathBuf,
    /// Print one JSON object (`variables`, `modifiers`, `constraints`) instead of tables.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `param apply`.
#[derive(Debug, Args)]
pub struct ApplyArgs {
    /// The case file (RON).
    pub case: PathBuf,
    /// Design vector: a RON map {"name": value, …}; variables not named keep their initial
    /// value. Without it, the initial design vector (the baseline geometry).
    #[arg(long, value_name = "DV.ron")]
    pub dv: Option<PathBuf>,
    /// The updated geometric database (RON).
    #[arg(short, long, value_name = "GEOM.ron")]
    pub output: PathBuf,
    /// Also write the exact Jacobian d(control node coordinates)/d(design variables) of the
    /// geometry written, model update included (the junctions' control nodes re-intersected),
    /// as JSON (CSR: row 3·node + coordinate, one column per design variable).
    #[arg(long, value_name = "J.json")]
    pub jacobian: Option<PathBuf>,
    /// Apply even if linear constraints are violated (they are still reported).
    #[arg(long)]
    pub allow_infeasible: bool,
    /// Also write the model update's report as JSON (the `model` record of `aeroshape run`'s
    /// report.json, with each junction's sampled distance to its surfaces, and the update's
    /// full report).
    #[arg(long, value_name = "report.json")]
    pub report: Option<PathBuf>,
    /// Tolerance of a junction's sampled distance to its defining surfaces (and of a
    /// corner's to its curves and surfaces), relative to the model size.
    #[arg(long, value_name = "REL", default_value_t = 1e-8)]
    pub junction_tol: f64,
}

/// Runs a `param` subcommand.
pub fn run(cmd: ParamCmd) -> anyhow::Result<()> {
    match cmd {
        ParamCmd::List(a) => list(a),
        ParamCmd::Apply(a) => apply(a),
    }
}

fn load(case_path: &Path) -> anyhow::Result<(Case, GeomDb, Prepared)> {
    let case = Case::load(case_path)?;
    let gpath = case.geometry_path(case_path);
    let text = std::fs::read_to_string(&gpath)
        .with_context(|| format!("{} (geometry of {})", gpath.display(), case_path.display()))?;
    let db = GeomDb::from_ron_str(&text, &gpath.display().to_string())?;
    // the case's wing masters are the sources of its `External` master modifiers, as in
    // `run` (a case naming another gets a clear error from `bind`)
    let masters = if case.wing_masters.is_empty() {
        MasterSources::new()
    } else {
        wingmaster::master::master_sources(&db, &case.parametrisation, &case.wing_masters)
            .with_context(|| format!("{}: wing masters", case_path.display()))?
    };
    let prep = case
        .parametrisation
        .bind(&db, &masters)
        .with_context(|| format!("{}: parametrisation", case_path.display()))?;
    let reach = aeroshape::reach::variable_reach(&prep)
        .with_context(|| format!("{}: parametrisation", case_path.display()))?;
    aeroshape::reach::check_live(&reach, case_path)?;
    Ok((case, db, prep))
}

#[derive(Serialize)]
struct VarRow<'a> {
    name: &'a str,
    value: f64,
    lower: f64,
    upper: f64,
    scale: f64,
    group: &'a str,
    modifier: &'a str,
}

#[derive(Serialize)]
struct ModRow<'a> {
    name: &'a str,
    level: &'a str,
    nodes_moved: usize,
}

fn list(a: ListArgs) -> anyhow::Result<()> {
    let (case, _db, prep) = load(&a.case)?;
    let reg = prep.registry();
    let cm = case
        .parametrisation
        .constraint_matrix()
        .with_context(|| a.case.display().to_string())?;
    let vars: Vec<VarRow> = reg
        .variables()
        .iter()
        .enumerate()
        .map(|(i, v)| VarRow {
            name: &v.name,
            value: v.value,
            lower: v.lower,
            upper: v.upper,
            scale: v.scale,
            group: &v.group,
            modifier: reg.owner(i),
        })
        .collect();
    let mods: Vec<ModRow> = prep
        .summary()
        .iter()
        .map(|(n, l, c)| ModRow {
            name: n,
            level: l,
            nodes_moved: *c,
        })
        .collect();
    if a.json {
        #[derive(Serialize)]
        struct Out<'a> {
            variables: Vec<VarRow<'a>>,
            modifiers: Vec<ModRow<'a>>,
            constraints: &'a param::ConstraintMatrix,
        }
        outln!(
            "{}",
            serde_json::to_string(&Out {
                variables: vars,
                modifiers: mods,
                constraints: &cm,
            })?
        );
        return Ok(());
    }
    outln!("modifiers ({}):", mods.len());
    for m in &mods {
        outln!(
            "  {:<20} {:<8} moves {} control nodes",
            m.name,
            m.level,
            m.nodes_moved
        );
    }
    outln!("design variables ({}):", vars.len());
    outln!(
        "  {:<16} {:>12} {:>12} {:>12} {:>8}  {:<14} modifier",
        "name",
        "value",
        "lower",
        "upper",
        "scale",
        "group"
    );
    for v in &vars {
        outln!(
            "  {:<16} {:>12.6} {:>12.6} {:>12.6} {:>8.3}  {:<14} {}",
            v.name,
            v.value,
            v.lower,
            v.upper,
            v.scale,
            v.group,
            v.modifier
        );
    }
    outln!("constraints ({}):", cm.names.len());
    for (k, name) in cm.names.iter().enumerate() {
        let terms: Vec<String> = cm.a[k]
            .iter()
            .zip(&cm.variables)
            .filter(|(a, _)| **a != 0.0)
            .map(|(a, n)| format!("{a} {n}"))
            .collect();
        outln!("  {name}: {} <= {}", terms.join(" + "), cm.b[k]);
    }
    Ok(())
}

fn apply(a: ApplyArgs) -> anyhow::Result<()> {
    if !(a.junction_tol.is_finite() && a.junction_tol > 0.0) {
        bail!(
            "--junction-tol must be a positive number, got {}",
            a.junction_tol
        );
    }
    let mut inputs: Vec<&Path> = vec![&a.case];
    if let Some(dv) = &a.dv {
        inputs.push(dv);
    }
    let (case, db, prep) = load(&a.case)?;
    let gpath = case.geometry_path(&a.case);
    inputs.push(&gpath);
    ensure_not_input(&a.output, &inputs).map_err(anyhow::Error::msg)?;
    if let Some(j) = &a.jacobian {
        ensure_not_input(j, &inputs).map_err(anyhow::Error::msg)?;
    }
    if let Some(r) = &a.report {
        ensure_not_input(r, &inputs).map_err(anyhow::Error::msg)?;
    }
    let reg = prep.registry();
    let x = match &a.dv {
        Some(p) => {
            let values = load_design_values(p)?;
            reg.vector_from_values(&values)
                .with_context(|| p.display().to_string())?
        }
        None => reg.initial(),
    };
    check_constraints(
        &case.parametrisation,
        &x,
        &a.case,
        a.allow_infeasible,
        "apply",
    )?;
    let (pts, jac) = if a.jacobian.is_some() {
        let (p, j) = prep.apply_with_jacobian(&x)?;
        (p, Some(j))
    } else {
        (prep.apply(&x)?, None)
    };
    let moved = pts
        .iter()
        .zip(db.control_points())
        .filter(|(p, q)| p != q)
        .count();
    let max_move = pts
        .iter()
        .zip(db.control_points())
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max);
    let opts = intersect::update::UpdateOptions::default().with_junction_rel_tol(a.junction_tol);
    let t0 = std::time::Instant::now();
    let label = || format!("{}: model update", a.case.display());
    let base = intersect::update::ModelBaseline::new(&db, &opts).with_context(label)?;
    let (new_db, report) = base.update(&pts).with_context(label)?;
    let model = aeroshape::study::ModelPhase::from_update(
        &report,
        db.reference_length(),
        t0.elapsed().as_secs_f64(),
    );
    // the Jacobian of the geometry written: the modifiers' through the model update, so the
    // junctions' control nodes (re-intersected) get their true rows
    let jac = match jac {
        Some(jp) => {
            let lin = base.linearise(&pts, &new_db).with_context(label)?;
            Some(aeroshape::study::model_jacobian(&lin, &jp).with_context(label)?)
        }
        None => None,
    };
    write_atomic(&a.output, |w| new_db.write_ron(w))?;
    if let Some(path) = &a.report {
        let v = serde_json::json!({
            "case": a.case.display().to_string(),
            "design_vector": a.dv.as_ref().map(|p| p.display().to_string()),
            "model": model,
            "update": report,
        });
        write_atomic(path, |w| {
            serde_json::to_writer_pretty(&mut *w, &v).map_err(std::io::Error::other)?;
            writeln!(w)
        })?;
    }
    if let (Some(path), Some(j)) = (&a.jacobian, &jac) {
        let names = reg.names();
        write_atomic(path, |w| param::jacobian::write_json(j, &names, w))?;
    }
    let reint = report.curves.iter().filter(|c| c.reintersected).count();
    let corners = report.corners.iter().filter(|c| c.updated).count();
    outln!(
        "{} design variables, {} control nodes moved (max {:.4e}); {} surfaces re-solved, {} curves re-intersected (max residual {:.3e}), {} corners updated (max residual {:.3e})",
        reg.len(),
        moved,
        max_move,
        report.surfaces_changed.len(),
        reint,
        report.max_curve_residual,
        corners,
        report.max_corner_residual
    );
    outln!("{}", model.junction_summary());
    outln!("wrote {}", a.output.display());
    if let (Some(path), Some(j)) = (&a.jacobian, &jac) {
        outln!(
            "wrote {} ({} × {}, {} non-zeros)",
            path.display(),
            j.rows(),
            j.cols(),
            j.nnz()
        );
    }
    Ok(())
}

/// Checks the design vector `x` against the linear constraints of `par` (the case file
/// `case`): every violated constraint is a warning on stderr, and any violation is an error
/// unless `allow_infeasible` (the message suggests the flag, `verb` naming what it allows).
pub(crate) fn check_constraints(
    par: &param::Parametrisation,
    x: &[f64],
    case: &std::path::Path,
    allow_infeasible: bool,
    verb: &str,
) -> anyhow::Result<()> {
    let cm = par
        .constraint_matrix()
        .with_context(|| case.display().to_string())?;
    let violations = cm.violations(x);
    for v in &violations {
        eprintln!("warning: {v}");
    }
    if !violations.is_empty() && !allow_infeasible {
        bail!(
            "{} linear constraint(s) violated (first: {}); use --allow-infeasible to {verb} anyway",
            violations.len(),
            violations[0]
        );
    }
    Ok(())
}
