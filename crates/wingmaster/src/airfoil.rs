//! Airfoil coordinate files (Selig and Lednicer formats) and the local chord frame of §6.2.
//!
//! Selig format: a name line, then `x z` pairs from the trailing edge over the upper surface to
//! the leading edge and back along the lower surface. Lednicer format: a name line, a line with
//! the point counts of the upper and lower surfaces (both > 1), then the upper surface from
//! leading to trailing edge and the lower surface from leading to trailing edge, usually
//! separated by blank lines. Blank lines and text lines before the data ("stray headers"), and
//! text after the data (comments) are skipped; consecutive duplicate points (a repeated
//! leading-edge point) are merged.

use std::io::BufRead;

use crate::error::{Error, Result};

/// An airfoil as read from a file: its name and its points in Selig order (trailing edge →
/// upper surface → leading edge → lower surface → trailing edge), in the file's coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Airfoil {
    /// The name line.
    pub name: String,
    /// Points in Selig order, consecutive duplicates removed.
    pub points: Vec<[f64; 2]>,
    /// Non-fatal observations made while reading (e.g. a truncated surface).
    pub warnings: Vec<String>,
}

/// The local frame of a section (§6.2): origin at the leading edge, x along the chord to the
/// trailing-edge midpoint, lengths scaled by the chord.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Frame {
    /// Leading edge in file coordinates.
    pub le: [f64; 2],
    /// Chord length.
    pub chord: f64,
    /// Angle of the chord line from the file's x axis, radians.
    pub angle: f64,
}

impl Frame {
    /// File coordinates → normalised local coordinates.
    pub fn to_local(&self, p: [f64; 2]) -> [f64; 2] {
        let (s, c) = self.angle.sin_cos();
        let d = [p[0] - self.le[0], p[1] - self.le[1]];
        [
            (c * d[0] + s * d[1]) / self.chord,
            (-s * d[0] + c * d[1]) / self.chord,
        ]
    }

    /// Normalised local coordinates → file coordinates.
    pub fn to_global(&self, q: [f64; 2]) -> [f64; 2] {
        let (s, c) = self.angle.sin_cos();
        let d = [q[0] * self.chord, q[1] * self.chord];
        [
            self.le[0] + c * d[0] - s * d[1],
            self.le[1] + s * d[0] + c * d[1],
        ]
    }
}

/// An airfoil in its local frame, split into the two surfaces.
#[derive(Debug, Clone, PartialEq)]
pub struct NormalisedAirfoil {
    /// The frame used.
    pub frame: Frame,
    /// All points in local coordinates, Selig order.
    pub points: Vec<[f64; 2]>,
    /// Index of the leading-edge point in `points` (the point farthest from the trailing-edge
    /// midpoint); it is (0, 0) in local coordinates.
    pub le_index: usize,
    /// Trailing-edge thickness (upper minus lower end point, normal to the chord, in chords);
    /// zero for a closed or crossed trailing edge or a truncated surface.
    pub te_thickness: f64,
}

fn parse_pair(line: &str) -> Option<Vec<f64>> {
    let toks: Vec<&str> = line
        .split(|c: char| c.is_whitespace() || c == ',' || c == ';')
        .filter(|t| !t.is_empty())
        .collect();
    if toks.is_empty() {
        return None;
    }
    let vals: Option<Vec<f64>> = toks.iter().map(|t| t.parse::<f64>().ok()).collect();
    vals
}

