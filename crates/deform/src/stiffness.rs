//! Spring stiffness K_ij (paper Eqs. 14–19): the choice ([`Stiffness`]), the volume and
//! wall-distance factors, and the evaluator the assembly reads (`Springs`).

use std::fmt;
use std::str::FromStr;

use mesh::{Adjacency, Mesh};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::error::Error;
use crate::wall_distance::edge_distance;

/// Spring stiffness K_ij of the edge ij (lengths and volumes of the grid at the start of the
/// increment).
///
/// The one stiffness choice of the workspace: serialised (case files) by the variant names
/// `InverseLength`, `InverseLengthSquared`, `Volume`, `WallDistance`; parsed from and
/// displayed as the command line's `inverse-length`, `inverse-length2`, `volume`,
/// `wall-distance`.
///
/// ```
/// use deform::Stiffness;
/// assert_eq!("wall-distance".parse::<Stiffness>().unwrap(), Stiffness::WallDistance);
/// assert_eq!(Stiffness::InverseLengthSquared.to_string(), "inverse-length2");
/// assert_eq!(Stiffness::default(), Stiffness::InverseLengthSquared);
/// let e = "stiff".parse::<Stiffness>().unwrap_err();
/// assert!(e.to_string().contains("wall-distance"));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Stiffness {
    /// K = 1 / l.
    InverseLength,
    /// K = 1 / l² (default).
    #[default]
    InverseLengthSquared,
    /// K = (1 / l²) · (V̄ / V_ij): V_ij the smaller of the end nodes' mean adjacent cell volumes,
    /// V̄ the mean cell volume; stiffens the small cells near walls.
    Volume,
    /// K = (1 / l²) · (1 + (ℓ / d_ij)²): d_ij the distance of the edge's midpoint to the
    /// moving boundary (mean of the end nodes' shortest paths along grid edges, ≥ l/2), ℓ =
    /// 0.2 × the diagonal of the moving boundary's bounding box; stiffens a layer around
    /// moving bodies so that it moves almost rigidly (with R) on any grid, graded or not.
    WallDistance,
}

impl Stiffness {
    /// Every choice, in declaration order.
    pub const ALL: [Stiffness; 4] = [
        Stiffness::InverseLength,
        Stiffness::InverseLengthSquared,
        Stiffness::Volume,
        Stiffness::WallDistance,
    ];

    /// The command line's name.
    pub fn name(self) -> &'static str {
        match self {
            Stiffness::InverseLength => "inverse-length",
            Stiffness::InverseLengthSquared => "inverse-length2",
            Stiffness::Volume => "volume",
            Stiffness::WallDistance => "wall-distance",
        }
    }
}

impl fmt::Display for Stiffness {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Stiffness {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self, Error> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| Error::BadOption {
                reason: format!(
                    "unknown stiffness {s:?} (expected inverse-length, inverse-length2, volume or wall-distance)"
                ),
            })
    }
}

/// Spring stiffness evaluator on a grid state.
///
/// The stiffness is scaled by a power of two (exact) that makes it dimensionless, then rounded
/// to single precision: the matrix stores it in f32 (a product reads 8 instead of 12 bytes per
/// entry), and the diagonal, the couplings to prescribed nodes and the R term use the same
/// rounded value, so the system solved is exactly the spring system of the rounded springs
/// (stiffness changed by ≤ 6e-8 relative; the solution does not depend on the scale).
pub(crate) struct Springs<'a> {
    x: &'a [[f64; 3]],
    kind: Stiffness,
    /// 2^e ≈ 1 / (diagonal of the baseline grid's bounding box)^p, p the power of the length
    /// in K.
    pub scale: f64,
    /// For [`Stiffness::Volume`]: V̄ / V_node per node; for [`Stiffness::WallDistance`]:
    /// the distance d_node to the moving boundary.
    vol_factor: Vec<f64>,
    /// ℓ of [`Stiffness::WallDistance`].
    wall_len: f64,
}

impl Springs<'_> {
    /// K_ij, scaled and rounded to single precision (see [`Springs`]).
    #[inline]
    pub fn k(&self, i: usize, j: usize) -> f64 {
        f64::from((self.scale * self.k_exact(i, j)) as f32)
    }

    /// K_ij in f64, unscaled.
    #[inline]
    pub fn k_exact(&self, i: usize, j: usize) -> f64 {
        let (a, b) = (self.x[i], self.x[j]);
        let l2 = (b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2);
        match self.kind {
            Stiffness::InverseLength => 1.0 / l2.sqrt(),
            Stiffness::InverseLengthSquared => 1.0 / l2,
            Stiffness::Volume => self.vol_factor[i].max(self.vol_factor[j]) / l2,
            Stiffness::WallDistance => {
                // Distance of the edge's midpoint, ≥ l / 2 next to the wall.
                let d = 0.5 * (self.vol_factor[i] + self.vol_factor[j]);
                let r = self.wall_len / d;
                (1.0 + r * r) / l2
            }
        }
    }
}

/// ℓ / (diagonal of the moving boundary's bounding box) of [`Stiffness::WallDistance`]
/// (0.1–0.2 measured best: docs/crates/deform.md, "Wall-distance stiffness").
pub(crate) const WALL_SCALE: f64 = 0.2;

