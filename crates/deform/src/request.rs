//! A deformation as the front ends ask for it ([`Request`]): the program's `aeroshape
//! deform` and Python's `deform()` take the same options, build the same boundary conditions
//! and solver options, and put the sliding nodes' new parameters back into the grid here,
//! once.

use std::collections::HashSet;

use geom_db::GeomDb;
use mesh::Mesh;

use crate::bc::{BoundaryConditions, MarkerRole, RigidMotion};
use crate::deformer::{Deformed, deform_on_supports_with_progress, deform_with_progress};
use crate::error::Result;
use crate::options::{DeformOptions, SolverKind};
use crate::stiffness::Stiffness;
use crate::support::{Support, Supports};

/// Iteration limit of one solve of the point iteration (Eq. 22), which needs many more
/// iterations than the conjugate gradients.
pub const POINT_ITERATION_MAX_ITERS: usize = 200_000;

/// Iteration limit of one solve of the conjugate gradients.
pub const CG_MAX_ITERS: usize = 20_000;

/// A deformation from prescribed boundary motion with the front ends' options: markers moved
/// rigidly by one motion (Eq. 34), per-node displacements, sliding and fixed markers; the
/// solver choices. Markers not named are fixed.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// Markers moved rigidly by [`motion`](Self::motion).
    pub rigid: Vec<String>,
    /// The rigid motion of the [`rigid`](Self::rigid) markers.
    pub motion: RigidMotion,
    /// Per-node displacements (node index as in the grid, displacement).
    pub displacements: Vec<(u32, [f64; 3])>,
    /// Markers whose nodes slide: on the geometry's supports when a geometry is given and
    /// every node of the marker is classified on one of its corners, curves or surfaces,
    /// otherwise on the marker's plane.
    pub slide: Vec<String>,
    /// Markers held fixed.
    pub fixed: Vec<String>,
    /// Linear solver.
    pub solver: SolverKind,
    /// Spring stiffness.
    pub stiffness: Stiffness,
    /// Use the adaptation matrices R (Eqs. 18–26).
    pub adapt_rotation: bool,
    /// How far R reaches from the moving boundary ([`DeformOptions::rotation_reach`]):
    /// `None`, everywhere; `Some(L)`, blended to the identity at the distance L.
    pub rotation_reach: Option<f64>,
    /// Relative residual at which the linear solves stop.
    pub rel_tol: f64,
    /// Return the grid even if cells are inverted after the incremental retries.
    pub allow_inverted: bool,
}

impl Default for Request {
    fn default() -> Self {
        Self {
            rigid: Vec::new(),
            motion: RigidMotion {
                angle_deg: 0.0,
                axis_point: [0.0; 3],
                axis_dir: [0.0, 0.0, 1.0],
                translation: [0.0; 3],
            },
            displacements: Vec::new(),
            slide: Vec::new(),
            fixed: Vec::new(),
            solver: SolverKind::default(),
            stiffness: Stiffness::default(),
            adapt_rotation: true,
            rotation_reach: None,
            rel_tol: 1e-8,
            allow_inverted: false,
        }
    }
}

impl Request {
    /// The solver options: [`POINT_ITERATION_MAX_ITERS`] or [`CG_MAX_ITERS`] by the solver,
    /// the defaults of [`DeformOptions`] otherwise.
    pub fn options(&self) -> DeformOptions {
        DeformOptions {
            solver: self.solver,
            stiffness: self.stiffness,
            adapt_rotation: self.adapt_rotation,
            rotation_reach: self.rotation_reach,
            rel_tol: self.rel_tol,
            max_iters: if self.solver == SolverKind::PointIteration {
                POINT_ITERATION_MAX_ITERS
            } else {
                CG_MAX_ITERS
            },
            allow_inverted: self.allow_inverted,
            ..Default::default()
        }
    }

