//! The four modifier levels of §5 as serialisable definitions: node (Eqs. 34–35), line
//! (Eq. 36), surface (Eqs. 37–38) and master (§5.4), with the entities they link to.
//!
//! A definition only describes the modifier; [`crate::Prepared`] binds it to a geometry
//! (entity ids checked, node parameters, normals and master projections computed once on
//! the initial shape) and evaluates it.

use geom_db::prelude::{Point3, Vector3};
use geom_db::{ControlNodeId, CurveId, SurfaceId};
use serde::{Deserialize, Serialize};

use crate::basis::Basis;
use crate::master::StationsMaster;
use crate::registry::DesignVariable;

/// A surface parameter direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Param {
    /// The first parameter u.
    U,
    /// The second parameter v.
    V,
}

/// An iso-parametric line of a support surface: `fixed` = `at` (global parameter), running
/// along the other parameter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IsoLine {
    /// The surface.
    pub surface: SurfaceId,
    /// The parameter held constant.
    pub fixed: Param,
    /// Its value (global: a surface of n_u × n_v patches has u ∈ [0, n_u], v ∈ [0, n_v]).
    pub at: f64,
}

/// Entities linked to a modifier; the modifier moves the union of their control nodes.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Links {
    /// Support surfaces: all their control nodes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub surfaces: Vec<SurfaceId>,
    /// Support curves: all their control nodes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub curves: Vec<CurveId>,
    /// Individual control nodes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub nodes: Vec<ControlNodeId>,
    /// The control nodes of a surface that lie on an iso-parametric line (parameter within
    /// 1e-9 of `at`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub iso_lines: Vec<IsoLine>,
}

impl Links {
    /// True when nothing is linked.
    pub fn is_empty(&self) -> bool {
        self.surfaces.is_empty()
            && self.curves.is_empty()
            && self.nodes.is_empty()
            && self.iso_lines.is_empty()
    }
}

/// A rotation axis: a point x₀ on it and its direction b (normalised when bound).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Axis {
    /// The fixed point x₀ of Eq. (35).
    pub point: Point3,
    /// The direction b (any non-zero length).
    pub direction: Vector3,
}

/// Node level (§5.1, Eqs. 34–35): a right-handed rotation by θ about the axis, then a
/// translation Δr_t, applied rigidly to the linked control nodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeModifier {
    /// Modifier name (unique in the parametrisation).
    pub name: String,
    /// The moved entities.
    pub links: Links,
    /// The rotation axis.
    pub axis: Axis,
    /// θ in radians (positive: right-handed about `axis.direction`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation: Option<DesignVariable>,
    /// Δr_t components x, y, z (length units); `None` for a component held at zero.
    #[serde(default)]
    pub translation: [Option<DesignVariable>; 3],
}

/// The direction along which a line or surface perturbation is added.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub enum Direction {
    /// The unit normal r_u × r_v of the (initial) surface at the control node.
    #[default]
    Normal,
    /// A fixed direction (normalised when bound), e.g. `Axis((0, 0, 1))`.
    Axis(Vector3),
}

/// Transverse decay w(d) of a line perturbation with the distance d of a node from the line
/// (parametric distance |u − u_line| for an iso-line, Euclidean distance from the foot of
/// the normal for a support curve).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub enum Decay {
    /// w = 1: every node moves with q(s) whatever its distance.
    #[default]
    Uniform,
    /// w = ½(1 + cos(π d / width)) for d < width, 0 beyond (C¹, compact support).
    Cosine {
        /// Support half-width (same units as d).
        width: f64,
    },
    /// w = exp(−(d / width)²).
    Gaussian {
        /// Width (same units as d).
        width: f64,
    },
}

impl Decay {
    /// w(d).
    pub fn weight(&self, d: f64) -> f64 {
        match *self {
            Decay::Uniform => 1.0,
            Decay::Cosine { width } => {
                if d >= width {
                    0.0
                } else {
                    0.5 * (1.0 + (std::f64::consts::PI * d / width).cos())
                }
            }
            Decay::Gaussian { width } => (-(d / width) * (d / width)).exp(),
        }
    }
}

/// The line of a line modifier.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum LineSupport {
    /// An iso-parametric line of a surface; the modifier moves that surface's control nodes,
    /// each at line parameter = its running parameter and distance = |fixed parameter − at|.
    Iso(IsoLine),
    /// A support curve; the modifier moves the control nodes of its `links`, each at line
    /// parameter = the foot of the normal on the curve and distance = the distance to it.
    Curve(CurveId),
    /// A straight line in space (x₀, b), not an entity of the model; the modifier moves the
    /// control nodes of its `links`, each at line parameter = its coordinate along the line
    /// (r − x₀) · b (b normalised) and distance = its distance from the line. With a
    /// `range` ending at the farthest linked node and a fixed `direction` this is a
    /// displacement field along an axis, e.g. a fuselage nose bent down or stretched
    /// forward from a section (Figs. 10 and 12).
    Axis(Axis),
}

