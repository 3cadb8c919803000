//! The re-fit of a junction whose sampled distance to its surfaces is above tolerance (step
//! 3b of [`ModelBaseline::update`](super::ModelBaseline::update)), and its linearisation
//! (issue 22).
//!
//! A re-fit raises the degree of the arcs above tolerance. A raised arc's new interior
//! control points are the old arc's points p = C(x_i) at the nodes x_i of the new degree,
//! seeded on both surfaces (Eq. 11: feet w_j with (S_j(w_j) − p)·∂S_j/∂w = 0) and
//! re-intersected by Eq. 12 with one parameter frozen at its seed value, or by the
//! normal-plane fallback (S₁ − p)·t = 0 with t = C′/|C′|. The arcs not raised and the raised
//! arcs' ends keep their points. Linearised, per re-fitted point:
//!
//! 1. δp = Σ ℓ_j(x) δr_j and δC′ = Σ ℓ_j′(x) δr_j on the old arc (its control points δr_j);
//! 2. the frozen parameter's seed value by the foot condition:
//!    H δw = −[(δS − δp)·S_w + g·δS_w], g = S(w) − p, H = S_wᵀ S_w + g·S_ww (a parameter
//!    on its domain border stays there);
//! 3. Eq. 12 with the frozen parameter moved by δw_f, or the fallback with the plane's
//!    constant moved: −δp·t + g₁·δt, δt = (I − t tᵀ) δC′ / |C′|, g₁ = S₁ − p.
//!
//! Several rounds are differentiated as they ran. An arc's re-fit depends on its own points
//! only and an arc is raised in consecutive rounds until it is within tolerance (its
//! distance does not change while other arcs are raised), so the rounds are replayed from
//! the initial and final degrees by the same code the update ran.

use geom_db::eval::{ParamSurface, SurfaceDerivs};
use geom_db::linearise::{Lagrange, ModelTangent, SurfaceTangent};
use geom_db::prelude::{Matrix2, Point3, Vector3};
use geom_db::{Arc, GeomDb, SurfaceId};

use super::linearise::{PointLin, arcs_to_chain, chain_to_arcs};
use super::{arcs_from_chain, refit_degree};
use crate::error::{Error, Result};
use crate::project::SurfaceProjector;
use crate::ssi::{CurveUpdate, IntersectionSeeds, SsiOptions, update_curve_points};

/// A re-fit's arcs, with what its linearisation needs.
pub(super) struct Refit {
    /// The re-fitted arcs.
    pub(super) arcs: Vec<Arc>,
    /// Per point of the new chain: the old arc and the local parameter sampled on it.
    samples: Vec<(usize, f64)>,
    /// Per point of the new chain: the sampled point, its curve derivative, and whether it
    /// is re-intersected (an interior point of a raised arc).
    pts: Vec<Point3>,
    tan: Vec<Vector3>,
    raised: Vec<bool>,
    seeds: IntersectionSeeds,
    update: CurveUpdate,
}

/// Re-fits a junction's arcs at new `degrees`: the new control points of the raised arcs
/// are the updated curve's points at the nodes of the new degree, seeded on the (updated)
/// surfaces by Eq. (11) and re-intersected by Eq. (12); arcs whose degree did not change
/// keep their control points, and so do the curve's ends (corners).
pub(super) fn refit_arcs<S: ParamSurface + ?Sized>(
    label: &str,
    arcs: &[Arc],
    degrees: &[usize],
    s1: &S,
    s2: &S,
    so: &SsiOptions,
) -> Result<Refit> {
    let mut pts = Vec::new();
    let mut tan = Vec::new();
    let mut raised = Vec::new();
    let mut samples = Vec::new();
    for (k, (arc, &n)) in arcs.iter().zip(degrees).enumerate() {
        for (i, &x) in geom_db::control::nodes(n).iter().enumerate() {
            if k > 0 && i == 0 {
                continue;
            }
            let d = arc.derivs(x);
            pts.push(d.point);
            tan.push(d.d1);
            raised.push(n != arc.degree && i > 0 && i < n);
            samples.push((k, x));
        }
    }
    let po = so.project.clone();
    let pa = SurfaceProjector::new(format!("{label}: surface 1"), s1, &po)?;
    let pb = SurfaceProjector::new(format!("{label}: surface 2"), s2, &po)?;
    // the updated curve is off its surfaces by the error being corrected: the seeds are
    // only Newton starts, so the initial-gap check is loosened
    let seed_opts = SsiOptions {
        max_initial_gap_rel: 1e-3,
        ..so.clone()
    };
    let seeds =
        IntersectionSeeds::new(label, &pts, Some(&tan), Some(degrees), &pa, &pb, &seed_opts)?;
    let update = update_curve_points(&seeds, s1, s2, so)?;
    let new: Vec<Point3> = update
        .new_points()
        .into_iter()
        .zip(&pts)
        .zip(&raised)
        .map(|((n, o), r)| if *r { n } else { *o })
        .collect();
    Ok(Refit {
        arcs: arcs_from_chain(degrees, &new),
        samples,
        pts,
        tan,
        raised,
        seeds,
        update,
    })
}

