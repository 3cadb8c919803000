//! Shared helpers: fixture loading, the wing-body size field, grid validity checks.

use geom_db::GeomDb;

/// Loads `fixtures/geom/<name>.ron` of the workspace.
pub fn fixture(name: &str) -> GeomDb {
    let path = format!(
        "{}/../../fixtures/geom/{name}.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap();
    GeomDb::from_ron_str(&text, &path).unwrap()
}

/// The size field of the wing-body tests: uniform `h`, and a line source of min(h/7.5, 0.02)
/// along the wing's leading edge (from the corner named "junction leading edge" to the one
/// named "tip leading edge") so that the leading-edge radius (about 0.013 at the tip) is
/// resolved: the generator has no curvature-based sizing.
pub fn wing_body_field(db: &GeomDb, h: f64) -> surfgrid::SizeField {
    let corner = |name: &str| {
        db.corners
            .iter()
            .find(|c| c.name == name)
            .unwrap_or_else(|| panic!("the wing-body fixture has no corner named {name:?}"))
            .point
    };
    surfgrid::SizeField::uniform(h)
        .unwrap()
        .with_line(surfgrid::spacing::LineSource {
            a: corner("junction leading edge"),
            b: corner("tip leading edge"),
            h0: (h / 7.5).min(0.02),
            r0: 0.02,
            growth: surfgrid::spacing::Growth::Smoothstep { radius: 0.4 },
        })
        .unwrap()
}

/// Checks a generated (or updated) grid against `db`: every triangle positively oriented
/// with respect to the inward normal (at its parametric centroid) and counter-clockwise in
/// its component's (u, v); every node on its support to 1e-12 relative; conformity (each
/// directed edge once, each edge in at most two triangles, an edge in one triangle only on
/// a curve bounding a single surface component; none if `closed`); every node's link a
/// single path or cycle (manifold, so fans at poles are complete).
pub fn check_grid(db: &GeomDb, g: &surfgrid::SurfaceGrid, closed: bool) {
    use geom_db::eval::ParamSurface;
    use std::collections::HashMap;
    use surfgrid::NodeSupport;
    let l = db.reference_length();
    for i in 0..g.n_nodes() {
        let p = g.evaluate_node(db, i);
        assert!(
            (p - g.coords[i]).norm() <= 1e-12 * l,
            "node {i} off its support"
        );
    }
    for c in &g.components {
        let sc = db.surface_component(c.comp);
        let s = db.surface(sc.surface);
        for (k, t) in c.global_triangles().enumerate() {
            let lt = c.triangles[k].map(|v| c.uv[v as usize]);
            let o = (lt[1][0] - lt[0][0]) * (lt[2][1] - lt[0][1])
                - (lt[1][1] - lt[0][1]) * (lt[2][0] - lt[0][0]);
            assert!(
                o > 0.0,
                "{} triangle {k} not counter-clockwise in (u, v)",
                sc.name
            );
            let uv = [
                (lt[0][0] + lt[1][0] + lt[2][0]) / 3.0,
                (lt[0][1] + lt[1][1] + lt[2][1]) / 3.0,
            ];
            let [a, b, cc] = t.map(|v| g.coords[v as usize]);
            let n = s.normal(uv[0], uv[1]).unwrap() * sc.inward.sign();
            let tn = (b - a).cross(&(cc - a));
            assert!(
                tn.dot(&n) > 0.0,
                "{} triangle {k} {t:?} not positive w.r.t. the inward normal: cos {:.3}, uv {lt:?}, x {:?}",
                sc.name,
                tn.normalize().dot(&n),
                [a, b, cc]
            );
        }
    }
    // curve components bounding a single surface component once (free edges allowed there)
    let mut uses = vec![0usize; db.curve_components.len()];
    for c in &g.components {
        for lp in &db.surface_component(c.comp).loops {
            for oc in lp {
                uses[oc.comp.index()] += 1;
            }
        }
    }
    let on_free_curve = |v: u32| match g.support[v as usize] {
        NodeSupport::Curve { comp, .. } => uses[comp.index()] == 1,
        NodeSupport::Corner(k) => db
            .curve_components
            .iter()
            .enumerate()
            .any(|(j, cc)| uses[j] == 1 && (cc.start == k || cc.end == k)),
        _ => false,
    };
    let mut count: HashMap<(u32, u32), usize> = HashMap::new();
    let mut link: Vec<Vec<(u32, u32)>> = vec![Vec::new(); g.n_nodes()];
    for c in &g.components {
        for t in c.global_triangles() {
            for i in 0..3 {
                *count.entry((t[i], t[(i + 1) % 3])).or_insert(0) += 1;
                link[t[i] as usize].push((t[(i + 1) % 3], t[(i + 2) % 3]));
            }
        }
    }
    for (&(a, b), &n) in &count {
        assert_eq!(n, 1, "directed edge {a}-{b} used {n} times");
        if !count.contains_key(&(b, a)) {
            assert!(!closed, "edge {a}-{b} has no twin: the grid is not closed");
            assert!(
                on_free_curve(a) && on_free_curve(b),
                "edge {a}-{b} has no twin and is not on a free curve: {:?} {:?}",
                g.support[a as usize],
                g.support[b as usize]
            );
        }
    }
    for (v, lk) in link.iter().enumerate() {
        if lk.is_empty() {
            continue;
        }
        let next: HashMap<u32, u32> = lk.iter().copied().collect();
        assert_eq!(next.len(), lk.len(), "node {v}: link not simple");
        let targets: std::collections::HashSet<u32> = lk.iter().map(|e| e.1).collect();
        let start = lk
            .iter()
            .map(|e| e.0)
            .find(|a| !targets.contains(a))
            .unwrap_or(lk[0].0);
        let (mut x, mut steps) = (start, 0);
        while let Some(&y) = next.get(&x) {
            steps += 1;
            x = y;
            if x == start || steps > lk.len() {
                break;
            }
        }
        assert_eq!(steps, lk.len(), "node {v}: its triangles are not one fan");
    }
}
