//! Fixture helper of `cargo xtask fixtures` for the default case's volume grid (not part of
//! the library): aeroshape makes the wall surface grid, Gmsh fills the far-field box with
//! tetrahedra keeping the wall nodes, and this program ties the result back to the geometry.
//!
//! ```text
//! chain_fixture surface GEOM.ron H OUT.txt NAME=K,K… [NAME=K…]
//!     surface grid of GEOM.ron at uniform size H (surfgrid::generate); OUT.txt lists, for
//!     the Gmsh script, the node coordinates (17 significant digits, exact round trip) and
//!     the triangles with their surface component; NAME=K,K groups components into markers.
//! chain_fixture attach GEOM.ron H VOLUME.msh OUT.msh
//!     regenerates the same surface grid, finds every wall node of VOLUME.msh (written by
//!     Gmsh) by exact coordinate match, re-attaches its classification (corner / curve + t /
//!     surface + (u, v)), numbers the wall nodes first (in surface-grid order) and writes
//!     MSH 4.1 (binary) with parametric nodes.
//! ```

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;
use std::process::ExitCode;

use geom_db::GeomDb;
use mesh::NodeClass;
use mesh::msh::Encoding;
use surfgrid::{GenerateOptions, SizeField, SurfaceGrid};

fn load(path: &str) -> Result<GeomDb, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    GeomDb::from_ron_str(&text, path).map_err(|e| e.to_string())
}

fn surface(db: &GeomDb, h: &str) -> Result<SurfaceGrid, String> {
    let h: f64 = h.parse().map_err(|e| format!("size {h:?}: {e}"))?;
    let field = SizeField::uniform(h).map_err(|e| e.to_string())?;
    surfgrid::generate(db, &field, &GenerateOptions::default()).map_err(|e| e.to_string())
}

fn write_surface(args: &[String]) -> Result<(), String> {
    let [geom, h, out, groups @ ..] = args else {
        return Err("usage: chain_fixture surface GEOM.ron H OUT.txt NAME=K,K…".into());
    };
    let db = load(geom)?;
    let grid = surface(&db, h)?;
    let mut marker_of = vec![None; db.surface_components.len()];
    let mut names = Vec::new();
    for g in groups {
        let (name, ks) = g
            .split_once('=')
            .ok_or_else(|| format!("group {g:?}: expected NAME=K,K…"))?;
        for k in ks.split(',') {
            let k: usize = k.parse().map_err(|e| format!("group {g:?}: {e}"))?;
            *marker_of
                .get_mut(k)
                .ok_or_else(|| format!("group {g:?}: no surface component {k}"))? =
                Some(names.len());
        }
        names.push(name.to_string());
    }
    let mut s = String::new();
    s.push_str(&format!("markers {}\n", names.len()));
    for n in &names {
        s.push_str(&format!("{n}\n"));
    }
    s.push_str(&format!("nodes {}\n", grid.n_nodes()));
    for p in &grid.coords {
        s.push_str(&format!("{:.17e} {:.17e} {:.17e}\n", p.x, p.y, p.z));
    }
    s.push_str(&format!("triangles {}\n", grid.n_triangles()));
    for c in &grid.components {
        let m = marker_of[c.comp.0 as usize]
            .ok_or_else(|| format!("surface component {} is in no group", c.comp.0))?;
        for t in c.global_triangles() {
            s.push_str(&format!("{} {} {} {} {}\n", t[0], t[1], t[2], c.comp.0, m));
        }
    }
    std::fs::write(out, s).map_err(|e| format!("{out}: {e}"))?;
    eprintln!(
        "surface grid: {} nodes, {} triangles → {out}",
        grid.n_nodes(),
        grid.n_triangles()
    );
    Ok(())
}

fn attach(args: &[String]) -> Result<(), String> {
    let [geom, h, vol, out] = args else {
        return Err("usage: chain_fixture attach GEOM.ron H VOLUME.msh OUT.msh".into());
    };
    let db = load(geom)?;
    let grid = surface(&db, h)?;
    let surf = grid.to_mesh(&db);
    let classes = surf
        .classes
        .as_ref()
        .ok_or("surface grid without classes")?;
    let key = |p: &[f64; 3]| p.map(f64::to_bits);
    let wall: HashMap<[u64; 3], usize> = surf
        .coords
        .iter()
        .enumerate()
        .map(|(i, p)| (key(p), i))
        .collect();
    let mut m = mesh::io::read_path(Path::new(vol)).map_err(|e| e.to_string())?;
    let n = m.n_nodes();
    let nw = grid.n_nodes();
    // wall nodes first, in surface-grid order; the others after, in Gmsh's order
    let mut perm = vec![u32::MAX; n];
    let mut found = 0usize;
    let mut seen = vec![false; nw];
    for (i, p) in m.coords.iter().enumerate() {
        if let Some(&w) = wall.get(&key(p)) {
            if seen[w] {
                return Err(format!("{vol}: node {i} duplicates wall node {w}"));
            }
            seen[w] = true;
            perm[i] = w as u32;
            found += 1;
        }
    }
    if found != nw {
        return Err(format!(
            "{vol}: {found} of the {nw} wall nodes found by exact coordinates"
        ));
    }
    for (k, p) in perm.iter_mut().filter(|p| **p == u32::MAX).enumerate() {
        *p = (nw + k) as u32;
    }
    // classification of the other nodes: by the marker entity they first appear on, else
    // the volume
    let mut cls: Vec<NodeClass> = vec![
        NodeClass {
            dim: 3,
            entity: 1,
            param: [0.0, 0.0],
        };
        n
    ];
    for mk in &m.markers {
        for g in mk.elements.groups() {
            for (e, el) in g.iter().enumerate() {
                for &v in el {
                    if cls[v as usize].dim == 3 {
                        cls[v as usize] = NodeClass {
                            dim: 2,
                            entity: g.entity.get(e).copied().unwrap_or(0),
                            param: [0.0, 0.0],
                        };
                    }
                }
            }
        }
    }
    for (i, p) in perm.iter().enumerate() {
        if (*p as usize) < nw {
            cls[i] = classes[*p as usize];
        }
    }
    m.classes = Some(cls);
    m.parametric = true;
    m.renumber_nodes(&perm).map_err(|e| e.to_string())?;
    for (i, p) in m.coords.iter().take(nw).enumerate() {
        if *p != surf.coords[i] {
            return Err(format!("node {i}: renumbering lost the wall order"));
        }
    }
    m.validate().map_err(|e| e.to_string())?;
    let mut buf = Vec::new();
    mesh::msh::write(&m, Encoding::Binary, &mut buf).map_err(|e| e.to_string())?;
    let back = mesh::msh::read(&buf[..], Path::new(out)).map_err(|e| e.to_string())?;
    if back.coords != m.coords || back.classes != m.classes {
        return Err(format!("{out}: MSH round trip changed the grid"));
    }
    let mut f = std::fs::File::create(out).map_err(|e| format!("{out}: {e}"))?;
    f.write_all(&buf).map_err(|e| format!("{out}: {e}"))?;
    eprintln!(
        "volume grid: {} nodes ({} on the wall), {} cells, markers {:?} → {out} ({} bytes)",
        n,
        nw,
        m.cells.len(),
        m.markers
            .iter()
            .map(|k| k.name.as_str())
            .collect::<Vec<_>>(),
        buf.len()
    );
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let r = match args.first().map(String::as_str) {
        Some("surface") => write_surface(&args[1..]),
        Some("attach") => attach(&args[1..]),
        _ => Err("usage: chain_fixture surface|attach …".into()),
    };
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}
