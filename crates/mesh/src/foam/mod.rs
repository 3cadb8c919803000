//! OpenFOAM `polyMesh`, read and written back: `constant/polyMesh/{points, faces, owner,
//! neighbour, boundary}` of a case, ASCII or binary, labels of 32 or 64 bits and scalars of
//! 32 or 64 bits as each file's header `arch` says, gzipped files (`points.gz`) too.
//!
//! Reading ([`read()`], given the case directory or its `constant/polyMesh`): the points are
//! the grid's nodes, in OpenFOAM's order; each cell is rebuilt from its faces (`owner`,
//! `neighbour`) and recognised as a tetrahedron, pyramid, prism or hexahedron (node orders in
//! docs/formats/openfoam.md); every patch with faces becomes a [`Marker`] of
//! its triangles and quadrilaterals, named as the patch (patches with no face are left out,
//! with a warning). A polyhedral cell is an error naming the cell, since the grid type holds
//! those four kinds only. The case is remembered in [`Mesh::foam`](crate::Mesh::foam).
//!
//! Writing ([`write()`]) is writing back: the output is the input case with its `points`
//! replaced by the grid's nodes, in the points file's own format, header and precision. Every
//! other file is copied byte for byte (the case's `system/`, `constant/`, `0/` and other
//! files; not `processor*/`, `postProcessing/` or time directories other than `0`), each
//! through a temporary name renamed into place. The output is a case directory, or a
//! `…/constant/polyMesh` directory (then only the polyMesh is written); never the polyMesh
//! the grid was read from (inputs are not overwritten). A grid not read from OpenFOAM cannot
//! be written as OpenFOAM (its faces would have to be made): an error says so.
//!
//! Fields ([`read_field`]): the `internalField` and the patches' `value`s of a field file,
//! for the adjoint sensitivities that `aeroshape gradient` reads.

mod cells;
mod field;
mod file;
mod write;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::grid::{ElementKind, Elements, Marker, Mesh};
pub use field::{Field, Values, read_field};
use file::FoamFile;
pub use file::Layout;
pub use write::write;

/// One patch of the `boundary` file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Patch {
    /// Its name (the marker's).
    pub name: String,
    /// Its `type` (`wall`, `patch`, `symmetryPlane`, `empty`, …).
    pub kind: String,
    /// Its first face.
    pub start_face: usize,
    /// Its number of faces.
    pub n_faces: usize,
}

/// Where a grid read by [`read()`] came from: what [`write()`] needs to write it back.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Source {
    /// The case directory, when the polyMesh is its `constant/polyMesh`.
    pub case: Option<PathBuf>,
    /// The polyMesh directory.
    pub poly_mesh: PathBuf,
    /// The points file's name (`points` or `points.gz`).
    pub points_name: String,
    /// The points file's layout (ASCII or binary, scalar width, byte order).
    pub points_layout: Layout,
    /// The points file's bytes before the list (header, banner, comments), written back.
    pub points_head: Vec<u8>,
    /// The points file's bytes after the list, written back.
    pub points_tail: Vec<u8>,
    /// The patches, in the `boundary` file's order.
    pub patches: Vec<Patch>,
    /// Number of points.
    pub n_points: usize,
    /// Number of faces; the first `n_internal` are internal.
    pub n_faces: usize,
    /// Number of internal faces (`neighbour`'s length).
    pub n_internal: usize,
    /// The OpenFOAM cell of each of the grid's cells (in [`Elements::iter`] order).
    pub cell_of_element: Vec<u32>,
}

/// The polyMesh directory and case of `path`: a case (with `constant/polyMesh`) or a
/// polyMesh directory itself.
pub fn locate(path: &Path) -> Result<(Option<PathBuf>, PathBuf)> {
    let under = path.join("constant").join("polyMesh");
    if file::find(&under, "faces").is_some() {
        return Ok((Some(path.to_path_buf()), under));
    }
    if file::find(path, "faces").is_some() {
        let case = path
            .parent()
            .filter(|c| c.file_name().is_some_and(|n| n == "constant"))
            .filter(|_| path.file_name().is_some_and(|n| n == "polyMesh"))
            .and_then(Path::parent)
            .map(Path::to_path_buf);
        return Ok((case, path.to_path_buf()));
    }
    Err(Error::Io {
        file: path.display().to_string(),
        error: std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "not an OpenFOAM case: no constant/polyMesh/faces (nor faces) in it",
        ),
    })
}

/// True when `path` is an OpenFOAM case or polyMesh directory (see [`locate`]).
pub fn is_case(path: &Path) -> bool {
    path.is_dir() && locate(path).is_ok()
}

