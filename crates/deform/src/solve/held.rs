//! Which components of which unknowns a constrained (sliding) system holds: the mask the
//! constrained multigrid ([`super::Amg::new_held`]) is built for.
//!
//! [`sparse::pcg`] runs in the constraints' subspace and projects the preconditioner's
//! output, but a multigrid built on A treats every node as free. On a y = 0 symmetry plane
//! the y component of the constrained system is A with the plane's nodes held (a Dirichlet
//! condition), and the free multigrid preconditions it as if they were free (a Neumann
//! condition). A right-hand side with a y component everywhere then converges at the rate
//! of a Neumann preconditioner of a Dirichlet problem: the adjoint of Eq. 21 (the output
//! weights X̄ have a y component at every node) took twice the iterations of the
//! evaluation's Eq. 21 solve, whose y displacements are small (docs/crates/deform.md,
//! "The constrained multigrid").
//!
//! A node sliding on a plane of unit normal n is held in the component of n's largest
//! entry; one sliding on a line of direction t in the two others. For planes and lines
//! along the axes this is the constrained system itself; otherwise the multigrid is an
//! approximation of it, still symmetric positive definite.

use sparse::{Constraint, Constraints};

/// The components a constraint holds its node in (bit c).
fn held_bits(c: &Constraint) -> u8 {
    let largest = |v: &[f64; 3]| {
        (0..3)
            .max_by(|&i, &j| v[i].abs().total_cmp(&v[j].abs()))
            .unwrap_or(0)
    };
    match c {
        Constraint::Plane(n) => 1 << largest(n),
        Constraint::Line(t) => 7 & !(1 << largest(t)),
    }
}

/// Per unknown of `n`, the components `cons` hold it in (bit c).
pub(crate) fn held_mask(n: usize, cons: &Constraints) -> Vec<u8> {
    let mut mask = vec![0u8; n];
    for (i, c) in &cons.items {
        mask[*i as usize] |= held_bits(c);
    }
    mask
}
