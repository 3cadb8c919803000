//! A wing support surface from a planform and sections (§6.2): "a wing from wingmaster" for
//! fixture generators and for starting a design from planform data.
//!
//! The surface runs in u round the section and in v along the span, one patch per planform
//! panel in v (degree 1: ruled between consecutive stations, so the surface at v = k is
//! exactly the section of station k at its interpolation nodes) and `2 × patches_per_side`
//! patches in u. On the section's curve parameter σ ∈ [−1, 1] (σ = −1 lower trailing edge,
//! 0 leading edge, +1 upper trailing edge; see [`crate::section`]) patch i covers
//! σ ∈ [−1 + i/p, −1 + (i + 1)/p], p = `patches_per_side`; so u = 0 is the lower trailing
//! edge, u = p the leading edge and u = 2p the upper trailing edge (the convention of the
//! `wing_body` fixture), and with p even the patch borders σ = ±½ fall on the thickness
//! join P4 (t = ½, the C0 knot of the thickness B-spline). Each patch interpolates the
//! section at the Chebyshev–Lobatto control nodes of its degree (A = V⁻¹R, Eq. 9); the
//! interpolation error between nodes is what [`LoftReport`] measures.
//!
//! Placement: the section point (x, z) (chords, local frame) of station k goes to
//! LE_k + c_k R(θ_k)(x, 0, z) with R the nose-up twist about the leading edge
//! (x′ = x cos θ + z sin θ, z′ = −x sin θ + z cos θ), LE_k, c_k from the [`Planform`] — the
//! placement of [`crate::planform::master_nodes`].

use geom_db::eval::ParamSurface;
use geom_db::prelude::Point3;
use geom_db::{Patch, SupportSurface};

use crate::error::{Error, Result};
use crate::planform::Planform;
use crate::section::Section;

/// The maximum interpolation error of a lofted surface, measured against the sections.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoftReport {
    /// max |surface − section point| over stations and 50 samples per patch (length units).
    pub max_error: f64,
}

fn place(planform: &Planform, k: usize, twist: f64, q: [f64; 2]) -> Point3 {
    let le = [planform.x_le[k], planform.y[k], planform.z[k]];
    let c = planform.chords[k];
    let (s, co) = twist.sin_cos();
    let x = co * q[0] + s * q[1];
    let z = -s * q[0] + co * q[1];
    Point3::new(le[0] + c * x, le[1], le[2] + c * z)
}

/// The section curve parameter σ of patch `i` at local x ∈ [0, 1].
fn sigma(i: usize, x: f64, p: usize) -> f64 {
    (-1.0 + (i as f64 + x) / p as f64).clamp(-1.0, 1.0)
}

/// Builds the wing support surface (module doc) from a resolved planform, one section and
/// twist (radians, nose up) per planform station `planform.eta` (root first), patches of
/// degree `degree` (1 ..= `geom_db::control::MAX_DEGREE`) in u, `patches_per_side` ≥ 1 on each surface. Returns the
/// surface (without control nodes: the database assigns them) and its interpolation error.
pub fn wing_surface(
    name: &str,
    planform: &Planform,
    sections: &[Section],
    twist: &[f64],
    patches_per_side: usize,
    degree: usize,
) -> Result<(SupportSurface, LoftReport)> {
    let n = planform.eta.len();
    let bad = |reason: String| Error::Planform { reason };
    if sections.len() != n || twist.len() != n {
        return Err(bad(format!(
            "{n} planform stations (root included) but {} sections and {} twists",
            sections.len(),
            twist.len()
        )));
    }
    if patches_per_side == 0 || !(1..=geom_db::control::MAX_DEGREE).contains(&degree) {
        return Err(bad(format!(
            "{patches_per_side} patches per side of degree {degree}: at least 1 patch, degree 1 ..= {}",
            geom_db::control::MAX_DEGREE
        )));
    }
    if let Some(k) = twist.iter().position(|t| !t.is_finite()) {
        return Err(bad(format!("twist at station {k} is not finite")));
    }
    let p = patches_per_side;
    let nu = 2 * p;
    let mut patches = Vec::with_capacity(nu * (n - 1));
    for k in 0..n - 1 {
        for i in 0..nu {
            let (sa, sb) = (&sections[k], &sections[k + 1]);
            patches.push(Patch::interpolate(degree, 1, |x, y| {
                let s = sigma(i, x, p);
                let a = place(planform, k, twist[k], sa.eval(s).p);
                let b = place(planform, k + 1, twist[k + 1], sb.eval(s).p);
                Point3::from(a.coords * (1.0 - y) + b.coords * y)
            }));
        }
    }
    let surf = SupportSurface::new(name, nu, n - 1, patches);
    let mut max_error = 0.0f64;
    for (k, sec) in sections.iter().enumerate() {
        for i in 0..nu {
            for m in 0..=50 {
                let x = m as f64 / 50.0;
                let want = place(planform, k, twist[k], sec.eval(sigma(i, x, p)).p);
                let got = surf.point(i as f64 + x, k as f64);
                max_error = max_error.max((got - want).norm());
            }
        }
    }
    Ok((surf, LoftReport { max_error }))
}
