//! `cargo xtask fixtures`: writes the geometry fixtures under `fixtures/geom/`.
//!
//! * `sphere.ron`: the unit sphere as six patches (equal-angle cube sphere, each face
//!   interpolated at Chebyshev–Lobatto points), 8 corners, 12 edges, closed.
//! * `cylinder.ron`: radius 1, height 2, with flat end caps (polar patches with a pole at
//!   the centre), closed, with a seam on the side and on each cap.
//! * `wing_body.ron`: half model on the symmetry plane y = 0: a fuselage of revolution
//!   (rounded nose, cylinder, tail cone), a wing lofted from a NACA 2412 root and a NACA 0012
//!   tip with a flat tip cap, and the wing/fuselage junction computed by a small Newton
//!   solve on the two support surfaces. Open (free edges on the symmetry plane).
//! * `../cases/default/wing_body.ron`: the same model with the junction in twice as many
//!   arcs (within ~3e-10 of both surfaces instead of ~5e-8), the geometry of the chain's
//!   default case.
//!
//! Then the chain cases' volume grids (`fixtures/cases/{default,sphere}/grid.msh`, see
//! [`case_grids`]).
//!
//! Every fixture carries control nodes shared along common borders.

use std::f64::consts::FRAC_PI_2;
use std::path::Path;

use geom_db::prelude::{Matrix3, Point3, Vector3};
use geom_db::{
    Arc, CheckOptions, CornerId, CurveCompId, CurveComponent, CurveId, GeomDb, Orientation,
    OrientedCurve, Patch, Side, SupportCurve, SupportSurface, SurfaceComponent, SurfaceId,
    eval::ParamSurface,
    merge::PointMerger,
    newton::{Eval, Problem, Settings, minimise},
};

/// Builds all fixtures, checks them and writes them atomically; then (unless
/// `--geometry-only`) the volume grids of the chain cases (see [`case_grids`]).
pub fn run(root: &Path, args: &[String]) -> Result<(), String> {
    geometry(root)?;
    if args.iter().any(|a| a == "--geometry-only") {
        return Ok(());
    }
    case_grids(root)
}

/// A chain case whose volume grid `cargo xtask fixtures` makes.
struct GridCase {
    /// Folder under fixtures/cases/.
    dir: &'static str,
    /// The geometry, relative to the workspace root.
    geometry: &'static str,
    /// Uniform wall size.
    h_wall: f64,
    /// Far-field size.
    h_far: f64,
    /// Far-field box: x min, x max, y max, z min, z max (y min is 0 for a half model, else
    /// −y max).
    bbox: [f64; 5],
    /// Markers: name = surface components.
    groups: &'static [&'static str],
}

const GRID_CASES: &[GridCase] = &[
    GridCase {
        dir: "default",
        geometry: "fixtures/cases/default/wing_body.ron",
        h_wall: 0.15,
        h_far: 4.0,
        bbox: [-10.0, 22.0, 14.0, -12.0, 12.0],
        groups: &["fuselage=0", "wing=1,2"],
    },
    GridCase {
        dir: "sphere",
        geometry: "fixtures/geom/sphere.ron",
        h_wall: 0.2,
        h_far: 1.5,
        bbox: [-5.0, 5.0, 5.0, -5.0, 5.0],
        groups: &["sphere=0,1,2,3,4,5"],
    },
];

