//! STEP → neutral model: the solids (`MANIFOLD_SOLID_BREP`, `BREP_WITH_VOIDS`), surface
//! models (`SHELL_BASED_SURFACE_MODEL`) and free shells of the file, their faces
//! (`ADVANCED_FACE`, `FACE_SURFACE`) bounded by edge loops of `ORIENTED_EDGE`s over
//! `EDGE_CURVE`s, the units of their representation context, and the exact curves and
//! surfaces they use ([`geometry`]).
//!
//! An edge use runs between the parameters of its two vertices on the edge's curve (closed
//! form on lines and conics, Newton on others); a closed edge (one vertex) makes a full
//! period. A face's orientation in its shell (`same_sense`, the oriented shell's and void's
//! orientation) is kept for the orientation stage.

mod geometry;

use std::collections::{BTreeSet, HashMap};

use step::{Entity, Id, StepFile};

use super::Error;
use super::model::{
    CadFace, CadLoop, CadModel, CadShell, Curve, EdgeUse, LengthUnit, ModelCurve, ModelSurface,
    Source, Surface,
};
use geometry::curve_period;

pub(super) struct Front<'a> {
    file: &'a StepFile,
    model: CadModel,
    /// Radians per unit of the file's plane angles.
    angle: f64,
    surface_index: HashMap<Id, usize>,
    curve_index: HashMap<Id, (usize, Option<(f64, f64)>)>,
}

/// A curve in a face's (u, v) parameters and its parameter range.
type UvCurve = (Curve, f64, f64);

fn source(file: &StepFile, id: Id) -> Source {
    Source {
        label: id.to_string(),
        kind: file.instance(id).map_or("?".into(), |i| i.type_name()),
    }
}

/// The roots of the shape: shells with the orientation of their faces (`false`: every
/// face is reversed).
struct Roots {
    shells: Vec<(Id, bool)>,
    /// The representation items found, for the units.
    items: Vec<Id>,
}

/// Converts a STEP file into the neutral model.
pub(super) fn model(file: &StepFile) -> Result<CadModel, Error> {
    let roots = roots(file)?;
    if roots.shells.is_empty() {
        return Err(Error::Model {
            file: file.name.clone(),
            reason: "no solid, shell-based surface model or shell to import \
                     (MANIFOLD_SOLID_BREP, SHELL_BASED_SURFACE_MODEL, CLOSED_SHELL, OPEN_SHELL)"
                .into(),
        });
    }
    // Units: the context of the representation that holds the first root item, else the
    // first context with units.
    let ctx = file
        .entities
        .iter()
        .find_map(|e| match e {
            Entity::Representation(r) if r.items.iter().any(|i| roots.items.contains(i)) => {
                Some(r.context)
            }
            _ => None,
        })
        .or_else(|| {
            file.iter().find_map(|(i, e)| match e {
                Entity::Context(c) if !c.units.is_empty() => Some(i.id),
                _ => None,
            })
        });
    let units = match ctx {
        Some(c) => Some(file.units(c)?),
        None => None,
    };
    let name = file
        .iter()
        .find_map(|(i, _)| {
            let r = i.record("PRODUCT")?;
            match r.params.first() {
                Some(step::Value::Str(s)) if !s.trim().is_empty() => Some(s.trim().to_string()),
                _ => None,
            }
        })
        .unwrap_or_default();
    let mut warnings = Vec::new();
    if file
        .entities
        .iter()
        .any(|e| matches!(e, Entity::PlacedRepresentation(_)))
    {
        warnings.push(
            "the file places representations in an assembly; the placements are not applied \
             (every solid is read in its own coordinates)"
                .to_string(),
        );
    }
    let length = units.as_ref().and_then(|u| u.length);
    let mut f = Front {
        file,
        model: CadModel {
            file: file.name.clone(),
            format: "STEP",
            name,
            unit: length.map(LengthUnit::from_metres),
            resolution: units.as_ref().and_then(|u| u.uncertainty),
            warnings,
            ..CadModel::default()
        },
        angle: units.as_ref().and_then(|u| u.plane_angle).unwrap_or(1.0),
        surface_index: HashMap::new(),
        curve_index: HashMap::new(),
    };
    if length.is_none() {
        f.model
            .warnings
            .push("the file assigns no length unit; its lengths are taken as they are".into());
    }
    for &(shell, sense) in &roots.shells {
        f.shell(shell, sense)?;
    }
    warn_unsupported(file, &mut f.model.warnings);
    Ok(f.model)
}

