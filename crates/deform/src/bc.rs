//! Boundary conditions (paper §4.3 and Eq. 34): moving markers (rigid motion or prescribed
//! node displacements), fixed markers, markers sliding on their plane; classification of
//! every node into moving / fixed / constrained (sliding) / free, with a precedence for nodes
//! shared by several markers.
//!
//! Precedence (a node is moved once, by the first that applies): (1) an explicit node
//! displacement; (2) a moving (rigid) marker; (3) a sliding marker — the node keeps to the
//! plane of every sliding marker it belongs to *and* to the local tangent plane of every
//! other (fixed) marker it belongs to, so a node on the seam between a symmetry plane and a
//! planar far-field face slides along the seam (a line) and one on three planes is frozen (a
//! corner); a node where a fixed marker is not locally flat is frozen; (4) fixed: nodes of
//! every other marker, named `fixed` or not named at all, do not move.

use std::collections::HashMap;

use mesh::{ElementKind, Mesh};
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::solve::Constraint;
use crate::support::{SupKind, SupNode, Support, Supports, check_kind, place, point};

/// A rigid motion of a marker (paper Eq. 34): rotation by `angle_deg` about the axis through
/// `axis_point` along `axis_dir`, then a translation.
///
/// Sign convention: Eq. 34 reads r = x_c + cos θ (r⁰ − x_c) − sin θ [(r⁰ − x_c) ∧ b] + Δr_t,
/// and −(d ∧ b) = b ∧ d, so a positive angle turns counter-clockwise about b (right-hand
/// rule). The paper's left side "Δr_i" is the new position; the displacement is r − r⁰.
/// Pitching an airfoil (x downstream, y up) nose-up is a negative angle about +z.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RigidMotion {
    /// Rotation angle θ in degrees (right-hand rule about `axis_dir`).
    pub angle_deg: f64,
    /// A point x₀ on the rotation axis.
    pub axis_point: [f64; 3],
    /// Direction b of the rotation axis (normalised internally).
    pub axis_dir: [f64; 3],
    /// Translation Δr_t applied after the rotation.
    pub translation: [f64; 3],
}

impl RigidMotion {
    /// A pure translation.
    pub fn translation(t: [f64; 3]) -> Self {
        Self {
            angle_deg: 0.0,
            axis_point: [0.0; 3],
            axis_dir: [0.0, 0.0, 1.0],
            translation: t,
        }
    }

    /// Checks the axis (finite, non-zero direction) and values.
    pub fn validate(&self) -> Result<()> {
        let d = Vector3::from(self.axis_dir);
        let finite = self.angle_deg.is_finite()
            && self
                .axis_point
                .iter()
                .chain(&self.axis_dir)
                .chain(&self.translation)
                .all(|v| v.is_finite());
        if !finite || (self.angle_deg != 0.0 && d.norm() == 0.0) {
            return Err(Error::BadMotion {
                reason: format!(
                    "invalid rigid motion {self:?} (axis direction must be non-zero and values finite)"
                ),
            });
        }
        Ok(())
    }

    /// Position of `p` after the fraction `s` ∈ [0, 1] of the motion (angle s θ, translation
    /// s Δr_t; Eqs. 34–35). `s = 0` returns `p` exactly.
    pub fn apply(&self, p: [f64; 3], s: f64) -> [f64; 3] {
        if s == 0.0 || (self.angle_deg == 0.0 && self.translation == [0.0; 3]) {
            return p;
        }
        let r0 = Vector3::from(p);
        let t = Vector3::from(self.translation) * s;
        if self.angle_deg == 0.0 {
            return (r0 + t).into();
        }
        let b = Vector3::from(self.axis_dir).normalize();
        let x0 = Vector3::from(self.axis_point);
        let xc = x0 + b * (r0 - x0).dot(&b); // Eq. 35
        let th = (s * self.angle_deg).to_radians();
        let d = r0 - xc;
        let r = xc + d * th.cos() - d.cross(&b) * th.sin() + t; // Eq. 34
        r.into()
    }

