//! IGES → neutral model: faces (144 trimmed surfaces with 142 boundaries, 143 bounded
//! surfaces with 141 boundaries, 510 B-rep faces with 508 loops over 504 edges, bounded 108
//! planes, independent untrimmed surfaces), shells (514, 186), and the exact curves and
//! surfaces they use ([`geometry`]).
//!
//! Entities that nothing converts are listed in the model's warnings by name; an entity
//! that bounds a face and cannot be converted is an error naming it.

mod geometry;

use std::collections::{BTreeMap, BTreeSet, HashMap};

use iges::{DeId, Entity, IgesFile};

use super::Error;
use super::model::{
    CadFace, CadLoop, CadModel, CadShell, Curve, EdgeUse, LengthUnit, ModelCurve, ModelSurface,
    Source,
};

/// One boundary curve of a face loop before conversion.
struct Leaf {
    /// The IGES curve (a leaf: not a 102 or 142).
    de: DeId,
    /// Traversed against its own direction (141 SENSE 2, 508 OF 0).
    reversed: bool,
    /// For a parameter-space curve (a 142 without model-space curve): the surface it lies
    /// on; the model curve is then S(B(t)).
    on_surface: Option<DeId>,
    /// The 504 edge (list, index) it is, in a B-rep.
    edge: Option<Source>,
}

pub(super) struct Front<'a> {
    file: &'a IgesFile,
    model: CadModel,
    curve_index: HashMap<(DeId, Option<DeId>), usize>,
    curve_range: Vec<(f64, f64)>,
    surface_index: HashMap<DeId, usize>,
}

fn source(file: &IgesFile, id: DeId) -> Source {
    Source {
        label: format!("D{}", id.line()),
        kind: file.get(id).map_or(0, |r| r.de.entity_type).to_string(),
    }
}

/// Converts an IGES file into the neutral model.
pub(super) fn model(file: &IgesFile) -> Result<CadModel, Error> {
    let name = if file.global.sender_product_id.trim().is_empty() {
        file.start.lines().next().unwrap_or("").trim().to_string()
    } else {
        file.global.sender_product_id.trim().to_string()
    };
    let mut f = Front {
        file,
        model: CadModel {
            file: file.name.clone(),
            format: "IGES",
            name,
            unit: file
                .global
                .unit_in_mm()
                .map(|mm| LengthUnit::from_metres(mm * 1e-3)),
            resolution: (file.global.resolution > 0.0).then_some(file.global.resolution),
            ..CadModel::default()
        },
        curve_index: HashMap::new(),
        curve_range: Vec::new(),
        surface_index: HashMap::new(),
    };
    f.faces()?;
    f.shells()?;
    f.warn_unused();
    Ok(f.model)
}

/// The curve of entity `id` and its range (for tests of the conversion).
#[cfg(test)]
pub(super) fn curve_of(file: &IgesFile, id: DeId) -> Result<(Curve, (f64, f64)), Error> {
    front(file).build_curve(id, 0)
}

/// The surface of entity `id` (for tests of the conversion).
#[cfg(test)]
pub(super) fn surface_of(file: &IgesFile, id: DeId) -> Result<super::model::Surface, Error> {
    front(file).build_surface(id, 0)
}

#[cfg(test)]
fn front(file: &IgesFile) -> Front<'_> {
    Front {
        file,
        model: CadModel::default(),
        curve_index: HashMap::new(),
        curve_range: Vec::new(),
        surface_index: HashMap::new(),
    }
}

