//! Foot of the normal (Eq. 11) on analytic surfaces and curves.

use crate::shapes::*;
use geom_db::eval::ParamSurface;
use geom_db::prelude::{Point3, Vector3};
use intersect::project::{CurveProjector, ProjectOptions, SurfaceProjector};
use testkit::assert_close;

fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64) / ((1u64 << 53) as f64)
}

#[test]
fn sphere_feet_are_exact() {
    let s = Sphere {
        c: Point3::new(0.3, -0.2, 0.1),
        r: 2.0,
    };
    let proj = SurfaceProjector::new("sphere", &s, &ProjectOptions::default()).unwrap();
    let mut st = 7u64;
    let mut n = 0;
    while n < 300 {
        // random direction away from the poles and the seam, radius 0.3..4
        let az = 0.2 + 5.8 * lcg(&mut st);
        let pol = 0.3 + (std::f64::consts::PI - 0.6) * lcg(&mut st);
        let rho = 0.3 + 3.7 * lcg(&mut st);
        let dir = Vector3::new(pol.sin() * az.cos(), pol.sin() * az.sin(), pol.cos());
        let p = s.c + dir * rho;
        let f = proj.project(&p).unwrap();
        let exact = s.c + dir * s.r;
        assert!(f.report.converged && !f.on_boundary, "{f:?}");
        assert_close!(f.distance, (rho - s.r).abs(), abs = 1e-12);
        assert_close!(f.point, [exact.x, exact.y, exact.z], abs = 1e-11);
        assert_close!(f.uv, [az, pol], abs = 1e-9);
        n += 1;
    }
}

#[test]
fn torus_patch_set_feet_cross_patch_borders() {
    let t = TorusPatches {
        big: 3.0,
        small: 1.0,
        nu: 12,
        nv: 8,
    };
    let proj = SurfaceProjector::new("torus", &t, &ProjectOptions::default()).unwrap();
    let mut st = 11u64;
    let mut worst: f64 = 0.0;
    let mut cross = 0;
    for _ in 0..400 {
        let th = 2.0 * std::f64::consts::PI * lcg(&mut st);
        let ph = 2.0 * std::f64::consts::PI * lcg(&mut st);
        let rr = 0.2 + 1.3 * lcg(&mut st); // inside and outside the tube
        let core = Point3::new(3.0 * th.cos(), 3.0 * th.sin(), 0.0);
        let radial = Vector3::new(th.cos(), th.sin(), 0.0);
        let p = core + (radial * ph.cos() + Vector3::z() * ph.sin()) * rr;
        let (foot, dist) = t.exact_foot(&p);
        let f = proj.project(&p).unwrap();
        assert_close!(f.distance, dist, abs = 1e-12);
        worst = worst.max((Point3::from(f.point) - foot).norm());
        // the reported patch contains the parameters
        assert_eq!(
            f.patch,
            [
                f.uv[0].floor().min(11.0) as usize,
                f.uv[1].floor().min(7.0) as usize
            ]
        );
        // a local Newton started in a neighbouring patch crosses the border to the same foot
        if f.uv[0] + 0.9 > 12.0 {
            continue;
        }
        let uv0 = [f.uv[0] + 0.9, f.uv[1]];
        let g = proj.project_from(&p, uv0);
        if g.report.converged && !g.on_boundary && proj.patch_of(uv0)[0] != f.patch[0] {
            cross += 1;
            assert_close!(g.distance, dist, abs = 1e-12);
        }
    }
    assert!(worst < 1e-10, "worst foot error {worst:e}");
    assert!(cross > 100, "only {cross} border crossings tested");
}

#[test]
fn foot_on_the_domain_boundary_is_reported() {
    let pl = Plane::horizontal(0.0, 1.0);
    let proj = SurfaceProjector::new("plane", &pl, &ProjectOptions::default()).unwrap();
    // beyond the edge u = 1: the foot is on the boundary, the normal condition holds in v only
    let f = proj.project(&Point3::new(1.5, 0.25, 0.3)).unwrap();
    assert!(f.on_boundary && f.report.converged);
    assert_close!(f.uv, [1.0, 0.25], abs = 1e-14);
    assert_close!(f.distance, (0.25f64 + 0.09).sqrt(), rel = 1e-14);
    // inside: interior foot
    let f = proj.project(&Point3::new(0.5, 0.25, -0.3)).unwrap();
    assert!(!f.on_boundary);
    assert_close!(f.distance, 0.3, rel = 1e-14);
}

#[test]
fn bicubic_patch_feet_satisfy_eq_11() {
    let b = BicubicGraph::sample();
    let proj = SurfaceProjector::new("bicubic", &b, &ProjectOptions::default()).unwrap();
    let mut st = 3u64;
    for _ in 0..200 {
        let (u, v) = (0.05 + 0.9 * lcg(&mut st), 0.05 + 0.9 * lcg(&mut st));
        let h = 0.2 * (lcg(&mut st) - 0.5);
        // a point at distance |h| along the normal of (u, v): its foot is (u, v) (for small h)
        let d = b.derivs(u, v);
        let n = d.unit_normal().unwrap();
        let p = d.point + n * h;
        let f = proj.project(&p).unwrap();
        assert_close!(f.distance, h.abs(), abs = 1e-12);
        assert_close!(f.uv, [u, v], abs = 1e-10);
    }
}