/// The volume grids of the chain cases: aeroshape's own surface grid of the geometry
/// (`surfgrid::generate`, example `chain_fixture surface`), a far-field box filled with
/// tetrahedra by Gmsh keeping the wall nodes identical (`fixtures/cases/make_volume.py`,
/// needs `pip install gmsh`; only here, never in CI), then the wall nodes' classification
/// re-attached by exact coordinate match (`chain_fixture attach`) and the grid written as
/// MSH 4.1 (binary) with parametric nodes to `fixtures/cases/<case>/grid.msh`.
pub fn case_grids(root: &Path) -> Result<(), String> {
    let py = std::process::Command::new("python3")
        .args(["-c", "import gmsh"])
        .status();
    if !matches!(py, Ok(s) if s.success()) {
        return Err(
            "the case grids need Gmsh's Python API: pip install gmsh (or run with --geometry-only)"
                .into(),
        );
    }
    let tmp = root.join("target").join("fixtures");
    std::fs::create_dir_all(&tmp).map_err(|e| format!("{}: {e}", tmp.display()))?;
    for c in GRID_CASES {
        let dir = root.join("fixtures").join("cases").join(c.dir);
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let geom = root.join(c.geometry).display().to_string();
        let surf = tmp
            .join(format!("{}_surface.txt", c.dir))
            .display()
            .to_string();
        let vol = tmp
            .join(format!("{}_volume.msh", c.dir))
            .display()
            .to_string();
        let h = format!("{}", c.h_wall);
        let mut a: Vec<&str> = vec!["surface", &geom, &h, &surf];
        a.extend(c.groups.iter().copied());
        crate::aeroshape(Some("chain_fixture"), &a)?;
        let bbox: Vec<String> = c.bbox.iter().map(|v| v.to_string()).collect();
        let mut py = std::process::Command::new("python3");
        py.arg(root.join("fixtures/cases/make_volume.py"))
            .args([&surf, &vol, "--box"])
            .args(&bbox)
            .args(["--h-far", &c.h_far.to_string()]);
        eprintln!("$ {py:?}");
        let st = py.status().map_err(|e| format!("python3: {e}"))?;
        if !st.success() {
            return Err(format!("make_volume.py failed for case {} ({st})", c.dir));
        }
        let out = dir.join("grid.msh").display().to_string();
        crate::aeroshape(Some("chain_fixture"), &["attach", &geom, &h, &vol, &out])?;
    }
    Ok(())
}

/// The geometry fixtures under fixtures/geom/.
fn geometry(root: &Path) -> Result<(), String> {
    let dir = root.join("fixtures").join("geom");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let (sphere, err) = sphere(SPHERE_DEGREE)?;
    eprintln!(
        "sphere: degree {SPHERE_DEGREE}, max | |r| - 1 | = {err:.3e} (sampled 41×41 per face)"
    );
    for (name, db) in [
        ("sphere", sphere),
        ("cylinder", cylinder()?),
        ("wing_body", wing_body(1)?),
        ("../cases/default/wing_body", wing_body(2)?),
    ] {
        db.validate().map_err(|e| format!("{name}: {e}"))?;
        let report = db.check(&CheckOptions::default());
        eprintln!(
            "{name}: {} surfaces, {} patches, {} curve components, {} control nodes, closed = {}, max gap = {:.3e} (ref. length {:.3})",
            report.counts.surfaces,
            report.counts.patches,
            report.counts.curve_components,
            report.counts.control_nodes,
            report.topology.closed,
            report.max_gap,
            report.reference_length
        );
        if !report.is_ok() {
            return Err(format!("{name}: {}", report.problems.join("; ")));
        }
        let path = dir.join(format!("{name}.ron"));
        let text = db.to_ron_string() + "\n";
        // The written text must load back into the same model.
        GeomDb::from_ron_str(&text, &path.display().to_string()).map_err(|e| e.to_string())?;
        write_atomic(&path, text.as_bytes())?;
        eprintln!("wrote {} ({} bytes)", path.display(), text.len());
    }
    Ok(())
}

/// Writes `bytes` to a temporary file next to `path`, then renames it over `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), String> {
    let tmp = path.with_extension(format!(
        "{}.tmp{}",
        path.extension().and_then(|e| e.to_str()).unwrap_or(""),
        std::process::id()
    ));
    std::fs::write(&tmp, bytes).map_err(|e| format!("{}: {e}", tmp.display()))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        format!("{}: {e}", path.display())
    })
}

/// Patch degree of the sphere faces.
pub const SPHERE_DEGREE: usize = 8;

/// Incremental construction of a database with shared corners and edges.
struct Builder {
    db: GeomDb,
    tol: f64,
    /// The corners, merged within `tol` (geom-db's point merger).
    corners: PointMerger,
    /// (start, end, midpoint, component) of edges made from patch borders.
    edges: Vec<(CornerId, CornerId, Point3, CurveCompId)>,
}

