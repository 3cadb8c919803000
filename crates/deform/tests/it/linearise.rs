//! [`deform::Linearisation`]: the forward product against central differences of the whole
//! deformation (with and without R, sliding on planes and on curved supports, several
//! increments), and the reverse product against the forward one (dot-product test).

use std::sync::OnceLock;

use deform::{BoundaryConditions, DeformOptions, Deformer, MarkerRole, Stiffness, Supports};
use mesh::Mesh;
use proptest::prelude::*;

/// The wing's nodes, sorted.
fn wing_nodes(m: &Mesh) -> Vec<u32> {
    let mut nodes: Vec<u32> = m
        .marker("wing")
        .unwrap()
        .elements
        .node_set()
        .into_iter()
        .collect();
    nodes.sort_unstable();
    nodes
}

/// A smooth displacement field of the wing: twist about y and heave, amplitude `amp`
/// (`lx`, `ly`, `lz`: the box size).
fn field(m: &Mesh, nodes: &[u32], amp: f64, size: [f64; 3]) -> Vec<[f64; 3]> {
    nodes
        .iter()
        .map(|&v| {
            let p = m.coords[v as usize];
            let s = p[1] / size[1];
            let (x, z) = (p[0] / size[0] - 0.5, p[2] / size[2] - 0.5);
            [
                amp * 0.08 * s * z,
                amp * 0.03 * s * (1.0 + x),
                amp * (0.1 * s * s - 0.08 * s * x),
            ]
        })
        .collect()
}

/// A second, different field: the perturbation direction.
fn direction(m: &Mesh, nodes: &[u32], size: [f64; 3]) -> Vec<[f64; 3]> {
    nodes
        .iter()
        .map(|&v| {
            let p = m.coords[v as usize];
            let (x, y, z) = (p[0] / size[0], p[1] / size[1], p[2] / size[2]);
            [
                0.05 * (3.0 * y + x).sin(),
                0.04 * (2.0 * z - x).cos() * y,
                0.06 * (x * z + y),
            ]
        })
        .collect()
}

/// The wing's nodes `nodes` prescribed (displacements given per call), the symmetry plane
/// y = 0 sliding, the rest of the boundary fixed.
fn sliding_wing(nodes: &[u32]) -> BoundaryConditions {
    BoundaryConditions {
        markers: vec![("y_m".into(), MarkerRole::SlidePlane)],
        displacements: nodes.iter().map(|&v| (v, [0.0; 3])).collect(),
    }
}

fn box_grid() -> Mesh {
    deform::generate::box_with_block([9, 6, 8], [0.0; 3], [2.0, 1.2, 1.6], [3, 0, 3], [6, 3, 5])
}

const BOX: [f64; 3] = [2.0, 1.2, 1.6];

fn tight(opts: DeformOptions) -> DeformOptions {
    DeformOptions {
        rel_tol: 1e-13,
        slide_rel_tol: 1e-13,
        ..opts
    }
}

fn add(a: &[[f64; 3]], h: f64, b: &[[f64; 3]]) -> Vec<[f64; 3]> {
    a.iter()
        .zip(b)
        .map(|(p, q)| [p[0] + h * q[0], p[1] + h * q[1], p[2] + h * q[2]])
        .collect()
}

fn norm(a: &[[f64; 3]]) -> f64 {
    a.iter().flatten().map(|v| v * v).sum::<f64>().sqrt()
}

