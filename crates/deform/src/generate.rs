//! Test and benchmark grids: a tetrahedral box with a rectangular block removed, the block's
//! faces forming a "wing" marker (a crude wing-like body in a box), built on
//! [`mesh::generate::box_tets`].

use std::collections::HashMap;

use mesh::{ElementKind, Elements, Marker, Mesh};

use crate::{BoundaryConditions, MarkerRole, RigidMotion};

/// A box of `n[0] × n[1] × n[2]` cubes over `[lo, hi]`, each split into six tetrahedra, with
/// the cubes of index range `[b0, b1)` (per axis) removed. Markers: `x_m x_p y_m y_p z_m z_p`
/// (the box faces, without the parts covered by the block) and `wing` (the block's faces
/// that border the remaining cells). Nodes left without cells are removed. Cells
/// ordered as generated.
///
/// ```
/// let m = deform::generate::box_with_block([4, 4, 4], [0.0; 3], [1.0; 3], [1, 0, 1], [3, 2, 3]);
/// assert_eq!(m.tets().len(), 6 * (64 - 8));
/// assert!(m.marker("wing").is_some());
/// ```
pub fn box_with_block(
    n: [usize; 3],
    lo: [f64; 3],
    hi: [f64; 3],
    b0: [usize; 3],
    b1: [usize; 3],
) -> Mesh {
    let full = mesh::generate::box_tets(n[0], n[1], n[2], lo, hi);
    let inside = |c: usize| {
        let i = c % n[0];
        let j = (c / n[0]) % n[1];
        let k = c / (n[0] * n[1]);
        (b0[0]..b1[0]).contains(&i) && (b0[1]..b1[1]).contains(&j) && (b0[2]..b1[2]).contains(&k)
    };
    let tets = full.tets();
    let key = |mut f: [u32; 3]| {
        f.sort_unstable();
        f
    };
    const FACES: [[usize; 3]; 4] = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
    // Faces of removed tets.
    let mut removed_faces: HashMap<[u32; 3], ()> = HashMap::new();
    for (t, tet) in tets.iter().enumerate() {
        if inside(t / 6) {
            for f in FACES {
                removed_faces.insert(key([tet[f[0]], tet[f[1]], tet[f[2]]]), ());
            }
        }
    }
    let mut kept: Vec<[u32; 4]> = Vec::new();
    let mut wing: Vec<u32> = Vec::new();
    for (t, tet) in tets.iter().enumerate() {
        if inside(t / 6) {
            continue;
        }
        kept.push(*tet);
        for f in FACES {
            let tri = [tet[f[0]], tet[f[1]], tet[f[2]]];
            if removed_faces.contains_key(&key(tri)) {
                wing.extend_from_slice(&tri);
            }
        }
    }
    // Compact nodes.
    let mut new_id = vec![u32::MAX; full.n_nodes()];
    let mut coords = Vec::new();
    for t in &kept {
        for &v in t {
            if new_id[v as usize] == u32::MAX {
                new_id[v as usize] = coords.len() as u32;
                coords.push(full.coords[v as usize]);
            }
        }
    }
    let mut out = Mesh::new(3);
    out.coords = coords;
    let g = out.cells.group_mut(ElementKind::Tetra);
    g.nodes = kept.iter().flatten().map(|&v| new_id[v as usize]).collect();
    for m in &full.markers {
        let mut el = Elements::new();
        if let Some(tris) = m.elements.group(ElementKind::Triangle) {
            let gg = el.group_mut(ElementKind::Triangle);
            for e in tris.iter() {
                if e.iter().all(|&v| new_id[v as usize] != u32::MAX)
                    && !removed_faces.contains_key(&key([e[0], e[1], e[2]]))
                {
                    gg.nodes.extend(e.iter().map(|&v| new_id[v as usize]));
                }
            }
        }
        el.prune();
        out.markers.push(Marker {
            name: m.name.clone(),
            tag: None,
            elements: el,
        });
    }
    let mut el = Elements::new();
    el.group_mut(ElementKind::Triangle).nodes = wing.iter().map(|&v| new_id[v as usize]).collect();
    out.markers.push(Marker {
        name: "wing".into(),
        tag: None,
        elements: el,
    });
    out
}