impl Builder {
    fn new(name: &str, model_size: f64) -> Self {
        let mut db = GeomDb::empty(name);
        db.units = Some("m".into());
        Self {
            db,
            tol: 1e-8 * model_size,
            corners: PointMerger::new(1e-8 * model_size),
            edges: Vec::new(),
        }
    }

    fn corner(&mut self, p: Point3, name: &str) -> CornerId {
        let m = self.corners.insert(p);
        if m.new {
            self.db.corners.push(geom_db::Corner {
                point: p,
                name: name.to_string(),
            });
        } else if self.db.corners[m.index].name.is_empty() {
            self.db.corners[m.index].name = name.to_string();
        }
        CornerId::from_index(m.index)
    }

    fn surface(&mut self, s: SupportSurface) -> SurfaceId {
        self.db.surfaces.push(s);
        SurfaceId::from_index(self.db.surfaces.len() - 1)
    }

    fn curve(&mut self, c: SupportCurve) -> CurveId {
        self.db.curves.push(c);
        CurveId::from_index(self.db.curves.len() - 1)
    }

    fn component(
        &mut self,
        name: &str,
        curve: CurveId,
        t0: f64,
        t1: f64,
        start: CornerId,
        end: CornerId,
    ) -> CurveCompId {
        self.db.curve_components.push(CurveComponent {
            name: name.to_string(),
            curve,
            t0,
            t1,
            start,
            end,
        });
        CurveCompId::from_index(self.db.curve_components.len() - 1)
    }

    fn surface_component(
        &mut self,
        name: &str,
        surface: SurfaceId,
        inward: Orientation,
        loops: Vec<Vec<OrientedCurve>>,
    ) {
        // `loops` follow the Positive convention (outer counter-clockwise in the parametric
        // plane, holes clockwise); a Negative surface traverses them backwards.
        let loops = match inward {
            Orientation::Positive => loops,
            Orientation::Negative => loops.into_iter().map(reverse_loop).collect(),
        };
        self.db.surface_components.push(SurfaceComponent {
            name: name.to_string(),
            surface,
            loops,
            inward,
        });
    }

    /// The boundary of the parameter rectangle of `sid` as a loop (Positive convention):
    /// one curve component per patch side, shared with any earlier identical side; sides
    /// that collapse to a point (poles) are skipped.
    fn rectangle_loop(&mut self, sid: SurfaceId) -> Vec<OrientedCurve> {
        let s = self.db.surfaces[sid.index()].clone();
        let mut sides: Vec<(Arc, bool)> = Vec::new();
        for i in 0..s.n_u {
            sides.push((s.patch(i, 0).border(Side::VMin), true));
        }
        for j in 0..s.n_v {
            sides.push((s.patch(s.n_u - 1, j).border(Side::UMax), true));
        }
        for i in (0..s.n_u).rev() {
            sides.push((s.patch(i, s.n_v - 1).border(Side::VMax), false));
        }
        for j in (0..s.n_v).rev() {
            sides.push((s.patch(0, j).border(Side::UMin), false));
        }
        let mut lp = Vec::new();
        for (arc, forward) in sides {
            let len: f64 = (0..16)
                .map(|k| (arc.point((k + 1) as f64 / 16.0) - arc.point(k as f64 / 16.0)).norm())
                .sum();
            if len <= self.tol {
                continue; // pole
            }
            let (a, b, mid) = (arc.point(0.0), arc.point(1.0), arc.point(0.5));
            let (ca, cb) = (self.corner(a, ""), self.corner(b, ""));
            let start = if forward { ca } else { cb };
            let found = self.edges.iter().find(|(s0, e0, m0, _)| {
                ((*s0 == ca && *e0 == cb) || (*s0 == cb && *e0 == ca))
                    && (m0 - mid).norm() <= self.tol
            });
            let oc = match found {
                Some(&(s0, _, _, comp)) => OrientedCurve {
                    comp,
                    reversed: s0 != start,
                },
                None => {
                    let name = format!("{} edge {}", s.name, self.edges.len());
                    let mut curve = SupportCurve::new(name.clone(), vec![arc]);
                    curve.defining_surfaces = vec![sid];
                    let cid = self.curve(curve);
                    let comp = self.component(&name, cid, 0.0, 1.0, ca, cb);
                    self.edges.push((ca, cb, mid, comp));
                    OrientedCurve {
                        comp,
                        reversed: !forward,
                    }
                }
            };
            lp.push(oc);
        }
        lp
    }