/// The forward product at `w` along `dw` (inputs: the nodes `nodes`) against central
/// differences with step `h`: returns (|J dw − FD| / |FD|, |FD| / |dw| over the nodes that
/// are not inputs, increments).
pub(crate) fn forward_vs_differences(
    d: &Deformer,
    nodes: &[u32],
    w: &[[f64; 3]],
    dw: &[[f64; 3]],
    h: f64,
) -> (f64, f64, usize) {
    let base = d.deform(w, None).unwrap();
    let lin = d.linearise(&base).unwrap().with_rel_tol(1e-13);
    let jv = lin.jvp(dw).unwrap();
    let (xp, xm) = (
        d.deform(&add(w, h, dw), None).unwrap(),
        d.deform(&add(w, -h, dw), None).unwrap(),
    );
    assert_eq!(xp.report.increments, base.report.increments);
    assert_eq!(xm.report.increments, base.report.increments);
    let fd: Vec<[f64; 3]> = xp
        .coords
        .iter()
        .zip(&xm.coords)
        .map(|(p, q)| {
            [
                (p[0] - q[0]) / (2.0 * h),
                (p[1] - q[1]) / (2.0 * h),
                (p[2] - q[2]) / (2.0 * h),
            ]
        })
        .collect();
    let err: Vec<[f64; 3]> = add(&jv.values, -1.0, &fd);
    let mut inner = fd.clone();
    for &v in nodes {
        inner[v as usize] = [0.0; 3];
    }
    (
        norm(&err) / norm(&fd),
        norm(&inner) / norm(dw),
        base.report.increments,
    )
}

/// The product on the nodes that are not inputs must be far from zero: the comparison is
/// then not won by a product that only copies dw onto the prescribed nodes.
fn check(what: &str, r: (f64, f64, usize), increments: usize) {
    let (err, size, inc) = r;
    eprintln!(
        "{what}: relative error {err:.2e}, |FD off the inputs| / |dw| = {size:.3}, {inc} increment(s)"
    );
    assert_eq!(inc, increments, "{what}: increments");
    assert!(
        size > 0.5,
        "{what}: the product is too small to test ({size})"
    );
    assert!(err < 1e-6, "{what}: relative error {err:e}");
}

#[test]
fn forward_product_matches_central_differences_with_and_without_r() {
    let m = box_grid();
    let nodes = wing_nodes(&m);
    // R in full, none, and blended to the identity across the field (the reach of R, 0.7:
    // the box's nodes lie 0 to ~1.5 from the wing).
    for (rot, reach) in [(true, None), (false, None), (true, Some(0.7))] {
        let opts = tight(DeformOptions {
            adapt_rotation: rot,
            rotation_reach: reach,
            ..Default::default()
        });
        let bc = sliding_wing(&nodes);
        let d = Deformer::new(&m, &bc, &opts).unwrap();
        let w = field(&m, &nodes, 1.0, BOX);
        let dw = direction(&m, &nodes, BOX);
        check(
            &format!("R {rot}, reach {reach:?}"),
            forward_vs_differences(&d, &nodes, &w, &dw, 1e-4),
            1,
        );
    }
}

#[test]
fn forward_product_matches_central_differences_at_zero_motion() {
    // The baseline itself (nothing is solved there): R's derivative is still there.
    let m = box_grid();
    let nodes = wing_nodes(&m);
    let bc = sliding_wing(&nodes);
    let d = Deformer::new(&m, &bc, &tight(DeformOptions::default())).unwrap();
    let w = vec![[0.0; 3]; nodes.len()];
    let dw = direction(&m, &nodes, BOX);
    check(
        "zero motion",
        forward_vs_differences(&d, &nodes, &w, &dw, 1e-4),
        1,
    );
}

#[test]
fn forward_product_matches_central_differences_over_increments() {
    let m = box_grid();
    let nodes = wing_nodes(&m);
    for stiffness in [Stiffness::InverseLengthSquared, Stiffness::InverseLength] {
        // Any loss of minimum quality splits the motion: 4 increments.
        let opts = tight(DeformOptions {
            stiffness,
            min_quality_ratio: 1.0,
            max_increments: 4,
            ..Default::default()
        });
        let bc = sliding_wing(&nodes);
        let d = Deformer::new(&m, &bc, &opts).unwrap();
        let w = field(&m, &nodes, 2.0, BOX);
        let dw = direction(&m, &nodes, BOX);
        check(
            &format!("4 increments, {stiffness}"),
            // The step of the study (docs/crates/deform.md, "Linearisation"): the later
            // increments' f32 stiffnesses add noise ∝ 1/h.
            forward_vs_differences(&d, &nodes, &w, &dw, 1e-2),
            4,
        );
    }
}

