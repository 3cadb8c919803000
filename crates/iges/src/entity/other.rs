//! Other entities: 116 point, 123 direction, 124 transformation matrix, 314 colour
//! definition.

use super::{Dec, Enc, write_err};
use crate::directory::DeId;
use crate::error::EntityProblem;

/// 116 point.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// (X, Y, Z).
    pub point: [f64; 3],
    /// PTR: subfigure definition used as display symbol, if any.
    pub symbol: Option<DeId>,
}

impl Point {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let point = d.reals("coordinate")?;
        let symbol = if d.has_more() {
            d.opt_ptr("display symbol")?
        } else {
            None
        };
        Ok(Point { point, symbol })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.reals(&self.point);
        e.opt_ptr(self.symbol);
    }
}

/// 124 transformation matrix: x' = R x + T. A 124 may itself point (directory field 7) to
/// another 124, applied after it; see [`IgesFile::transform`](crate::IgesFile::transform).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TransformationMatrix {
    /// R, row by row (R11 R12 R13; R21...).
    pub rotation: [[f64; 3]; 3],
    /// T.
    pub translation: [f64; 3],
}

impl TransformationMatrix {
    /// The identity.
    pub const IDENTITY: TransformationMatrix = TransformationMatrix {
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.0; 3],
    };

    /// R p + T.
    pub fn apply_point(&self, p: [f64; 3]) -> [f64; 3] {
        let mut out = self.apply_vector(p);
        for k in 0..3 {
            out[k] += self.translation[k];
        }
        out
    }

    /// R v (directions are not translated).
    pub fn apply_vector(&self, v: [f64; 3]) -> [f64; 3] {
        let r = &self.rotation;
        [0, 1, 2].map(|k| r[k][0] * v[0] + r[k][1] * v[1] + r[k][2] * v[2])
    }

    /// The transformation applying `self` first, then `outer`.
    pub fn then(&self, outer: &TransformationMatrix) -> TransformationMatrix {
        let mut rotation = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                rotation[i][j] = (0..3)
                    .map(|k| outer.rotation[i][k] * self.rotation[k][j])
                    .sum();
            }
        }
        TransformationMatrix {
            rotation,
            translation: outer.apply_point(self.translation),
        }
    }

    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let mut m = TransformationMatrix::IDENTITY;
        for k in 0..3 {
            let row: [f64; 4] = d.reals("matrix element")?;
            m.rotation[k] = [row[0], row[1], row[2]];
            m.translation[k] = row[3];
        }
        Ok(m)
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        for k in 0..3 {
            e.reals(&self.rotation[k]);
            e.real(self.translation[k]);
        }
    }
}

/// 314 colour definition.
#[derive(Debug, Clone, PartialEq)]
pub struct ColorDefinition {
    /// CC1, CC2, CC3: red, green, blue in percent.
    pub rgb: [f64; 3],
    /// CNAME: colour name, if given.
    pub name: Option<String>,
}

impl ColorDefinition {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        Ok(ColorDefinition {
            rgb: d.reals("colour component")?,
            name: d.opt_string("colour name")?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) -> Result<(), EntityProblem> {
        e.reals(&self.rgb);
        match &self.name {
            Some(s) if !s.is_ascii() => return Err(write_err("colour name is not ASCII")),
            Some(s) => e.0.push(crate::param::Param::Str(s.clone())),
            None => e.0.push(crate::param::Param::Empty),
        }
        Ok(())
    }
}

/// 123 direction (not necessarily of unit length).
#[derive(Debug, Clone, PartialEq)]
pub struct Direction {
    /// (X, Y, Z).
    pub direction: [f64; 3],
}

impl Direction {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        Ok(Direction {
            direction: d.reals("direction")?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.reals(&self.direction);
    }
}