    /// Records a second defining surface on the curves of a loop.
    fn add_defining_surface(&mut self, lp: &[OrientedCurve], sid: SurfaceId) {
        for oc in lp {
            let cid = self.db.curve_components[oc.comp.index()].curve;
            let ds = &mut self.db.curves[cid.index()].defining_surfaces;
            if !ds.contains(&sid) && ds.len() < 2 {
                ds.push(sid);
            }
        }
    }

    fn finish(mut self) -> Result<GeomDb, String> {
        self.db
            .assign_control_nodes()
            .map_err(|e| format!("{}: {e}", self.db.name))?;
        self.db
            .validate()
            .map_err(|e| format!("{}: {e}", self.db.name))?;
        Ok(self.db)
    }
}

fn reverse_loop(lp: Vec<OrientedCurve>) -> Vec<OrientedCurve> {
    lp.into_iter()
        .rev()
        .map(|oc| OrientedCurve {
            comp: oc.comp,
            reversed: !oc.reversed,
        })
        .collect()
}

fn oc(comp: CurveCompId, reversed: bool) -> OrientedCurve {
    OrientedCurve { comp, reversed }
}

/// The orientation whose inward normal points along `outward` at (u, v).
fn orientation_towards(s: &SupportSurface, u: f64, v: f64, outward: Vector3) -> Orientation {
    let d = s.derivs(u, v);
    if d.du.cross(&d.dv).dot(&outward) >= 0.0 {
        Orientation::Positive
    } else {
        Orientation::Negative
    }
}

// ------------------------------------------------------------------------ sphere

/// The unit sphere as an equal-angle cube sphere of degree `deg`; returns the database and
/// the largest radial error found on a 41×41 sample of each face.
pub fn sphere(deg: usize) -> Result<(GeomDb, f64), String> {
    let axes = [
        (Vector3::x(), Vector3::y(), Vector3::z(), "+x"),
        (-Vector3::x(), Vector3::z(), Vector3::y(), "-x"),
        (Vector3::y(), Vector3::z(), Vector3::x(), "+y"),
        (-Vector3::y(), Vector3::x(), Vector3::z(), "-y"),
        (Vector3::z(), Vector3::x(), Vector3::y(), "+z"),
        (-Vector3::z(), Vector3::y(), Vector3::x(), "-z"),
    ];
    let mut b = Builder::new("unit sphere (cube sphere)", 2.0);
    let mut ids = Vec::new();
    for (n, e1, e2, name) in axes {
        let map = move |u: f64, v: f64| {
            let a = (u - 0.5) * FRAC_PI_2;
            let c = (v - 0.5) * FRAC_PI_2;
            let p = n + e1 * a.tan() + e2 * c.tan();
            Point3::from(p / p.norm())
        };
        let patch = Patch::interpolate(deg, deg, map);
        let s = SupportSurface::new(format!("face {name}"), 1, 1, vec![patch]);
        ids.push((b.surface(s), name));
    }
    for &(sid, name) in &ids {
        let lp = b.rectangle_loop(sid);
        let inward = orientation_towards(
            b.db.surface(sid),
            0.5,
            0.5,
            b.db.surface(sid).point(0.5, 0.5).coords,
        );
        b.surface_component(&format!("sphere {name}"), sid, inward, vec![lp]);
    }
    // Edges belong to two faces: record the second defining surface.
    for k in 0..b.db.surface_components.len() {
        let sc = b.db.surface_components[k].clone();
        b.add_defining_surface(&sc.loops[0], sc.surface);
    }
    let db = b.finish()?;
    let mut err: f64 = 0.0;
    for s in &db.surfaces {
        for i in 0..=40 {
            for j in 0..=40 {
                let p = s.point(i as f64 / 40.0, j as f64 / 40.0);
                err = err.max((p.coords.norm() - 1.0).abs());
            }
        }
    }
    Ok((db, err))
}

// ------------------------------------------------------------------------ cylinder

