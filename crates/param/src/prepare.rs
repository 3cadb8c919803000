//! A parametrisation bound to a geometry ([`Prepared`]): everything that depends only on the
//! initial shape is computed once (linked node lists, node parameters, normals, decay
//! weights, basis values, master locations); [`Prepared::apply`] and
//! [`Prepared::apply_with_jacobian`] then map a design vector to control node positions.
//!
//! Composition (in modifier order), with p the current positions (initially r⁰):
//! * line, surface and master modifiers add a displacement computed entirely on the initial
//!   shape (parameters, normals, decay, master projection), independent of p — they commute
//!   with each other and their sum is order-free;
//! * a node modifier moves its nodes rigidly from their *current* position p
//!   (Eqs. 34–35 with r⁰ replaced by p), so any perturbation applied before it is carried
//!   along (a bump made before a twist turns with the section), while those after it are not.
//!
//! With only additive modifiers, or node modifiers first, this is the plain sum of
//! displacements computed on the initial shape, as the paper recommends. A modifier whose
//! design variables all equal their initial values is skipped, so the initial design vector
//! returns r⁰ bit for bit.

use std::collections::BTreeMap;
use std::sync::Arc;

use geom_db::control;
use geom_db::prelude::{Matrix3, Point3, Vector3};
use geom_db::{GeomDb, SurfaceId};
use intersect::project::{CurveProjector, ProjectOptions};

use crate::Parametrisation;
use crate::error::{Error, Result};
use crate::jacobian::Jacobian;
use crate::master::{MasterGrid, MasterSource, locate_on_master};
use crate::modifier::{
    Direction, LineModifier, LineSupport, Links, MasterModifier, MasterSpec, Modifier,
    NodeModifier, Param, SurfaceForm, SurfaceModifier,
};
use crate::registry::Registry;

/// Master generators supplied by the caller, by name (see [`MasterSpec::External`]).
pub type MasterSources = BTreeMap<String, Arc<dyn MasterSource>>;

/// Per control node: column → d(node)/dx_column.
type NodeRow = BTreeMap<usize, Vector3>;

/// A linear term: node displacement += δ_var · weight · dir.
#[derive(Debug, Clone)]
struct LinNode {
    node: usize,
    dir: Vector3,
    terms: Vec<(usize, f64)>,
}

/// A separable term: node displacement += (Σ δ_k u_k)(Σ δ_l v_l) · dir.
#[derive(Debug, Clone)]
struct SepNode {
    node: usize,
    dir: Vector3,
    u: Vec<(usize, f64)>,
    v: Vec<(usize, f64)>,
}

enum Bound {
    Node {
        nodes: Vec<usize>,
        x0: Point3,
        b: Vector3,
        rot: Option<usize>,
        tr: [Option<usize>; 3],
    },
    Linear {
        vars: Vec<usize>,
        nodes: Vec<LinNode>,
    },
    Separable {
        vars: Vec<usize>,
        nodes: Vec<SepNode>,
    },
    Master {
        name: String,
        source: Arc<dyn MasterSource>,
        vars: Vec<usize>,
        base: MasterGrid,
        nodes: Vec<(usize, [(usize, f64); 4])>,
    },
}