/// Line level (§5.2, Eq. 36): q(s) = Σ Δq_i H_i(s) along a line, added along the surface
/// normal or an axis, times the transverse decay.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LineModifier {
    /// Modifier name.
    pub name: String,
    /// The line.
    pub line: LineSupport,
    /// Moved entities (curve and axis lines; an iso line moves its own surface's nodes).
    #[serde(default)]
    pub links: Links,
    /// Range [a, b] of the line's global parameter mapped onto s ∈ [0, 1] (default: the
    /// whole line; for an `Axis` line, the linked nodes' extent along it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<[f64; 2]>,
    /// Basis family H_i.
    pub basis: Basis,
    /// Indices of the basis functions that carry a design variable (default: all, in
    /// order). The others are held at zero (e.g. to keep the line's ends fixed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub active: Option<Vec<usize>>,
    /// Direction of the perturbation.
    #[serde(default)]
    pub direction: Direction,
    /// Transverse decay.
    #[serde(default)]
    pub decay: Decay,
    /// The coefficients Δq_i, one per active basis function, in order.
    pub variables: Vec<DesignVariable>,
}

/// The two forms of the surface level.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum SurfaceForm {
    /// Eq. (37): q(s, t) = q_u(s) q_v(t), q_u = Σ a_i H_i(s), q_v = Σ b_j H_j(t).
    Separable {
        /// a_i, one per active u function.
        variables_u: Vec<DesignVariable>,
        /// b_j, one per active v function.
        variables_v: Vec<DesignVariable>,
    },
    /// Eq. (38): q(s, t) = Σ_i Σ_j Δq_ij H_i(s) H_j(t); `variables[a * n_v + b]` belongs to
    /// the a-th active u function and the b-th active v function.
    Tensor {
        /// Δq_ij.
        variables: Vec<DesignVariable>,
    },
}

/// Surface level (§5.3, Eqs. 37–38) over the (u, v) plane of each linked surface, each
/// surface's domain (or `range_u` × `range_v`) mapped onto (s, t) ∈ [0, 1]².
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceModifier {
    /// Modifier name.
    pub name: String,
    /// The surfaces.
    pub surfaces: Vec<SurfaceId>,
    /// Range of global u mapped onto s ∈ [0, 1] (default: each surface's u domain).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range_u: Option<[f64; 2]>,
    /// Range of global v mapped onto t ∈ [0, 1] (default: each surface's v domain).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range_v: Option<[f64; 2]>,
    /// Basis in u.
    pub basis_u: Basis,
    /// Basis in v.
    pub basis_v: Basis,
    /// Active u functions (default all).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub active_u: Option<Vec<usize>>,
    /// Active v functions (default all).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub active_v: Option<Vec<usize>>,
    /// Direction of the perturbation (default the normal, as in the paper).
    #[serde(default)]
    pub direction: Direction,
    /// Eq. (37) or Eq. (38) and the coefficients.
    pub form: SurfaceForm,
}

/// Where a master modifier's master discretisation comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum MasterSpec {
    /// A generator the caller supplies at bind time under this name (e.g. a wing master of
    /// `wingmaster`).
    External(String),
    /// The built-in station master ([`StationsMaster`]).
    Stations(StationsMaster),
}

/// Master level (§5.4): the deviation of the actual master discretisation from the initial
/// one, transferred to the linked control nodes by bilinear interpolation in the master's
/// parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MasterModifier {
    /// Modifier name.
    pub name: String,
    /// The moved entities.
    pub links: Links,
    /// The master generator.
    pub source: MasterSpec,
    /// The master's parameters, in the order the generator expects them.
    pub variables: Vec<DesignVariable>,
}

/// One modifier of a parametrisation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Modifier {
    /// Node level.
    Node(NodeModifier),
    /// Line level.
    Line(LineModifier),
    /// Surface level.
    Surface(SurfaceModifier),
    /// Master level.
    Master(MasterModifier),
}

impl Modifier {
    /// The modifier's name.
    pub fn name(&self) -> &str {
        match self {
            Modifier::Node(m) => &m.name,
            Modifier::Line(m) => &m.name,
            Modifier::Surface(m) => &m.name,
            Modifier::Master(m) => &m.name,
        }
    }

    /// The level: "node", "line", "surface" or "master".
    pub fn level(&self) -> &'static str {
        match self {
            Modifier::Node(_) => "node",
            Modifier::Line(_) => "line",
            Modifier::Surface(_) => "surface",
            Modifier::Master(_) => "master",
        }
    }

    /// The modifier's design variables, in design-vector order.
    pub fn variables(&self) -> Vec<&DesignVariable> {
        match self {
            Modifier::Node(m) => m
                .rotation
                .iter()
                .chain(m.translation.iter().flatten())
                .collect(),
            Modifier::Line(m) => m.variables.iter().collect(),
            Modifier::Surface(m) => match &m.form {
                SurfaceForm::Separable {
                    variables_u,
                    variables_v,
                } => variables_u.iter().chain(variables_v).collect(),
                SurfaceForm::Tensor { variables } => variables.iter().collect(),
            },
            Modifier::Master(m) => m.variables.iter().collect(),
        }
    }
}