/// Radius 1, height 2 (z ∈ [0, 2]), four 90° patches around, flat caps.
pub fn cylinder() -> Result<GeomDb, String> {
    const DEG: usize = 8;
    let mut b = Builder::new("cylinder with end caps", 3.0);
    let quarter = |i: usize, x: f64| {
        let th = (i as f64 + x) * FRAC_PI_2;
        (th.cos(), th.sin())
    };
    let side = SupportSurface::new(
        "side",
        4,
        1,
        (0..4)
            .map(|i| {
                Patch::interpolate(DEG, 1, move |u, v| {
                    let (c, s) = quarter(i, u);
                    Point3::new(c, s, 2.0 * v)
                })
            })
            .collect(),
    );
    // caps: u around, v from the rim (v = 0) to the centre (v = 1, a pole)
    let cap = |z: f64, name: &str| {
        SupportSurface::new(
            name,
            4,
            1,
            (0..4)
                .map(|i| {
                    Patch::interpolate(DEG, 1, move |u, v| {
                        let (c, s) = quarter(i, u);
                        Point3::new((1.0 - v) * c, (1.0 - v) * s, z)
                    })
                })
                .collect(),
        )
    };
    let s_side = b.surface(side);
    let s_bot = b.surface(cap(0.0, "bottom cap"));
    let s_top = b.surface(cap(2.0, "top cap"));
    for (sid, name, outward) in [
        (s_side, "side", None),
        (s_bot, "bottom", Some(-Vector3::z())),
        (s_top, "top", Some(Vector3::z())),
    ] {
        let lp = b.rectangle_loop(sid);
        let s = b.db.surface(sid);
        let out = outward.unwrap_or_else(|| {
            let p = s.point(0.5, 0.5);
            Vector3::new(p.x, p.y, 0.0)
        });
        let inward = orientation_towards(s, 0.5, 0.5, out);
        b.surface_component(name, sid, inward, vec![lp]);
    }
    for k in 0..b.db.surface_components.len() {
        let sc = b.db.surface_components[k].clone();
        b.add_defining_surface(&sc.loops[0], sc.surface);
    }
    b.finish()
}

// ------------------------------------------------------------------------ wing-body

/// A NACA 4-digit section (m = max camber, p = its position, t = thickness, chord fractions)
/// with the closed trailing edge (last thickness coefficient −0.1036).
#[derive(Clone, Copy)]
struct Naca {
    m: f64,
    p: f64,
    t: f64,
}

impl Naca {
    /// Point (x, z) at s = √x on the upper (or lower) side.
    fn point(self, s: f64, upper: bool) -> (f64, f64) {
        let x = s * s;
        let s2 = x;
        let yt = 5.0
            * self.t
            * (0.2969 * s - 0.1260 * s2 - 0.3516 * s2 * s2 + 0.2843 * s2 * s2 * s2
                - 0.1036 * s2 * s2 * s2 * s2);
        let (m, p) = (self.m, self.p);
        let (yc, dyc) = if m == 0.0 {
            (0.0, 0.0)
        } else if x < p {
            (
                m / (p * p) * (2.0 * p * x - x * x),
                2.0 * m / (p * p) * (p - x),
            )
        } else {
            (
                m / ((1.0 - p) * (1.0 - p)) * (1.0 - 2.0 * p + 2.0 * p * x - x * x),
                2.0 * m / ((1.0 - p) * (1.0 - p)) * (p - x),
            )
        };
        let th = dyc.atan();
        if upper {
            (x - yt * th.sin(), yc + yt * th.cos())
        } else {
            (x + yt * th.sin(), yc - yt * th.cos())
        }
    }
}

/// Global chordwise parameter u ∈ [0, 4] of the wing (TE lower → LE → TE upper) from the
/// patch index and local parameter: patches split each side at s = s1.
fn section_s(i: usize, x: f64, s1: f64) -> (f64, bool) {
    match i {
        0 => (1.0 - (1.0 - s1) * x, false),
        1 => (s1 - s1 * x, false),
        2 => (s1 * x, true),
        _ => (s1 + (1.0 - s1) * x, true),
    }
}

/// Fuselage dimensions: nose length, cylinder length, tail length, radius.
const NOSE: f64 = 2.0;
const MID: f64 = 5.0;
const TAIL: f64 = 3.0;
const RADIUS: f64 = 0.8;