impl<'a> Springs<'a> {
    /// The evaluator at `x` from per-node factors computed elsewhere (the distributed
    /// deformation's, over the ranks): `factor` is V̄ / V_node ([`Stiffness::Volume`]) or
    /// the distance from the moving boundary ([`Stiffness::WallDistance`]) of every node of
    /// `x`, `wall_len` the ℓ of the latter; `scale` as [`Springs::scale`].
    #[cfg(feature = "mpi")]
    pub(crate) fn with_factors(
        x: &'a [[f64; 3]],
        kind: Stiffness,
        scale: f64,
        factor: Vec<f64>,
        wall_len: f64,
    ) -> Self {
        Springs {
            x,
            kind,
            scale,
            vol_factor: factor,
            wall_len,
        }
    }
}

/// The springs' scale ([`Springs::scale`]) of a grid whose bounding box has the diagonal
/// `diag`: a power of two near 1 / diag^p (exact scaling; K is ~1 / length^p).
pub(crate) fn length_scale(diag: f64, kind: Stiffness) -> f64 {
    let power = if kind == Stiffness::InverseLength {
        1
    } else {
        2
    };
    if diag.is_finite() && diag > 0.0 {
        2f64.powi(power * diag.log2().round() as i32)
    } else {
        1.0
    }
}

/// The stiffness evaluator at `x`; for [`Stiffness::WallDistance`], `distance` is the
/// wall distance when already computed ([`edge_distance`] of `adj`, `x`, `moving`).
pub(crate) fn springs<'a>(
    mesh: &Mesh,
    x: &'a [[f64; 3]],
    kind: Stiffness,
    adj: &Adjacency,
    moving: &[bool],
    distance: Option<Vec<f64>>,
) -> Springs<'a> {
    let mut vol_factor = Vec::new();
    let mut wall_len = 0.0;
    if kind == Stiffness::WallDistance {
        let scale = WALL_SCALE;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (p, &m) in x.iter().zip(moving) {
            if m {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        let diag =
            ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt();
        wall_len = if diag.is_finite() { scale * diag } else { 0.0 };
        vol_factor = distance.unwrap_or_else(|| edge_distance(adj, x, moving));
    }
    if kind == Stiffness::Volume {
        let v = NodeVolumes::new(mesh, x, |_| true);
        vol_factor = v.factors(mean_volume(v.total, v.cells));
    }
    // A power of two near 1 / diag^p (exact scaling; K is ~1 / length^p): the baseline
    // grid's size serves every state (any power of two would give the same solution).
    let scale = length_scale(mesh.bbox_diagonal(), kind);
    Springs {
        x,
        kind,
        scale,
        vol_factor,
        wall_len,
    }
}

/// The cells' volumes around every node (tetrahedra; triangle areas in a plane grid):
/// per node their sum and count, and over the cells a filter accepts their sum and count
/// (for [`Stiffness::Volume`]'s V̄ / V_i).
pub(crate) struct NodeVolumes {
    /// Σ of the volumes of the cells around each node.
    pub sum: Vec<f64>,
    /// Number of cells around each node.
    pub count: Vec<u32>,
    /// Σ of the volumes of the accepted cells.
    pub total: f64,
    /// Number of accepted cells.
    pub cells: f64,
}

impl NodeVolumes {
    /// The volumes of `mesh`'s cells at `x`; `accept` picks the cells of the totals (a
    /// rank's share of a distributed grid; all of them serially).
    pub fn new(mesh: &Mesh, x: &[[f64; 3]], accept: impl Fn(&[u32]) -> bool) -> Self {
        let n = x.len();
        let mut out = Self {
            sum: vec![0.0; n],
            count: vec![0; n],
            total: 0.0,
            cells: 0.0,
        };
        let mut add = |e: &[u32], v: f64| {
            if accept(e) {
                out.total += v;
                out.cells += 1.0;
            }
            for &i in e {
                out.sum[i as usize] += v;
                out.count[i as usize] += 1;
            }
        };
        for t in mesh.tets() {
            let v = mesh::quality::tet_volume(t.map(|i| x[i as usize])).abs();
            add(t, v);
        }
        for t in mesh.triangles() {
            let p = |i: u32| Vector3::from(x[i as usize]);
            add(
                t,
                0.5 * (p(t[1]) - p(t[0])).cross(&(p(t[2]) - p(t[0]))).norm(),
            );
        }
        out
    }

    /// V̄ / V_i per node for the mean volume `mean` (1 where no cell or a zero volume is
    /// around the node).
    pub fn factors(&self, mean: f64) -> Vec<f64> {
        self.sum
            .iter()
            .zip(&self.count)
            .map(|(&s, &c)| {
                if c > 0 && s > 0.0 {
                    mean / (s / f64::from(c))
                } else {
                    1.0
                }
            })
            .collect()
    }
}

/// The mean cell volume of `total` over `cells` cells (1 without cells).
pub(crate) fn mean_volume(total: f64, cells: f64) -> f64 {
    if cells > 0.0 { total / cells } else { 1.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_in_case_files_and_on_the_command_line() {
        for k in Stiffness::ALL {
            // The case files' spelling: the variant name.
            let json = serde_json::to_string(&k).unwrap();
            assert_eq!(json, format!("\"{k:?}\""));
            assert_eq!(serde_json::from_str::<Stiffness>(&json).unwrap(), k);
            // The command line's spelling.
            assert_eq!(k.to_string().parse::<Stiffness>().unwrap(), k);
        }
        assert_eq!(
            serde_json::from_str::<Stiffness>("\"WallDistance\"").unwrap(),
            Stiffness::WallDistance
        );
        assert!("InverseLength".parse::<Stiffness>().is_err());
    }
}
