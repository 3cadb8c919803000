//! Spacing control (§2.3): the desired element size as a 3D metric tensor T(x) (a symmetric
//! positive definite 3×3 matrix; an isotropic size h is T = I / h²).
//!
//! * a uniform size `h_far`;
//! * point and line sources: h(d) = h0 for d ≤ r0, then growing with the distance d to the
//!   source either by a smoothstep over a radius R, h = h0 + (h_far − h0) s²(3 − 2s),
//!   s = min(1, (d − r0)/R), or linearly, h = h0 + g (d − r0);
//! * a background tetrahedral mesh carrying a metric T per node, interpolated linearly
//!   inside each tetrahedron (§2.3: "a transformation T … interpolated linearly").
//!
//! Sources combine by taking the smallest size; the background metric is combined with the
//! isotropic one by metric intersection (the largest metric along every direction).
//! This field is the *surface* spacing; a volume spacing, if any, is kept separate.
//!
//! On a surface r(u, v) the metric of the parametric plane is M = Jᵀ T J with J = [r_u r_v],
//! which for T = I/h² is the paper's M = G / h² with G the first fundamental form (Eq. 33):
//! lengths measured with M are in units of the desired size ("always unity").

use geom_db::prelude::{Matrix2, Matrix3, Point3, Vector3};

use crate::error::{Error, Result};

/// How the size grows away from a source.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Growth {
    /// Smoothstep from h0 to the far size over `radius` (length units).
    Smoothstep {
        /// Length over which the size reaches the far size.
        radius: f64,
    },
    /// Linear growth h0 + rate·(d − r0), capped by the far size.
    Linear {
        /// Growth rate (size per unit distance).
        rate: f64,
    },
}

/// A point source.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointSource {
    /// Centre.
    pub center: Point3,
    /// Size at the source.
    pub h0: f64,
    /// Radius of the core where the size is h0.
    pub r0: f64,
    /// Growth law outside the core.
    pub growth: Growth,
}

/// A line (segment) source.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineSource {
    /// First end.
    pub a: Point3,
    /// Second end.
    pub b: Point3,
    /// Size on the segment.
    pub h0: f64,
    /// Radius of the core where the size is h0.
    pub r0: f64,
    /// Growth law outside the core.
    pub growth: Growth,
}

/// A background tetrahedral mesh with a metric per node, interpolated linearly.
#[derive(Debug, Clone, PartialEq)]
pub struct Background {
    /// Node positions.
    pub nodes: Vec<Point3>,
    /// Metric T per node (symmetric positive definite).
    pub metric: Vec<Matrix3>,
    /// Tetrahedra (node indices).
    pub tets: Vec<[u32; 4]>,
    boxes: Vec<(Point3, Point3)>,
}

impl Background {
    /// A background mesh; checks indices and that every metric is symmetric positive definite.
    pub fn new(nodes: Vec<Point3>, metric: Vec<Matrix3>, tets: Vec<[u32; 4]>) -> Result<Self> {
        if metric.len() != nodes.len() {
            return Err(Error::Mismatch {
                what: format!(
                    "{} background metrics for {} nodes",
                    metric.len(),
                    nodes.len()
                ),
            });
        }
        for (i, m) in metric.iter().enumerate() {
            let sym = (m - m.transpose()).norm() <= 1e-12 * m.norm();
            if !sym || m.cholesky().is_none() {
                return Err(Error::BadSize {
                    what: format!("background metric at node {i} (not SPD), norm"),
                    value: m.norm(),
                });
            }
        }
        let mut boxes = Vec::with_capacity(tets.len());
        for (k, t) in tets.iter().enumerate() {
            if t.iter().any(|&v| v as usize >= nodes.len()) {
                return Err(Error::Mismatch {
                    what: format!("background tetrahedron {k} refers to a missing node"),
                });
            }
            let mut lo = nodes[t[0] as usize];
            let mut hi = lo;
            for &v in &t[1..] {
                let p = nodes[v as usize];
                lo = lo.inf(&p);
                hi = hi.sup(&p);
            }
            boxes.push((lo, hi));
        }
        Ok(Self {
            nodes,
            metric,
            tets,
            boxes,
        })
    }