/// The bulged box of `supports.rs` with its bottom sliding on the curved support and the
/// wing displaced.
struct OnSupports {
    m: Mesh,
    db: geom_db::GeomDb,
    sup: Vec<(u32, deform::Support)>,
    nodes: Vec<u32>,
}

fn on_supports() -> OnSupports {
    let (m, db, sup) = crate::supports::bulged_box(1.0);
    let nodes = wing_nodes(&m);
    OnSupports { m, db, sup, nodes }
}

impl OnSupports {
    fn deformer(&self, opts: &DeformOptions) -> Deformer<'_> {
        let bc = BoundaryConditions {
            markers: vec![("y_m".into(), MarkerRole::SlideOnSupport)],
            displacements: self.nodes.iter().map(|&v| (v, [0.0; 3])).collect(),
        };
        let sup = Supports {
            db: &self.db,
            nodes: self.sup.clone(),
        };
        Deformer::on_supports(&self.m, &bc, &sup, opts).unwrap()
    }
}

const BULGED: [f64; 3] = [2.0, 1.5, 2.2];

#[test]
fn forward_product_matches_central_differences_on_curved_supports() {
    let c = on_supports();
    for (inc, ratio) in [(1, 0.2), (2, 1.0)] {
        let opts = tight(DeformOptions {
            min_quality_ratio: ratio,
            max_increments: inc,
            ..Default::default()
        });
        let d = c.deformer(&opts);
        let w = field(&c.m, &c.nodes, 1.5, BULGED);
        let dw = direction(&c.m, &c.nodes, BULGED);
        check(
            &format!("supports, {inc} increment(s)"),
            forward_vs_differences(&d, &c.nodes, &w, &dw, if inc > 1 { 1e-2 } else { 1e-4 }),
            inc,
        );
    }
}

/// The reverse product of the most general case (R, curved supports, two increments).
fn general() -> &'static (OnSupports, Vec<[f64; 3]>) {
    static CASE: OnceLock<(OnSupports, Vec<[f64; 3]>)> = OnceLock::new();
    CASE.get_or_init(|| {
        let c = on_supports();
        let w = field(&c.m, &c.nodes, 1.5, BULGED);
        (c, w)
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    #[test]
    fn reverse_product_is_the_transpose_of_the_forward_one(seed in 0u64..1_000_000) {
        let (c, w) = general();
        let opts = DeformOptions {
            min_quality_ratio: 1.0,
            max_increments: 2,
            ..Default::default()
        };
        let d = c.deformer(&opts);
        let base = d.deform(w, None).unwrap();
        prop_assert_eq!(base.report.increments, 2);
        // 1e-12, not tighter: at 1e-14 the true residual of a solve that CG's recurrence
        // calls converged can sit at the rounding floor just above it (seed 491171: 1.001e-14
        // after 12 iterations), which is reported as NoConvergence. 1e-12 leaves the dot
        // products a margin of 100 below the 1e-10 checked here.
        let lin = d.linearise(&base).unwrap().with_rel_tol(1e-12);
        // Pseudo-random vectors from the seed.
        let mut s = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let mut next = move || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let dw: Vec<[f64; 3]> = (0..lin.n_inputs()).map(|_| [next(), next(), next()]).collect();
        let yb: Vec<[f64; 3]> = (0..lin.n_nodes()).map(|_| [next(), next(), next()]).collect();
        let jv = lin.jvp(&dw).unwrap().values;
        let jt = lin.vjp(&yb).unwrap().values;
        let dotp = |a: &[[f64; 3]], b: &[[f64; 3]]| -> f64 {
            a.iter().zip(b).map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2]).sum()
        };
        let (l, r) = (dotp(&jv, &yb), dotp(&dw, &jt));
        let scale = norm(&jv) * norm(&yb);
        prop_assert!((l - r).abs() <= 1e-10 * scale, "{} vs {} (scale {})", l, r, scale);
    }
}