/// A parametrisation bound to a geometry, ready to evaluate.
pub struct Prepared {
    registry: Registry,
    initial: Vec<Point3>,
    bound: Vec<Bound>,
    /// Per modifier: (name, level, moved node count).
    summary: Vec<(String, &'static str, usize)>,
}

/// A control node of a surface: global (u, v) of its first occurrence and the unit normal
/// (average over its occurrences in the surface's patches; `None` where singular).
#[derive(Debug, Clone, Copy)]
pub(crate) struct SurfNode {
    pub id: usize,
    pub uv: [f64; 2],
    pub normal: Option<Vector3>,
}

fn patch_normal(p: &geom_db::Patch, x: f64, y: f64) -> Option<Vector3> {
    if let Some(n) = p.derivs(x, y).unit_normal() {
        return Some(n);
    }
    // singular point (a pole): just inside the patch, towards its centre
    for eps in [1e-6, 1e-4, 1e-2] {
        let (xx, yy) = (x + eps * (0.5 - x), y + eps * (0.5 - y));
        if let Some(n) = p.derivs(xx, yy).unit_normal() {
            return Some(n);
        }
    }
    None
}

/// The control nodes of a surface with their parameters and normals, first occurrence order.
pub(crate) fn surface_nodes(db: &GeomDb, sid: SurfaceId) -> Vec<SurfNode> {
    let s = db.surface(sid);
    let mut seen: BTreeMap<usize, usize> = BTreeMap::new();
    let mut out: Vec<SurfNode> = Vec::new();
    let mut sums: Vec<Vector3> = Vec::new();
    for (pi, (ids, p)) in s.control.nodes.iter().zip(&s.patches).enumerate() {
        let (i, j) = (pi % s.n_u, pi / s.n_u);
        let xu = control::nodes(p.deg_u);
        let xv = control::nodes(p.deg_v);
        for (a, &x) in xu.iter().enumerate() {
            for (b, &y) in xv.iter().enumerate() {
                let id = ids[a * xv.len() + b].index();
                let n = patch_normal(p, x, y);
                let k = *seen.entry(id).or_insert_with(|| {
                    out.push(SurfNode {
                        id,
                        uv: [i as f64 + x, j as f64 + y],
                        normal: None,
                    });
                    sums.push(Vector3::zeros());
                    out.len() - 1
                });
                if let Some(n) = n {
                    sums[k] += n;
                    if out[k].normal.is_none() {
                        out[k].normal = Some(n);
                    }
                }
            }
        }
    }
    for (o, s) in out.iter_mut().zip(sums) {
        let l = s.norm();
        if l > 1e-8 {
            o.normal = Some(s / l);
        }
    }
    out
}

fn missing(modifier: &str, entity: String, available: usize) -> Error {
    Error::MissingEntity {
        modifier: modifier.to_string(),
        entity,
        available,
    }
}

fn bad(modifier: &str, reason: impl Into<String>) -> Error {
    Error::BadModifier {
        modifier: modifier.to_string(),
        reason: reason.into(),
    }
}

fn check_surface(db: &GeomDb, m: &str, s: SurfaceId) -> Result<()> {
    if s.index() >= db.surfaces.len() {
        return Err(missing(m, s.to_string(), db.surfaces.len()));
    }
    if db.surface(s).control.is_empty() {
        return Err(bad(m, format!("{s} has no control nodes")));
    }
    Ok(())
}

/// The control nodes of `links`, sorted and unique.
fn link_nodes(db: &GeomDb, m: &str, links: &Links) -> Result<Vec<usize>> {
    let mut out = std::collections::BTreeSet::new();
    for &s in &links.surfaces {
        check_surface(db, m, s)?;
        for ids in &db.surface(s).control.nodes {
            out.extend(ids.iter().map(|i| i.index()));
        }
    }
    for &c in &links.curves {
        if c.index() >= db.curves.len() {
            return Err(missing(m, c.to_string(), db.curves.len()));
        }
        let cc = &db.curve(c).control;
        if cc.is_empty() {
            return Err(bad(m, format!("{c} has no control nodes")));
        }
        for ids in &cc.nodes {
            out.extend(ids.iter().map(|i| i.index()));
        }
    }
    for &n in &links.nodes {
        if n.index() >= db.control_nodes.len() {
            return Err(missing(m, n.to_string(), db.control_nodes.len()));
        }
        out.insert(n.index());
    }
    for iso in &links.iso_lines {
        check_surface(db, m, iso.surface)?;
        let k = match iso.fixed {
            Param::U => 0,
            Param::V => 1,
        };
        let before = out.len();
        let mut any = false;
        for sn in surface_nodes(db, iso.surface) {
            if (sn.uv[k] - iso.at).abs() <= 1e-9 * (1.0 + iso.at.abs()) {
                out.insert(sn.id);
                any = true;
            }
        }
        if !any {
            return Err(bad(
                m,
                format!(
                    "no control node of {} lies on the line {:?} = {} (control nodes sit at patch borders and Chebyshev–Lobatto points)",
                    iso.surface, iso.fixed, iso.at
                ),
            ));
        }
        let _ = before;
    }
    if out.is_empty() {
        return Err(bad(m, "links no control node"));
    }
    Ok(out.into_iter().collect())
}

/// The normals of the control nodes of the linked surfaces (first surface first).
fn link_normals(db: &GeomDb, links: &Links) -> BTreeMap<usize, Option<Vector3>> {
    let mut normals = BTreeMap::new();
    for &s in &links.surfaces {
        for sn in surface_nodes(db, s) {
            normals.entry(sn.id).or_insert(sn.normal);
        }
    }
    normals
}

fn unit(m: &str, what: &str, v: Vector3) -> Result<Vector3> {
    let l = v.norm();
    if l > 0.0 && l.is_finite() {
        Ok(v / l)
    } else {
        Err(bad(m, format!("{what} must be a non-zero finite vector")))
    }
}

fn active_list(m: &str, what: &str, active: &Option<Vec<usize>>, n: usize) -> Result<Vec<usize>> {
    let a: Vec<usize> = match active {
        Some(a) => a.clone(),
        None => (0..n).collect(),
    };
    let mut seen = vec![false; n];
    for &i in &a {
        if i >= n {
            return Err(bad(
                m,
                format!("{what}: active function {i} does not exist (the basis has {n})"),
            ));
        }
        if seen[i] {
            return Err(bad(m, format!("{what}: active function {i} listed twice")));
        }
        seen[i] = true;
    }
    Ok(a)
}

fn param_range(range: Option<[f64; 2]>, dom: [f64; 2], m: &str, what: &str) -> Result<[f64; 2]> {
    let r = range.unwrap_or(dom);
    if r[1] <= r[0] || !r[0].is_finite() || !r[1].is_finite() {
        return Err(bad(m, format!("{what} [{}, {}] is empty", r[0], r[1])));
    }
    Ok(r)
}

fn direction_at(m: &str, dir: &Direction, node: usize, normal: Option<Vector3>) -> Result<Vector3> {
    match dir {
        Direction::Axis(a) => unit(m, "direction axis", *a),
        Direction::Normal => normal.ok_or_else(|| Error::NodeGeometry {
            modifier: m.to_string(),
            node: format!("control node {node}"),
            reason: "no surface normal (not on a linked surface, or singular)".into(),
        }),
    }
}

impl Prepared {
    /// Binds `p` to `db` (see the module doc). `masters` supplies external master
    /// generators by name.
    pub fn new(p: &Parametrisation, db: &GeomDb, masters: &MasterSources) -> Result<Self> {
        let registry = p.registry()?;
        let mut bound = Vec::with_capacity(p.modifiers.len());
        let mut summary = Vec::new();
        for m in &p.modifiers {
            let vars: Vec<usize> = m
                .variables()
                .iter()
                .map(|v| {
                    registry
                        .index_of(&v.name)
                        .expect("registry holds every variable")
                })
                .collect();
            let b = match m {
                Modifier::Node(n) => bind_node(db, n, &vars)?,
                Modifier::Line(l) => bind_line(db, l, &vars)?,
                Modifier::Surface(s) => bind_surface(db, s, &vars)?,
                Modifier::Master(ms) => bind_master(db, ms, &vars, &registry, masters)?,
            };
            let count = match &b {
                Bound::Node { nodes, .. } => nodes.len(),
                Bound::Linear { nodes, .. } => nodes.len(),
                Bound::Separable { nodes, .. } => nodes.len(),
                Bound::Master { nodes, .. } => nodes.len(),
            };
            summary.push((m.name().to_string(), m.level(), count));
            bound.push(b);
        }
        Ok(Self {
            registry,
            initial: db.control_points().to_vec(),
            bound,
            summary,
        })
    }