    /// The markers of `mesh` that this request does not name and that are symmetry planes
    /// by their shape: every node within `1e-9` of the grid's box diagonal of the plane
    /// fitted to the marker, and at least one node shared with a rigid marker or given a
    /// non-zero displacement (so a plane of a far-field box, which the moving boundary does not
    /// touch, stays fixed). Returns each with its nodes' largest distance from its plane.
    /// A front end slides them ([`Request::slide`]) unless told to fix them.
    pub fn symmetry_planes(&self, mesh: &Mesh) -> Vec<(String, f64)> {
        let named: HashSet<&str> = self
            .rigid
            .iter()
            .chain(&self.slide)
            .chain(&self.fixed)
            .map(String::as_str)
            .collect();
        let mut moving: HashSet<u32> = self
            .displacements
            .iter()
            .filter(|d| d.1 != [0.0; 3])
            .map(|d| d.0)
            .collect();
        for r in &self.rigid {
            if let Some(mk) = mesh.marker(r) {
                moving.extend(mk.elements.node_set());
            }
        }
        let tol = 1e-9 * mesh.bbox_diagonal();
        let dim = if mesh.dim == 2 { 2 } else { 3 };
        mesh.markers
            .iter()
            .filter(|mk| !named.contains(mk.name.as_str()))
            .filter_map(|mk| {
                let nodes = mk.elements.node_set();
                if nodes.len() < 3 || !nodes.iter().any(|v| moving.contains(v)) {
                    return None;
                }
                let pts: Vec<[f64; 3]> = nodes.iter().map(|&v| mesh.coords[v as usize]).collect();
                let (_, _, dev) = crate::bc::fit_plane(&pts, dim);
                (dev <= tol).then(|| (mk.name.clone(), dev))
            })
            .collect()
    }

    /// The boundary conditions on `mesh`: rigid markers, then sliding markers (on the
    /// supports when `supports` classifies every node of the marker, else on its plane),
    /// then fixed markers, and the displacements.
    pub fn boundary_conditions(
        &self,
        mesh: &Mesh,
        supports: Option<&Supports>,
    ) -> BoundaryConditions {
        let mut markers: Vec<(String, MarkerRole)> = self
            .rigid
            .iter()
            .map(|r| (r.clone(), MarkerRole::Rigid(self.motion)))
            .collect();
        let on: HashSet<u32> = supports
            .map(|sp| sp.nodes.iter().map(|e| e.0).collect())
            .unwrap_or_default();
        for s in &self.slide {
            let classified = supports.is_some()
                && mesh
                    .marker(s)
                    .is_some_and(|mk| mk.elements.node_set().iter().all(|v| on.contains(v)));
            let role = if classified {
                MarkerRole::SlideOnSupport
            } else {
                MarkerRole::SlidePlane
            };
            markers.push((s.clone(), role));
        }
        markers.extend(self.fixed.iter().map(|f| (f.clone(), MarkerRole::Fixed)));
        BoundaryConditions {
            markers,
            displacements: self.displacements.clone(),
        }
    }

    /// Deforms `mesh`, its classified nodes tied to `geometry` when one is given, calling
    /// `progress(phase, done, total)` as it goes. [`apply`] puts the result into the grid.
    ///
    /// Errors: the geometry's supports do not match the grid's classification, or the
    /// deformation fails (see [`crate::deform`]).
    pub fn run(
        &self,
        mesh: &Mesh,
        geometry: Option<&GeomDb>,
        progress: &mut dyn FnMut(&str, usize, usize),
    ) -> Result<Deformed> {
        let supports = geometry
            .map(|db| Supports::from_classes(mesh, db))
            .transpose()?;
        let bc = self.boundary_conditions(mesh, supports.as_ref());
        let opts = self.options();
        match &supports {
            Some(sp) => deform_on_supports_with_progress(mesh, &bc, sp, &opts, progress),
            None => deform_with_progress(mesh, &bc, &opts, progress),
        }
    }
}

/// Puts a deformation of `mesh` into it: the new coordinates, and the new parameters of the
/// nodes that slid on supports (in their classification); cells, markers and numbering are
/// unchanged.
pub fn apply(mesh: &mut Mesh, deformed: &Deformed) {
    mesh.coords.clone_from(&deformed.coords);
    if let Some(classes) = mesh.classes.as_mut() {
        for &(v, s) in &deformed.supports {
            let c = &mut classes[v as usize];
            match s {
                Support::Curve { t, .. } => c.param = [t, 0.0],
                Support::Surface { uv, .. } => c.param = uv,
                Support::Corner => {}
            }
        }
    }
}
