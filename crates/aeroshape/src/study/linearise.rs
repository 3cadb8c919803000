//! The whole chain linearised (issue 22): design variables → control nodes → updated model
//! → wall nodes → volume grid, forward (Jacobian–vector) and reverse (vector–Jacobian)
//! products, and their check against central differences of [`Study::evaluate`].
//!
//! [`Study::linearise`] evaluates the chain at x once and linearises every phase there:
//! 1. **param**: the exact modifier Jacobian J_p = dP/dx (`Prepared::apply_with_jacobian`);
//! 2. **model update**: `intersect`'s `ModelLinearisation` (Eq. 9 surfaces linear in their
//!    nodes; junction curves and corners by the implicit function theorem on Eqs. 12–13);
//! 3. **surface grid**: `surfgrid`'s `SurfaceLinearisation` (frozen parameters, the re-mapped
//!    (u, v) near a moved junction, curve nodes on their moved ranges);
//! 4. **volume deformation**: `deform`'s `Linearisation` (Eqs. 14–26 with R and its Eq. 26
//!    solve, sliding conditions, every increment that ran), wall nodes prescribed, fixed
//!    markers held.
//!
//! The forward product chains them: dX = J_d J_s J_m J_p dx; the reverse product runs the
//! transposes in the opposite order, x̄ = J_pᵀ J_mᵀ J_sᵀ J_dᵀ X̄ (one adjoint deformation
//! solve for the whole gradient). The wall variants stop after (start at) the surface grid,
//! for a solver that gives only surface sensitivities.
//!
//! When the study's last evaluation was at x (an optimiser evaluates first: the flow solver
//! needs the grid), [`Study::linearise`] reuses it — the updated model, the wall grid and
//! its update's record, the volume deformation — and only linearises; the linearisation is
//! then at the grid that evaluation returned. Otherwise it evaluates the chain at x with the
//! deformation started cold (never from the warm start), so the result belongs to x alone.
//! The deformation's solves and the products' run to the case's `deform.rel_tol`.

use std::sync::{Arc, PoisonError};

use geom_db::prelude::Vector3;

use super::error::{Result, StudyError};
use super::{EvaluatedAt, Study};
use geom_db::GeomDb;
use surfgrid::SurfaceGrid;

/// The chain linearised at one design vector ([`Study::linearise`]).
pub struct ChainLinearisation<'s> {
    study: &'s Study,
    x: Vec<f64>,
    jac: param::Jacobian,
    model: intersect::update::ModelLinearisation,
    surface: surfgrid::SurfaceLinearisation<'s>,
    deform: deform::Linearisation<'s, 'static>,
    at: Arc<EvaluatedAt>,
}

impl std::fmt::Debug for ChainLinearisation<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ChainLinearisation")
            .field("variables", &self.x.len())
            .field("nodes", &self.study.grid.n_nodes())
            .finish_non_exhaustive()
    }
}

/// A product checked against central differences ([`Study::check_jvp`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FdCheck {
    /// The step along the direction (design-variable units).
    pub h: f64,
    /// |central difference|.
    pub fd_norm: f64,
    /// |product|.
    pub product_norm: f64,
    /// |central difference − product| / |central difference| (the product's norm when the
    /// difference is zero).
    pub rel_error: f64,
}

pub(super) fn check_len(what: &'static str, expected: usize, found: usize) -> Result<()> {
    if expected == found {
        Ok(())
    } else {
        Err(StudyError::ProductLength {
            what,
            expected,
            found,
        })
    }
}

/// J v for the param Jacobian (CSR, rows 3k + c): one vector per control node.
fn jac_times(j: &param::Jacobian, v: &[f64]) -> Vec<Vector3> {
    let mut out = vec![Vector3::zeros(); j.rows() / 3];
    for (r, row) in j.outer_iterator().enumerate() {
        out[r / 3][r % 3] = row.iter().map(|(c, a)| a * v[c]).sum();
    }
    out
}

