//! Grid statistics against the targets: minimum angles of the triangles and edge lengths
//! relative to the spacing (the edge's length in the metric T at its midpoint, 1 = on size).

use std::collections::HashSet;

use geom_db::prelude::Point3;

use crate::grid::SurfaceGrid;
use crate::spacing::SizeField;

/// Quality figures of a surface grid.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct GridStats {
    /// Number of triangles.
    pub triangles: usize,
    /// Number of distinct edges.
    pub edges: usize,
    /// Smallest angle of any triangle, degrees.
    pub min_angle_deg: f64,
    /// Fraction of triangles whose smallest angle is at least 20°.
    pub frac_min_angle_ge_20: f64,
    /// Fraction of edges whose length is within ±30 % of the spacing.
    pub frac_edges_within_30: f64,
    /// Smallest 3-D mean ratio 4√3 A / Σ l².
    pub worst_quality: f64,
    /// Mean of the mean ratio.
    pub mean_quality: f64,
}

fn min_angle(a: &Point3, b: &Point3, c: &Point3) -> f64 {
    let ang = |p: &Point3, q: &Point3, r: &Point3| (q - p).angle(&(r - p));
    ang(a, b, c)
        .min(ang(b, c, a))
        .min(ang(c, a, b))
        .to_degrees()
}

/// Statistics of `grid` with edge lengths measured against `field`.
pub fn grid_stats(grid: &SurfaceGrid, field: &SizeField) -> GridStats {
    let x = &grid.coords;
    let mut n = 0usize;
    let (mut amin, mut good, mut qmin, mut qsum) = (f64::INFINITY, 0usize, f64::INFINITY, 0.0);
    let mut edges = HashSet::new();
    for c in &grid.components {
        for t in c.global_triangles() {
            let [a, b, cc] = t.map(|v| &x[v as usize]);
            let ma = min_angle(a, b, cc);
            amin = amin.min(ma);
            if ma >= 20.0 {
                good += 1;
            }
            let q = crate::smooth::quality3(a, b, cc);
            qmin = qmin.min(q);
            qsum += q;
            n += 1;
            for i in 0..3 {
                let (p, q) = (t[i], t[(i + 1) % 3]);
                edges.insert((p.min(q), p.max(q)));
            }
        }
    }
    let mut within = 0usize;
    for &(p, q) in &edges {
        let (a, b) = (x[p as usize], x[q as usize]);
        let d = b - a;
        let t = field.metric_at(&Point3::from((a.coords + b.coords) * 0.5));
        let l = d.dot(&(t * d)).sqrt();
        if (0.7..=1.3).contains(&l) {
            within += 1;
        }
    }
    GridStats {
        triangles: n,
        edges: edges.len(),
        min_angle_deg: amin,
        frac_min_angle_ge_20: good as f64 / n.max(1) as f64,
        frac_edges_within_30: within as f64 / edges.len().max(1) as f64,
        worst_quality: qmin,
        mean_quality: qsum / n.max(1) as f64,
    }
}
