//! B-spline and Bernstein bases (Piegl & Tiller, *The NURBS Book*, A2.1–A2.3).
//!
//! Shared by the Bézier/B-spline ↔ power-basis conversion of this crate, the line and surface
//! modifiers of `param` (Eq. 36–38) and the section B-splines of `wingmaster` (Eq. 40).
//!
//! A [`KnotVector`] of degree p with knots t_0 ≤ … ≤ t_{m} defines n = m − p basis functions
//! N_{i,p}(t) on the domain [t_p, t_n]. They are non-negative, sum to one on the domain
//! (partition of unity) and N_{i,p} vanishes outside [t_i, t_{i+p+1}) (local support).

use crate::error::{Error, Result};

/// A non-decreasing knot vector with its degree.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct KnotVector {
    degree: usize,
    knots: Vec<f64>,
}

impl KnotVector {
    /// A validated knot vector: finite, non-decreasing, at least 2(p+1) knots, no interior
    /// multiplicity above p+1 and a non-empty domain.
    pub fn new(degree: usize, knots: Vec<f64>) -> Result<Self> {
        let bad = |reason: String| Error::InvalidKnots { degree, reason };
        if knots.len() < 2 * (degree + 1) {
            return Err(bad(format!(
                "{} knots given, at least {} needed",
                knots.len(),
                2 * (degree + 1)
            )));
        }
        if let Some(i) = knots.iter().position(|k| !k.is_finite()) {
            return Err(bad(format!("knot {i} is not finite")));
        }
        if let Some(i) = knots.windows(2).position(|w| w[1] < w[0]) {
            return Err(bad(format!("knots decrease at index {}", i + 1)));
        }
        let n = knots.len() - degree - 1;
        if knots[n] <= knots[degree] {
            return Err(bad("empty domain".into()));
        }
        let mut run = 1;
        for w in knots.windows(2) {
            run = if w[1] == w[0] { run + 1 } else { 1 };
            if run > degree + 1 {
                return Err(bad(format!("a knot has multiplicity above {}", degree + 1)));
            }
        }
        Ok(Self { degree, knots })
    }

    /// The clamped uniform knot vector on [0, 1] for `n_basis` functions of degree `degree`
    /// (end knots repeated p+1 times, interior knots equally spaced).
    ///
    /// ```
    /// let kv = geom_db::bspline::KnotVector::clamped_uniform(2, 4).unwrap();
    /// assert_eq!(kv.knots(), &[0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0]);
    /// ```
    pub fn clamped_uniform(degree: usize, n_basis: usize) -> Result<Self> {
        if n_basis < degree + 1 {
            return Err(Error::InvalidKnots {
                degree,
                reason: format!("{n_basis} basis functions, at least {} needed", degree + 1),
            });
        }
        let n_spans = n_basis - degree;
        let mut knots = vec![0.0; degree + 1];
        knots.extend((1..n_spans).map(|i| i as f64 / n_spans as f64));
        knots.extend(std::iter::repeat_n(1.0, degree + 1));
        Self::new(degree, knots)
    }

    /// The Bézier knot vector of degree p: p+1 zeros then p+1 ones.
    pub fn bezier(degree: usize) -> Self {
        let mut knots = vec![0.0; degree + 1];
        knots.extend(std::iter::repeat_n(1.0, degree + 1));
        Self { degree, knots }
    }

    /// Degree p.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The knots.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// Number of basis functions, `knots.len() - degree - 1`.
    pub fn n_basis(&self) -> usize {
        self.knots.len() - self.degree - 1
    }

    /// The parameter domain [t_p, t_n].
    pub fn domain(&self) -> (f64, f64) {
        (self.knots[self.degree], self.knots[self.n_basis()])
    }

    /// The distinct knot values inside and at the ends of the domain (span breakpoints).
    pub fn breakpoints(&self) -> Vec<f64> {
        let (a, b) = self.domain();
        let mut out: Vec<f64> = Vec::new();
        for &k in &self.knots[self.degree..=self.n_basis()] {
            if out.last() != Some(&k) && (a..=b).contains(&k) {
                out.push(k);
            }
        }
        out
    }

