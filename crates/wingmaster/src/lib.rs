//! Wing parametrisation (paper §6): section thickness (the ten parameters of Eq. 39) and
//! camber B-splines, the section modification of Eq. 40, the least-squares fit of the
//! parametrisation to airfoil coordinates, and planform parameters (§6.2).
//!
//! Layer: depends on `geom-db` (the B-spline bases of [`geom_db::bspline`]) and `param`
//! (the [`param::MasterSource`] trait the wing master implements).
//!
//! * [`thickness`]: conditions 1–6 of §6.1 turn (r0, z1, z2, xtmax, tmax, crv4, x6, z6,
//!   phi_te, d78) (Eq. 39) into the polygons P0..P4 and P4..P8 of two quartic B-splines.
//! * [`camber`]: the camber line, a B-spline with polygon Q_j.
//! * [`section`]: the section z = z_c(x) ± z_t(x) in the local chord frame of §6.2.
//! * [`modify`]: Eq. (40), q(t) = q*(t) + Σ (P_i − P_i*) B_i(t) + Σ Q_j B_j(t), applied to
//!   the original points q* (zero deviation returns q* bit for bit).
//! * [`fit`](mod@fit): Levenberg–Marquardt fit on normal distances; [`airfoil`]: Selig/Lednicer files.
//! * [`planform`]: S, AR, span, chords, taper at stations, sweep, dihedral (§6.2), with the
//!   dependencies resolved explicitly, and linear interpolation of deviations between key
//!   sections.
//! * [`master`]: the wing master (§5.4, §6.2): [`WingMasterSpec`] (RON) bound to a support
//!   surface gives a [`WingMaster`], the [`param::MasterSource`] of a wing.
//! * [`loft`]: a wing support surface from a planform and sections (fixtures, new designs).
//!
//! The equations and their derivations are in `docs/crates/wingmaster.md`.

pub mod airfoil;
pub mod camber;
pub mod error;
pub mod fit;
pub mod loft;
pub mod master;
pub mod modify;
mod piecewise;
pub mod planform;
pub mod section;
pub mod thickness;

pub use airfoil::{Airfoil, Frame, NormalisedAirfoil};
pub use camber::CamberLine;
pub use error::{Error, Result};
pub use fit::{FitOptions, SectionFit, fit};
pub use master::{
    KeySection, PlanformVariables, SectionFace, SectionFrame, WingMaster, WingMasterSpec,
};
pub use section::{Section, SectionParams, write_selig};
pub use thickness::{ThicknessParams, ThicknessPolygon};