impl Airfoil {
    /// Reads Selig or Lednicer coordinates; `path` is used in error messages only.
    pub fn parse(reader: impl BufRead, path: &str) -> Result<Self> {
        let err = |line: usize, reason: String| Error::Parse {
            path: path.to_string(),
            line,
            reason,
        };
        // Blocks of consecutive numeric pairs, with the line number of their first line.
        let mut name: Option<String> = None;
        let mut blocks: Vec<(usize, Vec<[f64; 2]>)> = Vec::new();
        let mut in_block = false;
        let mut trailer_from: Option<usize> = None;
        for (i, line) in reader.lines().enumerate() {
            let lineno = i + 1;
            let line = line.map_err(|e| err(lineno, format!("cannot read: {e}")))?;
            let line = line.trim_start_matches('\u{feff}');
            let trimmed = line.trim();
            if trimmed.is_empty() {
                in_block = false;
                continue;
            }
            match parse_pair(trimmed) {
                Some(v) if v.len() == 2 && trailer_from.is_none() => {
                    if name.is_none() {
                        name = Some(String::new());
                    }
                    if !(v[0].is_finite() && v[1].is_finite()) {
                        return Err(err(lineno, format!("non-finite coordinate '{trimmed}'")));
                    }
                    if !in_block {
                        blocks.push((lineno, Vec::new()));
                        in_block = true;
                    }
                    blocks
                        .last_mut()
                        .expect("block pushed")
                        .1
                        .push([v[0], v[1]]);
                }
                Some(v) if trailer_from.is_none() && blocks.is_empty() => {
                    // A numeric header line that is not a coordinate pair (e.g. plot limits).
                    let _ = v;
                    in_block = false;
                }
                Some(v) if v.len() == 2 => {
                    let from = trailer_from.unwrap_or(lineno);
                    return Err(err(
                        lineno,
                        format!(
                            "coordinates after the text at line {from} (expected the end of the data)"
                        ),
                    ));
                }
                _ => {
                    let starts_numeric = trimmed
                        .split_whitespace()
                        .next()
                        .is_some_and(|t| t.parse::<f64>().is_ok());
                    if !blocks.is_empty() && trailer_from.is_none() && starts_numeric {
                        return Err(err(
                            lineno,
                            format!("malformed coordinate line '{trimmed}' (expected two numbers)"),
                        ));
                    }
                    if blocks.is_empty() {
                        if name.is_none() {
                            name = Some(trimmed.to_string());
                        }
                    } else if trailer_from.is_none() {
                        trailer_from = Some(lineno);
                    }
                    in_block = false;
                }
            }
        }
        let name = name.unwrap_or_default();
        if blocks.is_empty() {
            return Err(err(0, "no coordinate pairs found".into()));
        }
        let mut warnings = Vec::new();
        if let Some(l) = trailer_from {
            warnings.push(format!("text after the coordinates from line {l} ignored"));
        }
        // Lednicer: the first pair holds the two point counts.
        let first = blocks[0].1[0];
        let is_count = |v: f64| v >= 2.0 && v.fract() == 0.0 && v < 1.0e6;
        let raw: Vec<[f64; 2]> = if is_count(first[0]) && is_count(first[1]) {
            let (nu, nl) = (first[0] as usize, first[1] as usize);
            let mut rest: Vec<[f64; 2]> = blocks[0].1[1..].to_vec();
            for (_, b) in &blocks[1..] {
                rest.extend_from_slice(b);
            }
            if rest.len() != nu + nl {
                return Err(err(
                    blocks[0].0,
                    format!(
                        "Lednicer header announces {nu} + {nl} points but {} follow",
                        rest.len()
                    ),
                ));
            }
            let (upper, lower) = rest.split_at(nu);
            let mut pts: Vec<[f64; 2]> = upper.iter().rev().copied().collect();
            pts.extend_from_slice(lower);
            pts
        } else {
            if blocks.len() > 1 {
                return Err(err(
                    blocks[1].0,
                    "a second block of coordinates after a blank or text line (not Lednicer \
                     format: no point-count line)"
                        .into(),
                ));
            }
            blocks.swap_remove(0).1
        };
        let mut points: Vec<[f64; 2]> = Vec::with_capacity(raw.len());
        for p in raw {
            if points.last() != Some(&p) {
                points.push(p);
            }
        }
        if points.len() < 8 {
            return Err(err(
                0,
                format!("only {} distinct points; at least 8 needed", points.len()),
            ));
        }
        Ok(Self {
            name,
            points,
            warnings,
        })
    }