/// The seed value of a frozen parameter (a foot of the sampled point) linearised.
#[derive(Debug, Clone)]
struct FootLin {
    /// 0: surface 1, 1: surface 2.
    surface: usize,
    /// The frozen component of the foot (0: u, 1: v).
    comp: usize,
    uv: [f64; 2],
    d: SurfaceDerivs,
    /// S(w) − p.
    g: Vector3,
    /// H⁻¹ on the free components (zero for a component on its domain border).
    hinv: Matrix2,
}

impl FootLin {
    /// None when the frozen component is on its domain border (it stays there).
    fn new<S: ParamSurface + ?Sized>(
        label: &str,
        i: usize,
        (surface, comp): (usize, usize),
        uv: [f64; 2],
        s: &S,
        p: &Point3,
    ) -> Result<Option<Self>> {
        let (du, dv) = s.domain();
        let on_border: Vec<bool> = [du, dv]
            .iter()
            .zip(uv)
            .map(|(r, x)| {
                let w = r[1] - r[0];
                (x - r[0]).abs() <= 1e-12 * w || (r[1] - x).abs() <= 1e-12 * w
            })
            .collect();
        if on_border[comp] {
            return Ok(None);
        }
        let d = s.derivs(uv[0], uv[1]);
        let g = d.point - p;
        let h = Matrix2::new(
            d.du.dot(&d.du) + g.dot(&d.duu),
            d.du.dot(&d.dv) + g.dot(&d.duv),
            d.du.dot(&d.dv) + g.dot(&d.duv),
            d.dv.dot(&d.dv) + g.dot(&d.dvv),
        );
        let hinv = if on_border[1 - comp] {
            let mut m = Matrix2::zeros();
            m[(comp, comp)] = 1.0 / h[(comp, comp)];
            m
        } else {
            h.try_inverse().unwrap_or(Matrix2::from_element(f64::NAN))
        };
        if !hinv.iter().all(|v| v.is_finite()) {
            return Err(Error::BadEntity {
                entity: label.to_string(),
                reason: format!("re-fitted point {i}: the linearised seed foot is singular"),
            });
        }
        Ok(Some(Self {
            surface,
            comp,
            uv,
            d,
            g,
            hinv,
        }))
    }

    /// δw_f for the point's perturbation `dp` and the surfaces' `t`.
    fn forward(&self, t: &ModelTangent, db: &GeomDb, sid: SurfaceId, dp: &Vector3) -> f64 {
        let e = t.surface_at(db, sid, self.uv[0], self.uv[1]);
        let r = e.point - dp;
        let rhs = nalgebra::Vector2::new(
            r.dot(&self.d.du) + self.g.dot(&e.du),
            r.dot(&self.d.dv) + self.g.dot(&e.dv),
        );
        -(self.hinv * rhs)[self.comp]
    }

    /// The transpose of [`forward`](Self::forward): adds the surface's cotangent to `w`,
    /// returns the point's.
    fn reverse(&self, sb: f64, w: &mut ModelTangent, db: &GeomDb, sid: SurfaceId) -> Vector3 {
        let mut wb = nalgebra::Vector2::zeros();
        wb[self.comp] = sb;
        let rb = -(self.hinv.transpose() * wb);
        let r = self.d.du * rb[0] + self.d.dv * rb[1];
        let bar = SurfaceTangent {
            point: r,
            du: self.g * rb[0],
            dv: self.g * rb[1],
        };
        w.add_surface_at(db, sid, self.uv[0], self.uv[1], &bar);
        -r
    }
}