/// Words of the type names of geometric and topological entities ...
const GEOMETRIC: [&str; 8] = [
    "SURFACE", "CURVE", "SOLID", "SHELL", "FACE", "EDGE", "LOOP", "VERTEX",
];
/// ... and of the presentation and product data that name them (not geometry).
const NOT_GEOMETRIC: [&str; 8] = [
    "STYLE",
    "REPRESENTATION",
    "PRESENTATION",
    "RELATIONSHIP",
    "USAGE",
    "DEFINITION",
    "ASSIGNMENT",
    "PROPERTY",
];

/// Names every instance of a geometric or topological type the reader does not know (it
/// was skipped: no shell holds it, or the shell would have failed naming it).
fn warn_unsupported(file: &StepFile, warnings: &mut Vec<String>) {
    for (inst, e) in file.iter() {
        if !matches!(e, Entity::Other) {
            continue;
        }
        let ty = inst.type_name();
        if GEOMETRIC.iter().any(|w| ty.contains(w)) && !NOT_GEOMETRIC.iter().any(|w| ty.contains(w))
        {
            warnings.push(format!(
                "#{} (line {}, {ty}) is not supported and was skipped",
                inst.id.0, inst.line
            ));
        }
    }
}

/// Solids, surface models and the shells no solid or model holds.
fn roots(file: &StepFile) -> Result<Roots, Error> {
    let mut shells: Vec<(Id, bool)> = Vec::new();
    let mut items = Vec::new();
    let mut held = BTreeSet::new();
    let oriented = |from: Id, id: Id| -> Result<(Id, bool), Error> {
        match file.get(from, id, "shell")?.1 {
            Entity::Shell(_) => Ok((id, true)),
            Entity::OrientedShell(o) => match file.get(id, o.shell, "shell_element")?.1 {
                Entity::Shell(_) => Ok((o.shell, o.orientation)),
                _ => Err(file
                    .wrong_type(id, o.shell, "shell_element", "CLOSED_SHELL or OPEN_SHELL")
                    .into()),
            },
            _ => Err(file.wrong_type(from, id, "shell", "a shell").into()),
        }
    };
    for (inst, e) in file.iter() {
        match e {
            Entity::ManifoldSolidBrep(m) => {
                items.push(inst.id);
                let s = oriented(inst.id, m.outer)?;
                held.insert(s.0);
                shells.push(s);
                for &v in &m.voids {
                    let s = oriented(inst.id, v)?;
                    held.insert(s.0);
                    shells.push(s);
                }
            }
            Entity::ShellBasedSurfaceModel(m) => {
                items.push(inst.id);
                for &s in &m.shells {
                    let s = oriented(inst.id, s)?;
                    held.insert(s.0);
                    shells.push(s);
                }
            }
            _ => {}
        }
    }
    // Shells that no solid or model holds (some writers put shells in the representation).
    let referenced: BTreeSet<Id> = file
        .entities
        .iter()
        .filter(|e| matches!(e, Entity::OrientedShell(_)))
        .flat_map(|e| e.references())
        .collect();
    for (inst, e) in file.iter() {
        if let Entity::Shell(_) = e
            && !held.contains(&inst.id)
            && !referenced.contains(&inst.id)
        {
            items.push(inst.id);
            shells.push((inst.id, true));
        }
    }
    Ok(Roots { shells, items })
}