    /// The rotation matrix of the fraction `s` of the motion.
    pub fn rotation(&self, s: f64) -> Matrix3<f64> {
        if self.angle_deg == 0.0 || s == 0.0 {
            return Matrix3::identity();
        }
        let b = nalgebra::Unit::new_normalize(Vector3::from(self.axis_dir));
        *nalgebra::Rotation3::from_axis_angle(&b, (s * self.angle_deg).to_radians()).matrix()
    }
}

/// What a marker does.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum MarkerRole {
    /// The marker moves rigidly (Eq. 34).
    Rigid(RigidMotion),
    /// The marker stays fixed (the default for markers not named).
    Fixed,
    /// The marker's nodes slide on the marker's plane (the marker must be planar).
    SlidePlane,
    /// The marker's nodes slide on the support curves and surfaces of the geometry they are
    /// classified on (paper §4.3, Eqs. 27–33); needs [`crate::Supports`]
    /// ([`crate::deform_on_supports`]). Corners are frozen.
    SlideOnSupport,
}

/// The boundary conditions of a deformation.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct BoundaryConditions {
    /// Roles of named markers; markers not listed are fixed.
    pub markers: Vec<(String, MarkerRole)>,
    /// Prescribed displacements of individual nodes (node index as in the mesh).
    pub displacements: Vec<(u32, [f64; 3])>,
}

/// A plane fitted to a sliding marker.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlaneInfo {
    /// Marker name.
    pub marker: String,
    /// A point of the plane (centroid of the marker's nodes).
    pub point: [f64; 3],
    /// Unit normal.
    pub normal: [f64; 3],
    /// Largest distance of a marker node from the plane.
    pub max_deviation: f64,
    /// The tolerance it was checked against (relative tolerance × bounding-box diagonal).
    pub tolerance: f64,
}

/// How one node is treated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum NodeRole {
    /// Interior: an unknown without constraint.
    Free,
    /// An unknown constrained to a plane or line.
    Sliding(Constraint),
    /// Does not move.
    Fixed,
    /// Moves by the rigid motion of index `usize` in [`Classified::motions`].
    Rigid(usize),
    /// Moves by the displacement of index `usize` in the displacement list.
    Displaced(usize),
    /// An unknown sliding on the support of index `usize` in [`Classified::supports`].
    OnSupport(usize),
}

/// Result of classifying the nodes.
pub(crate) struct Classified {
    pub roles: Vec<NodeRole>,
    pub motions: Vec<RigidMotion>,
    pub planes: Vec<PlaneInfo>,
    /// Skin elements: those of the moving markers and the marker elements whose nodes all
    /// have prescribed displacements (node lists: triangles in 3D, segments in 2D).
    pub skin: Vec<Vec<u32>>,
    /// Nodes sliding on geometry supports, with their initial parameters.
    pub supports: Vec<SupNode>,
}

/// Fits a plane (3D) or a line in the xy plane (2D grids) to points: centroid and unit
/// normal (eigenvector of the smallest eigenvalue of the scatter matrix), largest deviation.
pub fn fit_plane(points: &[[f64; 3]], dim: u8) -> ([f64; 3], [f64; 3], f64) {
    let n = points.len().max(1) as f64;
    let mut c = Vector3::zeros();
    for p in points {
        c += Vector3::from(*p);
    }
    c /= n;
    let mut m = Matrix3::zeros();
    for p in points {
        let d = Vector3::from(*p) - c;
        m += d * d.transpose();
    }
    let normal = if dim == 2 {
        // Line in xy: normal is the in-plane direction of least scatter.
        let (a, b, d) = (m[(0, 0)], m[(0, 1)], m[(1, 1)]);
        let ang = 0.5 * (2.0 * b).atan2(a - d); // principal direction
        Vector3::new(-ang.sin(), ang.cos(), 0.0)
    } else {
        let e = SymmetricEigen::new(m);
        let k = e.eigenvalues.imin();
        e.eigenvectors.column(k).into_owned().normalize()
    };
    let dev = points
        .iter()
        .map(|p| (Vector3::from(*p) - c).dot(&normal).abs())
        .fold(0.0, f64::max);
    (c.into(), normal.into(), dev)
}