#[test]
fn batch_equals_single_and_is_thread_independent() {
    let t = TorusPatches {
        big: 3.0,
        small: 1.0,
        nu: 6,
        nv: 4,
    };
    let proj = SurfaceProjector::new("torus", &t, &ProjectOptions::default()).unwrap();
    let mut st = 5u64;
    let pts: Vec<Point3> = (0..500)
        .map(|_| {
            Point3::new(
                8.0 * lcg(&mut st) - 4.0,
                8.0 * lcg(&mut st) - 4.0,
                3.0 * lcg(&mut st) - 1.5,
            )
        })
        .filter(|p| (p.x * p.x + p.y * p.y).sqrt() > 0.5)
        .collect();
    let many = proj.project_all(&pts).unwrap();
    let one = testkit::with_threads(1, || proj.project_all(&pts).unwrap());
    assert_eq!(many, one);
    for (p, f) in pts.iter().zip(&many).step_by(50) {
        assert_eq!(*f, proj.project(p).unwrap());
    }
}

#[test]
fn curve_feet_on_a_circle_and_errors_name_the_entity() {
    let c = Circle {
        c: Point3::origin(),
        e1: Vector3::x(),
        e2: Vector3::y(),
        r: 2.0,
        dom: (0.0, 3.0),
    };
    let proj = CurveProjector::new("circle 4", &c, &ProjectOptions::default()).unwrap();
    for k in 0..50 {
        let t = 0.05 + 2.9 * k as f64 / 49.0;
        let p = Point3::new(3.0 * t.cos(), 3.0 * t.sin(), 0.7);
        let f = proj.project(&p).unwrap();
        assert_close!(f.t, t, abs = 1e-11);
        assert_close!(f.distance, (1.0f64 + 0.49).sqrt(), rel = 1e-12);
    }
    // beyond the end t = 3: boundary foot
    let p = Point3::new(2.0 * 3.3f64.cos(), 2.0 * 3.3f64.sin(), 0.0);
    let f = proj.project(&p).unwrap();
    assert!(f.on_boundary);
    assert_close!(f.t, 3.0, abs = 1e-15);
    let e = proj
        .project(&Point3::new(f64::INFINITY, 0.0, 0.0))
        .unwrap_err()
        .to_string();
    assert!(e.contains("circle 4"), "{e}");
}

#[test]
fn no_point_lands_on_a_wrong_patch() {
    // brute force: Newton restricted to every patch from a 5×5 grid of starts; the global
    // answer must be as near as the best patch, and on that patch unless it is a tie
    let s = HermitePatches::new(8, 6);
    let proj = SurfaceProjector::new("body", &s, &ProjectOptions::default()).unwrap();
    let subs: Vec<([usize; 2], Restricted<'_, HermitePatches>)> = (0..6)
        .flat_map(|j| (0..8).map(move |i| (i, j)))
        .map(|(i, j)| {
            let r = Restricted {
                s: &s,
                u: [i as f64, i as f64 + 1.0],
                v: [j as f64, j as f64 + 1.0],
            };
            ([i, j], r)
        })
        .collect();
    let one = ProjectOptions::default().with_min_cells(1);
    let subproj: Vec<_> = subs
        .iter()
        .map(|(ij, r)| (*ij, SurfaceProjector::new("patch", r, &one).unwrap()))
        .collect();
    let mut st = 19u64;
    let mut checked = 0;
    for _ in 0..60 {
        let (u, v) = (8.0 * lcg(&mut st), 6.0 * lcg(&mut st));
        let d = s.derivs(u, v);
        let n = d.unit_normal().unwrap();
        let p = d.point + n * (0.4 * (lcg(&mut st) - 0.5));
        let f = proj.project(&p).unwrap();
        let mut best = (f64::INFINITY, [0usize; 2]);
        for (ij, sp) in &subproj {
            for a in 0..5 {
                for b in 0..5 {
                    let uv0 = [
                        ij[0] as f64 + 0.1 + 0.2 * a as f64,
                        ij[1] as f64 + 0.1 + 0.2 * b as f64,
                    ];
                    let g = sp.project_from(&p, uv0);
                    if g.distance < best.0 {
                        best = (g.distance, *ij);
                    }
                }
            }
        }
        assert!(
            f.distance <= best.0 + 1e-12,
            "{} > brute {}",
            f.distance,
            best.0
        );
        if (best.0 - f.distance).abs() < 1e-12 && f.patch != best.1 {
            // only acceptable on a patch border (same point, two patch indices)
            let on_border = f.uv.iter().any(|x| (x - x.round()).abs() < 1e-9);
            assert!(on_border, "patch {:?} vs brute {:?}", f.patch, best.1);
        }
        checked += 1;
    }
    assert_eq!(checked, 60);
}

/// A surface restricted to a sub-rectangle of its domain (for the brute-force check).
struct Restricted<'a, S> {
    s: &'a S,
    u: [f64; 2],
    v: [f64; 2],
}

impl<S: ParamSurface> ParamSurface for Restricted<'_, S> {
    fn domain(&self) -> ([f64; 2], [f64; 2]) {
        (self.u, self.v)
    }
    fn derivs(&self, u: f64, v: f64) -> geom_db::eval::SurfaceDerivs {
        self.s.derivs(u, v)
    }
}