    /// The section in its local frame (§6.2): leading edge at the origin, trailing-edge
    /// midpoint at (1, 0), upper surface first. Checks that both surfaces exist.
    pub fn normalise(&self) -> Result<NormalisedAirfoil> {
        let bad = |reason: String| Error::Parse {
            path: self.name.clone(),
            line: 0,
            reason,
        };
        let pts = &self.points;
        let n = pts.len();
        let (a, b) = (pts[0], pts[n - 1]);
        let mut te = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        let far = |te: [f64; 2]| {
            let mut best = (0usize, -1.0);
            for (i, p) in pts.iter().enumerate() {
                let d = (p[0] - te[0]).powi(2) + (p[1] - te[1]).powi(2);
                if d > best.1 {
                    best = (i, d);
                }
            }
            best
        };
        let (mut le_index, mut d2) = far(te);
        let mut truncated = false;
        // A truncated surface: the two end points are far apart along the chord.
        let gap = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
        if gap > 0.05 * d2.sqrt() {
            let (la, lb) = (
                (a[0] - pts[le_index][0]).hypot(a[1] - pts[le_index][1]),
                (b[0] - pts[le_index][0]).hypot(b[1] - pts[le_index][1]),
            );
            te = if la >= lb { a } else { b };
            (le_index, d2) = far(te);
            truncated = true;
        }
        if le_index < 3 || le_index + 4 > n {
            return Err(bad(format!(
                "leading edge found at point {} of {n}: one surface has fewer than 3 points",
                le_index + 1
            )));
        }
        let le = pts[le_index];
        let chord = d2.sqrt();
        if chord <= 0.0 || !chord.is_finite() {
            return Err(bad("zero chord".into()));
        }
        let angle = (te[1] - le[1]).atan2(te[0] - le[0]);
        let frame = Frame { le, chord, angle };
        let mut local: Vec<[f64; 2]> = pts.iter().map(|&p| frame.to_local(p)).collect();
        local[le_index] = [0.0, 0.0];
        // Upper surface first: compare the mean heights of the two branches.
        let mean = |s: &[[f64; 2]]| s.iter().map(|p| p[1]).sum::<f64>() / s.len() as f64;
        if mean(&local[..le_index]) < mean(&local[le_index + 1..]) {
            local.reverse();
            le_index = n - 1 - le_index;
        }
        let te_thickness = if truncated {
            0.0
        } else {
            (local[0][1] - local[n - 1][1]).max(0.0)
        };
        Ok(NormalisedAirfoil {
            frame,
            points: local,
            le_index,
            te_thickness,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_round_trip() {
        let f = Frame {
            le: [0.3, -0.2],
            chord: 2.5,
            angle: 0.3,
        };
        let p = [1.7, 0.4];
        let q = f.to_global(f.to_local(p));
        assert!((p[0] - q[0]).abs() < 1e-14 && (p[1] - q[1]).abs() < 1e-14);
    }

    #[test]
    fn lednicer_and_selig_agree() {
        let selig = "foil\n1 0.01\n0.5 0.05\n0.2 0.06\n0.05 0.03\n0 0\n0.05 -0.02\n0.2 -0.04\n0.5 -0.03\n1 -0.01\n";
        let led = "foil\n5. 5.\n\n0 0\n0.05 0.03\n0.2 0.06\n0.5 0.05\n1 0.01\n\n0 0\n0.05 -0.02\n0.2 -0.04\n0.5 -0.03\n1 -0.01\n";
        let a = Airfoil::parse(selig.as_bytes(), "s").unwrap();
        let b = Airfoil::parse(led.as_bytes(), "l").unwrap();
        assert_eq!(a.points, b.points);
        assert_eq!(a.points.len(), 9);
    }

    #[test]
    fn second_block_without_counts_is_an_error() {
        let s = "foil\n1 0\n0.5 0.05\n0 0\n0.5 -0.05\n\n1 0\n0.5 0.05\n0 0\n0.5 -0.05\n";
        let e = Airfoil::parse(s.as_bytes(), "f.dat").unwrap_err();
        assert!(e.to_string().contains("f.dat:7"), "{e}");
    }
}
