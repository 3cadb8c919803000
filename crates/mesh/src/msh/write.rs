//! Writing Gmsh MSH 4.1 (ASCII and binary): entities, physical groups, parametric nodes
//! and elements (see the module doc of `msh`).

use std::collections::BTreeMap;
use std::io::Write;

use super::Encoding;
use crate::grid::{ElementKind, Elements, Entity, Mesh, PhysicalName};
use crate::text::{push_f64, push_u64};

/// Output in either encoding; ASCII puts a space between tokens and ends lines on request.
struct Out<'w, W: Write + ?Sized> {
    w: &'w mut W,
    b: Vec<u8>,
    enc: Encoding,
    first: bool,
}

impl<W: Write + ?Sized> Out<'_, W> {
    fn sep(&mut self) {
        if !self.first {
            self.b.push(b' ');
        }
        self.first = false;
    }
    fn size(&mut self, v: u64) {
        match self.enc {
            Encoding::Ascii => {
                self.sep();
                push_u64(&mut self.b, v);
            }
            Encoding::Binary => self.b.extend_from_slice(&v.to_le_bytes()),
        }
    }
    fn int(&mut self, v: i32) {
        match self.enc {
            Encoding::Ascii => {
                self.sep();
                if v < 0 {
                    self.b.push(b'-');
                }
                push_u64(&mut self.b, u64::from(v.unsigned_abs()));
            }
            Encoding::Binary => self.b.extend_from_slice(&v.to_le_bytes()),
        }
    }
    fn float(&mut self, v: f64) {
        match self.enc {
            Encoding::Ascii => {
                self.sep();
                push_f64(&mut self.b, v);
            }
            Encoding::Binary => self.b.extend_from_slice(&v.to_le_bytes()),
        }
    }
    /// Ends a line (ASCII only).
    fn eol(&mut self) -> std::io::Result<()> {
        if self.enc == Encoding::Ascii {
            self.b.push(b'\n');
        }
        self.first = true;
        self.maybe_flush()
    }
    fn text(&mut self, s: &str) -> std::io::Result<()> {
        self.b.extend_from_slice(s.as_bytes());
        self.first = true;
        self.maybe_flush()
    }
    /// Ends a binary data block with the newline Gmsh puts before `$End...`.
    fn end(&mut self, name: &str) -> std::io::Result<()> {
        if self.enc == Encoding::Binary {
            self.b.push(b'\n');
        }
        self.text(&format!("$End{name}\n"))
    }
    fn maybe_flush(&mut self) -> std::io::Result<()> {
        if self.b.len() > 1 << 16 {
            self.w.write_all(&self.b)?;
            self.b.clear();
        }
        Ok(())
    }
}

/// The entities, physical names and per-element entity tags to write.
struct Layout {
    entities: Vec<Entity>,
    names: Vec<PhysicalName>,
    /// Synthesised layout: cell entity tag, and per marker its entity tag.
    synth: Option<(i32, Vec<i32>)>,
}

fn has_entity_tags(set: &Elements) -> bool {
    set.groups().iter().all(|g| g.entity.len() == g.len())
}

fn bbox_of(mesh: &Mesh, nodes: impl Iterator<Item = u32>) -> [f64; 6] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for v in nodes {
        let p = mesh.coords[v as usize];
        for k in 0..3 {
            b[k] = b[k].min(p[k]);
            b[k + 3] = b[k + 3].max(p[k]);
        }
    }
    if b[0] > b[3] {
        return [0.0; 6];
    }
    b
}

fn layout(mesh: &Mesh) -> Layout {
    let keep = !mesh.entities.is_empty()
        && has_entity_tags(&mesh.cells)
        && mesh.markers.iter().all(|m| has_entity_tags(&m.elements));
    if keep {
        let mut entities = mesh.entities.clone();
        add_class_entities(mesh, &mut entities);
        return Layout {
            entities,
            names: mesh.physical_names.clone(),
            synth: None,
        };
    }
    let d = mesh.dim;
    let m = mesh.markers.len() as i32;
    let mut entities = Vec::new();
    let mut names = Vec::new();
    let mut bnd_tags = Vec::new();
    for (i, mk) in mesh.markers.iter().enumerate() {
        let tag = i as i32 + 1;
        entities.push(Entity {
            dim: d - 1,
            tag,
            bbox: bbox_of(
                mesh,
                mk.elements
                    .groups()
                    .iter()
                    .flat_map(|g| g.nodes.iter().copied()),
            ),
            physical: vec![tag],
            bounding: Vec::new(),
        });
        names.push(PhysicalName {
            dim: d - 1,
            tag,
            name: mk.name.clone(),
        });
        bnd_tags.push(tag);
    }
    let (lo, hi) = mesh.bbox();
    entities.push(Entity {
        dim: d,
        tag: 1,
        bbox: [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]],
        physical: vec![m + 1],
        bounding: bnd_tags.clone(),
    });
    names.push(PhysicalName {
        dim: d,
        tag: m + 1,
        name: "domain".into(),
    });
    add_class_entities(mesh, &mut entities);
    Layout {
        entities,
        names,
        synth: Some((1, bnd_tags)),
    }
}

