//! The wing master `case init` proposes for a wing ([`propose`]): when one of the wing's
//! support surfaces is wrapped round its leading edge (every section across the span runs
//! from the trailing edge round the leading edge back to the trailing edge, as the wing
//! master of `wingmaster` samples it, §6.2), a [`WingMasterSpec`] on that surface with key
//! sections at its root and tip, and the master modifier linking the wing's surfaces and
//! caps. Variables (deviations, §6.2): sweep and dihedral of the reference line (quarter
//! chord), twist at the root and the tip, tip chord, the maximum thickness `tmax` of Eq. 39
//! at the root and the tip, and one camber ordinate of Eq. 40 at the tip.
//!
//! A wing whose upper and lower faces lie on separate surfaces gets a wing master over the
//! two ([`WingMasterSpec::second`]): a pair of surfaces whose sections, one after the
//! other, run from the trailing edge round the leading edge (their shared edge) back to
//! the trailing edge, found by trying each surface's parameter directions.

use std::collections::BTreeMap;

use geom_db::eval::ParamSurface;
use geom_db::prelude::{Point3, Vector3};
use geom_db::{GeomDb, SurfaceId};
use param::{DesignVariable, Links, MasterModifier, MasterSpec, Param};
use wingmaster::{KeySection, PlanformVariables, SectionFace, WingMasterSpec};

/// Samples per section of the wing master (the key sections are fitted to them).
const N_S: usize = 81;
/// Stations of the wing master along the span.
const N_T: usize = 11;
/// Samples per section for the test of the section's shape.
const N_TEST: usize = 61;
/// A section is closed when its trailing-edge gap is at most this fraction of its chord.
const MAX_GAP: f64 = 0.05;
/// Largest thickness (both sides of the chord line) of a section, as a fraction of chord.
const MAX_THICKNESS: f64 = 0.5;
/// Two faces of a split wing meet at the leading edge within this fraction of the chord.
const SHARED_EDGE: f64 = 1e-4;

/// A section of a wrapped surface: leading and trailing edge (midpoint of the ends), chord.
#[derive(Debug, Clone, Copy)]
struct Section {
    le: Point3,
    te: Point3,
    chord: f64,
    centroid: Point3,
}

/// How the wing's sections are sampled: one wrapped surface, or two faces split at the
/// leading edge.
#[derive(Debug, Clone, Copy)]
struct Layout {
    first: SectionFace,
    second: Option<SectionFace>,
}

/// One face at normalised (section a, span t), its reversals applied (as the wing master
/// samples it).
fn sample_face(db: &GeomDb, f: &SectionFace, a: f64, t: f64) -> Point3 {
    let surf = db.surface(f.surface);
    let ([u0, u1], [v0, v1]) = surf.domain();
    let a = if f.reverse_section { 1.0 - a } else { a };
    let t = if f.reverse_span { 1.0 - t } else { t };
    let (x, y) = match f.spanwise {
        Param::V => (a, t),
        Param::U => (t, a),
    };
    surf.point(u0 + x * (u1 - u0), v0 + y * (v1 - v0))
}

/// The wing at normalised (section a, span t) as the wing master samples it.
fn sample(db: &GeomDb, l: &Layout, a: f64, t: f64) -> Point3 {
    match &l.second {
        None => sample_face(db, &l.first, a, t),
        Some(_) if a <= 0.5 => sample_face(db, &l.first, 2.0 * a, t),
        Some(second) => sample_face(db, second, 2.0 * a - 1.0, t),
    }
}

/// The section at span parameter `t` when it is an airfoil-like closed curve: ends
/// within [`MAX_GAP`] chords of each other, both sides leaving them forward (a trailing
/// edge), leading edge (the point farthest from the trailing edge) away from the ends,
/// thickness below [`MAX_THICKNESS`] chords.
fn section(db: &GeomDb, l: &Layout, t: f64) -> Option<Section> {
    let pts: Vec<Point3> = (0..N_TEST)
        .map(|i| sample(db, l, i as f64 / (N_TEST - 1) as f64, t))
        .collect();
    let (first, last) = (pts[0], pts[N_TEST - 1]);
    let te = Point3::from((first.coords + last.coords) * 0.5);
    let (i_le, le) = pts
        .iter()
        .enumerate()
        .max_by(|a, b| (a.1 - te).norm().total_cmp(&(b.1 - te).norm()))
        .map(|(i, p)| (i, *p))?;
    let chord = (le - te).norm();
    if chord.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        || (first - last).norm() > MAX_GAP * chord
    {
        return None;
    }
    if !(N_TEST / 5..=4 * N_TEST / 5).contains(&i_le) {
        return None;
    }
    // the ends are the trailing edge, where both sides run forward in a wedge, not the
    // leading edge, where they leave in opposite directions (two faces sewn along both
    // edges join at either)
    let (d0, d1) = (pts[1] - first, pts[N_TEST - 2] - last);
    if d0.dot(&d1) <= 0.0 {
        return None;
    }
    let x = (te - le) / chord;
    let thickness = pts
        .iter()
        .map(|p| {
            let d = p - le;
            (d - x * d.dot(&x)).norm()
        })
        .fold(0.0, f64::max);
    if thickness > MAX_THICKNESS * chord {
        return None;
    }
    let centroid = Point3::from(pts.iter().map(|p| p.coords).sum::<Vector3>() / N_TEST as f64);
    Some(Section {
        le,
        te,
        chord,
        centroid,
    })
}