/// One re-fitted control point linearised.
#[derive(Debug, Clone)]
struct RefitPoint {
    point: PointLin,
    /// The sampled point (the fallback's plane point).
    p: Point3,
    /// The unit tangent t = C′/|C′| and |C′|.
    t: Vector3,
    tan_norm: f64,
    foot: Option<FootLin>,
}

impl RefitPoint {
    fn new<S: ParamSurface + ?Sized>(
        label: &str,
        f: &Refit,
        k: usize,
        s1: &S,
        s2: &S,
    ) -> Result<Self> {
        let up = &f.update.points[k];
        let sp = &f.seeds.points[k];
        let y = [up.uv1[0], up.uv1[1], up.uv2[0], up.uv2[1]];
        let t = Vector3::new(sp.tangent[0], sp.tangent[1], sp.tangent[2]);
        let point = PointLin::new(
            label,
            k,
            y,
            s1.derivs(y[0], y[1]),
            s2.derivs(y[2], y[3]),
            up.method,
            t,
        )?;
        let foot = match point.frozen() {
            Some(fz) if fz < 2 => FootLin::new(label, k, (0, fz), sp.uv1, s1, &f.pts[k])?,
            Some(fz) => FootLin::new(label, k, (1, fz - 2), sp.uv2, s2, &f.pts[k])?,
            None => None,
        };
        Ok(Self {
            point,
            p: f.pts[k],
            t,
            tan_norm: f.tan[k].norm(),
            foot,
        })
    }

    fn forward(
        &self,
        t: &ModelTangent,
        db: &GeomDb,
        sf: &[SurfaceId; 2],
        dp: &Vector3,
        dc: &Vector3,
    ) -> Vector3 {
        let y = self.point.y();
        let e1 = t.surface_at(db, sf[0], y[0], y[1]).point;
        let e2 = t.surface_at(db, sf[1], y[2], y[3]).point;
        let s = match (&self.foot, self.point.frozen()) {
            (Some(f), _) => f.forward(t, db, sf[f.surface], dp),
            (None, None) => {
                let g1 = self.point.s1().point - self.p;
                let dt = (dc - self.t * self.t.dot(dc)) / self.tan_norm;
                -dp.dot(&self.t) + g1.dot(&dt)
            }
            (None, Some(_)) => 0.0,
        };
        self.point.forward(&e1, &e2, &self.t, s)
    }

    /// The transpose of [`forward`](Self::forward): the cotangents of the sampled point and
    /// of its curve derivative (the surfaces' added to `w`).
    fn reverse(
        &self,
        q: &Vector3,
        w: &mut ModelTangent,
        db: &GeomDb,
        sf: &[SurfaceId; 2],
    ) -> (Vector3, Vector3) {
        let y = self.point.y();
        let (e1, e2, sb) = self.point.reverse(q, &self.t);
        for (sid, (u, v), e) in [(sf[0], (y[0], y[1]), e1), (sf[1], (y[2], y[3]), e2)] {
            let bar = SurfaceTangent {
                point: e,
                ..SurfaceTangent::default()
            };
            w.add_surface_at(db, sid, u, v, &bar);
        }
        match (&self.foot, self.point.frozen()) {
            (Some(f), _) => (f.reverse(sb, w, db, sf[f.surface]), Vector3::zeros()),
            (None, None) => {
                let g1 = self.point.s1().point - self.p;
                let dtb = g1 * sb;
                (
                    -self.t * sb,
                    (dtb - self.t * self.t.dot(&dtb)) / self.tan_norm,
                )
            }
            (None, Some(_)) => (Vector3::zeros(), Vector3::zeros()),
        }
    }
}

/// One round of re-fits linearised.
#[derive(Debug, Clone)]
struct Round {
    /// Arc degrees before the round.
    old: Vec<usize>,
    /// Per point of the new chain: old arc and local parameter; the re-fitted points.
    samples: Vec<(usize, f64)>,
    points: Vec<Option<RefitPoint>>,
}

impl Round {
    fn forward(
        &self,
        t: &ModelTangent,
        db: &GeomDb,
        sf: &[SurfaceId; 2],
        chain: &[Vector3],
    ) -> Vec<Vector3> {
        let arcs = chain_to_arcs(&self.old, chain);
        self.samples
            .iter()
            .zip(&self.points)
            .map(|(&(a, x), rp)| {
                let l = Lagrange::at(self.old[a], x);
                let (mut dp, mut dc) = (Vector3::zeros(), Vector3::zeros());
                for (j, d) in arcs[a].iter().enumerate() {
                    dp += d * l.value[j];
                    dc += d * l.d1[j];
                }
                match rp {
                    Some(rp) => rp.forward(t, db, sf, &dp, &dc),
                    None => dp,
                }
            })
            .collect()
    }

