//! The guard on grids of hexahedra and prisms (boundary layers): every kind measured, a
//! motion that inverts a prism or a hexahedron refused naming the cell and its kind.

use deform::{BoundaryConditions, DeformOptions, MarkerRole, RigidMotion, deform};
use mesh::ElementKind;

/// A thin box of `kind` cells over the wall z = 0: 6 layers, 1 % of the width high.
fn layers(kind: ElementKind) -> mesh::Mesh {
    mesh::generate::box_layers([5, 4, 6], [0.0; 3], [1.0, 0.8, 0.01], kind)
}

/// The wall lifted by `dz`; every other marker fixed.
fn lift(dz: f64) -> BoundaryConditions {
    BoundaryConditions {
        markers: vec![(
            "z_m".into(),
            MarkerRole::Rigid(RigidMotion::translation([0.0, 0.0, dz])),
        )],
        displacements: vec![],
    }
}

#[test]
fn every_cell_of_a_layer_grid_is_measured() {
    for kind in [ElementKind::Hexa, ElementKind::Prism] {
        let m = layers(kind);
        let d = deform(&m, &lift(0.001), &DeformOptions::default()).unwrap();
        let (b, a) = (d.report.quality_before, d.report.quality_after);
        assert_eq!(
            (b.measured, a.measured),
            (m.cells.len(), m.cells.len()),
            "{kind:?}"
        );
        assert_eq!((b.n_nonpositive, a.n_nonpositive), (0, 0), "{kind:?}");
        assert!(d.cell_quality.iter().all(|q| q.is_finite()), "{kind:?}");
        // The wall moved a tenth of the height: the cells are sheared, not inverted.
        assert!(
            a.min < b.min && a.min > 0.0,
            "{kind:?}: {} → {}",
            b.min,
            a.min
        );
    }
}

#[test]
fn inverting_a_prism_or_a_hexahedron_is_refused() {
    for (kind, name) in [(ElementKind::Hexa, "hexa"), (ElementKind::Prism, "prism")] {
        let m = layers(kind);
        // The wall through the fixed top: impossible without inverting the layers.
        let opts = DeformOptions {
            max_increments: 2,
            ..Default::default()
        };
        let e = deform(&m, &lift(0.015), &opts).unwrap_err();
        assert!(matches!(e, deform::Error::Inverted { .. }), "{e}");
        let msg = e.to_string();
        assert!(msg.contains(&format!("({name}, q = -")), "{msg}");
        let d = deform(
            &m,
            &lift(0.015),
            &DeformOptions {
                allow_inverted: true,
                ..opts
            },
        )
        .unwrap();
        assert!(d.report.quality_after.n_nonpositive > 0, "{kind:?}");
        assert_eq!(d.report.attempts, vec![1, 2]);
    }
}
