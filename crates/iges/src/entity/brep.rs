//! B-rep entities: 186 manifold solid, 514 shell, 510 face, 508 loop, 504 edge list,
//! 502 vertex list.

use super::{Dec, Enc};
use crate::directory::DeId;
use crate::error::EntityProblem;

/// 186 manifold solid B-rep object: an outer shell and void shells.
#[derive(Debug, Clone, PartialEq)]
pub struct ManifoldSolid {
    /// SHELL: the outer 514 shell.
    pub shell: DeId,
    /// SOF: the shell's orientation agrees with the solid's.
    pub shell_agrees: bool,
    /// (VOID, VOF): void shells and their orientation flags.
    pub voids: Vec<(DeId, bool)>,
}

impl ManifoldSolid {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let shell = d.ptr("shell")?;
        let shell_agrees = d.flag("SOF")?;
        let n = d.count("N (number of void shells)", 2, 0)?;
        let mut voids = Vec::with_capacity(n);
        for _ in 0..n {
            voids.push((d.ptr("void shell")?, d.flag("VOF")?));
        }
        Ok(ManifoldSolid {
            shell,
            shell_agrees,
            voids,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.ptr(self.shell);
        e.flag(self.shell_agrees);
        e.len(self.voids.len());
        for &(v, f) in &self.voids {
            e.ptr(v);
            e.flag(f);
        }
    }
}

/// 514 shell: faces with orientation flags (form 1 closed, 2 open).
#[derive(Debug, Clone, PartialEq)]
pub struct Shell {
    /// (FACE, OF): 510 faces; the flag is true when the face's normal agrees with the
    /// shell's outward orientation.
    pub faces: Vec<(DeId, bool)>,
}

impl Shell {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let n = d.count("N (number of faces)", 2, 0)?;
        let mut faces = Vec::with_capacity(n);
        for _ in 0..n {
            faces.push((d.ptr("face")?, d.flag("OF")?));
        }
        Ok(Shell { faces })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.len(self.faces.len());
        for &(f, o) in &self.faces {
            e.ptr(f);
            e.flag(o);
        }
    }
}

/// 510 face: a surface bounded by 508 loops.
#[derive(Debug, Clone, PartialEq)]
pub struct Face {
    /// SURF: the underlying surface.
    pub surface: DeId,
    /// OF: the first loop is the outer one.
    pub outer_loop_first: bool,
    /// LOOP(1..N).
    pub loops: Vec<DeId>,
}

impl Face {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let surface = d.ptr("surface")?;
        let n = d.count("N (number of loops)", 1, 0)?;
        let outer_loop_first = d.flag("OF")?;
        let loops = (0..n).map(|_| d.ptr("loop")).collect::<Result<_, _>>()?;
        Ok(Face {
            surface,
            outer_loop_first,
            loops,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.ptr(self.surface);
        e.len(self.loops.len());
        e.flag(self.outer_loop_first);
        self.loops.iter().for_each(|&l| e.ptr(l));
    }
}

/// One edge use of a 508 loop.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopEdge {
    /// TYPE 1: the use is a vertex (a degenerate edge), TYPE 0: an edge.
    pub is_vertex: bool,
    /// E: the 504 edge list (or 502 vertex list).
    pub list: DeId,
    /// NDX: 1-based index into the list.
    pub index: usize,
    /// OF: the edge is used in the direction of its model curve.
    pub agrees: bool,
    /// (ISOP, CURV): parameter-space curves with their isoparametric flags.
    pub param_curves: Vec<(bool, DeId)>,
}

/// 508 loop: a closed chain of edge uses.
#[derive(Debug, Clone, PartialEq)]
pub struct Loop {
    /// The edge uses, in order.
    pub edges: Vec<LoopEdge>,
}

impl Loop {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let n = d.count("N (number of edge tuples)", 5, 0)?;
        let mut edges = Vec::with_capacity(n);
        for _ in 0..n {
            let is_vertex = d.flag("TYPE")?;
            let list = d.ptr("edge or vertex list")?;
            let index = d.count("NDX (list index)", 0, 1)?;
            let agrees = d.flag("OF")?;
            let k = d.count("K (number of parameter space curves)", 2, 0)?;
            let mut param_curves = Vec::with_capacity(k);
            for _ in 0..k {
                param_curves.push((d.flag("ISOP")?, d.ptr("parameter space curve")?));
            }
            edges.push(LoopEdge {
                is_vertex,
                list,
                index,
                agrees,
                param_curves,
            });
        }
        Ok(Loop { edges })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.len(self.edges.len());
        for x in &self.edges {
            e.flag(x.is_vertex);
            e.ptr(x.list);
            e.len(x.index);
            e.flag(x.agrees);
            e.len(x.param_curves.len());
            for &(iso, c) in &x.param_curves {
                e.flag(iso);
                e.ptr(c);
            }
        }
    }
}

/// One edge of a 504 edge list.
#[derive(Debug, Clone, PartialEq)]
pub struct Edge {
    /// CURV: the model-space curve.
    pub curve: DeId,
    /// SVP: vertex list of the start vertex.
    pub start_list: DeId,
    /// SV: 1-based index of the start vertex in its list.
    pub start_index: usize,
    /// TVP: vertex list of the terminate vertex.
    pub end_list: DeId,
    /// TV: 1-based index of the terminate vertex.
    pub end_index: usize,
}

/// 504 edge list.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeList {
    /// The edges.
    pub edges: Vec<Edge>,
}

impl EdgeList {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let n = d.count("N (number of edges)", 5, 0)?;
        let mut edges = Vec::with_capacity(n);
        for _ in 0..n {
            edges.push(Edge {
                curve: d.ptr("edge curve")?,
                start_list: d.ptr("start vertex list")?,
                start_index: d.count("SV (start vertex index)", 0, 1)?,
                end_list: d.ptr("terminate vertex list")?,
                end_index: d.count("TV (terminate vertex index)", 0, 1)?,
            });
        }
        Ok(EdgeList { edges })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.len(self.edges.len());
        for x in &self.edges {
            e.ptr(x.curve);
            e.ptr(x.start_list);
            e.len(x.start_index);
            e.ptr(x.end_list);
            e.len(x.end_index);
        }
    }
}

/// 502 vertex list.
#[derive(Debug, Clone, PartialEq)]
pub struct VertexList {
    /// The vertices.
    pub vertices: Vec<[f64; 3]>,
}

impl VertexList {
    pub(crate) fn decode(d: &mut Dec) -> Result<Self, EntityProblem> {
        let n = d.count("N (number of vertices)", 3, 0)?;
        let mut vertices = Vec::with_capacity(n);
        for _ in 0..n {
            vertices.push(d.reals("vertex")?);
        }
        Ok(VertexList { vertices })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.len(self.vertices.len());
        self.vertices.iter().for_each(|v| e.reals(v));
    }
}
