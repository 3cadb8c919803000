//! Units sanity: the declared length unit against the model's size.
//!
//! A file whose header says inches while its numbers are metres reads as a 0.91 m aircraft.
//! Nothing in the file contradicts its header, so the check is one of plausibility: a model
//! whose faces are recognised as an aircraft (a wing and a fuselage) whose length in metres
//! is outside [`AIRCRAFT_LENGTH`], or any model outside [`ANY_LENGTH`], gets a warning with
//! the evidence (its length in the declared unit and in metres) and, for each common unit in
//! which the file's numbers would give a plausible length, the option that reads them so
//! (`--file-units`). A wind-tunnel model of a transport aircraft is also small: the warning
//! says so, and it is only a warning.

use super::model::LengthUnit;
use super::report::ImportReport;
use crate::db::GeomDb;

/// Lengths in metres of full-size aircraft (a light aircraft to the largest transports).
pub const AIRCRAFT_LENGTH: (f64, f64) = (2.0, 120.0);
/// Lengths in metres any model is expected to have (a millimetre to 10 km, far fields
/// included).
pub const ANY_LENGTH: (f64, f64) = (1e-3, 1e4);
/// The units tried for the file's numbers, most likely first.
const CANDIDATES: [&str; 5] = ["m", "mm", "in", "ft", "cm"];

/// The warning for a model whose size does not fit its declared unit, if any.
///
/// `declared` is the unit the file's numbers are in (its header's, or `--file-units`);
/// `length` the model's largest bounding-box extent in the database's unit, which is
/// `scale` × the file's numbers.
pub fn size_warning(
    declared: &LengthUnit,
    length: f64,
    scale: f64,
    roles: &[&str],
) -> Option<String> {
    let numbers = length / scale;
    let metres = numbers * declared.metres;
    if !(metres.is_finite() && metres > 0.0) {
        return None;
    }
    let aircraft = roles.iter().any(|r| r.starts_with("wing"))
        && roles.iter().any(|r| r.starts_with("fuselage"))
        && !roles.contains(&"farfield");
    let (range, what) = if aircraft {
        (
            AIRCRAFT_LENGTH,
            "an aircraft (a wing and a fuselage recognised; full-size ones are 2 to 120 m long)",
        )
    } else {
        (ANY_LENGTH, "any model")
    };
    let inside = |m: f64| m >= range.0 && m <= range.1;
    if inside(metres) {
        return None;
    }
    let alternatives: Vec<String> = CANDIDATES
        .iter()
        .filter_map(|&n| LengthUnit::named(n))
        .filter(|u| u.name != declared.name && inside(numbers * u.metres))
        .map(|u| {
            format!(
                "read as {} they give {:.4} m (--file-units {})",
                u.name,
                numbers * u.metres,
                u.name
            )
        })
        .collect();
    let advice = if alternatives.is_empty() {
        String::new()
    } else {
        format!(
            "; if the file's numbers are not in {}: {}",
            declared.name,
            alternatives.join(", ")
        )
    };
    Some(format!(
        "the model is {numbers:.4} {} = {metres:.4} m long as the file declares, {} for {what}{advice}",
        declared.name,
        if metres < range.0 { "small" } else { "large" },
    ))
}

/// Adds [`size_warning`]'s warning to the report of an imported model.
pub(crate) fn check(db: &GeomDb, declared: Option<&LengthUnit>, rep: &mut ImportReport) {
    let (Some(declared), Some((lo, hi))) = (declared, db.bbox()) else {
        return;
    };
    let length = (hi - lo).amax();
    let roles: Vec<&str> = rep.faces.iter().map(|f| f.role.as_str()).collect();
    if let Some(w) = size_warning(declared, length, rep.scale, &roles) {
        rep.warnings.push(w);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_aircraft_of_36_inches_is_suspect_and_metres_are_offered() {
        let inch = LengthUnit::named("in").unwrap();
        let w = size_warning(&inch, 36.0, 1.0, &["fuselage", "wing"]).unwrap();
        assert!(w.contains("36.0000 in = 0.9144 m"), "{w}");
        assert!(w.contains("--file-units m"), "{w}");
        // 36 mm is not an aircraft; 36 ft is
        assert!(!w.contains("--file-units mm"), "{w}");
        assert!(w.contains("--file-units ft"), "{w}");
        // the same numbers in metres, or converted to mm on the way (scale 25.4): no warning
        // for metres; the length in the database's unit is what is divided by the scale
        let m = LengthUnit::named("m").unwrap();
        assert!(size_warning(&m, 36.0, 1.0, &["fuselage", "wing"]).is_none());
        assert!(size_warning(&inch, 36.0 * 25.4, 25.4, &["fuselage", "wing"]).is_some());
        // not an aircraft: a 0.9 m wing alone is fine, a 1e-5 m model is not
        assert!(size_warning(&inch, 36.0, 1.0, &["wing", "wing_tip"]).is_none());
        assert!(size_warning(&m, 1e-5, 1.0, &["body"]).is_some());
        // a far field makes the box the domain's, not the aircraft's
        assert!(size_warning(&inch, 36.0, 1.0, &["fuselage", "wing", "farfield"]).is_none());
    }
}
