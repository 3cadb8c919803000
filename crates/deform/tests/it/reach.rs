//! The reach of R ([`DeformOptions::rotation_reach`]): its limits (a reach of 0 is the plain
//! spring system, an infinite one the full R), that it bounds the far-field motion, and the
//! far-field report against an independent distance computation.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use deform::{BoundaryConditions, DeformOptions, Deformed, MarkerRole, RigidMotion};
use mesh::Mesh;

fn grid() -> Mesh {
    deform::generate::box_with_block([10, 8, 9], [0.0; 3], [2.0, 1.6, 1.8], [3, 0, 4], [7, 3, 5])
}

/// The wing pitched by 8° about a spanwise axis through its middle; the box's side y = 0
/// slides, the rest of the box is fixed.
fn pitch(m: &Mesh, opts: &DeformOptions) -> Deformed {
    let bc = BoundaryConditions {
        markers: vec![
            (
                "wing".into(),
                MarkerRole::Rigid(RigidMotion {
                    angle_deg: 8.0,
                    axis_point: [1.0, 0.0, 0.9],
                    axis_dir: [0.0, 1.0, 0.0],
                    translation: [0.0; 3],
                }),
            ),
            ("y_m".into(), MarkerRole::SlidePlane),
        ],
        displacements: Vec::new(),
    };
    deform::deform(m, &bc, opts).unwrap()
}

fn opts(adapt_rotation: bool, rotation_reach: Option<f64>) -> DeformOptions {
    DeformOptions {
        adapt_rotation,
        rotation_reach,
        rel_tol: 1e-12,
        ..Default::default()
    }
}

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max)
}

#[test]
fn reach_zero_is_the_plain_spring_system_and_infinite_reach_is_full_r() {
    let m = grid();
    let full = pitch(&m, &opts(true, None));
    let plain = pitch(&m, &opts(false, None));
    let wall = full.report.far_field.wall_max_displacement;
    assert!(wall > 0.05, "{wall}");
    // the two limits differ: the comparisons below are not won by a motion R does not change
    let apart = max_diff(&full.coords, &plain.coords);
    assert!(apart > 1e-2 * wall, "R changes little: {apart:e}");
    // infinite reach: the full R, bit for bit
    let inf = pitch(&m, &opts(true, Some(f64::INFINITY)));
    assert!(inf.coords == full.coords);
    // reach 0: R = I everywhere (skin included), to the solver tolerance
    let zero = pitch(&m, &opts(true, Some(0.0)));
    let e = max_diff(&zero.coords, &plain.coords);
    assert!(e <= 1e-9 * wall, "reach 0 vs no R: {e:e}");
    // a reach far beyond the grid tends to the full R (1 − φ ≤ 3 (diag / L)²)
    let diag = m.bbox_diagonal();
    let far = pitch(&m, &opts(true, Some(1e3 * diag)));
    let e = max_diff(&far.coords, &full.coords);
    assert!(
        e <= 1e-4 * apart,
        "reach 1e3 × diag vs full R: {e:e} of {apart:e}"
    );
    // a finite reach lies in between
    let mid = pitch(&m, &opts(true, Some(0.3 * diag)));
    let (a, b) = (
        max_diff(&mid.coords, &full.coords),
        max_diff(&mid.coords, &plain.coords),
    );
    assert!(a > 1e-3 * apart && b > 1e-3 * apart, "{a:e} {b:e}");
}

#[test]
fn a_short_reach_lowers_the_far_field_motion() {
    let m = grid();
    let full = pitch(&m, &opts(true, None)).report.far_field;
    let short = pitch(&m, &opts(true, Some(0.5 * full.distance)))
        .report
        .far_field;
    assert!(full.nodes > 0 && full.nodes == short.nodes);
    assert!(full.max_displacement > 0.0);
    assert!(
        short.max_displacement < full.max_displacement,
        "{short:?} vs {full:?}"
    );
}

/// Distance of every node from the `source` nodes along the grid's edges (the tetrahedra's
/// edges), by the textbook Dijkstra on an edge list built here.
pub(crate) fn dijkstra(m: &Mesh, source: &[bool]) -> Vec<f64> {
    let n = m.n_nodes();
    let mut nb: Vec<Vec<usize>> = vec![Vec::new(); n];
    for v in m.tets() {
        for a in 0..v.len() {
            for b in 0..v.len() {
                if a != b {
                    nb[v[a] as usize].push(v[b] as usize);
                }
            }
        }
    }
    let mut d = vec![f64::INFINITY; n];
    let mut heap = BinaryHeap::new();
    for i in (0..n).filter(|&i| source[i]) {
        d[i] = 0.0;
        heap.push(Reverse((0u64, i)));
    }
    while let Some(Reverse((k, i))) = heap.pop() {
        if f64::from_bits(k) > d[i] {
            continue;
        }
        for &j in &nb[i] {
            let (p, q) = (m.coords[i], m.coords[j]);
            let l = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            if d[i] + l < d[j] {
                d[j] = d[i] + l;
                heap.push(Reverse((d[j].to_bits(), j)));
            }
        }
    }
    d
}

#[test]
fn far_field_report_matches_an_independent_maximum() {
    let m = grid();
    let out = pitch(&m, &opts(true, None));
    let ff = out.report.far_field;
    let wing = m.marker("wing").unwrap().elements.node_set();
    let mut source = vec![false; m.n_nodes()];
    for &v in &wing {
        source[v as usize] = true;
    }
    let d = dijkstra(&m, &source);
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &v in &wing {
        for k in 0..3 {
            lo[k] = lo[k].min(m.coords[v as usize][k]);
            hi[k] = hi[k].max(m.coords[v as usize][k]);
        }
    }
    let diag = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    testkit::assert_close!(ff.distance, diag, rel = 1e-15);
    let disp = |i: usize| {
        let (p, q) = (m.coords[i], out.coords[i]);
        (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt()
    };
    let far: Vec<usize> = (0..m.n_nodes()).filter(|&i| d[i] >= diag).collect();
    assert_eq!(ff.nodes, far.len());
    assert!(!far.is_empty());
    let max = far.iter().map(|&i| disp(i)).fold(0.0, f64::max);
    assert_eq!(ff.max_displacement, max);
    assert_eq!(disp(ff.node.unwrap() as usize), max);
    let wall = wing.iter().map(|&v| disp(v as usize)).fold(0.0, f64::max);
    assert_eq!(ff.wall_max_displacement, wall);
}
