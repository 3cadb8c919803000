//! Typed `u32` ids into the arenas of a [`GeomDb`](crate::GeomDb).
//!
//! Each id is an index into one `Vec` of the database: a [`CurveId`] indexes
//! `GeomDb::curves`, a [`SurfaceId`] indexes `GeomDb::surfaces`, and so on. In RON files an
//! id is written as a bare integer (`#[serde(transparent)]`).

macro_rules! id_type {
    ($(#[$doc:meta])* $name:ident, $label:literal) => {
        $(#[$doc])*
        #[derive(
            Copy, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Debug,
            serde::Serialize, serde::Deserialize,
        )]
        #[serde(transparent)]
        pub struct $name(pub u32);

        impl $name {
            /// The index into the database's arena.
            #[inline]
            pub fn index(self) -> usize {
                self.0 as usize
            }

            /// The id of arena index `i` (ids are `u32`; the database rejects larger arenas).
            #[inline]
            pub fn from_index(i: usize) -> Self {
                debug_assert!(i <= u32::MAX as usize);
                Self(i as u32)
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, concat!($label, " {}"), self.0)
            }
        }
    };
}

id_type!(
    /// A corner (an end point of curve components).
    CornerId,
    "corner"
);
id_type!(
    /// A support curve (Eqs. 2–6).
    CurveId,
    "curve"
);
id_type!(
    /// A support surface (Eqs. 7–10).
    SurfaceId,
    "surface"
);
id_type!(
    /// A curve component: a range of a support curve between two corners (§2.1).
    CurveCompId,
    "curve component"
);
id_type!(
    /// A surface component: a support surface bounded by oriented loops (§2.1).
    SurfCompId,
    "surface component"
);
id_type!(
    /// A control node (§3): a point whose position defines arcs and patches.
    ControlNodeId,
    "control node"
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_and_index() {
        assert_eq!(CurveId(3).to_string(), "curve 3");
        assert_eq!(SurfCompId(1).to_string(), "surface component 1");
        assert_eq!(ControlNodeId::from_index(7).index(), 7);
    }
}
