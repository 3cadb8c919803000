//! Stage 9, database: corners, one support curve and curve component per sewn edge,
//! support surfaces, surface components with their oriented loops, roles and names; the
//! database is validated. The report collects what every stage found.

use super::super::model::CadModel;
use super::super::roles;
use super::super::{EdgeReport, Error, FaceReport, ImportReport, ShellReport};
use super::corners::Corners;
use super::edges::Edges;
use super::faces::Faces;
use super::orientation::Oriented;
use super::sewing::Sewn;
use super::shells::Shells;
use crate::curve::SupportCurve;
use crate::db::GeomDb;
use crate::ids::{CornerId, CurveCompId, CurveId, SurfaceId};
use crate::topology::{Corner, CurveComponent, Orientation, OrientedCurve, SurfaceComponent};

/// Runs stage 9.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run(
    model: &CadModel,
    faces: &Faces,
    edges: &Edges,
    corners: &Corners,
    sewn: &Sewn,
    oriented: &Oriented,
    shells: &Shells,
    mut rep: ImportReport,
) -> Result<(GeomDb, ImportReport), Error> {
    let mut db = GeomDb::empty(model.name.clone());
    db.units = rep.units.clone();
    db.corners = corners
        .points
        .iter()
        .map(|&p| Corner {
            point: p,
            name: String::new(),
        })
        .collect();
    for (k, s) in sewn.edges.iter().enumerate() {
        let ed = &edges.edges[s.master];
        let name = match &ed.src {
            Some(src) => src.describe(),
            None => format!(
                "domain boundary of surface {}",
                faces.faces[ed.face].support
            ),
        };
        let n = ed.arcs.len() as f64;
        db.curves
            .push(SupportCurve::new(name.clone(), ed.arcs.clone()));
        db.curve_components.push(CurveComponent {
            name,
            curve: CurveId::from_index(k),
            t0: 0.0,
            t1: n,
            start: s.corners.0,
            end: s.corners.1,
        });
    }
    db.surfaces = faces
        .supports
        .iter()
        .map(|s| {
            let mut surface = s.surface.clone();
            surface.name = model.surfaces[s.model_surface].source.describe();
            surface
        })
        .collect();
    db.surface_components = model
        .faces
        .iter()
        .enumerate()
        .map(|(fi, f)| SurfaceComponent {
            name: f.source.describe(),
            surface: SurfaceId::from_index(faces.faces[fi].support),
            loops: oriented.loops[fi]
                .iter()
                .map(|lp| {
                    lp.iter()
                        .map(|&(k, reversed)| OrientedCurve {
                            comp: CurveCompId::from_index(k),
                            reversed,
                        })
                        .collect()
                })
                .collect(),
            inward: oriented.inward[fi],
        })
        .collect();

    // Report.
    rep.reference_length = faces.size;
    rep.tolerance = faces.tol;
    rep.sew_tolerance = faces.sew;
    rep.entities = faces.conversions.clone();
    rep.entities.extend(edges.conversions.iter().cloned());
    rep.max_error = rep.entities.iter().map(|e| e.max_error).fold(0.0, f64::max);
    rep.orientation_conflicts = oriented.conflicts;
    rep.max_sew_gap = sewn.max_gap;
    rep.curve_components = db.curve_components.len();
    for (k, s) in sewn.edges.iter().enumerate() {
        let mut users: Vec<usize> = s.uses.iter().map(|u| u.face).collect();
        users.sort_unstable();
        let er = EdgeReport {
            component: k,
            curves: s.sources.iter().map(|x| x.label.clone()).collect(),
            faces: s
                .uses
                .iter()
                .map(|u| model.faces[u.face].source.label.clone())
                .collect(),
        };
        match s.uses.len() {
            2 => rep.sewn_edges += 1,
            1 => rep.free_edges.push(er),
            _ => rep.non_manifold_edges.push(er),
        }
    }
    let roles = roles::recognise(&db, faces.sew);
    for (fi, (c, r)) in db.surface_components.iter_mut().zip(&roles).enumerate() {
        c.name = format!(
            "{}.{}",
            r.name().replace(' ', ""),
            model.faces[fi].source.label
        );
    }
    for (fi, c) in db.surface_components.iter().enumerate() {
        let f = &model.faces[fi];
        rep.faces.push(FaceReport {
            role: roles[fi].name(),
            entity: f.source.label.clone(),
            kind: f.source.kind.clone(),
            surface: model.surfaces[f.surface].source.label.clone(),
            component: fi,
            loops: c.loops.len(),
            inward: match c.inward {
                Orientation::Positive => "positive",
                Orientation::Negative => "negative",
            },
            shell: oriented.shell_of[fi],
            area: shells.areas[fi].abs(),
        });
    }
    for sh in 0..oriented.n_shells {
        rep.shells.push(ShellReport {
            faces: oriented.shell_of.iter().filter(|&&s| s == sh).count(),
            closed: shells.closed[sh],
            volume: shells.volumes[sh],
            size: shells.sizes[sh],
        });
    }
    if oriented.conflicts > 0 {
        rep.warnings.push(format!(
            "{} shared edges could not be oriented consistently (non-orientable or inconsistent model)",
            oriented.conflicts
        ));
    }
    let _ = CornerId::from_index;
    db.validate().map_err(|e| Error::Invalid {
        file: model.file.clone(),
        source: Box::new(e),
    })?;
    db.refresh_baseline();
    Ok((db, rep))
}
