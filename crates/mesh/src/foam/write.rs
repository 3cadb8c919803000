//! Writing a grid back as its OpenFOAM case: the case copied byte for byte, `points`
//! replaced (see the module doc of [`crate::foam`]).

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use super::Source;
use crate::error::{Error, Result};
use crate::grid::Mesh;
use crate::text::push_f64;

fn io_err(path: &Path, error: std::io::Error) -> Error {
    Error::Io {
        file: path.display().to_string(),
        error,
    }
}

/// A temporary name beside `path` (hidden, with the process id), for write-then-rename.
fn temp_beside(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.part", std::process::id()))
}

/// Writes `bytes` to `path` through a temporary name renamed into place.
fn put(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = temp_beside(path);
    let r = (|| {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if r.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    r.map_err(|e| io_err(path, e))
}

/// Copies `src` to `dst` byte for byte, through a temporary name.
fn copy(src: &Path, dst: &Path) -> Result<()> {
    let tmp = temp_beside(dst);
    let r = fs::copy(src, &tmp).and_then(|_| fs::rename(&tmp, dst));
    if r.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    r.map(|_| ()).map_err(|e| io_err(dst, e))
}

/// True for a case entry that is not copied: `processor*`, `postProcessing` and time
/// directories other than `0` (results of earlier runs).
fn skipped(name: &str, is_dir: bool) -> bool {
    if !is_dir {
        return false;
    }
    name.starts_with("processor")
        || name == "postProcessing"
        || name.parse::<f64>().is_ok_and(|t| t != 0.0)
}

/// Copies the tree `src` into `dst`, leaving out `skip` (canonical paths) and, at the top,
/// the entries [`skipped`] names.
fn copy_tree(src: &Path, dst: &Path, skip: &[PathBuf], top: bool) -> Result<()> {
    fs::create_dir_all(dst).map_err(|e| io_err(dst, e))?;
    let mut entries: Vec<_> = fs::read_dir(src)
        .map_err(|e| io_err(src, e))?
        .collect::<std::io::Result<_>>()
        .map_err(|e| io_err(src, e))?;
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        let p = e.path();
        let canon = p.canonicalize().map_err(|err| io_err(&p, err))?;
        if skip.contains(&canon) {
            continue;
        }
        let is_dir = canon.is_dir();
        let name = e.file_name().to_string_lossy().into_owned();
        if top && skipped(&name, is_dir) {
            continue;
        }
        let target = dst.join(&name);
        if is_dir {
            copy_tree(&p, &target, skip, false)?;
        } else {
            copy(&p, &target)?;
        }
    }
    Ok(())
}

/// The points file's bytes for `coords`, in the layout and with the header of `src`.
fn points_bytes(src: &Source, coords: &[[f64; 3]]) -> Vec<u8> {
    let lay = src.points_layout;
    let mut out = Vec::with_capacity(src.points_head.len() + coords.len() * 60 + 64);
    out.extend_from_slice(&src.points_head);
    out.extend_from_slice(format!("{}\n(", coords.len()).as_bytes());
    if lay.binary {
        for p in coords {
            for &x in p {
                match (lay.scalar_bytes, lay.msb) {
                    (4, false) => out.extend_from_slice(&(x as f32).to_le_bytes()),
                    (4, true) => out.extend_from_slice(&(x as f32).to_be_bytes()),
                    (_, false) => out.extend_from_slice(&x.to_le_bytes()),
                    (_, true) => out.extend_from_slice(&x.to_be_bytes()),
                }
            }
        }
    } else {
        out.push(b'\n');
        for p in coords {
            out.push(b'(');
            push_f64(&mut out, p[0]);
            out.push(b' ');
            push_f64(&mut out, p[1]);
            out.push(b' ');
            push_f64(&mut out, p[2]);
            out.extend_from_slice(b")\n");
        }
    }
    out.push(b')');
    out.extend_from_slice(&src.points_tail);
    out
}

/// Writes `mesh`, read from an OpenFOAM case by [`super::read`], back as a case at `out`
/// (a case directory, or a `…/constant/polyMesh` directory): see the module doc.
pub fn write(mesh: &Mesh, out: &Path) -> Result<()> {
    let Some(src) = mesh.foam.as_deref() else {
        return Err(Error::Invalid {
            what: format!(
                "{}: an OpenFOAM case is written back from a grid read from one; this grid came from another format (write .su2, .msh or .vtu)",
                out.display()
            ),
        });
    };
    let poly_given = out.ends_with(Path::new("constant").join("polyMesh"));
    let out_poly = if poly_given {
        out.to_path_buf()
    } else {
        out.join("constant").join("polyMesh")
    };
    let n_src = src.cell_of_element.len();
    if mesh.cells.len() != n_src || mesh.coords.len() != src.n_points {
        return Err(Error::Mismatch {
            what: format!(
                "{} nodes and {} cells, the OpenFOAM case {} has {} points and {n_src} cells",
                mesh.coords.len(),
                mesh.cells.len(),
                src.poly_mesh.display(),
                src.n_points
            ),
        });
    }
    fs::create_dir_all(&out_poly).map_err(|e| io_err(&out_poly, e))?;
    let canon = |p: &Path| p.canonicalize().map_err(|e| io_err(p, e));
    let out_poly_c = canon(&out_poly)?;
    let src_poly_c = canon(&src.poly_mesh)?;
    if out_poly_c == src_poly_c {
        return Err(Error::Invalid {
            what: format!(
                "{}: this is the polyMesh the grid was read from; inputs are never overwritten (write a new case)",
                out.display()
            ),
        });
    }
    {
        let out_c = canon(out)?;
        let mut skip = vec![out_c];
        for name in ["points", "points.gz"] {
            let p = src.poly_mesh.join(name);
            if p.exists() {
                skip.push(canon(&p)?);
            }
        }
        match (&src.case, poly_given) {
            (Some(case), false) => {
                let case_c = canon(case)?;
                // the source polyMesh lies in the case: copied with it
                copy_tree(&case_c, out, &skip, true)?;
            }
            _ => copy_tree(&src.poly_mesh, &out_poly, &skip, false)?,
        }
    }
    let bytes = points_bytes(src, &mesh.coords);
    let target = out_poly.join(&src.points_name);
    if src.points_name.ends_with(".gz") {
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        gz.write_all(&bytes).map_err(|e| io_err(&target, e))?;
        let z = gz.finish().map_err(|e| io_err(&target, e))?;
        put(&target, &z)
    } else {
        put(&target, &bytes)
    }
}
