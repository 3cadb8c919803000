//! Stage 3, loops: each face loop's pieces chained head to tail — each piece turned so that
//! it starts where the previous one ends, within the sewing tolerance — and closed; an open
//! loop is an error naming the face.

use super::super::Error;
use super::super::model::CadModel;
use super::edges::Edges;
use super::entity_name;

/// Per face, per loop: (edge, traversed reversed) in loop order.
pub(crate) type Loops = Vec<Vec<Vec<(usize, bool)>>>;

/// Runs stage 3.
pub(crate) fn run(model: &CadModel, edges: &Edges, sew: f64) -> Result<Loops, Error> {
    let e = &edges.edges;
    let mut out = Vec::with_capacity(edges.loops.len());
    for (fi, loops) in edges.loops.iter().enumerate() {
        let mut face = Vec::with_capacity(loops.len());
        for (li, ids) in loops.iter().enumerate() {
            let chain = |first_rev: bool| -> Option<Vec<(usize, bool)>> {
                let mut v = Vec::with_capacity(ids.len());
                let e0 = &e[ids[0]];
                let (s0, mut cur) = if first_rev {
                    (e0.end, e0.start)
                } else {
                    (e0.start, e0.end)
                };
                v.push((ids[0], first_rev));
                for &k in &ids[1..] {
                    let x = &e[k];
                    if (x.start - cur).norm() <= sew {
                        v.push((k, false));
                        cur = x.end;
                    } else if (x.end - cur).norm() <= sew {
                        v.push((k, true));
                        cur = x.start;
                    } else {
                        return None;
                    }
                }
                ((cur - s0).norm() <= sew).then_some(v)
            };
            let chained = chain(false)
                .or_else(|| chain(true))
                .ok_or_else(|| Error::Entity {
                    file: model.file.clone(),
                    entity: entity_name(model, &model.faces[fi].source),
                    reason: format!(
                        "boundary loop {} is not closed within the sewing tolerance {sew:.3e}",
                        li + 1
                    ),
                })?;
            face.push(chained);
        }
        out.push(face);
    }
    Ok(out)
}
