//! Planform identities and the resolution of S, AR, b, c_root, c̄.

use testkit::assert_close;
use wingmaster::planform::{Planform, PlanformSpec, interpolate_deviations};

fn cranked() -> PlanformSpec {
    PlanformSpec {
        stations: vec![0.35, 1.0],
        taper: vec![0.7, 0.25],
        sweep_chord_fraction: 0.25,
        sweep: vec![0.4, 0.5],
        dihedral: vec![0.05, 0.1],
        ..Default::default()
    }
}

#[test]
fn area_and_aspect_ratio_set_span_and_chords() {
    let spec = PlanformSpec {
        area: Some(120.0),
        aspect_ratio: Some(9.0),
        ..cranked()
    };
    let p = Planform::resolve(&spec).unwrap();
    assert_close!(p.span, (120.0f64 * 9.0).sqrt(), rel = 1e-14);
    assert_close!(p.area, p.span * p.mean_chord, rel = 1e-14);
    assert_close!(p.aspect_ratio, p.span * p.span / p.area, rel = 1e-14);
    // S = 2 ∫ c dy by the trapezoidal rule on the stations (exact: c is piecewise linear).
    let s: f64 = (0..2)
        .map(|k| (p.chords[k] + p.chords[k + 1]) * (p.y[k + 1] - p.y[k]))
        .sum();
    assert_close!(s, 120.0, rel = 1e-13);
    assert_close!(p.chords[2] / p.chords[0], 0.25, rel = 1e-14);
    // Sweep measured back at the quarter chord equals the input; dihedral raises the tip.
    assert_close!(p.sweep_at(0, 0.25), 0.4, rel = 1e-12);
    assert_close!(p.sweep_at(1, 0.25), 0.5, rel = 1e-12);
    let z = p.z[1] + 0.1f64.tan() * (p.y[2] - p.y[1]);
    assert_close!(p.leading_edge_at(1.0)[2], z, rel = 1e-12);
}

#[test]
fn every_independent_pair_gives_the_same_planform() {
    let base = Planform::resolve(&PlanformSpec {
        area: Some(50.0),
        aspect_ratio: Some(7.5),
        ..cranked()
    })
    .unwrap();
    let pairs: Vec<PlanformSpec> = vec![
        PlanformSpec {
            area: Some(base.area),
            span: Some(base.span),
            ..cranked()
        },
        PlanformSpec {
            area: Some(base.area),
            root_chord: Some(base.root_chord),
            ..cranked()
        },
        PlanformSpec {
            aspect_ratio: Some(base.aspect_ratio),
            span: Some(base.span),
            ..cranked()
        },
        PlanformSpec {
            aspect_ratio: Some(base.aspect_ratio),
            mean_chord: Some(base.mean_chord),
            ..cranked()
        },
        PlanformSpec {
            span: Some(base.span),
            root_chord: Some(base.root_chord),
            ..cranked()
        },
    ];
    for spec in pairs {
        let p = Planform::resolve(&spec).unwrap();
        assert_close!(p.span, base.span, rel = 1e-12);
        assert_close!(p.root_chord, base.root_chord, rel = 1e-12);
        assert_close!(p.x_le.clone(), base.x_le.clone(), rel = 1e-12, abs = 1e-12);
    }
}

#[test]
fn over_and_under_determined_sets_are_errors() {
    let over = PlanformSpec {
        area: Some(1.0),
        aspect_ratio: Some(5.0),
        span: Some(2.0),
        ..cranked()
    };
    let e = Planform::resolve(&over).unwrap_err().to_string();
    assert!(e.contains("3 of") && e.contains("give exactly two"), "{e}");
    let under = PlanformSpec {
        area: Some(1.0),
        ..cranked()
    };
    assert!(
        Planform::resolve(&under)
            .unwrap_err()
            .to_string()
            .contains("1 of")
    );
    let dependent = PlanformSpec {
        root_chord: Some(1.0),
        mean_chord: Some(0.8),
        ..cranked()
    };
    assert!(
        Planform::resolve(&dependent)
            .unwrap_err()
            .to_string()
            .contains("not independent")
    );
    let bad = PlanformSpec {
        area: Some(1.0),
        span: Some(2.0),
        stations: vec![0.5],
        taper: vec![0.5],
        ..Default::default()
    };
    assert!(
        Planform::resolve(&bad)
            .unwrap_err()
            .to_string()
            .contains("tip")
    );
}

#[test]
fn deviations_interpolate_linearly_between_key_sections() {
    let d = interpolate_deviations(
        &[0.0, 0.4, 1.0],
        &[vec![0.0, 1.0], vec![0.02, 3.0], vec![0.0, 0.0]],
        0.2,
    )
    .unwrap();
    assert_close!(d, vec![0.01, 2.0], rel = 1e-14);
    // Zero deviations at every key section give zero everywhere.
    let z = interpolate_deviations(&[0.0, 1.0], &[vec![0.0; 3], vec![0.0; 3]], 0.37).unwrap();
    assert_eq!(z, vec![0.0; 3]);
    assert!(interpolate_deviations(&[0.0, 1.0], &[vec![0.0]], 0.5).is_err());
}

#[test]
fn master_nodes_place_sections_on_the_planform() {
    use wingmaster::planform::master_nodes;
    let spec = PlanformSpec {
        span: Some(10.0),
        root_chord: Some(2.0),
        stations: vec![1.0],
        taper: vec![0.5],
        sweep: vec![0.0],
        ..Default::default()
    };
    let p = Planform::resolve(&spec).unwrap();
    let sec = vec![[0.0, 0.0], [0.5, 0.06], [1.0, 0.0]];
    let nodes = master_nodes(&p, &[(0.0, 0.0), (1.0, 0.1)], &[sec.clone(), sec.clone()]).unwrap();
    assert_eq!(nodes.len(), 6);
    // Root: chord 2, untwisted.
    assert_close!(nodes[1].to_vec(), vec![1.0, 0.0, 0.12], rel = 1e-14);
    // Tip: chord 1 at y = 5; 0.1 rad nose-up twist lowers the trailing edge by sin(0.1).
    assert_close!(
        nodes[5].to_vec(),
        vec![0.1f64.cos(), 5.0, -(0.1f64.sin())],
        rel = 1e-14
    );
    // Zero change of the inputs gives the same master bit for bit.
    let again = master_nodes(&p, &[(0.0, 0.0), (1.0, 0.1)], &[sec.clone(), sec]).unwrap();
    assert_eq!(again, nodes);
    assert!(master_nodes(&p, &[(0.0, 0.0)], &[vec![[0.0, 0.0]], vec![]]).is_err());
}