fn unit_normal(mesh: &Mesh, kind: ElementKind, e: &[u32]) -> Option<Vector3<f64>> {
    let x = |i: u32| Vector3::from(mesh.coords[i as usize]);
    let n = match kind {
        ElementKind::Line => {
            let t = x(e[1]) - x(e[0]);
            Vector3::new(-t.y, t.x, 0.0)
        }
        ElementKind::Triangle => (x(e[1]) - x(e[0])).cross(&(x(e[2]) - x(e[0]))),
        ElementKind::Quad => (x(e[2]) - x(e[0])).cross(&(x(e[3]) - x(e[1]))),
        _ => return None,
    };
    let l = n.norm();
    (l > 0.0).then(|| n / l)
}

/// Classifies every node; `plane_rel_tol` is the planarity tolerance relative to the
/// bounding-box diagonal.
pub(crate) fn classify(
    mesh: &Mesh,
    bc: &BoundaryConditions,
    plane_rel_tol: f64,
    supports: Option<&Supports>,
) -> Result<Classified> {
    let n = mesh.n_nodes();
    let diag = mesh.bbox_diagonal();
    let mut role_of_marker: Vec<Option<MarkerRole>> = vec![None; mesh.markers.len()];
    for (name, role) in &bc.markers {
        let Some(k) = mesh.markers.iter().position(|m| &m.name == name) else {
            return Err(Error::UnknownMarker {
                name: name.clone(),
                available: mesh.markers.iter().map(|m| m.name.clone()).collect(),
            });
        };
        if let Some(prev) = role_of_marker[k]
            && prev != *role
        {
            return Err(Error::BadMotion {
                reason: format!("marker {name} is given two different roles"),
            });
        }
        if let MarkerRole::Rigid(m) = role {
            m.validate()?;
        }
        role_of_marker[k] = Some(*role);
    }
    let mut roles = vec![NodeRole::Free; n];
    let mut motions = Vec::new();
    let mut skin = Vec::new();
    // (4) fixed: every marker node first; overwritten by higher precedence below.
    for m in &mesh.markers {
        for (_, e) in m.elements.iter() {
            for &v in e {
                roles[v as usize] = NodeRole::Fixed;
            }
        }
    }
    // (3) sliding planes.
    let mut planes = Vec::new();
    let mut slide_normals: HashMap<u32, Vec<Vector3<f64>>> = HashMap::new();
    let mut frozen: Vec<bool> = vec![false; n];
    for (k, m) in mesh.markers.iter().enumerate() {
        if role_of_marker[k] != Some(MarkerRole::SlidePlane) {
            continue;
        }
        let nodes = m.elements.node_set();
        let pts: Vec<[f64; 3]> = nodes.iter().map(|&v| mesh.coords[v as usize]).collect();
        let (c, nrm, dev) = fit_plane(&pts, mesh.dim);
        let tol = plane_rel_tol * diag;
        if dev > tol || nodes.len() < mesh.dim as usize {
            return Err(Error::NotPlanar {
                marker: m.name.clone(),
                deviation: dev,
                tolerance: tol,
            });
        }
        planes.push(PlaneInfo {
            marker: m.name.clone(),
            point: c,
            normal: nrm,
            max_deviation: dev,
            tolerance: tol,
        });
        for &v in &nodes {
            slide_normals.entry(v).or_default().push(Vector3::from(nrm));
        }
    }
    if !slide_normals.is_empty() {
        // Local tangent planes of the other non-moving markers at sliding nodes.
        for (k, m) in mesh.markers.iter().enumerate() {
            if matches!(
                role_of_marker[k],
                Some(MarkerRole::SlidePlane) | Some(MarkerRole::Rigid(_))
            ) {
                continue;
            }
            let mut local: HashMap<u32, Vec<Vector3<f64>>> = HashMap::new();
            for g in m.elements.groups() {
                for e in g.iter() {
                    let nn = unit_normal(mesh, g.kind, e);
                    for &v in e {
                        if slide_normals.contains_key(&v) {
                            match nn {
                                Some(u) => local.entry(v).or_default().push(u),
                                None => frozen[v as usize] = true,
                            }
                        }
                    }
                }
            }
            for (v, ns) in local {
                let flat = ns.iter().all(|u| u.dot(&ns[0]).abs() > 1.0 - 1e-9);
                if flat {
                    if let Some(list) = slide_normals.get_mut(&v) {
                        list.push(ns[0]);
                    }
                } else {
                    frozen[v as usize] = true;
                }
            }
        }
        for (&v, ns) in &slide_normals {
            let vi = v as usize;
            if frozen[vi] {
                roles[vi] = NodeRole::Fixed;
                continue;
            }
            // Distinct normals.
            let mut distinct: Vec<Vector3<f64>> = Vec::new();
            for u in ns {
                if !distinct.iter().any(|d| d.dot(u).abs() > 1.0 - 1e-9) {
                    distinct.push(*u);
                }
            }
            roles[vi] = match distinct.len() {
                1 => NodeRole::Sliding(Constraint::Plane(distinct[0].into())),
                2 => {
                    let t = distinct[0].cross(&distinct[1]).normalize();
                    NodeRole::Sliding(Constraint::Line(t.into()))
                }
                _ => NodeRole::Fixed,
            };
        }
    }
    // (3') sliding on geometry supports: curve before surface (a surface node also on a
    // marker that does not slide on supports lies on their common curve: frozen).
    let sup_nodes = classify_supports(mesh, &role_of_marker, supports, plane_rel_tol, diag)?;
    for s in &sup_nodes {
        if s.kind.is_none() {
            roles[s.node as usize] = NodeRole::Fixed;
        }
    }
    let supports: Vec<SupNode> = sup_nodes
        .into_iter()
        .filter_map(|s| {
            s.kind.map(|kind| SupNode {
                node: s.node,
                kind,
                param: s.param,
            })
        })
        .collect();
    for (k, s) in supports.iter().enumerate() {
        roles[s.node as usize] = NodeRole::OnSupport(k);
    }
    // (2) rigid markers.
    for (k, m) in mesh.markers.iter().enumerate() {
        let Some(MarkerRole::Rigid(motion)) = role_of_marker[k] else {
            continue;
        };
        let idx = motions
            .iter()
            .position(|x| *x == motion)
            .unwrap_or_else(|| {
                motions.push(motion);
                motions.len() - 1
            });
        for g in m.elements.groups() {
            for e in g.iter() {
                for &v in e {
                    if let NodeRole::Rigid(other) = roles[v as usize]
                        && other != idx
                    {
                        return Err(Error::BadMotion {
                            reason: format!(
                                "node {v} belongs to moving markers with different rigid motions (marker {})",
                                m.name
                            ),
                        });
                    }
                    roles[v as usize] = NodeRole::Rigid(idx);
                }
                push_skin(&mut skin, g.kind, e);
            }
        }
    }
    // (1) explicit displacements.
    for (k, &(v, d)) in bc.displacements.iter().enumerate() {
        if v as usize >= n {
            return Err(Error::NodeOutOfRange {
                node: v as usize,
                nodes: n,
            });
        }
        if !d.iter().all(|x| x.is_finite()) {
            return Err(Error::BadMotion {
                reason: format!("node {v}: displacement {d:?} is not finite"),
            });
        }
        roles[v as usize] = NodeRole::Displaced(k);
    }
    let rigid = |k: usize| matches!(role_of_marker[k], Some(MarkerRole::Rigid(_)));
    push_displaced_skin(mesh, rigid, &roles, |_| true, &mut skin);
    // Sliding nodes overridden by a motion are no longer sliding.
    let supports = supports
        .into_iter()
        .filter(|s| {
            !matches!(
                roles[s.node as usize],
                NodeRole::Rigid(_) | NodeRole::Displaced(_)
            )
        })
        .collect::<Vec<_>>();
    for (k, s) in supports.iter().enumerate() {
        roles[s.node as usize] = NodeRole::OnSupport(k);
    }
    Ok(Classified {
        roles,
        motions,
        planes,
        skin,
        supports,
    })
}