    /// The knot span index s with t_s ≤ t < t_{s+1}, t clamped to the domain; at the right
    /// end the last non-empty span is returned (A2.1).
    pub fn find_span(&self, t: f64) -> usize {
        let p = self.degree;
        let n = self.n_basis();
        let k = &self.knots;
        if t >= k[n] {
            let mut s = n - 1;
            while s > p && k[s] == k[s + 1] {
                s -= 1;
            }
            return s;
        }
        if t <= k[p] {
            let mut s = p;
            while s < n - 1 && k[s] == k[s + 1] {
                s += 1;
            }
            return s;
        }
        // upper_bound over [p, n]: first knot strictly greater than t, minus one.
        let idx = k[p..=n].partition_point(|&x| x <= t);
        p + idx - 1
    }

    /// The p+1 non-zero basis functions at t, N_{s-p..=s}, written to `out[..p+1]`;
    /// returns the span s (A2.2).
    /// No heap allocation for degrees below 16.
    pub fn basis_into(&self, t: f64, out: &mut [f64]) -> usize {
        const N: usize = 16;
        let p = self.degree;
        if p < N {
            let (mut left, mut right) = ([0.0; N], [0.0; N]);
            self.basis_with(t, out, &mut left, &mut right)
        } else {
            let (mut left, mut right) = (vec![0.0; p + 1], vec![0.0; p + 1]);
            self.basis_with(t, out, &mut left, &mut right)
        }
    }