impl Front<'_> {
    fn bad(&self, id: Id, reason: impl Into<String>) -> Error {
        Error::Step(self.file.invalid(id, reason))
    }

    fn surface(&mut self, id: Id) -> Result<usize, Error> {
        if let Some(&k) = self.surface_index.get(&id) {
            return Ok(k);
        }
        let surface = self.build_surface(id, 0)?;
        self.model.surfaces.push(ModelSurface {
            source: source(self.file, id),
            surface,
        });
        let k = self.model.surfaces.len() - 1;
        self.surface_index.insert(id, k);
        Ok(k)
    }

    fn curve(&mut self, id: Id) -> Result<(usize, Option<(f64, f64)>), Error> {
        if let Some(&c) = self.curve_index.get(&id) {
            return Ok(c);
        }
        let (curve, range) = self.build_curve(id, 0)?;
        self.model.curves.push(ModelCurve {
            source: source(self.file, id),
            curve,
        });
        let c = (self.model.curves.len() - 1, range);
        self.curve_index.insert(id, c);
        Ok(c)
    }

    /// The parameter of vertex point `p` on `curve` (an error naming `edge` when there is
    /// none).
    fn param_on(
        &self,
        edge: Id,
        curve: &Curve,
        p: &crate::prelude::Point3,
        range: Option<(f64, f64)>,
    ) -> Result<f64, Error> {
        curve
            .closest_param(p, range)
            .filter(|t| t.is_finite())
            .ok_or_else(|| self.bad(edge, "cannot place a vertex on the edge's curve"))
    }

    fn vertex(&self, from: Id, id: Id) -> Result<crate::prelude::Point3, Error> {
        match self.file.get(from, id, "vertex")?.1 {
            Entity::VertexPoint(v) => Ok(crate::prelude::Point3::from(self.file.point(
                id,
                v.point,
                "vertex_geometry",
            )?)),
            _ => Err(self
                .file
                .wrong_type(from, id, "vertex", "VERTEX_POINT")
                .into()),
        }
    }

    /// One use of an `EDGE_CURVE` in a loop; `forward`: along the edge (start → end vertex).
    fn edge_use(
        &mut self,
        oe: Id,
        edge: Id,
        forward: bool,
        face_surface: Id,
    ) -> Result<(EdgeUse, Vec<UvCurve>), Error> {
        let Entity::EdgeCurve(ec) = self.file.get(oe, edge, "edge_element")?.1.clone() else {
            return Err(self
                .file
                .wrong_type(oe, edge, "edge_element", "EDGE_CURVE")
                .into());
        };
        let (c, range) = self.curve(ec.curve)?;
        let curve = &self.model.curves[c].curve;
        let a = self.vertex(edge, ec.start)?;
        let b = self.vertex(edge, ec.end)?;
        let mut ta = self.param_on(edge, curve, &a, range)?;
        let mut tb = self.param_on(edge, curve, &b, range)?;
        let closed = ec.start == ec.end;
        match curve_period(curve) {
            Some(p) => {
                // Along the curve from the start of the edge's run to its end.
                let (s, e) = if ec.same_sense {
                    (&mut ta, &mut tb)
                } else {
                    (&mut tb, &mut ta)
                };
                if let Some((lo, _)) = range {
                    while *s < lo - 1e-9 * p {
                        *s += p;
                    }
                }
                while *e <= *s + if closed { 1e-9 * p } else { 0.0 } {
                    *e += p;
                }
                if closed && *e - *s < 0.5 * p {
                    *e += p;
                }
            }
            None if closed => {
                // A closed non-periodic curve (a closed B-spline): its whole range.
                let (lo, hi) =
                    range.ok_or_else(|| self.bad(edge, "a closed edge on an unbounded curve"))?;
                if ec.same_sense {
                    (ta, tb) = (lo, hi);
                } else {
                    (ta, tb) = (hi, lo);
                }
            }
            None => {
                // A vertex at the joint of a closed non-periodic curve (a wing section's
                // trailing edge, where the edges of the upper and lower sides start and end)
                // is at both ends of its range: the edge runs from the start along the curve
                // (same_sense) or against it.
                if let Some((lo, hi)) = range {
                    let (pl, ph) = (curve.point(lo), curve.point(hi));
                    let extent = (0..=8)
                        .map(|k| (curve.point(lo + (hi - lo) * k as f64 / 8.0) - pl).norm())
                        .fold(0.0, f64::max);
                    let near = 1e-7 * extent;
                    let at_both = |p: &crate::prelude::Point3| {
                        (pl - p).norm() <= near && (ph - p).norm() <= near
                    };
                    if at_both(&a) {
                        ta = if ec.same_sense { lo } else { hi };
                    }
                    if at_both(&b) {
                        tb = if ec.same_sense { hi } else { lo };
                    }
                }
            }
        }
        // pcurves of this edge on the face's surface (for the trimming box).
        let mut uv = Vec::new();
        if let Entity::SurfaceCurve(sc) = self.file.get(edge, ec.curve, "edge_geometry")?.1 {
            for &g in &sc.associated {
                if let Entity::Pcurve(pc) = self.file.get(ec.curve, g, "associated_geometry")?.1
                    && pc.surface == face_surface
                    && let Entity::Representation(r) =
                        self.file.get(g, pc.representation, "reference_to_curve")?.1
                    && let Some(&item) = r.items.first()
                {
                    let (pcurve, _) = self.build_curve(item, 1)?;
                    uv.push((pcurve, ta.min(tb), ta.max(tb)));
                }
            }
        }
        let (t0, t1) = if forward { (ta, tb) } else { (tb, ta) };
        Ok((
            EdgeUse {
                curve: c,
                t0,
                t1,
                edge: Some(source(self.file, edge)),
                pcurve: None,
            },
            uv,
        ))
    }

    fn shell(&mut self, id: Id, sense: bool) -> Result<(), Error> {
        let Entity::Shell(s) = self.file.get(id, id, "shell")?.1.clone() else {
            return Err(self
                .file
                .wrong_type(id, id, "shell", "CLOSED_SHELL or OPEN_SHELL")
                .into());
        };
        let mut faces = Vec::with_capacity(s.faces.len());
        for &fid in &s.faces {
            let Entity::Face(fc) = self.file.get(id, fid, "cfs_faces")?.1.clone() else {
                return Err(self
                    .file
                    .wrong_type(id, fid, "cfs_faces", "ADVANCED_FACE or FACE_SURFACE")
                    .into());
            };
            let surface = self.surface(fc.surface)?;
            let nurbs = matches!(&self.model.surfaces[surface].surface, Surface::Nurbs(_));
            let mut loops = Vec::new();
            let mut uv_all = Vec::new();
            for &b in &fc.bounds {
                let Entity::FaceBound(fb) = self.file.get(fid, b, "bounds")?.1.clone() else {
                    return Err(self.file.wrong_type(fid, b, "bounds", "FACE_BOUND").into());
                };
                match self.file.get(b, fb.bound, "bound")?.1.clone() {
                    Entity::EdgeLoop(el) => {
                        let mut edges = Vec::with_capacity(el.edges.len());
                        for &oe in &el.edges {
                            let Entity::OrientedEdge(o) =
                                self.file.get(fb.bound, oe, "edge_list")?.1.clone()
                            else {
                                return Err(self
                                    .file
                                    .wrong_type(fb.bound, oe, "edge_list", "ORIENTED_EDGE")
                                    .into());
                            };
                            let (u, uv) = self.edge_use(oe, o.edge, o.orientation, fc.surface)?;
                            edges.push(u);
                            uv_all.extend(uv);
                        }
                        if !fb.orientation {
                            edges.reverse();
                            for e in &mut edges {
                                std::mem::swap(&mut e.t0, &mut e.t1);
                            }
                        }
                        loops.push(CadLoop {
                            edges,
                            outer: fb.outer,
                        });
                    }
                    // A vertex loop bounds nothing (a pole of a sphere or a cone's apex).
                    Entity::VertexLoop(_) => {}
                    _ => {
                        return Err(self
                            .file
                            .wrong_type(b, fb.bound, "bound", "EDGE_LOOP or VERTEX_LOOP")
                            .into());
                    }
                }
            }
            // Put the outer loop first when the file marks one.
            if let Some(k) = loops.iter().position(|l| l.outer)
                && k > 0
            {
                let l = loops.remove(k);
                loops.insert(0, l);
            }
            self.model.faces.push(CadFace {
                source: source(self.file, fid),
                surface,
                loops,
                same_sense: Some(fc.same_sense == sense),
                // Parameter-space curves only where the parametrisation is the file's own
                // (B-splines); the others are bounded from the edges in 3D.
                uv_bounds: if nurbs { uv_all } else { Vec::new() },
            });
            faces.push(self.model.faces.len() - 1);
        }
        self.model.shells.push(CadShell {
            source: source(self.file, id),
            faces,
            closed: s.closed,
        });
        Ok(())
    }
}