/// Jᵀ w for the param Jacobian.
pub(super) fn jac_t_times(j: &param::Jacobian, w: &[Vector3]) -> Vec<f64> {
    let mut out = vec![0.0; j.cols()];
    for (r, row) in j.outer_iterator().enumerate() {
        let wr = w[r / 3][r % 3];
        for (c, a) in row.iter() {
            out[c] += a * wr;
        }
    }
    out
}

fn norm3(v: &[[f64; 3]]) -> f64 {
    v.iter()
        .map(|p| p[0] * p[0] + p[1] * p[1] + p[2] * p[2])
        .sum::<f64>()
        .sqrt()
}

impl Study {
    /// Linearises every phase of the chain at `x` (module doc): at the last evaluation when
    /// it was at `x` (reused, not run again), otherwise at a cold evaluation made here. The
    /// products of the result can be taken as many times as wanted.
    pub fn linearise(&self, x: &[f64]) -> Result<ChainLinearisation<'_>> {
        super::evaluate::check_length(&self.prepared, x)?;
        let (points, jac) = self.prepared.apply_with_jacobian(x)?;
        let recent = self
            .recent
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
            .filter(|r| r.x == x);
        let at = match recent {
            Some(r) => r,
            None => Arc::new(self.evaluate_cold(x, &points)?),
        };
        let model = self.model.linearise(&points, &at.geometry)?;
        let surface = self.surface_updater.linearise_recorded(
            &self.surface,
            &self.db,
            &at.geometry,
            &at.surface,
            &at.record,
        )?;
        let deform = match &at.deformed {
            Some(d) => self.deformer.linearise(d)?,
            None => {
                // No wall node moved: the deformation is the identity, linearised there.
                let (positions, _) = self.prescribed(&at.surface);
                self.deformer
                    .linearise(&self.deformer.deform_to(&positions, None)?)?
            }
        };
        Ok(ChainLinearisation {
            study: self,
            x: x.to_vec(),
            jac,
            model,
            surface,
            deform,
            at,
        })
    }

    /// The chain at `x` for its linearisation (control nodes `points`), the deformation
    /// started cold.
    fn evaluate_cold(&self, x: &[f64], points: &[geom_db::prelude::Point3]) -> Result<EvaluatedAt> {
        let (geometry, surface, record, positions) = self.wall_positions(points)?;
        let mut d = self.deformer.deform_to(&positions, None)?;
        let coords = std::mem::take(&mut d.coords);
        d.cell_quality = Vec::new();
        Ok(EvaluatedAt {
            x: x.to_vec(),
            geometry,
            surface,
            record,
            deformed: Some(Arc::new(d)),
            coords,
        })
    }

    /// dX = J dx at `x`: the volume grid's coordinates (one per node) for the design
    /// direction `dx` ([`Study::linearise`] then [`ChainLinearisation::jvp`]).
    pub fn jvp(&self, x: &[f64], dx: &[f64]) -> Result<Vec<[f64; 3]>> {
        self.linearise(x)?.jvp(dx)
    }

    /// x̄ = Jᵀ X̄ at `x`: the gradient with respect to the design variables of an objective
    /// whose gradient with respect to the volume grid's coordinates is `x_bar` (one per node).
    pub fn vjp(&self, x: &[f64], x_bar: &[[f64; 3]]) -> Result<Vec<f64>> {
        self.linearise(x)?.vjp(x_bar)
    }

    /// Checks the forward product at `x` along `dx` against the fourth-order central
    /// difference [8 (X(x + h dx) − X(x − h dx)) − (X(x + 2h dx) − X(x − 2h dx))] / 12h of
    /// [`Study::evaluate`] (four evaluations, each started cold; its truncation error is
    /// O(h⁴), so a step large against the solvers' noise can be taken). `wall`: compare the
    /// wall nodes only ([`ChainLinearisation::jvp_wall`]).
    pub fn check_jvp(&self, x: &[f64], dx: &[f64], h: f64, wall: bool) -> Result<FdCheck> {
        let lin = self.linearise(x)?;
        let jv = if wall {
            lin.jvp_wall(dx)?
        } else {
            lin.jvp(dx)?
        };
        let at = |step: f64| -> Result<Vec<[f64; 3]>> {
            let y: Vec<f64> = x.iter().zip(dx).map(|(a, b)| a + step * b).collect();
            self.forget_warm_start();
            Ok(self.evaluate(&y)?.grid.coords)
        };
        let (p1, m1, p2, m2) = (at(h)?, at(-h)?, at(2.0 * h)?, at(-2.0 * h)?);
        let mut fd: Vec<[f64; 3]> = (0..p1.len())
            .map(|i| {
                std::array::from_fn(|c| {
                    (8.0 * (p1[i][c] - m1[i][c]) - (p2[i][c] - m2[i][c])) / (12.0 * h)
                })
            })
            .collect();
        if wall {
            for (f, w) in fd.iter_mut().zip(&self.wall) {
                if !*w {
                    *f = [0.0; 3];
                }
            }
        }
        let err: Vec<[f64; 3]> = fd
            .iter()
            .zip(&jv)
            .map(|(a, b)| std::array::from_fn(|c| a[c] - b[c]))
            .collect();
        let (fd_norm, product_norm) = (norm3(&fd), norm3(&jv));
        let den = if fd_norm > 0.0 { fd_norm } else { product_norm };
        Ok(FdCheck {
            h,
            fd_norm,
            product_norm,
            rel_error: if den > 0.0 { norm3(&err) / den } else { 0.0 },
        })
    }
}