/// The dot-product test with R blended to the identity (the reach of R) in several
/// increments, for a few fixed random vectors.
#[test]
fn reverse_product_is_the_transpose_of_the_forward_one_with_a_reach() {
    let m = box_grid();
    let nodes = wing_nodes(&m);
    let opts = DeformOptions {
        min_quality_ratio: 1.0,
        max_increments: 4,
        rotation_reach: Some(0.7),
        ..Default::default()
    };
    let bc = sliding_wing(&nodes);
    let d = Deformer::new(&m, &bc, &opts).unwrap();
    let base = d.deform(&field(&m, &nodes, 2.0, BOX), None).unwrap();
    assert!(base.report.increments > 1, "{}", base.report.increments);
    let lin = d.linearise(&base).unwrap().with_rel_tol(1e-14);
    for seed in [3u64, 77] {
        let mut s = seed;
        let mut next = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let dw: Vec<[f64; 3]> = (0..lin.n_inputs())
            .map(|_| [next(), next(), next()])
            .collect();
        let yb: Vec<[f64; 3]> = (0..lin.n_nodes())
            .map(|_| [next(), next(), next()])
            .collect();
        let jv = lin.jvp(&dw).unwrap().values;
        let jt = lin.vjp(&yb).unwrap().values;
        let dotp = |a: &[[f64; 3]], b: &[[f64; 3]]| -> f64 {
            a.iter()
                .zip(b)
                .map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
                .sum()
        };
        let (l, r) = (dotp(&jv, &yb), dotp(&dw, &jt));
        let scale = norm(&jv) * norm(&yb);
        assert!((l - r).abs() <= 1e-10 * scale, "{l} vs {r} (scale {scale})");
    }
}

/// The forward product with the reach of R on curved supports against central differences
/// (one increment).
#[test]
fn forward_product_matches_central_differences_on_supports_with_a_reach() {
    let c = on_supports();
    let opts = tight(DeformOptions {
        rotation_reach: Some(0.6),
        ..Default::default()
    });
    let d = c.deformer(&opts);
    let w = field(&c.m, &c.nodes, 1.5, BULGED);
    let dw = direction(&c.m, &c.nodes, BULGED);
    check(
        "supports, reach 0.6",
        forward_vs_differences(&d, &c.nodes, &w, &dw, 1e-4),
        1,
    );
}

/// The step-size study of docs/crates/deform.md ("Linearisation"): the error of central
/// differences against the forward product for steps h from 3e-2 to 1e-6, one and four
/// increments. One increment: truncation (∝ h²) down to ~1e-11 at h ≈ 3e-4, then the
/// solver's residual (∝ 1/h). Four increments: ∝ 1/h from h ≈ 1e-2 down: the stiffnesses of
/// the later increments are rounded to f32 (6e-8 relative) at a state that moves with h.
/// Checks that the best step is below the tests' 1e-6.
#[test]
#[ignore = "step-size study (a few seconds); run by cargo xtask regress"]
fn step_size_study() {
    let m = box_grid();
    let nodes = wing_nodes(&m);
    for inc in [1usize, 4] {
        let opts = tight(DeformOptions {
            min_quality_ratio: if inc > 1 { 1.0 } else { 0.2 },
            max_increments: inc,
            ..Default::default()
        });
        let bc = sliding_wing(&nodes);
        let d = Deformer::new(&m, &bc, &opts).unwrap();
        let w = field(&m, &nodes, 2.0, BOX);
        let dw = direction(&m, &nodes, BOX);
        let mut best = f64::INFINITY;
        for h in [3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 1e-6] {
            let r = forward_vs_differences(&d, &nodes, &w, &dw, h);
            eprintln!("{inc} increment(s), h = {h:e}: relative error {:.3e}", r.0);
            best = best.min(r.0);
        }
        assert!(best < 1e-6, "{inc} increment(s): best {best:e}");
    }
}