impl Front<'_> {
    fn bad(&self, id: DeId, reason: impl Into<String>) -> Error {
        Error::Entity {
            file: self.file.name.clone(),
            entity: format!(
                "entity at D line {} (type {})",
                id.line(),
                self.file.get(id).map_or(0, |r| r.de.entity_type)
            ),
            reason: reason.into(),
        }
    }

    /// Faces, loops and the containers (144, 143, 510, 142, 141, 508) carry no transform
    /// the import would apply: refuse one rather than ignore it.
    fn untransformed(&self, id: DeId) -> Result<(), Error> {
        if self.own_map(id)?.is_some() {
            return Err(self.bad(
                id,
                "a transformation matrix on a face or loop entity is not supported",
            ));
        }
        Ok(())
    }

    fn surface(&mut self, id: DeId) -> Result<usize, Error> {
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

    /// The model curve of a leaf (cached per entity and surface).
    fn curve(&mut self, leaf: &Leaf) -> Result<usize, Error> {
        let key = (leaf.de, leaf.on_surface);
        if let Some(&k) = self.curve_index.get(&key) {
            return Ok(k);
        }
        let (curve, range) = match leaf.on_surface {
            None => self.build_curve(leaf.de, 0)?,
            Some(s) => {
                let si = self.surface(s)?;
                let (pcurve, range) = self.build_curve(leaf.de, 0)?;
                (
                    Curve::OnSurface {
                        surface: Box::new(self.model.surfaces[si].surface.clone()),
                        pcurve: Box::new(pcurve),
                    },
                    range,
                )
            }
        };
        self.model.curves.push(ModelCurve {
            source: source(self.file, leaf.de),
            curve,
        });
        self.curve_range.push(range);
        let k = self.model.curves.len() - 1;
        self.curve_index.insert(key, k);
        Ok(k)
    }

    fn edge_use(&mut self, leaf: &Leaf) -> Result<EdgeUse, Error> {
        let c = self.curve(leaf)?;
        let (a, b) = self.curve_range[c];
        let (t0, t1) = if leaf.reversed { (b, a) } else { (a, b) };
        Ok(EdgeUse {
            curve: c,
            t0,
            t1,
            edge: leaf.edge.clone(),
            pcurve: None,
        })
    }

    /// Leaves of a curve: 102 composites and 142 model curves resolved.
    fn leaves(
        &self,
        id: DeId,
        reversed: bool,
        out: &mut Vec<Leaf>,
        depth: usize,
    ) -> Result<(), Error> {
        if depth > 16 {
            return Err(self.bad(id, "curves nest more than 16 levels deep"));
        }
        let rec = self
            .file
            .get(id)
            .ok_or_else(|| self.bad(id, "pointer names no entity"))?;
        match &rec.entity {
            Entity::CompositeCurve(c) if rec.de.transform.is_none() => {
                let mut v = Vec::new();
                for &p in &c.curves {
                    self.leaves(p, false, &mut v, depth + 1)?;
                }
                if reversed {
                    v.reverse();
                    v.iter_mut().for_each(|l| l.reversed = !l.reversed);
                }
                out.extend(v);
            }
            Entity::CurveOnSurface(c) => {
                self.untransformed(id)?;
                match (c.model_curve, c.param_curve) {
                    (Some(m), _) => self.leaves(m, reversed, out, depth + 1)?,
                    (None, Some(b)) => {
                        let mut v = Vec::new();
                        self.leaves(b, reversed, &mut v, depth + 1)?;
                        v.iter_mut().for_each(|l| l.on_surface = Some(c.surface));
                        out.extend(v);
                    }
                    (None, None) => {
                        return Err(self.bad(id, "curve on surface without any curve"));
                    }
                }
            }
            _ => out.push(Leaf {
                de: id,
                reversed,
                on_surface: None,
                edge: None,
            }),
        }
        Ok(())
    }

    /// True when the face's parameter-space curves are trusted for its trimming box: on
    /// B-splines (128) and 114 splines, whose parameters writers agree on. On the others
    /// (120's order and scaling, the analytic surfaces' degrees or radians) the box comes
    /// from the 3D edges.
    fn uv_trusted(&self, surface: usize) -> bool {
        matches!(
            self.model.surfaces[surface].surface,
            super::model::Surface::Nurbs(_) | super::model::Surface::Spline { .. }
        )
    }

    /// The parameter-space curves of a face boundary, with their ranges (for the trimming
    /// box of the surface).
    fn uv_curve(&self, id: DeId) -> Result<(Curve, f64, f64), Error> {
        let (c, (a, b)) = self.build_curve(id, 0)?;
        Ok((c, a, b))
    }

    fn loop_of(&mut self, leaves: Vec<Leaf>, outer: bool) -> Result<CadLoop, Error> {
        let mut edges = Vec::with_capacity(leaves.len());
        for l in &leaves {
            edges.push(self.edge_use(l)?);
        }
        Ok(CadLoop { edges, outer })
    }

    fn faces(&mut self) -> Result<(), Error> {
        let f = self.file;
        let mut used_surfaces = BTreeSet::new();
        for (id, r) in f.iter() {
            match &r.entity {
                Entity::TrimmedSurface(t) => {
                    self.untransformed(id)?;
                    used_surfaces.insert(t.surface);
                    let surface = self.surface(t.surface)?;
                    let mut loops = Vec::new();
                    let mut uv = Vec::new();
                    let bounds: Vec<(DeId, bool)> = t
                        .outer
                        .map(|o| (o, true))
                        .into_iter()
                        .chain(t.inner.iter().map(|&b| (b, false)))
                        .collect();
                    if t.outer.is_none() && !t.inner.is_empty() {
                        // The outer loop is the domain boundary: an empty loop stands for it.
                        loops.push(CadLoop {
                            edges: Vec::new(),
                            outer: true,
                        });
                    }
                    for (b, outer) in bounds {
                        f.expect(id, b, &[142]).map_err(Error::Iges)?;
                        if let Entity::CurveOnSurface(c) = &f.get(b).expect("checked").entity
                            && let Some(pc) = c.param_curve
                        {
                            uv.push(self.uv_curve(pc)?);
                        }
                        let mut lp = Vec::new();
                        self.leaves(b, false, &mut lp, 0)?;
                        loops.push(self.loop_of(lp, outer)?);
                    }
                    if !self.uv_trusted(surface) {
                        uv.clear();
                    }
                    self.push_face(id, surface, loops, uv, None);
                }
                Entity::BoundedSurface(s) => {
                    self.untransformed(id)?;
                    used_surfaces.insert(s.surface);
                    let surface = self.surface(s.surface)?;
                    let mut loops = Vec::new();
                    let mut uv = Vec::new();
                    for (k, &b) in s.boundaries.iter().enumerate() {
                        let r = f.expect(id, b, &[141]).map_err(Error::Iges)?;
                        self.untransformed(b)?;
                        let Entity::Boundary(bd) = &r.entity else {
                            continue;
                        };
                        let mut lp = Vec::new();
                        for c in &bd.curves {
                            self.leaves(c.model_curve, c.reversed, &mut lp, 0)?;
                            for &p in &c.param_curves {
                                uv.push(self.uv_curve(p)?);
                            }
                        }
                        loops.push(self.loop_of(lp, k == 0)?);
                    }
                    if !self.uv_trusted(surface) {
                        uv.clear();
                    }
                    self.push_face(id, surface, loops, uv, None);
                }
                Entity::Face(fc) => {
                    self.untransformed(id)?;
                    used_surfaces.insert(fc.surface);
                    let surface = self.surface(fc.surface)?;
                    let trusted = self.uv_trusted(surface);
                    let mut loops = Vec::new();
                    let mut uv = Vec::new();
                    if !fc.outer_loop_first && !fc.loops.is_empty() {
                        loops.push(CadLoop {
                            edges: Vec::new(),
                            outer: true,
                        });
                    }
                    for (k, &l) in fc.loops.iter().enumerate() {
                        let r = f.expect(id, l, &[508]).map_err(Error::Iges)?;
                        self.untransformed(l)?;
                        let Entity::Loop(lp) = &r.entity else {
                            continue;
                        };
                        let mut leaves = Vec::new();
                        for e in &lp.edges {
                            if e.is_vertex {
                                continue;
                            }
                            let er = f.expect(l, e.list, &[504]).map_err(Error::Iges)?;
                            let Entity::EdgeList(el) = &er.entity else {
                                continue;
                            };
                            let edge = el.edges.get(e.index - 1).ok_or_else(|| {
                                self.bad(
                                    l,
                                    format!(
                                        "edge index {} is beyond the {} edges of D{}",
                                        e.index,
                                        el.edges.len(),
                                        e.list.line()
                                    ),
                                )
                            })?;
                            let mut v = Vec::new();
                            self.leaves(edge.curve, !e.agrees, &mut v, 0)?;
                            let key = Source {
                                label: format!("D{}[{}]", e.list.line(), e.index),
                                kind: "504".into(),
                            };
                            v.iter_mut().for_each(|x| x.edge = Some(key.clone()));
                            leaves.extend(v);
                            if trusted {
                                for &(_, c) in &e.param_curves {
                                    uv.push(self.uv_curve(c)?);
                                }
                            }
                        }
                        loops.push(self.loop_of(leaves, k == 0 && fc.outer_loop_first)?);
                    }
                    self.push_face(id, surface, loops, uv, None);
                }
                Entity::Plane(p) if r.de.form == 1 && p.boundary.is_some() => {
                    // A bounded plane is a face unless a 144 or 143 trims it.
                    let Some(b) = p.boundary else { continue };
                    if r.de.status.subordinate != 0 {
                        continue;
                    }
                    let surface = self.surface(id)?;
                    let mut lp = Vec::new();
                    self.leaves(b, false, &mut lp, 0)?;
                    let lp = self.loop_of(lp, true)?;
                    self.push_face(id, surface, vec![lp], Vec::new(), None);
                    used_surfaces.insert(id);
                }
                Entity::CurveOnSurface(c) => {
                    used_surfaces.insert(c.surface);
                }
                Entity::Boundary(b) => {
                    used_surfaces.insert(b.surface);
                }
                _ => {}
            }
        }
        // Independent surfaces used by nothing: untrimmed faces over their natural domain.
        for (id, r) in f.iter() {
            let is_surface = matches!(
                r.entity,
                Entity::SplineSurface(_)
                    | Entity::BSplineSurface(_)
                    | Entity::RuledSurface(_)
                    | Entity::SurfaceOfRevolution(_)
                    | Entity::TabulatedCylinder(_)
                    | Entity::OffsetSurface(_)
                    | Entity::SphericalSurface(_)
                    | Entity::ToroidalSurface(_)
            );
            if is_surface && r.de.status.subordinate == 0 && !used_surfaces.contains(&id) {
                let surface = self.surface(id)?;
                self.push_face(id, surface, Vec::new(), Vec::new(), None);
            }
        }
        Ok(())
    }

    fn push_face(
        &mut self,
        id: DeId,
        surface: usize,
        loops: Vec<CadLoop>,
        uv: Vec<(Curve, f64, f64)>,
        same_sense: Option<bool>,
    ) {
        self.model.faces.push(CadFace {
            source: source(self.file, id),
            surface,
            loops,
            same_sense,
            uv_bounds: uv,
        });
    }

    /// 186 solids and 514 shells: the faces' orientation (OF flags, the solid's SOF and VOF).
    fn shells(&mut self) -> Result<(), Error> {
        let f = self.file;
        let face_of: BTreeMap<String, usize> = self
            .model
            .faces
            .iter()
            .enumerate()
            .map(|(k, fc)| (fc.source.label.clone(), k))
            .collect();
        // Shell → its orientation in the solid that holds it.
        let mut shell_sense: BTreeMap<DeId, bool> = BTreeMap::new();
        for (_, r) in f.iter() {
            if let Entity::ManifoldSolid(m) = &r.entity {
                shell_sense.insert(m.shell, m.shell_agrees);
                for &(v, vof) in &m.voids {
                    shell_sense.insert(v, vof);
                }
            }
        }
        for (id, r) in f.iter() {
            let Entity::Shell(s) = &r.entity else {
                continue;
            };
            let sense = shell_sense.get(&id).copied().unwrap_or(true);
            let mut faces = Vec::new();
            for &(fid, of) in &s.faces {
                f.expect(id, fid, &[510]).map_err(Error::Iges)?;
                if let Some(&k) = face_of.get(&format!("D{}", fid.line())) {
                    let same = of == sense;
                    let face = &mut self.model.faces[k];
                    // 508 loops run counter-clockwise about the surface normal; the model's
                    // run counter-clockwise about the face's (outward) normal.
                    if !same && face.same_sense.is_none() {
                        for lp in &mut face.loops {
                            lp.edges.reverse();
                            for e in &mut lp.edges {
                                std::mem::swap(&mut e.t0, &mut e.t1);
                            }
                        }
                    }
                    face.same_sense = Some(same);
                    faces.push(k);
                }
            }
            self.model.shells.push(CadShell {
                source: source(f, id),
                faces,
                closed: r.de.form != 2,
            });
        }
        Ok(())
    }

    /// Lists entities of types the import does not convert and that no face uses.
    fn warn_unused(&mut self) {
        for (id, r) in self.file.iter() {
            let t = r.de.entity_type;
            match &r.entity {
                Entity::Unknown(_) => self.model.warnings.push(format!(
                    "entity at D line {} (type {}, form {}) is not supported and was skipped",
                    id.line(),
                    t,
                    r.de.form
                )),
                Entity::CopiousData(_)
                    if (1..=3).contains(&r.de.form) && r.de.status.subordinate == 0 =>
                {
                    self.model.warnings.push(format!(
                        "entity at D line {} (type 106, form {}) is a point set and was skipped",
                        id.line(),
                        r.de.form
                    ))
                }
                _ => {}
            }
        }
    }
}