fn open(dir: &Path, name: &str) -> Result<FoamFile> {
    match file::find(dir, name) {
        Some(p) => FoamFile::open(&p),
        None => Err(Error::Io {
            file: dir.join(name).display().to_string(),
            error: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        }),
    }
}

/// Labels to `u32` indices below `limit` (`what` and the file name the first bad one).
fn indices(f: &FoamFile, v: &[i64], limit: u64, what: &str) -> Result<Vec<u32>> {
    v.iter()
        .enumerate()
        .map(|(i, &x)| {
            u32::try_from(x)
                .ok()
                .filter(|&x| u64::from(x) < limit)
                .ok_or_else(|| Error::Invalid {
                    what: format!("{}: {what} {i} is {x}, not in 0..{limit}", f.name),
                })
        })
        .collect()
}

/// The patches of a `boundary` file.
fn boundary(f: &mut FoamFile) -> Result<Vec<Patch>> {
    let n = f.count()?;
    f.expect(b'(')?;
    let mut out = Vec::with_capacity(n.min(1 << 16));
    for _ in 0..n {
        let name = f.word_or("file ends inside the patch list")?;
        let name = String::from_utf8_lossy(name).into_owned();
        f.expect(b'{')?;
        let (mut kind, mut start, mut count) = (None, None, None);
        loop {
            f.skip_blank();
            if f.bytes.get(f.pos) == Some(&b'}') {
                f.pos += 1;
                break;
            }
            let key = f
                .word_or(&format!("file ends inside patch {name}"))?
                .to_vec();
            match &key[..] {
                b"type" => {
                    let w = f.word_or("expected a patch type")?;
                    kind = Some(String::from_utf8_lossy(w).into_owned());
                    f.expect(b';')?;
                }
                b"nFaces" | b"startFace" => {
                    let v = f.ascii_label("a patch entry")?;
                    let v = usize::try_from(v).map_err(|_| {
                        f.err(format!(
                            "patch {name}: negative {}",
                            String::from_utf8_lossy(&key)
                        ))
                    })?;
                    if key == b"nFaces" {
                        count = Some(v);
                    } else {
                        start = Some(v);
                    }
                    f.expect(b';')?;
                }
                _ => f.skip_value()?,
            }
        }
        let (Some(kind), Some(start_face), Some(n_faces)) = (kind, start, count) else {
            return Err(f.err(format!(
                "patch {name} lacks one of type, nFaces and startFace"
            )));
        };
        out.push(Patch {
            name,
            kind,
            start_face,
            n_faces,
        });
    }
    f.expect(b')')?;
    Ok(out)
}

/// The polyMesh files as OpenFOAM holds them, checked (labels in range, one owner per face,
/// patches contiguous): what [`read()`] builds a grid from, and what the readers of
/// OpenFOAM's fields need (the patches' faces in their order).
#[derive(Debug, Clone)]
pub struct PolyMesh {
    /// The case directory, when the polyMesh is its `constant/polyMesh`.
    pub case: Option<PathBuf>,
    /// The polyMesh directory.
    pub dir: PathBuf,
    /// The points.
    pub points: Vec<[f64; 3]>,
    /// Face `f` is `face_points[face_offsets[f]..face_offsets[f + 1]]`.
    pub face_offsets: Vec<usize>,
    /// The faces' points.
    pub face_points: Vec<u32>,
    /// The owner cell of each face.
    pub owner: Vec<u32>,
    /// The neighbour cell of each internal face.
    pub neighbour: Vec<u32>,
    /// The patches.
    pub patches: Vec<Patch>,
    points_file: (String, Layout, Vec<u8>, Vec<u8>),
    faces_file: String,
}

impl PolyMesh {
    /// The points of face `f`.
    pub fn face(&self, f: usize) -> &[u32] {
        &self.face_points[self.face_offsets[f]..self.face_offsets[f + 1]]
    }

    /// The patch called `name`.
    pub fn patch(&self, name: &str) -> Option<&Patch> {
        self.patches.iter().find(|p| p.name == name)
    }
}

