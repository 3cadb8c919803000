//! Stage 9, database: corners, one support curve and curve component per sewn edge,
//! support surfaces, surface components with their oriented loops, roles (recognised by
//! shape, or given by [`ImportOptions::roles`]) and names; a shell holding the far field is
//! turned to enclose the fluid (V < 0), and every shell with [`ImportOptions::flip`]; the
//! database is validated and, with [`ImportOptions::control_nodes`], given its control
//! nodes (Eq. 9). The report collects what every stage found.

use super::super::model::CadModel;
use super::super::roles;
use super::super::{
    EdgeReport, Error, FaceReport, ImportOptions, ImportReport, JunctionReport, ShellReport,
};
use super::corners::Corners;
use super::edges::Edges;
use super::faces::Faces;
use super::orientation::Oriented;
use super::sewing::Sewn;
use super::shells::Shells;
use crate::curve::Arc;
use crate::curve::SupportCurve;
use crate::db::GeomDb;
use crate::error::Entity;
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
    db.size = Some(faces.size);
    db.corners = corners
        .points
        .iter()
        .map(|&p| Corner {
            point: p,
            name: String::new(),
        })
        .collect();
    // Per support curve, the file's entity it was made from (for messages).
    let mut curve_from = Vec::with_capacity(sewn.edges.len());
    for (k, s) in sewn.edges.iter().enumerate() {
        let ed = &edges.edges[s.master];
        curve_from.push(match &ed.src {
            Some(src) => format!("entity {}", src.describe()),
            None => format!(
                "the domain boundary of {}",
                surface_from(model, faces, faces.faces[ed.face].support)
            ),
        });
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
    curves_on_borders(&mut db, faces, sewn);
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
    let junctions = record_junctions(&mut db, faces, sewn, &names);
    rebuild_junctions(&mut db, &junctions, faces, &mut rep);
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
    db.validate()
        .map_err(|e| invalid(model, faces, &curve_from, &db, e))?;
    if opts.control_nodes
        && let Err(e) = db.assign_control_nodes()
    {
        return Err(invalid(model, faces, &curve_from, &db, e));
    }
    db.refresh_baseline();
    Ok((db, rep))
}

/// The file's entity support surface `i` was made from.
fn surface_from(model: &CadModel, faces: &Faces, i: usize) -> String {
    let src = &model.surfaces[faces.supports[i].model_surface].source;
    format!("entity {}", src.describe())
}

/// The import's error for the database's error `e`, naming the file's entity the item at
/// fault was made from when it is a support curve (`curve_from`), a curve component (its
/// curve's) or a support surface.
fn invalid(
    model: &CadModel,
    faces: &Faces,
    curve_from: &[String],
    db: &GeomDb,
    e: crate::Error,
) -> Error {
    let from = match &e {
        crate::Error::Invalid { entity, .. } => match *entity {
            Entity::Curve(c) | Entity::Arc { curve: c, .. } => curve_from.get(c.index()).cloned(),
            Entity::CurveComp(k) => db
                .curve_components
                .get(k.index())
                .and_then(|cc| curve_from.get(cc.curve.index()).cloned()),
            Entity::Surface(s) | Entity::Patch { surface: s, .. } => {
                (s.index() < faces.supports.len()).then(|| surface_from(model, faces, s.index()))
            }
            _ => None,
        },
        _ => None,
    };
    Error::Invalid {
        file: model.file.clone(),
        source: Box::new(e),
        from,
    }
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
fn record_junctions(db: &mut GeomDb, faces: &Faces, sewn: &Sewn, names: &[String]) -> Vec<usize> {
    let opts = InvertOptions::for_model(db);
    let mut out = Vec::new();
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
            out.push(k);
        }
    }
    out
}

