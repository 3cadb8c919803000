//! Curve discretisation: equidistribution and the segment count against the arc length
//! measured independently (fine polyline).

use geom_db::CurveCompId;
use surfgrid::SizeField;
use surfgrid::curves::{discretise_curve, segment_lengths};
use surfgrid::spacing::{Growth, PointSource};

use crate::common::fixture;

#[test]
fn uniform_size_gives_equal_segments() {
    let db = fixture("sphere");
    let h = 0.07;
    let field = SizeField::uniform(h).unwrap();
    for k in 0..db.curve_components.len() {
        let id = CurveCompId::from_index(k);
        let ts = discretise_curve(&db, id, &field).unwrap();
        let l = segment_lengths(&db, id, &ts);
        let total: f64 = l.iter().sum();
        // a cube-sphere edge is the great-circle arc between adjacent cube corners
        // (±1, ±1, ±1)/√3: angle acos(1/3) on the unit sphere
        assert!((total - (1.0f64 / 3.0).acos()).abs() < 1e-4, "{total}");
        assert_eq!(l.len(), (total / h).round() as usize);
        let mean = total / l.len() as f64;
        for s in &l {
            assert!((s / mean - 1.0).abs() < 1e-3, "segment {s} vs mean {mean}");
        }
    }
}

#[test]
fn a_point_source_refines_the_curve_near_it() {
    let db = fixture("sphere");
    let id = CurveCompId(0);
    let c = db.curve_component(id);
    let start = db.corner(c.start).point;
    let field = SizeField::uniform(0.2)
        .unwrap()
        .with_point(PointSource {
            center: start,
            h0: 0.02,
            r0: 0.0,
            growth: Growth::Linear { rate: 0.3 },
        })
        .unwrap();
    let ts = discretise_curve(&db, id, &field).unwrap();
    let l = segment_lengths(&db, id, &ts);
    // segments grow away from the source and stay near the local size
    assert!(l[0] < 0.03 && *l.last().unwrap() > 0.15, "{l:?}");
    for w in l.windows(2) {
        assert!(w[1] >= w[0] * 0.999, "{l:?}");
    }
}