    /// The interpolated metric at `p`, `None` outside the background mesh (linear search
    /// over the tetrahedra's bounding boxes: meant for small background meshes).
    pub fn metric_at(&self, p: &Point3) -> Option<Matrix3> {
        for (k, t) in self.tets.iter().enumerate() {
            let (lo, hi) = &self.boxes[k];
            let tol = 1e-12 * (hi - lo).norm();
            if (0..3).any(|i| p[i] < lo[i] - tol || p[i] > hi[i] + tol) {
                continue;
            }
            let x: Vec<Point3> = t.iter().map(|&v| self.nodes[v as usize]).collect();
            let m = Matrix3::from_columns(&[x[1] - x[0], x[2] - x[0], x[3] - x[0]]);
            let Some(l) = m.try_inverse().map(|inv| inv * (p - x[0])) else {
                continue;
            };
            let w = [1.0 - l.x - l.y - l.z, l.x, l.y, l.z];
            if w.iter().all(|&w| w >= -1e-12) {
                let mut out = Matrix3::zeros();
                for (j, &v) in t.iter().enumerate() {
                    out += self.metric[v as usize] * w[j];
                }
                return Some(out);
            }
        }
        None
    }
}

/// The surface spacing: uniform size, sources and an optional background metric.
#[derive(Debug, Clone, PartialEq)]
pub struct SizeField {
    /// The far-field (uniform) size.
    pub h_far: f64,
    /// Point sources.
    pub points: Vec<PointSource>,
    /// Line sources.
    pub lines: Vec<LineSource>,
    /// Background mesh, if any.
    pub background: Option<Background>,
}

fn grow(h0: f64, r0: f64, growth: Growth, h_far: f64, d: f64) -> f64 {
    if d <= r0 {
        return h0;
    }
    let h = match growth {
        Growth::Smoothstep { radius } => {
            let s = ((d - r0) / radius).clamp(0.0, 1.0);
            h0 + (h_far - h0) * s * s * (3.0 - 2.0 * s)
        }
        Growth::Linear { rate } => h0 + rate * (d - r0),
    };
    h.min(h_far.max(h0))
}

fn check_pos(what: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::BadSize {
            what: what.into(),
            value: v,
        })
    }
}

impl SizeField {
    /// A uniform size h.
    pub fn uniform(h: f64) -> Result<Self> {
        check_pos("uniform size", h)?;
        Ok(Self {
            h_far: h,
            points: Vec::new(),
            lines: Vec::new(),
            background: None,
        })
    }

    /// Adds a point source.
    pub fn with_point(mut self, s: PointSource) -> Result<Self> {
        check_pos("point source h0", s.h0)?;
        check_growth(s.growth)?;
        self.points.push(s);
        Ok(self)
    }

    /// Adds a line source.
    pub fn with_line(mut self, s: LineSource) -> Result<Self> {
        check_pos("line source h0", s.h0)?;
        check_growth(s.growth)?;
        self.lines.push(s);
        Ok(self)
    }

    /// Sets the background mesh.
    pub fn with_background(mut self, b: Background) -> Self {
        self.background = Some(b);
        self
    }

