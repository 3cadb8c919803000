//! Stage 9, database: corners, one support curve and curve component per sewn edge,
//! support surfaces, surface components with their oriented loops, roles (recognised by
//! shape, or given by [`ImportOptions::roles`]) and names; a shell holding the far field is
//! turned to enclose the fluid (V < 0), and every shell with [`ImportOptions::flip`]; the
//! database is validated and, with [`ImportOptions::control_nodes`], given its control
//! nodes (Eq. 9). The report collects what every stage found.

use super::super::model::CadModel;
use super::super::roles;
use super::super::{EdgeReport, Error, FaceReport, ImportOptions, ImportReport, ShellReport};
use super::corners::Corners;
use super::edges::Edges;
use super::faces::Faces;
use super::orientation::Oriented;
use super::sewing::Sewn;
use super::shells::Shells;
use crate::curve::Arc;
use crate::curve::SupportCurve;
use crate::db::GeomDb;
use crate::eval::{ParamCurve, ParamSurface};
use crate::ids::{CornerId, CurveCompId, CurveId, SurfaceId};
use crate::invert::{InvertOptions, SurfaceInverter};
use crate::surface::{Side, SupportSurface};
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
    opts: &ImportOptions,
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
    seams_on_borders(&mut db, faces, sewn);
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
    let mut names: Vec<String> = roles.iter().map(|r| r.name()).collect();
    for (entity, role) in &opts.roles {
        let Some(fi) = model.faces.iter().position(|f| &f.source.label == entity) else {
            return Err(Error::Model {
                file: model.file.clone(),
                reason: format!(
                    "the roles mapping names face {entity}, which the file does not have"
                ),
            });
        };
        names[fi] = role.clone();
    }
    for (fi, c) in db.surface_components.iter_mut().enumerate() {
        c.name = format!("{}.{}", names[fi], model.faces[fi].source.label);
    }
    // A shell holding the far field encloses the fluid: V < 0.
    let mut volumes = shells.volumes.clone();
    for (sh, v) in volumes.iter_mut().enumerate() {
        let far =
            (0..model.faces.len()).any(|fi| oriented.shell_of[fi] == sh && names[fi] == "farfield");
        if far != opts.flip {
            *v = -*v;
            for (fi, c) in db.surface_components.iter_mut().enumerate() {
                if oriented.shell_of[fi] == sh {
                    flip_component(c);
                }
            }
        }
    }
    record_junctions(&mut db, faces, sewn, &names, &mut rep);
    for (fi, c) in db.surface_components.iter().enumerate() {
        let f = &model.faces[fi];
        rep.faces.push(FaceReport {
            role: names[fi].clone(),
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
            volume: volumes[sh],
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
    if opts.control_nodes {
        db.assign_control_nodes().map_err(|e| Error::Invalid {
            file: model.file.clone(),
            source: Box::new(e),
        })?;
    }
    db.refresh_baseline();
    Ok((db, rep))
}

/// Reverses a surface component: its loops run backwards and its inward normal turns.
fn flip_component(c: &mut SurfaceComponent) {
    for lp in &mut c.loops {
        lp.reverse();
        lp.iter_mut().for_each(|oc| oc.reversed = !oc.reversed);
    }
    c.inward = match c.inward {
        Orientation::Positive => Orientation::Negative,
        Orientation::Negative => Orientation::Positive,
    };
}

/// Smallest angle between two surfaces along a junction (sine): below it they are tangent
/// and their intersection is not well defined.
const MIN_JUNCTION_SINE: f64 = 0.1;

/// Junctions: a curve shared by two faces of different roles on different support
/// surfaces that cross there, inside both (wing ∩ fuselage, a cap plane ∩ the symmetry
/// plane), is their intersection. Its two defining surfaces let the model update re-intersect it
/// (Eq. 12) and the corners on it (Eq. 13); tangent pairs (smooth joins) are left to their
/// shared control nodes.
fn record_junctions(
    db: &mut GeomDb,
    faces: &Faces,
    sewn: &Sewn,
    names: &[String],
    rep: &mut ImportReport,
) {
    let opts = InvertOptions::for_model(db);
    for (k, s) in sewn.edges.iter().enumerate() {
        let [a, b] = s.uses.as_slice() else { continue };
        let (fa, fb) = (a.face, b.face);
        let (sa, sb) = (faces.faces[fa].support, faces.faces[fb].support);
        if fa == fb || sa == sb || names[fa] == names[fb] {
            continue;
        }
        let curve = &db.curves[k];
        // A curve on a border of either support (a wing ending at its tip cap, a half
        // fuselage at the symmetry plane) shares that surface's control nodes and follows
        // it; it is not re-intersected.
        if border_of(&db.surfaces[sa], &curve.arcs, faces.sew).is_some()
            || border_of(&db.surfaces[sb], &curve.arcs, faces.sew).is_some()
        {
            continue;
        }
        let (Ok(ia), Ok(ib)) = (
            SurfaceInverter::new("", &db.surfaces[sa], &opts),
            SurfaceInverter::new("", &db.surfaces[sb], &opts),
        ) else {
            continue;
        };
        let n = curve.arcs.len() as f64;
        let crossing = (1..8).all(|j| {
            let p = curve.point(n * j as f64 / 8.0);
            let normal = |inv: &SurfaceInverter<'_, SupportSurface>| {
                inv.nearest_indexed(&p, j)
                    .ok()
                    .and_then(|f| inv.surface().normal(f.uv[0], f.uv[1]))
            };
            match (normal(&ia), normal(&ib)) {
                (Some(x), Some(y)) => x.cross(&y).norm() >= MIN_JUNCTION_SINE,
                _ => false,
            }
        });
        if crossing {
            db.curves[k].defining_surfaces =
                vec![SurfaceId::from_index(sa), SurfaceId::from_index(sb)];
            rep.junctions.push(k);
        }
    }
}

/// Seams: an edge used twice by one face (the seam of a closed surface) that runs along a
/// border of the face's support surface becomes the part of that whole border (the
/// patches' border arcs, uncut): its control nodes are then the surface's own, so the seam
/// follows every change of the surface, and it reaches past the face (into the fuselage at
/// a wing root) for the corners on it to be re-intersected (Eq. 13).
fn seams_on_borders(db: &mut GeomDb, faces: &Faces, sewn: &Sewn) {
    for (k, s) in sewn.edges.iter().enumerate() {
        let [a, b] = s.uses.as_slice() else { continue };
        if a.face != b.face {
            continue;
        }
        let sup = &db.surfaces[faces.faces[a.face].support];
        let curve = &db.curves[k];
        let Some(border) = border_of(sup, &curve.arcs, faces.sew) else {
            continue;
        };
        let samples = super::curve_samples(&border, 16);
        let comp = &db.curve_components[k];
        let (start, end) = (
            db.corners[comp.start.index()].point,
            db.corners[comp.end.index()].point,
        );
        let (t0, t1) = (
            super::foot_on_arcs(&border, &samples, &start).1,
            super::foot_on_arcs(&border, &samples, &end).1,
        );
        if (t1 - t0).abs() <= 1e-9 {
            continue;
        }
        let name = curve.name.clone();
        db.curves[k] = SupportCurve::new(name, border);
        db.curve_components[k].t0 = t0;
        db.curve_components[k].t1 = t1;
    }
}

/// The whole border of `sup` (its patches' border arcs, in order) along which the curve
/// made of `arcs` runs within `tol`, if any.
fn border_of(sup: &SupportSurface, arcs: &[Arc], tol: f64) -> Option<Vec<Arc>> {
    let (nu, nv) = (sup.n_u, sup.n_v);
    let sides: [Vec<Arc>; 4] = [
        (0..nv)
            .map(|j| sup.patch(0, j).border(Side::UMin))
            .collect(),
        (0..nv)
            .map(|j| sup.patch(nu - 1, j).border(Side::UMax))
            .collect(),
        (0..nu)
            .map(|i| sup.patch(i, 0).border(Side::VMin))
            .collect(),
        (0..nu)
            .map(|i| sup.patch(i, nv - 1).border(Side::VMax))
            .collect(),
    ];
    let probe = super::curve_samples(arcs, 8);
    sides.into_iter().find(|side| {
        let samples = super::curve_samples(side, 16);
        probe
            .iter()
            .all(|(_, p)| super::foot_on_arcs(side, &samples, p).0 <= tol)
    })
}