/// Reads the polyMesh of the case or polyMesh directory `path`.
pub fn read_poly_mesh(path: &Path) -> Result<PolyMesh> {
    let (case, dir) = locate(path)?;
    let points_name = file::find(&dir, "points")
        .and_then(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "points".into());
    let mut pf = open(&dir, "points")?;
    pf.skip_blank();
    let head_end = pf.pos;
    let coords = pf.vectors("points")?;
    let points_tail = pf.bytes[pf.pos..].to_vec();
    let points_head = pf.bytes[..head_end].to_vec();
    let n_points = coords.len() as u64;

    let mut ff = open(&dir, "faces")?;
    let (off, labels) = ff.faces()?;
    let pts = indices(&ff, &labels, n_points, "face point")?;
    if let Some(f) = (0..off.len() - 1).find(|&f| off[f + 1] - off[f] < 3) {
        return Err(Error::Invalid {
            what: format!("{}: face {f} has {} points", ff.name, off[f + 1] - off[f]),
        });
    }
    let n_faces = off.len() - 1;
    let mut of = open(&dir, "owner")?;
    let owner = of.labels("owner")?;
    if owner.len() != n_faces {
        return Err(Error::Invalid {
            what: format!("{}: {} owners for {n_faces} faces", of.name, owner.len()),
        });
    }
    let mut nf = open(&dir, "neighbour")?;
    let neighbour = nf.labels("neighbour")?;
    if neighbour.len() > n_faces {
        return Err(Error::Invalid {
            what: format!(
                "{}: {} neighbours for {n_faces} faces",
                nf.name,
                neighbour.len()
            ),
        });
    }
    let owner = indices(&of, &owner, u64::from(u32::MAX), "owner of face")?;
    let neighbour = indices(&nf, &neighbour, u64::from(u32::MAX), "neighbour of face")?;
    let mut bf = open(&dir, "boundary")?;
    let patches = boundary(&mut bf)?;
    let n_internal = neighbour.len();
    let mut next = n_internal;
    for p in &patches {
        if p.start_face != next || p.start_face + p.n_faces > n_faces {
            return Err(Error::Invalid {
                what: format!(
                    "{}: patch {} has faces {}..{}, expected to start at face {next} (of {n_faces})",
                    bf.name,
                    p.name,
                    p.start_face,
                    p.start_face + p.n_faces
                ),
            });
        }
        next += p.n_faces;
    }
    if next != n_faces {
        return Err(Error::Invalid {
            what: format!(
                "{}: the patches end at face {next}, the grid has {n_faces} faces",
                bf.name
            ),
        });
    }

    Ok(PolyMesh {
        case,
        dir,
        points: coords,
        face_offsets: off,
        face_points: pts,
        owner,
        neighbour,
        patches,
        points_file: (points_name, pf.layout, points_head, points_tail),
        faces_file: ff.name,
    })
}

/// Reads the OpenFOAM case or polyMesh directory `path` (see the module doc).
pub fn read(path: &Path) -> Result<Mesh> {
    let pm = read_poly_mesh(path)?;
    let faces = cells::Faces {
        off: &pm.face_offsets,
        pts: &pm.face_points,
    };
    let (owner, neighbour) = (&pm.owner, &pm.neighbour);
    let n_cells = owner.iter().chain(neighbour).max().map_or(0, |&c| c + 1) as usize;
    let n_faces = faces.len();
    let n_internal = neighbour.len();
    let (cells, cell_of_element) = cells::cells(&pm.faces_file, &faces, owner, neighbour, n_cells)?;
    let mut mesh = Mesh::new(3);
    let PolyMesh {
        case,
        dir,
        points,
        patches,
        points_file: (points_name, points_layout, points_head, points_tail),
        faces_file,
        ..
    } = pm;
    mesh.coords = points;
    mesh.cells = cells;
    for p in &patches {
        if p.n_faces == 0 {
            mesh.warnings.push(format!(
                "patch {} ({}) has no faces: no marker made",
                p.name, p.kind
            ));
            continue;
        }
        let mut el = Elements::new();
        for f in p.start_face..p.start_face + p.n_faces {
            let kind = match faces.face(f).len() {
                3 => ElementKind::Triangle,
                4 => ElementKind::Quad,
                k => {
                    return Err(Error::Invalid {
                        what: format!(
                            "{}: face {f} of patch {} has {k} points (boundary faces must be triangles or quadrilaterals)",
                            faces_file, p.name
                        ),
                    });
                }
            };
            el.push(kind, faces.face(f), None);
        }
        mesh.markers.push(Marker {
            name: p.name.clone(),
            tag: None,
            elements: el,
        });
    }
    mesh.foam = Some(Box::new(Source {
        case,
        poly_mesh: dir,
        points_name,
        points_layout,
        points_head,
        points_tail,
        patches,
        n_points: mesh.coords.len(),
        n_faces,
        n_internal,
        cell_of_element,
    }));
    mesh.validate()?;
    Ok(mesh)
}