    /// [`KnotVector::basis_into`] with `left` and `right` (at least p + 1 long) as scratch.
    fn basis_with(&self, t: f64, out: &mut [f64], left: &mut [f64], right: &mut [f64]) -> usize {
        let p = self.degree;
        let s = self.find_span(t);
        let t = t.clamp(self.domain().0, self.domain().1);
        let k = &self.knots;
        out[0] = 1.0;
        for j in 1..=p {
            left[j] = t - k[s + 1 - j];
            right[j] = k[s + j] - t;
            let mut saved = 0.0;
            for r in 0..j {
                let temp = out[r] / (right[r + 1] + left[j - r]);
                out[r] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            out[j] = saved;
        }
        s
    }

    /// All `n_basis()` basis functions at t (zeros outside the support).
    ///
    /// ```
    /// let kv = geom_db::bspline::KnotVector::clamped_uniform(3, 7).unwrap();
    /// let n = kv.eval_all(0.37);
    /// assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    /// ```
    pub fn eval_all(&self, t: f64) -> Vec<f64> {
        let p = self.degree;
        let mut local = vec![0.0; p + 1];
        let s = self.basis_into(t, &mut local);
        let mut all = vec![0.0; self.n_basis()];
        all[s - p..=s].copy_from_slice(&local);
        all
    }

    /// The table of The NURBS Book's A2.2 at t into `ndu` ((p + 1)² long, row-major:
    /// ndu[j][r] at j (p + 1) + r): the basis functions of every degree up to p above its
    /// diagonal and the knot differences below it, as A2.3 uses them. `left` and `right` are
    /// scratch, p + 1 long. Returns the span.
    fn ndu_table(&self, t: f64, ndu: &mut [f64], left: &mut [f64], right: &mut [f64]) -> usize {
        let p = self.degree;
        let w = p + 1;
        let s = self.find_span(t);
        let t = t.clamp(self.domain().0, self.domain().1);
        let k = &self.knots;
        ndu[0] = 1.0;
        for j in 1..=p {
            left[j] = t - k[s + 1 - j];
            right[j] = k[s + j] - t;
            let mut saved = 0.0;
            for r in 0..j {
                ndu[j * w + r] = right[r + 1] + left[j - r];
                let temp = ndu[r * w + j - 1] / ndu[j * w + r];
                ndu[r * w + j] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            ndu[j * w + j] = saved;
        }
        s
    }

    /// Basis functions and their derivatives up to order `n_ders` at t (A2.3):
    /// returns the span s and `ders[k][j]` = d^k N_{s-p+j} / dt^k.
    pub fn basis_ders(&self, t: f64, n_ders: usize) -> (usize, Vec<Vec<f64>>) {
        let p = self.degree;
        let w = p + 1;
        let (mut ndu, mut left, mut right) = (vec![0.0; w * w], vec![0.0; w], vec![0.0; w]);
        let s = self.ndu_table(t, &mut ndu, &mut left, &mut right);
        let ndu: Vec<&[f64]> = ndu.chunks(w).collect();
        let mut ders = vec![vec![0.0; p + 1]; n_ders + 1];
        for j in 0..=p {
            ders[0][j] = ndu[j][p];
        }
        let mut a = vec![vec![0.0; p + 1]; 2];
        for r in 0..=p {
            let (mut s1, mut s2) = (0usize, 1usize);
            a[0][0] = 1.0;
            for kk in 1..=n_ders.min(p) {
                let mut d = 0.0;
                let rk = r as isize - kk as isize;
                let pk = p - kk;
                if r >= kk {
                    a[s2][0] = a[s1][0] / ndu[pk + 1][r - kk];
                    d = a[s2][0] * ndu[r - kk][pk];
                }
                let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
                let j2 = if (r as isize - 1) <= pk as isize {
                    kk - 1
                } else {
                    p - r
                };
                for j in j1..=j2 {
                    let idx = (rk + j as isize) as usize;
                    a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][idx];
                    d += a[s2][j] * ndu[idx][pk];
                }
                if r <= pk {
                    a[s2][kk] = -a[s1][kk - 1] / ndu[pk + 1][r];
                    d += a[s2][kk] * ndu[r][pk];
                }
                ders[kk][r] = d;
                std::mem::swap(&mut s1, &mut s2);
            }
        }
        let mut factor = p as f64;
        for kk in 1..=n_ders.min(p) {
            for v in ders[kk].iter_mut() {
                *v *= factor;
            }
            factor *= (p - kk) as f64;
        }
        (s, ders)
    }

    /// The p + 1 nonzero basis functions at t into `n0` and their first derivatives into
    /// `n1` (each at least p + 1 long); returns the span. The same arithmetic as
    /// [`KnotVector::basis_ders`] with one derivative, so the same bits, without allocating
    /// below degree 16 (the surface evaluations of the CAD import call it millions of times).
    pub fn basis_ders1_into(&self, t: f64, n0: &mut [f64], n1: &mut [f64]) -> usize {
        const N: usize = 16;
        let p = self.degree;
        if p >= N {
            let (s, d) = self.basis_ders(t, 1);
            n0[..=p].copy_from_slice(&d[0]);
            n1[..=p].copy_from_slice(&d[1]);
            return s;
        }
        let w = p + 1;
        let (mut table, mut left, mut right) = ([0.0; N * N], [0.0; N], [0.0; N]);
        let s = self.ndu_table(t, &mut table[..w * w], &mut left, &mut right);
        let ndu = |j: usize, r: usize| table[j * w + r];
        for j in 0..=p {
            n0[j] = ndu(j, p);
            n1[j] = 0.0;
        }
        if p == 0 {
            return s;
        }
        // N'_r = p (N_{r-1,p-1} / (t_{r+p} - t_r) - N_{r,p-1} / (t_{r+p+1} - t_{r+1})),
        // the knot differences being ndu(p, ·) (The NURBS Book, A2.3 with n = 1).
        for r in 0..=p {
            let mut d = 0.0;
            if r >= 1 {
                d = (1.0 / ndu(p, r - 1)) * ndu(r - 1, p - 1);
            }
            if r < p {
                d += (-1.0 / ndu(p, r)) * ndu(r, p - 1);
            }
            n1[r] = d * p as f64;
        }
        s
    }

    /// Evaluates a B-spline curve with control points of dimension D at t.
    pub fn curve_point<const D: usize>(&self, ctrl: &[[f64; D]], t: f64) -> [f64; D] {
        debug_assert_eq!(ctrl.len(), self.n_basis());
        let p = self.degree;
        let mut local = vec![0.0; p + 1];
        let s = self.basis_into(t, &mut local);
        let mut out = [0.0; D];
        for (j, n) in local.iter().enumerate() {
            let c = &ctrl[s - p + j];
            for d in 0..D {
                out[d] += n * c[d];
            }
        }
        out
    }

    /// Derivatives of a B-spline curve up to order `n_ders` at t: `out[k]` = d^k C / dt^k.
    pub fn curve_ders<const D: usize>(
        &self,
        ctrl: &[[f64; D]],
        t: f64,
        n_ders: usize,
    ) -> Vec<[f64; D]> {
        let p = self.degree;
        let (s, ders) = self.basis_ders(t, n_ders);
        (0..=n_ders)
            .map(|kk| {
                let mut out = [0.0; D];
                for j in 0..=p {
                    let c = &ctrl[s - p + j];
                    for d in 0..D {
                        out[d] += ders[kk][j] * c[d];
                    }
                }
                out
            })
            .collect()
    }
}

/// The Bernstein polynomial B_{i,n}(t) = C(n,i) t^i (1−t)^(n−i).
///
/// ```
/// use geom_db::bspline::bernstein;
/// assert_eq!(bernstein(3, 0, 0.0), 1.0);
/// assert!((bernstein(2, 1, 0.5) - 0.5).abs() < 1e-15);
/// ```
pub fn bernstein(n: usize, i: usize, t: f64) -> f64 {
    if i > n {
        return 0.0;
    }
    binomial(n, i) * t.powi(i as i32) * (1.0 - t).powi((n - i) as i32)
}

/// The binomial coefficient C(n, k) as f64 (exact for n ≤ 60).
pub fn binomial(n: usize, k: usize) -> f64 {
    if k > n {
        return 0.0;
    }
    let k = k.min(n - k);
    let mut c = 1.0f64;
    for j in 0..k {
        c = c * (n - j) as f64 / (j + 1) as f64;
    }
    c.round()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_of_unity_and_support() {
        let kv =
            KnotVector::new(3, vec![0., 0., 0., 0., 0.2, 0.5, 0.5, 0.8, 1., 1., 1., 1.]).unwrap();
        for i in 0..=100 {
            let t = i as f64 / 100.0;
            let n = kv.eval_all(t);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14, "t = {t}");
            for (j, v) in n.iter().enumerate() {
                assert!(*v >= -1e-15);
                let (a, b) = (kv.knots()[j], kv.knots()[j + 4]);
                if t < a || t > b {
                    assert_eq!(*v, 0.0, "N_{j} at {t}");
                }
            }
        }
    }