/// Clusters the nodes of `mesh` towards the box `[lo, hi]` (e.g. the body), axis by axis:
/// along each axis the node spacing is divided by up to `ratio` near the interval
/// `[lo_k, hi_k]` (density 1 + (ratio − 1) exp(−(d / σ)²), d the distance to the interval,
/// σ = 0.1 × the axis length). The map is monotone per axis, so tetrahedra of a structured
/// box keep their orientation; boundary planes of the bounding box stay in place.
pub fn grade_towards(mesh: &mut Mesh, lo: [f64; 3], hi: [f64; 3], ratio: f64) {
    let (blo, bhi) = mesh.bbox();
    for k in 0..3 {
        let (a, b) = (blo[k], bhi[k]);
        if b <= a {
            continue;
        }
        let sigma = 0.1 * (b - a);
        let w = |x: f64| {
            let d = if x < lo[k] {
                lo[k] - x
            } else if x > hi[k] {
                x - hi[k]
            } else {
                0.0
            };
            1.0 + (ratio - 1.0) * (-(d / sigma).powi(2)).exp()
        };
        // Cumulative density G on a fine table (trapezoid rule).
        let m = 8192;
        let xs: Vec<f64> = (0..=m).map(|i| a + (b - a) * i as f64 / m as f64).collect();
        let mut g = vec![0.0; m + 1];
        for i in 0..m {
            g[i + 1] = g[i] + 0.5 * (w(xs[i]) + w(xs[i + 1])) * (xs[i + 1] - xs[i]);
        }
        let total = g[m];
        for p in mesh.coords.iter_mut() {
            let x = p[k];
            if x <= a || x >= b {
                continue;
            }
            // New position x' with G(x') = (x − a)/(b − a) · G(b).
            let target = (x - a) / (b - a) * total;
            let i = g.partition_point(|&v| v < target).clamp(1, m);
            let t = (target - g[i - 1]) / (g[i] - g[i - 1]);
            p[k] = xs[i - 1] + t * (xs[i] - xs[i - 1]);
        }
    }
}

/// The benchmark case of the deformation issue: the box `[0,4]×[0,2]×[0,4]` of `n × n/2 × n`
/// cubes with the block x ∈ [1.5, 2.5], y ∈ [0, 1], z ≈ [1.88, 2.12] removed (the "wing",
/// touching the symmetry plane y = 0). n = 30, 46, 84, 126 give ~15k, ~53k, ~310k, ~1.03M
/// nodes. Boundary conditions: [`wing_pitch_conditions`].
pub fn wing_in_box(n: usize) -> Mesh {
    let ny = n / 2;
    let b0 = [(0.375 * n as f64) as usize, 0, (0.47 * n as f64) as usize];
    let b1 = [
        (0.625 * n as f64) as usize,
        ny / 2,
        ((0.53 * n as f64) as usize).max(b0[2] + 1),
    ];
    box_with_block([n, ny, n], [0.0; 3], [4.0, 2.0, 4.0], b0, b1)
}

/// The benchmark motion on [`wing_in_box`]: the `wing` marker pitched 5° nose up about the
/// spanwise axis through (1.75, 0, 2), the symmetry plane `y_m` sliding, every other
/// marker fixed.
pub fn wing_pitch_conditions() -> BoundaryConditions {
    BoundaryConditions {
        markers: vec![
            (
                "wing".into(),
                MarkerRole::Rigid(RigidMotion {
                    angle_deg: -5.0,
                    axis_point: [1.75, 0.0, 2.0],
                    axis_dir: [0.0, 1.0, 0.0],
                    translation: [0.0; 3],
                }),
            ),
            ("y_m".into(), MarkerRole::SlidePlane),
        ],
        displacements: vec![],
    }
}