/// True when every node of `e` has a prescribed displacement in `roles`.
pub(crate) fn all_displaced(roles: &[NodeRole], e: &[u32]) -> bool {
    e.iter()
        .all(|&v| matches!(roles[v as usize], NodeRole::Displaced(_)))
}

/// Adds to `skin` the skin of the prescribed displacements: the elements of the markers
/// that are not rigid (`rigid(k)` for marker `k`) whose nodes all have one in `roles`, and
/// that `keep` accepts (a wall moved by the surface-grid update carries R like a rigid
/// marker).
pub(crate) fn push_displaced_skin(
    mesh: &Mesh,
    rigid: impl Fn(usize) -> bool,
    roles: &[NodeRole],
    keep: impl Fn(&[u32]) -> bool,
    skin: &mut Vec<Vec<u32>>,
) {
    for (k, m) in mesh.markers.iter().enumerate() {
        if rigid(k) {
            continue;
        }
        for g in m.elements.groups() {
            for e in g.iter() {
                if all_displaced(roles, e) && keep(e) {
                    push_skin(skin, g.kind, e);
                }
            }
        }
    }
}

/// Adds a boundary element to the skin: segments and triangles as they are, a quadrilateral
/// as two triangles; other kinds carry no surface frame.
fn push_skin(skin: &mut Vec<Vec<u32>>, kind: ElementKind, e: &[u32]) {
    match kind {
        ElementKind::Line | ElementKind::Triangle => skin.push(e.to_vec()),
        ElementKind::Quad => {
            skin.push(vec![e[0], e[1], e[2]]);
            skin.push(vec![e[0], e[2], e[3]]);
        }
        _ => {}
    }
}