/// The coordinate axis nearest to `d`, with its sign (`None` for a zero vector).
fn nearest_axis(d: Vector3) -> Option<Vector3> {
    let k = (0..3).max_by(|&a, &b| d[a].abs().total_cmp(&d[b].abs()))?;
    if d[k] == 0.0 || !d[k].is_finite() {
        return None;
    }
    let mut e = Vector3::zeros();
    e[k] = d[k].signum();
    Some(e)
}

/// A wing's sections found on its surfaces: how they are sampled, root and tip sections.
#[derive(Debug, Clone, Copy)]
struct Wrapped {
    layout: Layout,
    root: Section,
    tip: Section,
    span: f64,
}

/// The layout as a wing when every sampled section along the span is closed.
fn as_wing(db: &GeomDb, layout: Layout) -> Option<Wrapped> {
    let secs: Vec<Section> = [0.0, 0.25, 0.5, 0.75, 1.0]
        .iter()
        .map(|&t| section(db, &layout, t))
        .collect::<Option<_>>()?;
    let (root, tip) = (secs[0], secs[4]);
    let span = (tip.centroid - root.centroid).norm();
    (span > 0.5 * tip.chord.min(root.chord)).then_some(Wrapped {
        layout,
        root,
        tip,
        span,
    })
}

/// `s` as a wrapped wing surface, if every sampled section along one parameter is closed.
fn wrapped(db: &GeomDb, s: SurfaceId) -> Option<Wrapped> {
    [Param::V, Param::U].into_iter().find_map(|spanwise| {
        let face = SectionFace {
            surface: s,
            spanwise,
            reverse_section: false,
            reverse_span: false,
        };
        as_wing(
            db,
            Layout {
                first: face,
                second: None,
            },
        )
    })
}

/// `a` then `b` as the two faces of a wing split at the leading edge: tries the spanwise
/// parameter and directions of each, and keeps a layout whose sections are closed and
/// continuous at the shared leading edge (within [`SHARED_EDGE`] chords) at three stations.
fn split(db: &GeomDb, a: SurfaceId, b: SurfaceId) -> Option<Wrapped> {
    let params = [Param::V, Param::U];
    let faces = |s: SurfaceId, span_too: bool| {
        let mut out = Vec::new();
        for spanwise in params {
            for reverse_section in [false, true] {
                for reverse_span in [false, true] {
                    if reverse_span && !span_too {
                        continue;
                    }
                    out.push(SectionFace {
                        surface: s,
                        spanwise,
                        reverse_section,
                        reverse_span,
                    });
                }
            }
        }
        out
    };
    for first in faces(a, false) {
        for second in faces(b, true) {
            let joined = [0.0, 0.5, 1.0].iter().all(|&t| {
                let (te, le) = (
                    sample_face(db, &first, 0.0, t),
                    sample_face(db, &first, 1.0, t),
                );
                let chord = (le - te).norm();
                chord > 0.0 && (sample_face(db, &second, 0.0, t) - le).norm() <= SHARED_EDGE * chord
            });
            if !joined {
                continue;
            }
            let layout = Layout {
                first,
                second: Some(second),
            };
            if let Some(w) = as_wing(db, layout) {
                return Some(w);
            }
        }
    }
    None
}

/// A proposed wing master.
#[derive(Debug, Clone)]
pub struct Proposal {
    /// The spec (the case's `wing_masters` entry, keyed by the role).
    pub spec: WingMasterSpec,
    /// The master modifier (source `External(role)`).
    pub modifier: MasterModifier,
    /// What was found, in words.
    pub summary: String,
}