/// Adds an entity for every (dim, tag) of the node classification that has none, so that
/// every node block refers to a declared entity.
fn add_class_entities(mesh: &Mesh, entities: &mut Vec<Entity>) {
    let Some(classes) = &mesh.classes else { return };
    let mut known: std::collections::HashSet<(u8, i32)> =
        entities.iter().map(|e| (e.dim, e.tag)).collect();
    let mut extra: BTreeMap<(u8, i32), Vec<u32>> = BTreeMap::new();
    for (i, c) in classes.iter().enumerate() {
        if !known.contains(&(c.dim, c.entity)) {
            extra.entry((c.dim, c.entity)).or_default().push(i as u32);
        }
    }
    for ((dim, tag), nodes) in extra {
        known.insert((dim, tag));
        entities.push(Entity {
            dim,
            tag,
            bbox: bbox_of(mesh, nodes.into_iter()),
            physical: Vec::new(),
            bounding: Vec::new(),
        });
    }
}

/// Writes `mesh` as Gmsh MSH 4.1 in the given encoding. Coordinates are written in their
/// shortest round-trip form (ASCII) or as raw doubles (binary), so reading back gives the
/// same bits.
pub fn write<W: Write + ?Sized>(mesh: &Mesh, enc: Encoding, w: &mut W) -> std::io::Result<()> {
    let lay = layout(mesh);
    let mut o = Out {
        w,
        b: Vec::with_capacity(1 << 17),
        enc,
        first: true,
    };
    o.text("$MeshFormat\n")?;
    match enc {
        Encoding::Ascii => o.text("4.1 0 8\n")?,
        Encoding::Binary => {
            o.text("4.1 1 8\n")?;
            o.b.extend_from_slice(&1i32.to_le_bytes());
            o.text("\n")?;
        }
    }
    o.text("$EndMeshFormat\n")?;
    if !lay.names.is_empty() {
        o.text("$PhysicalNames\n")?;
        o.text(&format!("{}\n", lay.names.len()))?;
        for p in &lay.names {
            o.text(&format!(
                "{} {} \"{}\"\n",
                p.dim,
                p.tag,
                p.name.replace('"', "'")
            ))?;
        }
        o.text("$EndPhysicalNames\n")?;
    }
    // Entities.
    o.text("$Entities\n")?;
    let mut by_dim: [Vec<&Entity>; 4] = Default::default();
    for e in &lay.entities {
        by_dim[usize::from(e.dim.min(3))].push(e);
    }
    for v in &by_dim {
        o.size(v.len() as u64);
    }
    o.eol()?;
    for (d, v) in by_dim.iter().enumerate() {
        for e in v {
            o.int(e.tag);
            let nb = if d == 0 { 3 } else { 6 };
            for &x in &e.bbox[..nb] {
                o.float(x);
            }
            o.size(e.physical.len() as u64);
            for &p in &e.physical {
                o.int(p);
            }
            if d > 0 {
                o.size(e.bounding.len() as u64);
                for &b in &e.bounding {
                    o.int(b);
                }
            }
            o.eol()?;
        }
    }
    o.end("Entities")?;
    // Nodes: consecutive runs of nodes on the same entity form a block.
    let n = mesh.coords.len();
    let cell_entity = lay.synth.as_ref().map_or(1, |s| s.0);
    let class_of = |i: usize| -> (u8, i32) {
        match &mesh.classes {
            Some(c) => (c[i].dim, c[i].entity),
            None => (mesh.dim, cell_entity),
        }
    };
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut s = 0;
    for i in 1..=n {
        if i == n || class_of(i) != class_of(s) {
            runs.push((s, i));
            s = i;
        }
    }
    o.text("$Nodes\n")?;
    o.size(runs.len() as u64);
    o.size(n as u64);
    o.size(if n == 0 { 0 } else { 1 });
    o.size(n as u64);
    o.eol()?;
    for &(a, b) in &runs {
        let (d, t) = class_of(a);
        let param = mesh.parametric && mesh.classes.is_some() && (d == 1 || d == 2);
        o.int(i32::from(d));
        o.int(t);
        o.int(i32::from(param));
        o.size((b - a) as u64);
        o.eol()?;
        for i in a..b {
            o.size(i as u64 + 1);
            o.eol()?;
        }
        for i in a..b {
            for &x in &mesh.coords[i] {
                o.float(x);
            }
            if param {
                let c = mesh.classes.as_ref().map_or([0.0; 2], |c| c[i].param);
                for &u in &c[..usize::from(d)] {
                    o.float(u);
                }
            }
            o.eol()?;
        }
    }
    o.end("Nodes")?;
    // Elements: runs of the same entity within each kind group.
    struct Block<'a> {
        dim: u8,
        entity: i32,
        kind: ElementKind,
        nodes: &'a [u32],
    }
    let mut blocks: Vec<Block<'_>> = Vec::new();
    let runs_of = |set: &Elements, fixed: Option<i32>| -> Vec<(ElementKind, i32, usize, usize)> {
        let mut out = Vec::new();
        for g in set.groups() {
            let ent = |i: usize| fixed.unwrap_or_else(|| g.entity[i]);
            let len = g.len();
            let mut s = 0;
            for i in 1..=len {
                if i == len || ent(i) != ent(s) {
                    out.push((g.kind, ent(s), s, i));
                    s = i;
                }
            }
        }
        out
    };
    let cell_fixed = lay.synth.as_ref().map(|s| s.0);
    for (kind, e, a, b) in runs_of(&mesh.cells, cell_fixed) {
        let g = mesh.cells.group(kind).expect("group exists");
        let nn = kind.n_nodes();
        blocks.push(Block {
            dim: mesh.dim,
            entity: e,
            kind,
            nodes: &g.nodes[a * nn..b * nn],
        });
    }
    let mut written: std::collections::HashSet<(i32, ElementKind)> =
        std::collections::HashSet::new();
    for (mi, mk) in mesh.markers.iter().enumerate() {
        let fixed = lay.synth.as_ref().map(|s| s.1[mi]);
        let mut here: Vec<(i32, ElementKind)> = Vec::new();
        for (kind, e, a, b) in runs_of(&mk.elements, fixed) {
            if written.contains(&(e, kind)) {
                continue;
            }
            here.push((e, kind));
            let g = mk.elements.group(kind).expect("group exists");
            let nn = kind.n_nodes();
            blocks.push(Block {
                dim: mesh.dim - 1,
                entity: e,
                kind,
                nodes: &g.nodes[a * nn..b * nn],
            });
        }
        written.extend(here);
    }
    let n_el: usize = blocks
        .iter()
        .map(|b| b.nodes.len() / b.kind.n_nodes())
        .sum();
    o.text("$Elements\n")?;
    o.size(blocks.len() as u64);
    o.size(n_el as u64);
    o.size(if n_el == 0 { 0 } else { 1 });
    o.size(n_el as u64);
    o.eol()?;
    let mut tag = 1u64;
    for b in &blocks {
        let nn = b.kind.n_nodes();
        o.int(i32::from(b.dim));
        o.int(b.entity);
        o.int(b.kind.gmsh_code());
        o.size((b.nodes.len() / nn) as u64);
        o.eol()?;
        // This crate's local numbering to Gmsh's: Gmsh's node `order[i]` is our node `i`.
        let order = b.kind.gmsh_order();
        let mut gm = [0u32; 8];
        for el in b.nodes.chunks_exact(nn) {
            o.size(tag);
            tag += 1;
            for (i, &v) in el.iter().enumerate() {
                gm[order[i] as usize] = v;
            }
            for &v in &gm[..nn] {
                o.size(u64::from(v) + 1);
            }
            o.eol()?;
        }
    }
    o.end("Elements")?;
    o.w.write_all(&o.b)?;
    Ok(())
}
