//! Poles: sides of a support surface's parameter rectangle whose whole image is one point
//! (the nose and tail of a body of revolution, the centre of a disc in polar form, the ends
//! of a tip cap ruled between two sections that meet). There the first fundamental form G
//! (Eq. 33) is singular (the tangent along the side vanishes), so the metric M = Jᵀ T J of
//! the parametric plane degenerates and an advancing front in (u, v) cannot reach the side.
//!
//! Treatment (see `docs/crates/surfgrid.md`, "Poles"):
//! * detection: a side is degenerate when every sample of its image is within a tolerance
//!   (relative to the model size) of the first;
//! * in a component's boundary loop a pole is one node (the corner or curve node it is); the
//!   loop runs along the degenerate side from the arrival of the incoming curve to the
//!   departure of the outgoing one;
//! * the elements at the pole are a fan in physical space: ring nodes on the iso-parametric
//!   line at the neighbours' offset from the side, at equal angles as seen from the pole
//!   between the two boundary neighbours; the front then starts from the ring and never
//!   touches the side;
//! * the pole appears in the component's parametric triangulation once per fan triangle (a
//!   "pole copy"); convention: its (u, v) is on the degenerate side, with the along-side
//!   coordinate the mean of the triangle's two other vertices' (so each fan triangle is a
//!   proper, counter-clockwise triangle of the parametric plane).

use geom_db::SupportSurface;
use geom_db::eval::ParamSurface;
use geom_db::prelude::Point3;

/// A side of the parameter rectangle [u_min, u_max] × [v_min, v_max].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Side {
    /// u = u_min.
    UMin,
    /// u = u_max.
    UMax,
    /// v = v_min.
    VMin,
    /// v = v_max.
    VMax,
}

/// The parameter rectangle of a surface.
pub type Domain = ([f64; 2], [f64; 2]);

impl Side {
    /// All four sides.
    pub const ALL: [Side; 4] = [Side::UMin, Side::UMax, Side::VMin, Side::VMax];

    /// Index of the coordinate that varies along the side (1 = v for the u sides).
    #[inline]
    pub fn along_axis(self) -> usize {
        match self {
            Side::UMin | Side::UMax => 1,
            Side::VMin | Side::VMax => 0,
        }
    }

    /// The coordinate along the side of a parameter pair.
    #[inline]
    pub fn along(self, uv: [f64; 2]) -> f64 {
        uv[self.along_axis()]
    }

    /// The fixed coordinate of the side.
    #[inline]
    pub fn fixed(self, dom: Domain) -> f64 {
        match self {
            Side::UMin => dom.0[0],
            Side::UMax => dom.0[1],
            Side::VMin => dom.1[0],
            Side::VMax => dom.1[1],
        }
    }

    /// The range of the along-side coordinate.
    #[inline]
    pub fn along_range(self, dom: Domain) -> [f64; 2] {
        if self.along_axis() == 1 { dom.1 } else { dom.0 }
    }

    /// Distance of a parameter pair from the side, measured into the rectangle (≥ 0 inside).
    #[inline]
    pub fn inward(self, dom: Domain, uv: [f64; 2]) -> f64 {
        match self {
            Side::UMin => uv[0] - dom.0[0],
            Side::UMax => dom.0[1] - uv[0],
            Side::VMin => uv[1] - dom.1[0],
            Side::VMax => dom.1[1] - uv[1],
        }
    }

    /// The parameter pair at along-side coordinate `t` and inward offset `s`.
    #[inline]
    pub fn uv(self, dom: Domain, t: f64, s: f64) -> [f64; 2] {
        match self {
            Side::UMin => [dom.0[0] + s, t],
            Side::UMax => [dom.0[1] - s, t],
            Side::VMin => [t, dom.1[0] + s],
            Side::VMax => [t, dom.1[1] - s],
        }
    }
}

/// A degenerate side of a support surface and the point it maps to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pole {
    /// The side.
    pub side: Side,
    /// Its image.
    pub point: Point3,
}

/// Degenerate sides of `surf`: sides whose image (sampled 16 times per patch and at the
/// patch borders) stays within `tol` of its first point.
pub fn degenerate_sides(surf: &SupportSurface, tol: f64) -> Vec<Pole> {
    let dom = surf.domain();
    let mut out = Vec::new();
    for side in Side::ALL {
        let [a, b] = side.along_range(dom);
        let m = 16 * ((b - a).ceil() as usize).max(1);
        let s = side.fixed(dom);
        let at = |t: f64| {
            if side.along_axis() == 1 {
                surf.point(s, t)
            } else {
                surf.point(t, s)
            }
        };
        let p0 = at(a);
        let degenerate =
            (1..=m).all(|i| (at(a + (b - a) * i as f64 / m as f64) - p0).norm() <= tol);
        if degenerate {
            out.push(Pole { side, point: p0 });
        }
    }
    out
}

/// The parameters of a pole copy by the convention: on `side`, along-side coordinate the mean
/// of those of the triangle's two other vertices `a` and `b`.
#[inline]
pub fn pole_copy_uv(side: Side, dom: Domain, a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    side.uv(dom, 0.5 * (side.along(a) + side.along(b)), 0.0)
}

/// Along-side coordinates of the `k − 1` ring nodes of a pole fan on the iso-line at offset
/// `s` from `side`, between along-side coordinates `t_next` (fraction 0) and `t_prev`
/// (fraction 1), at equal angles as seen from the pole `p` (the swept angle integrated over
/// 64 samples of the iso-line). Returns the swept angle and the coordinates (fractions
/// j / k, j = 1 … k − 1, k = max(1, round(angle / 60°)), or `k_min` if larger).
pub fn fan_ring(
    surf: &SupportSurface,
    side: Side,
    p: &Point3,
    s: f64,
    t_next: f64,
    t_prev: f64,
    k_min: usize,
) -> (f64, Vec<f64>) {
    let dom = surf.domain();
    const M: usize = 64;
    let ts: Vec<f64> = (0..=M)
        .map(|i| t_next + (t_prev - t_next) * i as f64 / M as f64)
        .collect();
    let dirs: Vec<_> = ts
        .iter()
        .map(|&t| {
            let q = side.uv(dom, t, s);
            surf.point(q[0], q[1]) - p
        })
        .collect();
    let mut phi = vec![0.0; M + 1];
    for i in 0..M {
        phi[i + 1] = phi[i] + dirs[i].angle(&dirs[i + 1]);
    }
    let alpha = phi[M];
    let k = ((alpha / std::f64::consts::FRAC_PI_3).round() as usize)
        .max(1)
        .max(k_min);
    let mut out = Vec::with_capacity(k.saturating_sub(1));
    let mut i = 0;
    for j in 1..k {
        let target = alpha * j as f64 / k as f64;
        while i + 1 < M && phi[i + 1] < target {
            i += 1;
        }
        let f = if phi[i + 1] > phi[i] {
            ((target - phi[i]) / (phi[i + 1] - phi[i])).clamp(0.0, 1.0)
        } else {
            0.5
        };
        out.push(ts[i] + f * (ts[i + 1] - ts[i]));
    }
    (alpha, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn side_maps_are_consistent() {
        let dom = ([0.0, 3.0], [0.0, 2.0]);
        for side in Side::ALL {
            let uv = side.uv(dom, 0.7, 0.25);
            assert_eq!(side.along(uv), 0.7);
            assert!((side.inward(dom, uv) - 0.25).abs() < 1e-15);
            assert_eq!(side.inward(dom, side.uv(dom, 0.3, 0.0)), 0.0);
        }
    }
}