impl ChainLinearisation<'_> {
    /// The relative residual the deformation products' solves stop at (default: the case's
    /// `deform.rel_tol`).
    pub fn with_rel_tol(mut self, rel_tol: f64) -> Self {
        self.deform = self.deform.with_rel_tol(rel_tol);
        self
    }

    /// The design vector linearised at.
    pub fn x(&self) -> &[f64] {
        &self.x
    }

    /// The updated model at x.
    pub fn geometry(&self) -> &GeomDb {
        &self.at.geometry
    }

    /// The updated wall grid at x.
    pub fn surface(&self) -> &SurfaceGrid {
        &self.at.surface
    }

    /// The deformed grid's coordinates at x (the last evaluation's when it was at x,
    /// otherwise the deformation started cold).
    pub fn coords(&self) -> &[[f64; 3]] {
        &self.at.coords
    }

    /// The number of increments of the deformation differentiated.
    pub fn increments(&self) -> usize {
        self.deform.increments()
    }

    /// The wall nodes' perturbation, one per grid node (zero off the wall).
    fn wall_tangent(&self, dx: &[f64]) -> Result<Vec<Vector3>> {
        check_len("design direction", self.x.len(), dx.len())?;
        let dp = jac_times(&self.jac, dx);
        let t = self.model.jvp(&dp)?;
        Ok(self.surface.jvp(&t)?)
    }

    /// dX on the wall alone: one vector per grid node, zero off the wall (no volume solve).
    pub fn jvp_wall(&self, dx: &[f64]) -> Result<Vec<[f64; 3]>> {
        Ok(self
            .wall_tangent(dx)?
            .iter()
            .map(|v| [v.x, v.y, v.z])
            .collect())
    }

    /// dX = J dx: one vector per grid node.
    pub fn jvp(&self, dx: &[f64]) -> Result<Vec<[f64; 3]>> {
        let s = &self.study;
        let dxs = self.wall_tangent(dx)?;
        let mut dw = Vec::with_capacity(self.deform.n_inputs());
        for (i, w) in s.wall.iter().enumerate() {
            if *w {
                dw.push([dxs[i].x, dxs[i].y, dxs[i].z]);
            }
        }
        dw.resize(self.deform.n_inputs(), [0.0; 3]);
        Ok(self.deform.jvp(&dw)?.values)
    }

    /// x̄ = Jᵀ X̄ from the wall nodes' cotangent `x_bar` (one per grid node; entries off the
    /// wall are ignored).
    pub fn vjp_wall(&self, x_bar: &[[f64; 3]]) -> Result<Vec<f64>> {
        let s = &self.study;
        check_len("wall sensitivities", s.grid.n_nodes(), x_bar.len())?;
        let xb: Vec<Vector3> = x_bar
            .iter()
            .zip(&s.wall)
            .map(|(b, w)| {
                if *w {
                    Vector3::new(b[0], b[1], b[2])
                } else {
                    Vector3::zeros()
                }
            })
            .collect();
        let mut bar = self.model.zero_tangent();
        self.surface.vjp(&xb, &mut bar)?;
        let pb = self.model.vjp(&bar)?;
        Ok(jac_t_times(&self.jac, &pb))
    }

    /// x̄ = Jᵀ X̄ from the volume grid's cotangent `x_bar` (one per node): one adjoint
    /// deformation, then the wall's transposes.
    pub fn vjp(&self, x_bar: &[[f64; 3]]) -> Result<Vec<f64>> {
        let s = &self.study;
        check_len("volume sensitivities", s.grid.n_nodes(), x_bar.len())?;
        let wb = if s.case.deform.warm_start {
            // The adjoint solves start from the previous reverse product's solutions.
            let mut start = s
                .adjoint
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .take()
                .unwrap_or_default();
            let p = self.deform.vjp_from(x_bar, &mut start)?;
            *s.adjoint.lock().unwrap_or_else(PoisonError::into_inner) = Some(start);
            p.values
        } else {
            self.deform.vjp(x_bar)?.values
        };
        let mut xs = vec![[0.0; 3]; s.grid.n_nodes()];
        let mut k = 0;
        for (i, w) in s.wall.iter().enumerate() {
            if *w {
                xs[i] = wb[k];
                k += 1;
            }
        }
        self.vjp_wall(&xs)
    }
}

