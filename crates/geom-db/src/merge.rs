//! Point merging within a tolerance: the one "same point" clustering of the workspace
//! (control nodes shared between arcs and patches, corners of an import, corners of the
//! fixtures).
//!
//! Points are inserted one at a time. A point joins the *nearest* earlier representative
//! within the tolerance (ties to the lower index); otherwise it becomes a new representative.
//! Representatives never move, so the result depends only on the insertion order, never on
//! hashing or threads. A hash grid of cell size `tol` finds the candidates: every
//! representative within `tol` of a point lies in the 3 × 3 × 3 cells around the point's
//! cell, so each insertion costs O(1) for well-spread points.

use std::collections::HashMap;

use crate::prelude::Point3;

/// The result of [`PointMerger::insert`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Merged {
    /// Index of the representative the point joined (or became).
    pub index: usize,
    /// Distance from the point to that representative (0 for a new one).
    pub distance: f64,
    /// The point became a new representative.
    pub new: bool,
}

/// Deterministic merging of points within a tolerance (see the module documentation).
///
/// ```
/// use geom_db::merge::PointMerger;
/// use geom_db::prelude::Point3;
/// let mut m = PointMerger::new(1e-6);
/// assert_eq!(m.insert(Point3::new(0.0, 0.0, 0.0)).index, 0);
/// assert_eq!(m.insert(Point3::new(1.0, 0.0, 0.0)).index, 1);
/// let j = m.insert(Point3::new(1.0, 5e-7, 0.0));
/// assert!(!j.new && j.index == 1 && (j.distance - 5e-7).abs() < 1e-15);
/// assert_eq!(m.points().len(), 2);
/// ```
#[derive(Debug, Clone)]
pub struct PointMerger {
    tol: f64,
    cell: f64,
    grid: HashMap<[i64; 3], Vec<u32>>,
    points: Vec<Point3>,
}

impl PointMerger {
    /// A merger joining points within `tol` (model units; a non-positive or NaN tolerance
    /// joins only identical points).
    pub fn new(tol: f64) -> Self {
        let tol = if tol > 0.0 { tol } else { 0.0 };
        let cell = if tol > 0.0 { tol } else { f64::MIN_POSITIVE };
        Self {
            tol,
            cell,
            grid: HashMap::new(),
            points: Vec::new(),
        }
    }

    /// The merging tolerance.
    pub fn tolerance(&self) -> f64 {
        self.tol
    }

    fn key(&self, p: &Point3) -> [i64; 3] {
        // `as i64` saturates (and maps NaN to 0), so any input gives a key.
        [
            (p.x / self.cell).floor() as i64,
            (p.y / self.cell).floor() as i64,
            (p.z / self.cell).floor() as i64,
        ]
    }

    /// The nearest representative within the tolerance of `p` (ties to the lower index)
    /// and its distance, without inserting.
    pub fn find(&self, p: &Point3) -> Option<(usize, f64)> {
        let k = self.key(p);
        let mut best: Option<(usize, f64)> = None;
        for dx in -1i64..=1 {
            for dy in -1i64..=1 {
                for dz in -1i64..=1 {
                    let kk = [
                        k[0].saturating_add(dx),
                        k[1].saturating_add(dy),
                        k[2].saturating_add(dz),
                    ];
                    let Some(list) = self.grid.get(&kk) else {
                        continue;
                    };
                    for &i in list {
                        let i = i as usize;
                        let d = (self.points[i] - p).norm();
                        let better = match best {
                            None => true,
                            Some((bi, bd)) => d < bd || (d == bd && i < bi),
                        };
                        if d <= self.tol && better {
                            best = Some((i, d));
                        }
                    }
                }
            }
        }
        best
    }

    /// Inserts `p`: it joins the nearest representative within the tolerance, or becomes a
    /// new one.
    pub fn insert(&mut self, p: Point3) -> Merged {
        if let Some((index, distance)) = self.find(&p) {
            return Merged {
                index,
                distance,
                new: false,
            };
        }
        let index = self.points.len();
        let k = self.key(&p);
        self.points.push(p);
        self.grid.entry(k).or_default().push(index as u32);
        Merged {
            index,
            distance: 0.0,
            new: true,
        }
    }

    /// The representatives, in order of creation.
    pub fn points(&self) -> &[Point3] {
        &self.points
    }

    /// The representatives, consuming the merger.
    pub fn into_points(self) -> Vec<Point3> {
        self.points
    }

    /// Number of representatives.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when no point was inserted.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joins_nearest_not_first() {
        let mut m = PointMerger::new(1.0);
        m.insert(Point3::new(0.0, 0.0, 0.0));
        m.insert(Point3::new(1.5, 0.0, 0.0));
        // within tolerance of both: joins the nearer (index 1)
        let j = m.insert(Point3::new(0.9, 0.0, 0.0));
        assert_eq!((j.index, j.new), (1, false));
        // equidistant: the lower index
        let mut m = PointMerger::new(1.0);
        m.insert(Point3::new(-0.5, 0.0, 0.0));
        m.insert(Point3::new(0.5, 0.0, 0.0));
        assert_eq!(m.insert(Point3::origin()).index, 0);
    }

    #[test]
    fn agrees_with_brute_force() {
        // pseudo-random points on a coarse lattice plus jitter of the order of the tolerance
        let tol = 1e-3;
        let mut state = 12345u64;
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut m = PointMerger::new(tol);
        let mut reps: Vec<Point3> = Vec::new();
        for _ in 0..2000 {
            let p = Point3::new(
                (rnd() * 8.0).floor() * 0.01 + rnd() * 2e-3,
                (rnd() * 8.0).floor() * 0.01 + rnd() * 2e-3,
                (rnd() * 2.0).floor() * 0.01 - rnd() * 2e-3,
            );
            let want = reps
                .iter()
                .enumerate()
                .map(|(i, q)| (i, (q - p).norm()))
                .filter(|&(_, d)| d <= tol)
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            let got = m.insert(p);
            match want {
                Some((i, d)) => assert!(!got.new && got.index == i && got.distance == d),
                None => {
                    assert!(got.new && got.index == reps.len());
                    reps.push(p);
                }
            }
        }
        assert_eq!(m.points(), reps.as_slice());
    }

    #[test]
    fn zero_tolerance_and_nan() {
        let mut m = PointMerger::new(0.0);
        let p = Point3::new(1.0, 2.0, 3.0);
        assert!(m.insert(p).new);
        assert!(!m.insert(p).new);
        assert!(m.insert(Point3::new(1.0, 2.0, 3.0 + 1e-15)).new);
        let mut m = PointMerger::new(f64::NAN);
        let q = Point3::new(f64::NAN, 0.0, 0.0);
        assert!(m.insert(q).new);
        assert!(m.insert(q).new, "NaN is never the same point");
        assert_eq!(m.len(), 2);
    }
}