    /// The isotropic size at `p`: the smallest over the uniform size and the sources.
    pub fn size_at(&self, p: &Point3) -> f64 {
        let mut h = self.h_far;
        for s in &self.points {
            h = h.min(grow(
                s.h0,
                s.r0,
                s.growth,
                self.h_far,
                (p - s.center).norm(),
            ));
        }
        for s in &self.lines {
            let ab = s.b - s.a;
            let l2 = ab.norm_squared();
            let t = if l2 > 0.0 {
                ((p - s.a).dot(&ab) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let d = (p - (s.a + ab * t)).norm();
            h = h.min(grow(s.h0, s.r0, s.growth, self.h_far, d));
        }
        h
    }

    /// The metric T(p): I/h² from [`size_at`](Self::size_at), intersected with the
    /// background metric where there is one.
    pub fn metric_at(&self, p: &Point3) -> Matrix3 {
        let h = self.size_at(p);
        let iso = Matrix3::identity() / (h * h);
        match self.background.as_ref().and_then(|b| b.metric_at(p)) {
            None => iso,
            Some(bg) => intersect_metrics(&iso, &bg),
        }
    }

    /// The metric of the parametric plane M = Jᵀ T J, J = [r_u r_v] (Eq. 33 with T = I/h²).
    pub fn surface_metric(&self, p: &Point3, du: &Vector3, dv: &Vector3) -> Matrix2 {
        let t = self.metric_at(p);
        let (tu, tv) = (t * du, t * dv);
        let b = du.dot(&tv);
        Matrix2::new(du.dot(&tu), b, b, dv.dot(&tv))
    }
}

fn check_growth(g: Growth) -> Result<()> {
    match g {
        Growth::Smoothstep { radius } => check_pos("smoothstep radius", radius),
        Growth::Linear { rate } => check_pos("growth rate", rate),
    }
}

/// Metric intersection: the metric whose unit ball is the largest ellipsoid inside both
/// unit balls (simultaneous reduction: M = A^{1/2} max(I, A^{-1/2} B A^{-1/2}) A^{1/2}).
pub fn intersect_metrics(a: &Matrix3, b: &Matrix3) -> Matrix3 {
    let ea = a.symmetric_eigen();
    let sq = ea.eigenvectors
        * Matrix3::from_diagonal(&ea.eigenvalues.map(|x| x.max(0.0).sqrt()))
        * ea.eigenvectors.transpose();
    let isq = ea.eigenvectors
        * Matrix3::from_diagonal(
            &ea.eigenvalues
                .map(|x| 1.0 / x.max(f64::MIN_POSITIVE).sqrt()),
        )
        * ea.eigenvectors.transpose();
    let c = isq * b * isq;
    let c = (c + c.transpose()) * 0.5;
    let ec = c.symmetric_eigen();
    let d = ec.eigenvectors
        * Matrix3::from_diagonal(&ec.eigenvalues.map(|x| x.max(1.0)))
        * ec.eigenvectors.transpose();
    sq * d * sq
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sources_take_the_smallest_size() {
        let f = SizeField::uniform(1.0)
            .unwrap()
            .with_point(PointSource {
                center: Point3::origin(),
                h0: 0.1,
                r0: 0.5,
                growth: Growth::Smoothstep { radius: 2.0 },
            })
            .unwrap()
            .with_line(LineSource {
                a: Point3::new(10.0, 0.0, 0.0),
                b: Point3::new(10.0, 10.0, 0.0),
                h0: 0.2,
                r0: 0.0,
                growth: Growth::Linear { rate: 0.1 },
            })
            .unwrap();
        assert_eq!(f.size_at(&Point3::new(0.3, 0.0, 0.0)), 0.1);
        // halfway through the smoothstep: h0 + (1 - h0)/2
        let h = f.size_at(&Point3::new(1.5, 0.0, 0.0));
        assert!((h - 0.55).abs() < 1e-14, "{h}");
        assert_eq!(f.size_at(&Point3::new(5.0, -20.0, 0.0)), 1.0);
        let h = f.size_at(&Point3::new(12.0, 5.0, 0.0));
        assert!((h - 0.4).abs() < 1e-14, "{h}");
        assert!(SizeField::uniform(0.0).is_err());
    }

    #[test]
    fn background_interpolates_and_intersects() {
        let nodes = vec![
            Point3::origin(),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(0.0, 0.0, 1.0),
        ];
        let m0 = Matrix3::from_diagonal(&Vector3::new(100.0, 1.0, 1.0));
        let m1 = Matrix3::from_diagonal(&Vector3::new(300.0, 1.0, 1.0));
        let bg = Background::new(nodes, vec![m0, m1, m0, m0], vec![[0, 1, 2, 3]]).unwrap();
        let t = bg.metric_at(&Point3::new(0.5, 0.1, 0.1)).unwrap();
        assert!((t[(0, 0)] - 200.0).abs() < 1e-9);
        assert!(bg.metric_at(&Point3::new(2.0, 0.0, 0.0)).is_none());
        let f = SizeField::uniform(0.5).unwrap().with_background(bg);
        let t = f.metric_at(&Point3::new(0.5, 0.1, 0.1));
        // x: background 200 > 4; y, z: the isotropic 1/0.25 = 4
        assert!((t[(0, 0)] - 200.0).abs() < 1e-9 && (t[(1, 1)] - 4.0).abs() < 1e-9);
    }
}