    fn reverse(
        &self,
        w: &mut ModelTangent,
        db: &GeomDb,
        sf: &[SurfaceId; 2],
        chain: &[Vector3],
    ) -> Vec<Vector3> {
        let mut arcs: Vec<Vec<Vector3>> = self
            .old
            .iter()
            .map(|&n| vec![Vector3::zeros(); n + 1])
            .collect();
        for ((&(a, x), rp), q) in self.samples.iter().zip(&self.points).zip(chain) {
            let (pb, cb) = match rp {
                Some(rp) => rp.reverse(q, w, db, sf),
                None => (*q, Vector3::zeros()),
            };
            let l = Lagrange::at(self.old[a], x);
            for (j, d) in arcs[a].iter_mut().enumerate() {
                *d += pb * l.value[j] + cb * l.d1[j];
            }
        }
        arcs_to_chain(&arcs)
    }
}

/// A junction's re-fit rounds linearised (module doc).
#[derive(Debug, Clone)]
pub(super) struct RefitLin {
    surfaces: [SurfaceId; 2],
    rounds: Vec<Round>,
}

impl RefitLin {
    /// Replays the re-fits that took the arcs `arcs` (degrees `from`) to the degrees `to`
    /// (each arc raised by [`refit_degree`] capped at `cap`) on the surfaces `s1`, `s2`
    /// (ids `surfaces`), linearising every round; returns it with the re-fitted arcs.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new<S: ParamSurface + ?Sized>(
        label: &str,
        surfaces: [SurfaceId; 2],
        arcs: Vec<Arc>,
        to: &[usize],
        cap: usize,
        (s1, s2): (&S, &S),
        so: &SsiOptions,
    ) -> Result<(Self, Vec<Arc>)> {
        let from: Vec<usize> = arcs.iter().map(|a| a.degree).collect();
        let mut raises = Vec::with_capacity(from.len());
        for (&a, &b) in from.iter().zip(to) {
            let (mut d, mut m) = (a, 0);
            while d != b {
                let n = refit_degree(d, cap);
                if n == d {
                    return Err(Error::BadEntity {
                        entity: label.to_string(),
                        reason: format!(
                            "arcs of degrees {to:?} after the update cannot come from {from:?} by re-fits"
                        ),
                    });
                }
                (d, m) = (n, m + 1);
            }
            raises.push(m);
        }
        let mut rounds = Vec::new();
        let (mut arcs, mut cur) = (arcs, from.clone());
        for r in 1..=raises.iter().copied().max().unwrap_or(0) {
            let new: Vec<usize> = cur
                .iter()
                .zip(&raises)
                .map(|(&d, &m)| if m >= r { refit_degree(d, cap) } else { d })
                .collect();
            let f = refit_arcs(label, &arcs, &new, s1, s2, so)?;
            let points = (0..f.samples.len())
                .map(|k| {
                    f.raised[k]
                        .then(|| RefitPoint::new(label, &f, k, s1, s2))
                        .transpose()
                })
                .collect::<Result<Vec<_>>>()?;
            rounds.push(Round {
                old: cur,
                samples: f.samples,
                points,
            });
            (arcs, cur) = (f.arcs, new);
        }
        Ok((Self { surfaces, rounds }, arcs))
    }

    /// The re-fitted chain's tangent from the chain's before the re-fits.
    pub(super) fn forward(&self, t: &ModelTangent, db: &GeomDb, chain: &[Vector3]) -> Vec<Vector3> {
        let mut c = chain.to_vec();
        for r in &self.rounds {
            c = r.forward(t, db, &self.surfaces, &c);
        }
        c
    }

    /// The transpose of [`forward`](Self::forward): the chain's cotangent before the re-fits
    /// (the surfaces' cotangents added to `w`).
    pub(super) fn reverse(
        &self,
        w: &mut ModelTangent,
        db: &GeomDb,
        chain: &[Vector3],
    ) -> Vec<Vector3> {
        let mut c = chain.to_vec();
        for r in self.rounds.iter().rev() {
            c = r.reverse(w, db, &self.surfaces, &c);
        }
        c
    }
}