    #[test]
    fn derivatives_match_central_differences() {
        let kv = KnotVector::clamped_uniform(4, 9).unwrap();
        let h = 1e-6;
        for &t in &[0.03, 0.21, 0.5, 0.77, 0.96] {
            let (s, d) = kv.basis_ders(t, 2);
            let p = kv.degree();
            let (fp, fm) = (kv.eval_all(t + h), kv.eval_all(t - h));
            let f0 = kv.eval_all(t);
            for j in 0..=p {
                let i = s - p + j;
                let d1 = (fp[i] - fm[i]) / (2.0 * h);
                let d2 = (fp[i] - 2.0 * f0[i] + fm[i]) / (h * h);
                assert!((d[0][j] - f0[i]).abs() < 1e-14);
                assert!((d[1][j] - d1).abs() < 1e-6 * (1.0 + d1.abs()), "{t} {j}");
                assert!((d[2][j] - d2).abs() < 1e-2 * (1.0 + d2.abs()), "{t} {j}");
            }
        }
    }

    #[test]
    fn first_derivative_fast_path_gives_the_bits_of_the_general_one() {
        // Degrees 1 to 17 (beyond the stack path's 16), with a repeated interior knot.
        for p in 1..=17 {
            let mut knots = vec![0.0; p + 1];
            knots.extend([0.1, 0.35, 0.35, 0.6, 0.9]);
            knots.extend(vec![1.0; p + 1]);
            let kv = KnotVector::new(p, knots).unwrap();
            for i in 0..=40 {
                let t = i as f64 / 40.0 + if i % 3 == 1 { 1e-3 } else { 0.0 };
                let (s, d) = kv.basis_ders(t, 1);
                let (mut n0, mut n1) = (vec![7.0; p + 1], vec![7.0; p + 1]);
                assert_eq!(kv.basis_ders1_into(t, &mut n0, &mut n1), s);
                assert_eq!(n0, d[0], "p = {p}, t = {t}");
                assert_eq!(n1, d[1], "p = {p}, t = {t}");
            }
        }
    }

    #[test]
    fn bezier_basis_is_bernstein() {
        let kv = KnotVector::bezier(5);
        for &t in &[0.0, 0.1, 0.45, 0.9, 1.0] {
            let n = kv.eval_all(t);
            for (i, v) in n.iter().enumerate() {
                assert!((v - bernstein(5, i, t)).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn rejects_bad_knots() {
        assert!(KnotVector::new(2, vec![0., 0., 0., 1., 1.]).is_err());
        assert!(KnotVector::new(1, vec![0., 0., f64::NAN, 1.]).is_err());
        assert!(KnotVector::new(1, vec![0., 0., 0., 0., 1., 1.]).is_err());
        assert!(KnotVector::new(1, vec![0., 0., 0., 0.]).is_err());
    }

    #[test]
    fn end_spans() {
        let kv = KnotVector::clamped_uniform(3, 6).unwrap();
        assert_eq!(kv.find_span(1.0), 5);
        assert_eq!(kv.find_span(0.0), 3);
        let n = kv.eval_all(1.0);
        assert_eq!(n[5], 1.0);
    }
}