/// The wing master of the wing `role` whose own support surfaces are `surfaces` and whose
/// caps' support surfaces are `caps`; `Err` says why there is none.
pub fn propose(
    db: &GeomDb,
    role: &str,
    surfaces: &[SurfaceId],
    caps: &[SurfaceId],
) -> Result<Proposal, String> {
    let size = |w: &Wrapped| w.span * w.root.chord;
    let mut w = surfaces
        .iter()
        .filter_map(|&s| wrapped(db, s))
        .max_by(|a, b| size(a).total_cmp(&size(b)));
    if w.is_none() {
        // upper and lower faces on separate surfaces: the largest pair that joins
        w = surfaces
            .iter()
            .flat_map(|&a| surfaces.iter().map(move |&b| (a, b)))
            .filter(|(a, b)| a < b)
            .filter_map(|(a, b)| split(db, a, b).or_else(|| split(db, b, a)))
            .max_by(|a, b| size(a).total_cmp(&size(b)));
    }
    let w = w.ok_or_else(|| {
        format!(
            "no support surface of {role} is wrapped round the leading edge, and no two of \
             its {} surfaces join there as upper and lower faces",
            surfaces.len()
        )
    })?;
    let e = nearest_axis(w.tip.centroid - w.root.centroid)
        .ok_or_else(|| format!("{role}: root and tip sections coincide"))?;
    let chord_dir = w.root.te - w.root.le;
    let a = nearest_axis(chord_dir - e * chord_dir.dot(&e))
        .ok_or_else(|| format!("{role}: the root chord is along the span"))?;
    let name = |what: &str| format!("{role}.{what}");
    let var = |what: &str, bound: f64| {
        DesignVariable::new(name(what), -bound, bound)
            .with_group(role.to_string())
            .with_scale(bound / 10.0)
    };
    let variables = vec![
        var("sweep", 0.05),
        var("dihedral", 0.05),
        var("twist.root", 0.05),
        var("tmax.root", 0.01),
        var("twist.tip", 0.05),
        var("chord.tip", 0.1 * w.tip.chord),
        var("tmax.tip", 0.01),
        var("camber.tip", 0.01),
    ];
    let first = w.layout.first;
    let spec = WingMasterSpec {
        surface: first.surface,
        spanwise: first.spanwise,
        reverse_section: first.reverse_section,
        reverse_span: first.reverse_span,
        second: w.layout.second,
        span_axis: e,
        streamwise: a,
        n_s: N_S,
        n_t: N_T,
        reference_chord_fraction: 0.25,
        camber_points: 8,
        thickness_extra: 0,
        planform: PlanformVariables {
            sweep: Some(name("sweep")),
            dihedral: Some(name("dihedral")),
            span: None,
        },
        key_sections: vec![
            KeySection {
                t: 0.0,
                twist: Some(name("twist.root")),
                thickness: BTreeMap::from([("tmax".to_string(), name("tmax.root"))]),
                ..Default::default()
            },
            KeySection {
                t: 1.0,
                twist: Some(name("twist.tip")),
                chord: Some(name("chord.tip")),
                thickness: BTreeMap::from([("tmax".to_string(), name("tmax.tip"))]),
                camber: BTreeMap::from([(3, name("camber.tip"))]),
                ..Default::default()
            },
        ],
    };
    let mut linked: Vec<SurfaceId> = surfaces.iter().chain(caps).copied().collect();
    linked.sort_unstable();
    linked.dedup();
    let modifier = MasterModifier {
        name: role.to_string(),
        links: Links {
            surfaces: linked.clone(),
            ..Default::default()
        },
        source: MasterSpec::External(role.to_string()),
        variables,
    };
    let pname = |p: Param| match p {
        Param::U => "u",
        Param::V => "v",
    };
    let sampled = match &w.layout.second {
        None => format!(
            "surface {} ({} along the span)",
            first.surface.index(),
            pname(first.spanwise)
        ),
        Some(b) => format!(
            "surfaces {} and {} split at the leading edge ({} and {} along the span)",
            first.surface.index(),
            b.surface.index(),
            pname(first.spanwise),
            pname(b.spanwise)
        ),
    };
    let summary = format!(
        "{role}: wing master on {sampled}, root chord {:.4}, tip chord {:.4}, moving \
         surfaces {:?}",
        w.root.chord,
        w.tip.chord,
        linked.iter().map(|s| s.index()).collect::<Vec<_>>()
    );
    Ok(Proposal {
        spec,
        modifier,
        summary,
    })
}