/// The Jacobian of the updated model's control nodes with respect to the design variables,
/// d(updated control node coordinates)/dx = J_m J_p: the modifiers' Jacobian `jp`
/// (`Prepared::apply_with_jacobian`) through the model update's linearisation `lin`, so the
/// rows of the junctions' control nodes (re-intersected, Eqs. 12–13) are their true
/// derivatives. Same layout as `jp` (row 3·node + coordinate, one column per variable),
/// with a row per control node of the updated model (a re-fit adds nodes after the input's).
pub fn model_jacobian(
    lin: &intersect::update::ModelLinearisation,
    jp: &param::Jacobian,
) -> Result<param::Jacobian> {
    // the rows are the updated model's nodes: a junction the update re-fitted has more
    let n = lin.model().control_nodes.len();
    check_len("modifier Jacobian rows", 3 * lin.n_inputs(), jp.rows())?;
    let cols: Vec<Vec<Vector3>> = (0..jp.cols())
        .map(|l| {
            let c = param::jacobian::column(jp, l);
            let dp: Vec<Vector3> = c
                .chunks_exact(3)
                .map(|v| Vector3::new(v[0], v[1], v[2]))
                .collect();
            lin.jvp(&dp).map(|t| t.nodes)
        })
        .collect::<std::result::Result<_, _>>()?;
    let mut indptr = Vec::with_capacity(3 * n + 1);
    let (mut indices, mut data) = (Vec::new(), Vec::new());
    indptr.push(0);
    for k in 0..n {
        for c in 0..3 {
            for (l, col) in cols.iter().enumerate() {
                let v = col[k][c];
                if v != 0.0 {
                    indices.push(l);
                    data.push(v);
                }
            }
            indptr.push(indices.len());
        }
    }
    Ok(param::Jacobian::new(
        (3 * n, jp.cols()),
        indptr,
        indices,
        data,
    ))
}