/// A reverse product whose adjoint solves start from an earlier one's solutions (at a
/// nearby motion and cotangent, two increments, R on) gives the cold product's answer to
/// the solver tolerance in fewer iterations; a start that does not fit (another set-up's)
/// is ignored. Jacobi-preconditioned: on this small grid the multigrid is a single dense
/// level, an exact solve that leaves a start nothing to save.
#[test]
fn warm_started_reverse_product_agrees_with_the_cold_one() {
    let m = box_grid();
    let nodes = wing_nodes(&m);
    let opts = DeformOptions {
        min_quality_ratio: 1.0,
        max_increments: 2,
        rel_tol: 1e-10,
        solver: deform::SolverKind::PcgJacobi,
        ..Default::default()
    };
    let bc = sliding_wing(&nodes);
    let d = Deformer::new(&m, &bc, &opts).unwrap();
    let w = field(&m, &nodes, 2.0, BOX);
    let w2: Vec<[f64; 3]> = w.iter().map(|v| v.map(|c| 1.01 * c)).collect();
    let (a, b) = (d.deform(&w, None).unwrap(), d.deform(&w2, None).unwrap());
    assert_eq!(a.report.increments, 2);
    assert_eq!(b.report.increments, 2);
    let (la, lb) = (d.linearise(&a).unwrap(), d.linearise(&b).unwrap());
    let yb: Vec<[f64; 3]> = m
        .coords
        .iter()
        .map(|p| [(p[0] + p[2]).sin(), (2.0 * p[1]).cos(), (p[0] * p[2]).sin()])
        .collect();
    let yb2: Vec<[f64; 3]> = yb
        .iter()
        .zip(&m.coords)
        .map(|(y, p)| std::array::from_fn(|c| y[c] * (1.0 + 0.01 * (p[c] + 0.3).sin())))
        .collect();
    let mut start = deform::AdjointStart::default();
    la.vjp_from(&yb, &mut start).unwrap();
    let cold = lb.vjp(&yb2).unwrap();
    let warm = lb.vjp_from(&yb2, &mut start).unwrap();
    let diff: Vec<[f64; 3]> = add(&warm.values, -1.0, &cold.values);
    let rel = norm(&diff) / norm(&cold.values);
    assert!(rel < 1e-8, "warm against cold: {rel:e}");
    assert!(
        warm.iterations < cold.iterations,
        "warm {} against cold {} iterations",
        warm.iterations,
        cold.iterations
    );
    // The same start again: already the solution of this product.
    let again = lb.vjp_from(&yb2, &mut start).unwrap();
    assert!(again.iterations < warm.iterations, "{}", again.iterations);
    // Another set-up's start (other unknowns) is not used.
    let small = deform::generate::box_with_block([7, 5, 6], [0.0; 3], BOX, [2, 0, 2], [5, 3, 4]);
    let sn = wing_nodes(&small);
    let sbc = sliding_wing(&sn);
    let ds = Deformer::new(&small, &sbc, &opts).unwrap();
    let rs = ds.deform(&field(&small, &sn, 2.0, BOX), None).unwrap();
    let ls = ds.linearise(&rs).unwrap();
    let ys: Vec<[f64; 3]> = (0..ls.n_nodes()).map(|_| [1.0, 0.5, -0.3]).collect();
    let cold_s = ls.vjp(&ys).unwrap();
    let other = ls.vjp_from(&ys, &mut start).unwrap();
    assert_eq!(other, cold_s);
}
