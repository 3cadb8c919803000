//! `aeroshape constraints CASE.ron [--dv DV.ron] [--jacobian J.json]`: the case's geometric
//! constraints (issue 46, `aeroshape::constraints`) measured on the model updated to the
//! design vector, as a table (name, value, initial, ratio, bounds); with `--jacobian`, their
//! exact Jacobian d(reported)/dx written as JSON, with the specifications and a point inside
//! each surface they name (so that another program can find the same faces); with `--iges`,
//! the updated model as IGES trimmed surfaces (`geom_db::import::to_iges`), for measuring
//! it elsewhere (fixtures/constraints/occ_check.py).

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use serde::Serialize;

use aeroshape::case::Case;
use aeroshape::fsio::{ensure_not_input, write_atomic};
use aeroshape::study::{ConstraintRow, Study};

/// Arguments of `aeroshape constraints`.
#[derive(Debug, Args)]
pub struct ConstraintsArgs {
    /// The case file (RON; docs/formats/case-ron.md) with a `constraints` section.
    pub case: PathBuf,
    /// Design vector: a RON map {"name": value, …}; variables not named keep their initial
    /// value. Without it, the initial design vector.
    #[arg(long, value_name = "DV.ron")]
    pub dv: Option<PathBuf>,
    /// Also write the constraints and their Jacobian (one row per constraint, one column
    /// per design variable) to this JSON file.
    #[arg(long, value_name = "J.json")]
    pub jacobian: Option<PathBuf>,
    /// Also write the model updated to the design vector as IGES (144 trimmed surfaces).
    #[arg(long, value_name = "UPDATED.igs")]
    pub iges: Option<PathBuf>,
}

/// A support surface a constraint names, and a point inside it (at the middle of its
/// parameter rectangle) on the model measured.
#[derive(Serialize)]
struct SurfaceRef {
    id: u32,
    name: String,
    centre: [f64; 3],
}

/// The file `J.json`.
#[derive(Serialize)]
struct JacobianFile<'a> {
    case: String,
    design_vector: Option<String>,
    /// Design variables (the columns), in the registry's order.
    variables: &'a [String],
    /// The constraints' specifications, as in the case.
    specs: &'a [aeroshape::constraints::ConstraintSpec],
    /// The surfaces they name.
    surfaces: Vec<SurfaceRef>,
    /// The model's reference length.
    reference_length: f64,
    /// The constraints at x (the rows).
    constraints: &'a [ConstraintRow],
    /// d(reported)/dx, row by row.
    jacobian: &'a [Vec<f64>],
    seconds: f64,
}

fn bound(b: Option<f64>) -> String {
    b.map_or_else(|| "-".to_string(), |v| format!("{v:.6}"))
}

fn has_extension(p: &std::path::Path, exts: &[&str]) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| exts.iter().any(|x| e.eq_ignore_ascii_case(x)))
}

/// Runs `aeroshape constraints`.
pub fn run(a: ConstraintsArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    if let Some(j) = &a.jacobian
        && !has_extension(j, &["json"])
    {
        anyhow::bail!("{}: the Jacobian file must end in .json", j.display());
    }
    let case = Case::load(&a.case)?;
    if case.constraints.is_empty() {
        anyhow::bail!(
            "{}: the case has no constraints (section `constraints`, docs/constraints.md)",
            a.case.display()
        );
    }
    for out in [&a.jacobian, &a.iges].into_iter().flatten() {
        let mut inputs: Vec<PathBuf> = vec![a.case.clone(), case.geometry_path(&a.case)];
        inputs.extend(case.grid_path(&a.case));
        inputs.extend(a.dv.clone());
        let refs: Vec<&std::path::Path> = inputs.iter().map(PathBuf::as_path).collect();
        ensure_not_input(out, &refs).map_err(anyhow::Error::msg)?;
    }
    if let Some(p) = &a.iges
        && !has_extension(p, &["igs", "iges"])
    {
        anyhow::bail!("{}: the IGES file must end in .igs or .iges", p.display());
    }
    let study = Study::new(case, &a.case)?;
    let x = super::run::design_vector(&study, a.dv.as_deref())?;
    let (rows, jac) = match &a.jacobian {
        Some(_) => {
            let j = study.constraints_jacobian(&x)?;
            (j.rows.clone(), Some(j))
        }
        None => (study.constraint_rows(&x)?, None),
    };
    let width = rows.iter().map(|r| r.name.len()).max().unwrap_or(4).max(4);
    outln!(
        "{:<width$}  {:>16}  {:>16}  {:>12}  {:>10}  {:>10}  ok",
        "name",
        "value",
        "initial",
        "ratio",
        "lower",
        "upper"
    );
    for r in &rows {
        let of = if r.relative { " (ratio)" } else { "" };
        outln!(
            "{:<width$}  {:>16.9e}  {:>16.9e}  {:>12.9}  {:>10}  {:>10}  {}{of}",
            r.name,
            r.value,
            r.initial,
            r.ratio,
            bound(r.lower),
            bound(r.upper),
            if r.satisfied() { "yes" } else { "NO" }
        );
    }
    let violated = rows.iter().filter(|r| !r.satisfied()).count();
    let updated = if a.iges.is_some() || a.jacobian.is_some() {
        Some(study.updated_model(&x)?)
    } else {
        None
    };
    if let (Some(path), Some(db)) = (&a.iges, &updated) {
        let name = path.file_name().map_or_else(
            || "updated.igs".into(),
            |n| n.to_string_lossy().into_owned(),
        );
        let file = geom_db::import::to_iges(db, &name);
        write_atomic(path, |w| {
            file.write(w, &name).map_err(std::io::Error::other)
        })?;
        outln!("wrote the updated model to {}", path.display());
    }
    if let (Some(path), Some(j), Some(db)) = (&a.jacobian, &jac, &updated) {
        let mut ids: Vec<geom_db::SurfaceId> = Vec::new();
        for s in &study.case().constraints {
            use aeroshape::constraints::Measure;
            let list = match &s.measure {
                Measure::Thickness { surfaces, .. }
                | Measure::Volume { surfaces, .. }
                | Measure::Area { surfaces } => surfaces,
            };
            for id in list {
                if !ids.contains(id) {
                    ids.push(*id);
                }
            }
        }
        let surfaces = ids
            .iter()
            .map(|&id| {
                use geom_db::eval::ParamSurface;
                let s = db.surface(id);
                let p = s.point(0.5 * s.n_u as f64, 0.5 * s.n_v as f64);
                SurfaceRef {
                    id: id.0,
                    name: s.name.clone(),
                    centre: [p.x, p.y, p.z],
                }
            })
            .collect();
        let file = JacobianFile {
            case: a.case.display().to_string(),
            design_vector: a.dv.as_ref().map(|p| p.display().to_string()),
            variables: &j.variables,
            specs: &study.case().constraints,
            surfaces,
            reference_length: db.reference_length(),
            constraints: &j.rows,
            jacobian: &j.jacobian,
            seconds: t0.elapsed().as_secs_f64(),
        };
        write_atomic(path, |w| {
            serde_json::to_writer_pretty(&mut *w, &file).map_err(std::io::Error::other)?;
            writeln!(w)
        })?;
        outln!(
            "{} constraints ({violated} violated), Jacobian over {} design variables written to {} ({:.2} s)",
            rows.len(),
            j.variables.len(),
            path.display(),
            t0.elapsed().as_secs_f64()
        );
    } else {
        outln!(
            "{} constraints ({violated} violated) ({:.2} s)",
            rows.len(),
            t0.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