    /// The registry (design-vector order).
    pub fn registry(&self) -> &Registry {
        &self.registry
    }

    /// The initial control node positions r⁰.
    pub fn initial_points(&self) -> &[Point3] {
        &self.initial
    }

    /// Per modifier: name, level and number of control nodes it moves.
    pub fn summary(&self) -> &[(String, &'static str, usize)] {
        &self.summary
    }

    /// Control node positions for design vector `x` (physical units; bounds are not
    /// checked here, see [`Registry::check_bounds`]).
    pub fn apply(&self, x: &[f64]) -> Result<Vec<Point3>> {
        Ok(self.run(x, false)?.0)
    }

    /// Positions and the exact Jacobian d(positions)/dx at `x`.
    pub fn apply_with_jacobian(&self, x: &[f64]) -> Result<(Vec<Point3>, Jacobian)> {
        let (p, rows) = self.run(x, true)?;
        let j = crate::jacobian::from_node_rows(&rows.unwrap_or_default(), self.registry.len());
        Ok((p, j))
    }

    fn run(&self, x: &[f64], jac: bool) -> Result<(Vec<Point3>, Option<Vec<NodeRow>>)> {
        self.registry.check_len(x)?;
        let vars = self.registry.variables();
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(Error::OutOfBounds {
                name: vars[i].name.clone(),
                value: x[i],
                lower: vars[i].lower,
                upper: vars[i].upper,
            });
        }
        let delta: Vec<f64> = x.iter().zip(vars).map(|(x, v)| x - v.value).collect();
        let moved = |ids: &[usize]| ids.iter().any(|&i| x[i] != vars[i].value);
        let mut p = self.initial.clone();
        let mut rows: Option<Vec<NodeRow>> = jac.then(|| vec![BTreeMap::new(); p.len()]);
        let add = |p: &mut Point3, d: Vector3| {
            for c in 0..3 {
                if d[c] != 0.0 {
                    p[c] += d[c];
                }
            }
        };
        for b in &self.bound {
            match b {
                Bound::Node {
                    nodes,
                    x0,
                    b,
                    rot,
                    tr,
                } => {
                    let theta = rot.map_or(0.0, |k| delta[k]);
                    let t = Vector3::new(
                        tr[0].map_or(0.0, |k| delta[k]),
                        tr[1].map_or(0.0, |k| delta[k]),
                        tr[2].map_or(0.0, |k| delta[k]),
                    );
                    let ids: Vec<usize> = rot.iter().chain(tr.iter().flatten()).copied().collect();
                    let go = moved(&ids);
                    let (s, c) = theta.sin_cos();
                    let r = Matrix3::identity() * c
                        + b.cross_matrix() * s
                        + (b * b.transpose()) * (1.0 - c);
                    for &n in nodes {
                        // Eq. (35): x_c, the foot of the node on the axis; v = p − x_c.
                        let xc = x0.coords + b * (p[n] - x0).dot(b);
                        let v = p[n].coords - xc;
                        let vxb = v.cross(b);
                        if let Some(rows) = rows.as_mut() {
                            let row = &mut rows[n];
                            for d in row.values_mut() {
                                *d = r * *d;
                            }
                            if let Some(k) = rot {
                                *row.entry(*k).or_insert_with(Vector3::zeros) += -v * s - vxb * c;
                            }
                            for (ci, k) in tr.iter().enumerate() {
                                if let Some(k) = k {
                                    row.entry(*k).or_insert_with(Vector3::zeros)[ci] += 1.0;
                                }
                            }
                        }
                        if go {
                            // Eq. (34) as a displacement: new − p = (cos θ − 1) v − sin θ (v ∧ b) + Δr_t
                            add(&mut p[n], v * (c - 1.0) - vxb * s + t);
                        }
                    }
                }
                Bound::Linear { vars: ids, nodes } => {
                    let go = moved(ids);
                    for ln in nodes {
                        if go {
                            let q: f64 = ln.terms.iter().map(|&(k, w)| delta[k] * w).sum();
                            add(&mut p[ln.node], ln.dir * q);
                        }
                        if let Some(rows) = rows.as_mut() {
                            for &(k, w) in &ln.terms {
                                *rows[ln.node].entry(k).or_insert_with(Vector3::zeros) +=
                                    ln.dir * w;
                            }
                        }
                    }
                }
                Bound::Separable { vars: ids, nodes } => {
                    let go = moved(ids);
                    for sn in nodes {
                        let qu: f64 = sn.u.iter().map(|&(k, w)| delta[k] * w).sum();
                        let qv: f64 = sn.v.iter().map(|&(k, w)| delta[k] * w).sum();
                        if go {
                            add(&mut p[sn.node], sn.dir * (qu * qv));
                        }
                        if let Some(rows) = rows.as_mut() {
                            for &(k, w) in &sn.u {
                                *rows[sn.node].entry(k).or_insert_with(Vector3::zeros) +=
                                    sn.dir * (w * qv);
                            }
                            for &(k, w) in &sn.v {
                                *rows[sn.node].entry(k).or_insert_with(Vector3::zeros) +=
                                    sn.dir * (qu * w);
                            }
                        }
                    }
                }
                Bound::Master {
                    name,
                    source,
                    vars: ids,
                    base,
                    nodes,
                } => {
                    let xm: Vec<f64> = ids.iter().map(|&k| x[k]).collect();
                    if moved(ids) {
                        let g = generate(name, source.as_ref(), &xm, base)?;
                        for (n, w) in nodes {
                            let mut d = Vector3::zeros();
                            for &(k, wk) in w {
                                d += (g.points[k] - base.points[k]) * wk;
                            }
                            add(&mut p[*n], d);
                        }
                    }
                    if let Some(rows) = rows.as_mut() {
                        let dm =
                            master_jacobian(name, source.as_ref(), &xm, ids, base, &self.registry)?;
                        for (n, w) in nodes {
                            for (l, &k) in ids.iter().enumerate() {
                                let mut d = Vector3::zeros();
                                for &(pk, wk) in w {
                                    d += dm[pk][l] * wk;
                                }
                                *rows[*n].entry(k).or_insert_with(Vector3::zeros) += d;
                            }
                        }
                    }
                }
            }
        }
        Ok((p, rows))
    }
}

fn generate(
    name: &str,
    src: &dyn MasterSource,
    x: &[f64],
    base: &MasterGrid,
) -> Result<MasterGrid> {
    let err = |reason: String| Error::Master {
        modifier: name.to_string(),
        reason,
    };
    let g = src.generate(x).map_err(|source| Error::MasterSource {
        modifier: name.to_string(),
        source,
    })?;
    g.validate().map_err(&err)?;
    if g.n_s != base.n_s || g.n_t != base.n_t {
        return Err(err(format!(
            "the master is {} × {}, the initial master {} × {} (the node count must not change)",
            g.n_s, g.n_t, base.n_s, base.n_t
        )));
    }
    Ok(g)
}

/// d(master point k)/d(x_l): the source's exact Jacobian, or central differences with step
/// h_l = 1e-6 · max(|x_l|, scale_l).
fn master_jacobian(
    name: &str,
    src: &dyn MasterSource,
    x: &[f64],
    ids: &[usize],
    base: &MasterGrid,
    reg: &Registry,
) -> Result<Vec<Vec<Vector3>>> {
    let err = |reason: String| Error::Master {
        modifier: name.to_string(),
        reason,
    };
    if let Some(j) = src.jacobian(x) {
        let j = j.map_err(|source| Error::MasterSource {
            modifier: name.to_string(),
            source,
        })?;
        if j.len() != base.points.len() || j.iter().any(|r| r.len() != x.len()) {
            return Err(err("the source's Jacobian has the wrong size".into()));
        }
        return Ok(j);
    }
    let mut out = vec![vec![Vector3::zeros(); x.len()]; base.points.len()];
    for l in 0..x.len() {
        let h = 1e-6 * x[l].abs().max(reg.variables()[ids[l]].scale);
        let mut xp = x.to_vec();
        let mut xm = x.to_vec();
        xp[l] += h;
        xm[l] -= h;
        let gp = generate(name, src, &xp, base)?;
        let gm = generate(name, src, &xm, base)?;
        for k in 0..base.points.len() {
            out[k][l] = (gp.points[k] - gm.points[k]) / (2.0 * h);
        }
    }
    Ok(out)
}

fn bind_node(db: &GeomDb, m: &NodeModifier, vars: &[usize]) -> Result<Bound> {
    let nodes = link_nodes(db, &m.name, &m.links)?;
    let b = unit(&m.name, "axis direction", m.axis.direction)?;
    if !m.axis.point.coords.iter().all(|c| c.is_finite()) {
        return Err(bad(&m.name, "axis point is not finite"));
    }
    let mut it = vars.iter().copied();
    let rot = m.rotation.as_ref().and_then(|_| it.next());
    let mut tr = [None; 3];
    for (c, t) in m.translation.iter().enumerate() {
        if t.is_some() {
            tr[c] = it.next();
        }
    }
    Ok(Bound::Node {
        nodes,
        x0: m.axis.point,
        b,
        rot,
        tr,
    })
}

fn bind_line(db: &GeomDb, m: &LineModifier, vars: &[usize]) -> Result<Bound> {
    let name = &m.name;
    let basis = m.basis.prepare(name)?;
    let active = active_list(name, "basis", &m.active, basis.len())?;
    if active.len() != m.variables.len() {
        return Err(bad(
            name,
            format!(
                "{} variables for {} active basis functions",
                m.variables.len(),
                active.len()
            ),
        ));
    }
    match m.decay {
        crate::modifier::Decay::Cosine { width } | crate::modifier::Decay::Gaussian { width }
            if !(width > 0.0 && width.is_finite()) =>
        {
            return Err(bad(name, format!("decay width {width} must be positive")));
        }
        _ => {}
    }
    // (node, s, distance, normal)
    let mut pts: Vec<(usize, f64, f64, Option<Vector3>)> = Vec::new();
    match &m.line {
        LineSupport::Iso(iso) => {
            if !m.links.is_empty() {
                return Err(bad(
                    name,
                    "an iso-line modifier moves its own surface's nodes; remove `links`",
                ));
            }
            check_surface(db, name, iso.surface)?;
            let s = db.surface(iso.surface);
            let (k, run) = match iso.fixed {
                Param::U => (0, 1),
                Param::V => (1, 0),
            };
            let dom = [0.0, if run == 0 { s.n_u } else { s.n_v } as f64];
            let fdom = if k == 0 { s.n_u } else { s.n_v } as f64;
            if !(iso.at >= 0.0 && iso.at <= fdom) {
                return Err(bad(
                    name,
                    format!(
                        "iso-line {:?} = {} is outside [0, {fdom}]",
                        iso.fixed, iso.at
                    ),
                ));
            }
            let r = param_range(m.range, dom, name, "range")?;
            for sn in surface_nodes(db, iso.surface) {
                let sp = (sn.uv[run] - r[0]) / (r[1] - r[0]);
                pts.push((sn.id, sp, (sn.uv[k] - iso.at).abs(), sn.normal));
            }
        }
        LineSupport::Axis(axis) => {
            let b = unit(name, "line axis direction", axis.direction)?;
            if !axis.point.coords.iter().all(|c| c.is_finite()) {
                return Err(bad(name, "line axis point is not finite"));
            }
            let nodes = link_nodes(db, name, &m.links)?;
            let normals = link_normals(db, &m.links);
            // (node, coordinate along the axis, distance from it)
            let along: Vec<(usize, f64, f64)> = nodes
                .iter()
                .map(|&n| {
                    let v = db.control_nodes[n] - axis.point;
                    let t = v.dot(&b);
                    (n, t, (v - b * t).norm())
                })
                .collect();
            let extent = along
                .iter()
                .fold([f64::INFINITY, f64::NEG_INFINITY], |r, a| {
                    [r[0].min(a.1), r[1].max(a.1)]
                });
            let r = param_range(m.range, extent, name, "range")?;
            for (n, t, d) in along {
                let sp = (t - r[0]) / (r[1] - r[0]);
                pts.push((n, sp, d, normals.get(&n).copied().flatten()));
            }
        }
        LineSupport::Curve(cid) => {
            if cid.index() >= db.curves.len() {
                return Err(missing(name, cid.to_string(), db.curves.len()));
            }
            let nodes = link_nodes(db, name, &m.links)?;
            let normals = link_normals(db, &m.links);
            let curve = db.curve(*cid);
            let opts = ProjectOptions::default().with_length_scale(db.reference_length());
            let proj = CurveProjector::new(cid.to_string(), curve, &opts)?;
            let r = param_range(m.range, [0.0, curve.n_arcs() as f64], name, "range")?;
            for n in nodes {
                let f = proj.project_indexed(&db.control_nodes[n], n)?;
                let sp = (f.t - r[0]) / (r[1] - r[0]);
                pts.push((n, sp, f.distance, normals.get(&n).copied().flatten()));
            }
        }
    }
    let mut nodes = Vec::new();
    for (node, sp, d, normal) in pts {
        let w = m.decay.weight(d);
        if w == 0.0 {
            continue;
        }
        let h = basis.eval(sp);
        let terms: Vec<(usize, f64)> = active
            .iter()
            .zip(vars)
            .map(|(&a, &k)| (k, h[a] * w))
            .filter(|t| t.1 != 0.0)
            .collect();
        if terms.is_empty() {
            continue;
        }
        let dir = direction_at(name, &m.direction, node, normal)?;
        nodes.push(LinNode { node, dir, terms });
    }
    Ok(Bound::Linear {
        vars: vars.to_vec(),
        nodes,
    })
}

fn bind_surface(db: &GeomDb, m: &SurfaceModifier, vars: &[usize]) -> Result<Bound> {
    let name = &m.name;
    let bu = m.basis_u.prepare(name)?;
    let bv = m.basis_v.prepare(name)?;
    let au = active_list(name, "basis_u", &m.active_u, bu.len())?;
    let av = active_list(name, "basis_v", &m.active_v, bv.len())?;
    let (nvu, nvv) = match &m.form {
        SurfaceForm::Separable {
            variables_u,
            variables_v,
        } => (variables_u.len(), variables_v.len()),
        SurfaceForm::Tensor { variables } => {
            if variables.len() != au.len() * av.len() {
                return Err(bad(
                    name,
                    format!(
                        "{} variables for {} × {} active functions (Eq. 38 needs one per pair)",
                        variables.len(),
                        au.len(),
                        av.len()
                    ),
                ));
            }
            (au.len(), av.len())
        }
    };
    if nvu != au.len() || nvv != av.len() {
        return Err(bad(
            name,
            format!(
                "{nvu} u and {nvv} v variables for {} u and {} v active functions",
                au.len(),
                av.len()
            ),
        ));
    }
    if m.surfaces.is_empty() {
        return Err(bad(name, "links no surface"));
    }
    let separable = matches!(m.form, SurfaceForm::Separable { .. });
    let mut seen = std::collections::BTreeSet::new();
    let mut lin = Vec::new();
    let mut sep = Vec::new();
    for &sid in &m.surfaces {
        check_surface(db, name, sid)?;
        let s = db.surface(sid);
        let ru = param_range(m.range_u, [0.0, s.n_u as f64], name, "range_u")?;
        let rv = param_range(m.range_v, [0.0, s.n_v as f64], name, "range_v")?;
        for sn in surface_nodes(db, sid) {
            if !seen.insert(sn.id) {
                continue;
            }
            let hu = bu.eval((sn.uv[0] - ru[0]) / (ru[1] - ru[0]));
            let hv = bv.eval((sn.uv[1] - rv[0]) / (rv[1] - rv[0]));
            let tu: Vec<f64> = au.iter().map(|&a| hu[a]).collect();
            let tv: Vec<f64> = av.iter().map(|&a| hv[a]).collect();
            if tu.iter().all(|&w| w == 0.0) || tv.iter().all(|&w| w == 0.0) {
                continue;
            }
            let dir = direction_at(name, &m.direction, sn.id, sn.normal)?;
            if separable {
                let (vu, vv) = vars.split_at(au.len());
                sep.push(SepNode {
                    node: sn.id,
                    dir,
                    u: vu
                        .iter()
                        .zip(&tu)
                        .map(|(&k, &w)| (k, w))
                        .filter(|t| t.1 != 0.0)
                        .collect(),
                    v: vv
                        .iter()
                        .zip(&tv)
                        .map(|(&k, &w)| (k, w))
                        .filter(|t| t.1 != 0.0)
                        .collect(),
                });
            } else {
                let mut terms = Vec::new();
                for (a, &wu) in tu.iter().enumerate() {
                    for (b, &wv) in tv.iter().enumerate() {
                        let w = wu * wv;
                        if w != 0.0 {
                            terms.push((vars[a * av.len() + b], w));
                        }
                    }
                }
                lin.push(LinNode {
                    node: sn.id,
                    dir,
                    terms,
                });
            }
        }
    }
    Ok(if separable {
        Bound::Separable {
            vars: vars.to_vec(),
            nodes: sep,
        }
    } else {
        Bound::Linear {
            vars: vars.to_vec(),
            nodes: lin,
        }
    })
}

fn bind_master(
    db: &GeomDb,
    m: &MasterModifier,
    vars: &[usize],
    reg: &Registry,
    masters: &MasterSources,
) -> Result<Bound> {
    let name = &m.name;
    let nodes = link_nodes(db, name, &m.links)?;
    let names: Vec<String> = m.variables.iter().map(|v| v.name.clone()).collect();
    let source: Arc<dyn MasterSource> = match &m.source {
        MasterSpec::External(s) => {
            masters
                .get(s)
                .cloned()
                .ok_or_else(|| Error::MissingMasterSource {
                    modifier: name.clone(),
                    source_name: s.clone(),
                })?
        }
        MasterSpec::Stations(st) => {
            Arc::new(st.bind(db, &names).map_err(|reason| Error::Master {
                modifier: name.clone(),
                reason,
            })?)
        }
    };
    let want = source.variable_names();
    if want != names {
        return Err(bad(
            name,
            format!("the master source takes variables {want:?}, the modifier defines {names:?}"),
        ));
    }
    let x0: Vec<f64> = vars.iter().map(|&k| reg.variables()[k].value).collect();
    let err = |reason: String| Error::Master {
        modifier: name.clone(),
        reason,
    };
    let base = source.generate(&x0).map_err(|source| Error::MasterSource {
        modifier: name.clone(),
        source,
    })?;
    base.validate().map_err(&err)?;
    let pts: Vec<Point3> = nodes.iter().map(|&n| db.control_nodes[n]).collect();
    let locs = locate_on_master(&base, &pts);
    let nodes = nodes
        .into_iter()
        .zip(locs)
        .map(|(n, l)| (n, l.weights(&base)))
        .collect();
    Ok(Bound::Master {
        name: name.clone(),
        source,
        vars: vars.to_vec(),
        base,
        nodes,
    })
}