/// A node of a support-sliding marker: its support (`None`: frozen) and parameters.
struct SupCandidate {
    node: u32,
    kind: Option<SupKind>,
    param: [f64; 2],
}

/// The nodes of the [`MarkerRole::SlideOnSupport`] markers, with their supports checked
/// (the node must lie on its support within `rel_tol` × `diag`; its parameters are refined
/// to the nearest point by Eq. 31 iterations).
fn classify_supports(
    mesh: &Mesh,
    role_of_marker: &[Option<MarkerRole>],
    supports: Option<&Supports>,
    rel_tol: f64,
    diag: f64,
) -> Result<Vec<SupCandidate>> {
    let tol = rel_tol * diag;
    let n = mesh.n_nodes();
    let mut on_sup = vec![u32::MAX; n];
    let mut on_other = vec![false; n];
    let mut any = false;
    for (k, m) in mesh.markers.iter().enumerate() {
        let slide = role_of_marker[k] == Some(MarkerRole::SlideOnSupport);
        any |= slide;
        let moving = matches!(role_of_marker[k], Some(MarkerRole::Rigid(_)));
        for (_, e) in m.elements.iter() {
            for &v in e {
                if slide {
                    on_sup[v as usize] = k as u32;
                } else if !moving {
                    on_other[v as usize] = true;
                }
            }
        }
    }
    if !any {
        return Ok(Vec::new());
    }
    let Some(sp) = supports else {
        let k = on_sup
            .iter()
            .find(|&&k| k != u32::MAX)
            .copied()
            .unwrap_or(0);
        return Err(Error::Support {
            node: None,
            entity: format!("marker {}", mesh.markers[k as usize].name),
            reason: "slides on geometry supports but no geometry / node supports were given".into(),
        });
    };
    let mut of_node: HashMap<u32, Support> = HashMap::new();
    for &(v, s) in &sp.nodes {
        if v as usize >= n {
            return Err(Error::NodeOutOfRange {
                node: v as usize,
                nodes: n,
            });
        }
        of_node.insert(v, s);
    }
    let db = sp.db;
    let mut out = Vec::new();
    for v in 0..n {
        let k = on_sup[v];
        if k == u32::MAX {
            continue;
        }
        let node = v as u32;
        let marker = &mesh.markers[k as usize].name;
        let Some(s) = of_node.get(&node) else {
            return Err(Error::Support {
                node: Some(node),
                entity: format!("marker {marker}"),
                reason: "the node slides on the geometry but has no support (not classified on \
                         a curve, surface or corner)"
                    .into(),
            });
        };
        let (kind, param) = match *s {
            Support::Corner => {
                out.push(SupCandidate {
                    node,
                    kind: None,
                    param: [0.0; 2],
                });
                continue;
            }
            Support::Curve { curve, t } => (SupKind::Curve(curve), [t, 0.0]),
            Support::Surface { surface, uv } => {
                if on_other[v] {
                    // On the seam with a marker that does not slide on this surface.
                    out.push(SupCandidate {
                        node,
                        kind: None,
                        param: [0.0; 2],
                    });
                    continue;
                }
                (SupKind::Surface(surface), uv)
            }
        };
        check_kind(db, node, kind)?;
        let x = mesh.coords[v];
        let p = place(db, node, kind, param, x, 1e-14 * diag)?;
        let r = point(db, kind, p);
        let dist = ((r[0] - x[0]).powi(2) + (r[1] - x[1]).powi(2) + (r[2] - x[2]).powi(2)).sqrt();
        if dist.is_nan() || dist > tol {
            return Err(Error::Support {
                node: Some(node),
                entity: crate::support::entity_name(db, kind),
                reason: format!(
                    "the node is {dist:e} away from its support (tolerance {tol:e}); given parameters {param:?}"
                ),
            });
        }
        out.push(SupCandidate {
            node,
            kind: Some(kind),
            param: p,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eq34_rotates_counter_clockwise_about_axis() {
        let m = RigidMotion {
            angle_deg: 90.0,
            axis_point: [1.0, 0.0, 5.0],
            axis_dir: [0.0, 0.0, 2.0],
            translation: [0.0, 0.0, 1.0],
        };
        let p = m.apply([2.0, 0.0, 0.0], 1.0);
        testkit::assert_close!(p, [1.0, 1.0, 1.0], abs = 1e-15);
        let half = m.apply([2.0, 0.0, 0.0], 0.5);
        let s = 0.5f64.sqrt();
        testkit::assert_close!(half, [1.0 + s, s, 0.5], abs = 1e-15);
        assert_eq!(m.apply([2.0, 3.0, 4.0], 0.0), [2.0, 3.0, 4.0]);
        // Rotation matrix agrees with apply.
        let r = m.rotation(1.0);
        let v = r * Vector3::new(1.0, 0.0, 0.0);
        testkit::assert_close!([v.x, v.y, v.z], [0.0, 1.0, 0.0], abs = 1e-15);
    }

    #[test]
    fn plane_fit_finds_tilted_plane() {
        let n = Vector3::new(0.2, -0.4, 1.0).normalize();
        let t1 = n.cross(&Vector3::x()).normalize();
        let t2 = n.cross(&t1);
        let pts: Vec<[f64; 3]> = (0..50)
            .map(|i| {
                let (a, b) = ((i as f64 * 0.7).sin(), (i as f64 * 1.3).cos());
                (Vector3::new(1.0, 2.0, 3.0) + t1 * a + t2 * b).into()
            })
            .collect();
        let (_, nrm, dev) = fit_plane(&pts, 3);
        assert!(dev < 1e-14);
        assert!(Vector3::from(nrm).dot(&n).abs() > 1.0 - 1e-14);
    }
}