/// Rebuilds every junction as the intersection of its two supports
/// ([`intersections`](super::intersections)), moves its end corners onto it and re-finds
/// the ends of the other curve components at those corners; a junction that cannot be
/// rebuilt (or whose ends would move by more than the sewing tolerance) is kept as read,
/// with a warning.
fn rebuild_junctions(db: &mut GeomDb, junctions: &[usize], faces: &Faces, rep: &mut ImportReport) {
    const DRIVERS: [&str; 4] = ["u1", "v1", "u2", "v2"];
    let mut moved: Vec<usize> = Vec::new();
    for &k in junctions {
        let [sa, sb] = [
            db.curves[k].defining_surfaces[0].index(),
            db.curves[k].defining_surfaces[1].index(),
        ];
        let comp = &db.curve_components[k];
        let (c0, c1) = (comp.start.index(), comp.end.index());
        let mut jr = JunctionReport {
            component: k,
            surfaces: [sa, sb],
            driver: None,
            arcs: db.curves[k].arcs.len(),
            max_distance: None,
            corner_move: 0.0,
        };
        let fitted = super::intersections::fit(
            &db.surfaces[sa],
            &db.surfaces[sb],
            &db.curves[k].arcs,
            faces.size,
        )
        .and_then(|f| {
            let n = f.arcs.len();
            let (p0, p1) = (f.arcs[0].point(0.0), f.arcs[n - 1].point(1.0));
            let m0 = (p0 - db.corners[c0].point).norm();
            let m1 = (p1 - db.corners[c1].point).norm();
            let gap = if c0 == c1 { (p1 - p0).norm() } else { 0.0 };
            if m0.max(m1) > faces.sew || gap > 1e-9 * faces.size {
                return Err(format!(
                    "its ends would move by {:.3e} (sewing tolerance {:.3e}) and be {gap:.3e} apart",
                    m0.max(m1),
                    faces.sew
                ));
            }
            Ok((f, p0, p1, m0.max(m1)))
        });
        match fitted {
            Ok((f, p0, p1, m)) => {
                jr.driver = Some(DRIVERS[f.driver]);
                jr.arcs = f.arcs.len();
                jr.max_distance = Some(f.max_distance);
                jr.corner_move = m;
                db.curves[k].arcs = f.arcs;
                db.curve_components[k].t0 = 0.0;
                db.curve_components[k].t1 = jr.arcs as f64;
                db.corners[c0].point = p0;
                db.corners[c1].point = p1;
                moved.extend([c0, c1]);
            }
            Err(e) => rep.warnings.push(format!(
                "junction {} ({}) is kept as read, not rebuilt on its supports: {e}",
                k, db.curves[k].name
            )),
        }
        rep.junctions.push(jr);
    }
    // the other components that end at a moved corner: their end parameter is the corner's
    // foot on their curve, continued from the old one
    for k in 0..db.curve_components.len() {
        if junctions.contains(&k) {
            continue;
        }
        let cc = db.curve_components[k].clone();
        let curve = &db.curves[cc.curve.index()];
        let (lo, hi) = crate::eval::ParamCurve::domain(curve);
        let settings = InvertOptions::new(faces.size).settings();
        let foot = |c: CornerId, t: f64| {
            let p = db.corners[c.index()].point;
            crate::invert::foot_on_curve(curve, &p, t, lo, hi, settings).x[0]
        };
        let (t0, t1) = (
            if moved.contains(&cc.start.index()) {
                foot(cc.start, cc.t0)
            } else {
                cc.t0
            },
            if moved.contains(&cc.end.index()) {
                foot(cc.end, cc.t1)
            } else {
                cc.t1
            },
        );
        if (t1 - t0).abs() > 1e-9 {
            db.curve_components[k].t0 = t0;
            db.curve_components[k].t1 = t1;
        }
    }
}

/// Curves on support borders: an edge that runs along a border of the support surface of a
/// face using it (the seam of a closed surface, used twice by one face; a half fuselage's
/// edge on the symmetry plane; a wing's edge at its tip cap) becomes the part of that whole
/// border (the patches' border arcs, uncut). Its control nodes are then the surface's own,
/// so the curve follows every change of the surface (a fuselage waist moves its edges on the
/// symmetry plane with it), and a seam reaches past the face (into the fuselage at a wing
/// root) for the corners on it to be re-intersected (Eq. 13).
fn curves_on_borders(db: &mut GeomDb, faces: &Faces, sewn: &Sewn) {
    for (k, s) in sewn.edges.iter().enumerate() {
        let mut supports: Vec<usize> = s.uses.iter().map(|u| faces.faces[u.face].support).collect();
        supports.dedup();
        let curve = &db.curves[k];
        // On the borders of two supports (the M6's tip edge is a border of its lower wing
        // surface and of its tip cap, 3.5e-7 m apart), the curve follows the one it fits
        // best: the one the file's curve was made from.
        let Some((border, _)) = supports
            .iter()
            .filter_map(|&i| border_of(&db.surfaces[i], &curve.arcs, faces.sew))
            .min_by(|a, b| a.1.total_cmp(&b.1))
        else {
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
/// made of `arcs` runs within `tol`, if any, with the curve's largest distance from it (the
/// best-fitting side when several do).
fn border_of(sup: &SupportSurface, arcs: &[Arc], tol: f64) -> Option<(Vec<Arc>, f64)> {
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
    sides
        .into_iter()
        .filter_map(|side| {
            let samples = super::curve_samples(&side, 16);
            let worst = probe
                .iter()
                .map(|(_, p)| super::foot_on_arcs(&side, &samples, p).0)
                .fold(0.0, f64::max);
            (worst <= tol).then_some((side, worst))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
}