fn fuselage_point(i: usize, x: f64, j: usize, y: f64) -> Point3 {
    let (px, r) = match i {
        0 => {
            let a = x * FRAC_PI_2;
            (NOSE * (1.0 - a.cos()), RADIUS * a.sin())
        }
        1 => (NOSE + MID * x, RADIUS),
        _ => (NOSE + MID + TAIL * x, RADIUS * (1.0 - x * x)),
    };
    let phi = (j as f64 + y) * FRAC_PI_2;
    Point3::new(px, r * phi.sin(), -r * phi.cos())
}

/// Eq. (12) at fixed wing u: ½|wing(u, v) − fuselage(a, b)|² in (v, a, b), Gauss–Newton
/// Hessian JᵀJ, residual |wing − fuselage|.
struct JunctionProblem<'s> {
    wing: &'s SupportSurface,
    fus: &'s SupportSurface,
    u: f64,
}

impl Problem<3> for JunctionProblem<'_> {
    fn eval(&self, x: &[f64; 3], _active: &[bool; 3]) -> Eval<3> {
        let w = self.wing.derivs(self.u, x[0]);
        let f = self.fus.derivs(x[1], x[2]);
        let r = w.point - f.point;
        let jac = Matrix3::from_columns(&[w.dv, -f.du, -f.dv]);
        let n = r.norm();
        Eval {
            f: if n.is_finite() {
                0.5 * n * n
            } else {
                f64::INFINITY
            },
            g: jac.transpose() * r,
            h: jac.transpose() * jac,
            res: if n.is_finite() { n } else { f64::INFINITY },
            fnoise: 16.0 * f64::EPSILON * n * (w.point.coords.norm() + f.point.coords.norm()),
        }
    }
}

/// Solves wing(u, v) = fuselage(a, b) for (v, a, b) at fixed u (geom-db's safeguarded
/// Newton); returns v and the wing point.
fn junction_point(
    wing: &SupportSurface,
    fus: &SupportSurface,
    u: f64,
    tol: f64,
) -> Result<(f64, Point3), String> {
    // initial guess: the spanwise line meets the cylinder y² + z² = R² (bisection in v)
    let g = |v: f64| {
        let p = wing.point(u, v);
        p.y * p.y + p.z * p.z - RADIUS * RADIUS
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    if g(lo) >= 0.0 || g(hi) <= 0.0 {
        return Err(format!("wing line at u = {u} does not cross the fuselage"));
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if g(mid) < 0.0 { lo = mid } else { hi = mid }
    }
    let v = 0.5 * (lo + hi);
    let p = wing.point(u, v);
    let a = 1.0 + (p.x - NOSE) / MID;
    let b = p.y.atan2(-p.z) / FRAC_PI_2;
    let o = minimise(
        &JunctionProblem { wing, fus, u },
        [v, a, b],
        &[0.0, 0.0, 0.0],
        &[1.0, 3.0, 2.0],
        Settings { tol, max_iters: 50 },
    );
    if !o.report.converged {
        return Err(format!(
            "junction Newton did not converge at u = {u} ({} iterations, |wing − fuselage| = {:e})",
            o.report.iterations, o.report.residual
        ));
    }
    Ok((o.x[0], wing.point(u, o.x[0])))
}

/// The wing-body half model (see the module doc) with `split` junction arcs per chordwise
/// wing patch (1 for `fixtures/geom/wing_body.ron`, whose curve parameter ranges other
/// crates' tests rely on; 2 for the chain's default case,
/// `fixtures/cases/default/wing_body.ron`, whose fuselage cylinder is also of degree 4
/// along x so that the case's waist modifier has control nodes to move).
pub fn wing_body(split: usize) -> Result<GeomDb, String> {
    const DEG: usize = 8;
    let len = NOSE + MID + TAIL;
    let mut b = Builder::new("wing-body half model", len);
    let tol = 1e-13 * len;

    // fuselage: 3 patches along x (nose, cylinder, tail) × 2 around (bottom → side → top).
    // The default case's cylinder is of degree 4 along x (the same straight generators,
    // exactly): its interior control nodes carry the waist at the wing junction (Fig. 9),
    // which a degree-1 cylinder, with nodes only at its two ends, cannot have.
    let deg_u = [DEG, if split > 1 { 4 } else { 1 }, 2];
    let mut patches = Vec::new();
    for j in 0..2 {
        for (i, &du) in deg_u.iter().enumerate() {
            patches.push(Patch::interpolate(du, DEG, move |x, y| {
                fuselage_point(i, x, j, y)
            }));
        }
    }
    let fus = SupportSurface::new("fuselage", 3, 2, patches);

    // wing: root NACA 2412 (chord 2, inside the fuselage at y = 0), tip NACA 0012 (chord 0.8)
    let root = Naca {
        m: 0.02,
        p: 0.4,
        t: 0.12,
    };
    let tip = Naca {
        m: 0.0,
        p: 0.4,
        t: 0.12,
    };
    let s1 = root.p.sqrt();
    let (le_root, c_root) = (Vector3::new(3.0, 0.0, -0.1), 2.0);
    let half_span = 5.0;
    let le_tip = Vector3::new(3.0 + half_span * 25f64.to_radians().tan(), half_span, 0.15);
    let c_tip = 0.8;
    let section = |naca: Naca, le: Vector3, c: f64, i: usize, x: f64| {
        let (s, upper) = section_s(i, x, s1);
        let (px, pz) = naca.point(s, upper);
        Point3::from(le + Vector3::new(c * px, 0.0, c * pz))
    };
    let mut wing_patches = Vec::new();
    for i in 0..4 {
        let r = Arc::interpolate(DEG, |x| section(root, le_root, c_root, i, x));
        let t = Arc::interpolate(DEG, |x| section(tip, le_tip, c_tip, i, x));
        let mut coeffs = Vec::with_capacity(2 * (DEG + 1));
        for k in 0..=DEG {
            coeffs.push(r.coeffs[k]);
            coeffs.push(Point3::from(t.coeffs[k] - r.coeffs[k]));
        }
        wing_patches.push(Patch {
            deg_u: DEG,
            deg_v: 1,
            coeffs,
        });
    }
    let wing = SupportSurface::new("wing", 4, 1, wing_patches);

    // tip cap: u = s from the leading edge (0) to the trailing edge (1) in two patches,
    // v from the lower (0) to the upper (1) side; both chordwise ends are poles
    let cap_patches: Vec<Patch> = (0..2)
        .map(|k| {
            let wing = &wing;
            Patch::interpolate(DEG, 1, move |x, w| {
                let s = if k == 0 { s1 * x } else { s1 + (1.0 - s1) * x };
                let lower_u = if s >= s1 {
                    (1.0 - s) / (1.0 - s1)
                } else {
                    1.0 + (s1 - s) / s1
                };
                let upper_u = if s <= s1 {
                    2.0 + s / s1
                } else {
                    3.0 + (s - s1) / (1.0 - s1)
                };
                let lo = wing.point(lower_u, 1.0);
                let up = wing.point(upper_u, 1.0);
                Point3::from(lo.coords * (1.0 - w) + up.coords * w)
            })
        })
        .collect();
    let cap = SupportSurface::new("tip cap", 2, 1, cap_patches);

    // junction: one support curve following the wing's chordwise patches, `split` arcs of
    // degree 8 per patch (with one arc per patch the curve leaves the surfaces by ~5e-8
    // between control points; with two, ~3e-10: see `cargo xtask fixtures`'s printout)
    let mut arcs = Vec::new();
    let mut v_te = 0.0;
    let sf = split as f64;
    for k in 0..4 * split {
        let mut pts = Vec::new();
        for &x in geom_db::control::nodes(DEG) {
            let (v, p) = junction_point(&wing, &fus, (k as f64 + x) / sf, tol)?;
            if k == 0 && x == 0.0 {
                v_te = v;
            }
            pts.push(p);
        }
        arcs.push(Arc::from_control_points(&pts));
    }
    let mut dev: f64 = 0.0;
    for (k, a) in arcs.iter().enumerate() {
        for i in 0..=100 {
            let x = i as f64 / 100.0;
            let (_, p) = junction_point(&wing, &fus, (k as f64 + x) / sf, tol)?;
            dev = dev.max((a.point(x) - p).norm());
        }
    }
    eprintln!(
        "wing_body ({split} junction arc(s) per wing patch): junction within {dev:.2e} ({:.2e} of the fuselage length) of the exact intersection",
        dev / len
    );
    let te_j = arcs[0].point(0.0);
    let le_j = arcs[2 * split].point(0.0);

    let s_fus = b.surface(fus);
    let s_wing = b.surface(wing);
    let s_cap = b.surface(cap);
    let fus = b.db.surface(s_fus).clone();
    let wing = b.db.surface(s_wing).clone();

    let nose = b.corner(fus.point(0.0, 0.0), "nose");
    let tail = b.corner(fus.point(3.0, 0.0), "tail");
    let c_te_j = b.corner(te_j, "junction trailing edge");
    let c_le_j = b.corner(le_j, "junction leading edge");
    let c_te_t = b.corner(wing.point(0.0, 1.0), "tip trailing edge");
    let c_le_t = b.corner(wing.point(2.0, 1.0), "tip leading edge");

    // curves
    let mut junction = SupportCurve::new("junction", arcs);
    junction.defining_surfaces = vec![s_wing, s_fus];
    let k_junction = b.curve(junction);
    let mut bottom = SupportCurve::new(
        "fuselage bottom (symmetry plane)",
        (0..3).map(|i| fus.patch(i, 0).border(Side::VMin)).collect(),
    );
    bottom.defining_surfaces = vec![s_fus];
    let k_bottom = b.curve(bottom);
    let mut top = SupportCurve::new(
        "fuselage top (symmetry plane)",
        (0..3).map(|i| fus.patch(i, 1).border(Side::VMax)).collect(),
    );
    top.defining_surfaces = vec![s_fus];
    let k_top = b.curve(top);
    let mut te = SupportCurve::new(
        "wing trailing edge",
        vec![wing.patch(0, 0).border(Side::UMin)],
    );
    te.defining_surfaces = vec![s_wing];
    let k_te = b.curve(te);
    let mut tipc = SupportCurve::new(
        "wing tip section",
        (0..4)
            .map(|i| wing.patch(i, 0).border(Side::VMax))
            .collect(),
    );
    tipc.defining_surfaces = vec![s_wing, s_cap];
    let k_tip = b.curve(tipc);

    // curve components
    let (t_le, t_te) = (2.0 * sf, 4.0 * sf);
    let jl = b.component("junction lower", k_junction, 0.0, t_le, c_te_j, c_le_j);
    let ju = b.component("junction upper", k_junction, t_le, t_te, c_le_j, c_te_j);
    let cb = b.component("fuselage bottom", k_bottom, 0.0, 3.0, nose, tail);
    let ct = b.component("fuselage top", k_top, 0.0, 3.0, nose, tail);
    let cte = b.component("trailing edge", k_te, v_te, 1.0, c_te_j, c_te_t);
    let tl = b.component("tip lower", k_tip, 0.0, 2.0, c_te_t, c_le_t);
    let tu = b.component("tip upper", k_tip, 2.0, 4.0, c_le_t, c_te_t);

    // surface components (loops in the Positive convention, see Builder::surface_component)
    let o_fus = orientation_towards(&fus, 1.5, 1.0, Vector3::y());
    let o_wing = orientation_towards(&wing, 2.5, 0.5, Vector3::z());
    let o_cap = orientation_towards(b.db.surface(s_cap), 0.5, 0.5, Vector3::y());
    b.surface_component(
        "fuselage",
        s_fus,
        o_fus,
        vec![
            vec![oc(cb, false), oc(ct, true)],
            vec![oc(jl, false), oc(ju, false)],
        ],
    );
    b.surface_component(
        "wing",
        s_wing,
        o_wing,
        vec![vec![
            oc(jl, false),
            oc(ju, false),
            oc(cte, false),
            oc(tu, true),
            oc(tl, true),
            oc(cte, true),
        ]],
    );
    b.surface_component(
        "wing tip",
        s_cap,
        o_cap,
        vec![vec![oc(tl, true), oc(tu, true)]],
    );
    b.finish()
}
