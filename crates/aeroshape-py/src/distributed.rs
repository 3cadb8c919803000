//! `DistributedDeformer` (cargo feature `mpi`): the distributed deformation
//! (`deform::distributed::Deformer`) on the processes of an mpi4py communicator, set up once
//! and deformed as often as asked; the Python half is `aeroshape.distributed.Deformer(comm,
//! ...)` and `aeroshape.distributed.deform(comm, ...)` (one set-up, one deformation), which
//! pass the communicator as the `MPI_COMM_WORLD` ranks of its processes (docs/python.md,
//! "MPI").
//!
//! The communicator is rebuilt here from those ranks, with safe rsmpi calls only: the group of
//! the world ranks, then `MPI_Comm_create_group` (collective over the communicator's processes
//! alone). It is a new communicator over the same processes in the same order (as
//! `MPI_Comm_dup` gives), so the deformation's messages never meet the caller's. The MPI
//! library is the one mpi4py initialised: this module never initialises or finalises MPI.
//!
//! Two ways in, as the library's:
//! - the whole grid on rank 0 (`mesh` a `Mesh` or a grid file read there, `None` elsewhere):
//!   partitioned there (METIS, or bisection) and scattered; the serial boundary conditions;
//! - each rank's part given (`mesh` its local grid, owned nodes first, with `global_ids` and
//!   `n_owned`), as a CFD solver holds it: rigid and fixed markers, local displacements.
//!
//! Every argument error and every failure is raised on every rank (the ranks agree before
//! any exchange that could block), so no rank is left waiting.

use std::path::PathBuf;

use ::deform::distributed::{self, Comm, Deformer, LocalGrid, Partitioner, all_ok, mpi};
use mpi::topology::{Communicator, Group, SimpleCommunicator};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use self_cell::self_cell;

use crate::arrays;
use crate::deformation::{Motion, Rotation, request};
use crate::errors::{self, Kind};
use crate::grid::PyMesh;

/// The result of `aeroshape.distributed.deform` on one rank.
#[pyclass(frozen, module = "aeroshape._native", name = "DistributedDeformation")]
pub struct PyDistributedDeformation {
    /// The whole grid's new coordinates in global-id order (`N × 3`) on rank 0 of the
    /// communicator; `None` on the others.
    #[pyo3(get)]
    coordinates: Option<Py<PyAny>>,
    /// This rank's nodes (owned first, then ghosts) at their new positions (`n × 3`).
    #[pyo3(get)]
    local_coordinates: Py<PyAny>,
    /// Global id of every local node (`n`, int64).
    #[pyo3(get)]
    global_ids: Py<PyAny>,
    /// Number of owned nodes (the first rows of `local_coordinates`).
    #[pyo3(get)]
    n_owned: usize,
    /// The distributed report (the `distributed` object of `aeroshape deform --report`
    /// under mpirun; the same on every rank).
    #[pyo3(get)]
    report: Py<PyAny>,
}

#[pymethods]
impl PyDistributedDeformation {
    fn __repr__(&self, py: Python<'_>) -> String {
        let it = |k: &str| {
            self.report
                .bind(py)
                .get_item(k)
                .map(|v| v.to_string())
                .unwrap_or_default()
        };
        format!(
            "DistributedDeformation({} ranks, {} owned nodes here, {} + {} iterations)",
            it("ranks"),
            self.n_owned,
            it("iterations"),
            it("rotation_iterations")
        )
    }
}

/// The communicator over the world ranks `world_ranks`, in their order; `rank` is this
/// process's rank in the caller's communicator (checked against the one made).
fn communicator(world_ranks: &[i32], rank: i32) -> Result<Comm, String> {
    if !mpi::environment::is_initialized() || mpi::environment::is_finalized() {
        return Err(
            "MPI is not initialised in the MPI library aeroshape was built with: mpi4py must \
             use the same library (Open MPI; docs/python.md, \"MPI\")"
                .into(),
        );
    }
    let world = SimpleCommunicator::world();
    let n = world.size();
    let mut seen = vec![false; n as usize];
    for &r in world_ranks {
        if r < 0 || r >= n || std::mem::replace(&mut seen[r as usize], true) {
            return Err(format!(
                "world rank {r} of the communicator: out of 0..{n} or given twice"
            ));
        }
    }
    let group = world.group().include(world_ranks);
    let comm = world
        .split_by_subgroup(&group)
        .ok_or("this process is not in the communicator")?;
    if comm.rank() != rank || comm.size() as usize != world_ranks.len() {
        return Err(format!(
            "the communicator made from the world ranks has rank {} of {}, mpi4py's {rank} of {}",
            comm.rank(),
            comm.size(),
            world_ranks.len()
        ));
    }
    Ok(comm)
}

/// What a rank brings to the deformation once its arguments are read.
enum Input {
    /// The whole grid and its boundary conditions (rank 0), or nothing (the others).
    Root(Option<(mesh::Mesh, ::deform::BoundaryConditions)>),
    /// This rank's part and its boundary conditions.
    Given(LocalGrid, ::deform::BoundaryConditions),
}

/// The grid argument on rank 0: a `Mesh`, or a grid file read here.
fn whole_grid(obj: &Bound<'_, PyAny>) -> PyResult<mesh::Mesh> {
    if let Ok(m) = obj.cast::<PyMesh>() {
        return Ok(m.borrow().inner.clone());
    }
    let path: PathBuf = obj.extract().map_err(|_| {
        PyValueError::new_err("mesh: expected a Mesh or the path of a grid file on rank 0")
    })?;
    mesh::io::read_path(&path)
        .map_err(|e| errors::raise(obj.py(), Kind::Mesh, errors::one_line(&e)))
}

/// The keywords of `aeroshape.distributed.deform` and `Deformer` but the communicator and
/// the grid.
struct Keywords<'py> {
    motion: Motion,
    displacements: Option<Bound<'py, PyAny>>,
    slide: Vec<String>,
    fixed: Vec<String>,
    solver: String,
    stiffness: String,
    rotation: Rotation,
    tolerance: f64,
    allow_inverted: bool,
    partition: String,
}

/// What a rank's arguments give: its way in, the options, the partitioner and, for the
/// kept deformer, the set-up's prescribed nodes and displacements with the number of them
/// the caller gave (rank 0's whole-grid list on a made partition, a rank's own on a given
/// one; the held nodes of `hold_fixed_nodes` after the caller's).
struct Read {
    input: Input,
    opts: ::deform::DeformOptions,
    by: Partitioner,
    prescribed: Vec<(u32, [f64; 3])>,
    given: usize,
    n_nodes: usize,
}

/// Reads this rank's arguments (see [`PyDistributedDeformer::new`]).
fn read(
    root: bool,
    mesh: Option<&Bound<'_, PyAny>>,
    global_ids: Option<&Bound<'_, PyAny>>,
    n_owned: Option<usize>,
    k: Keywords<'_>,
) -> PyResult<Read> {
    let by: Partitioner = k
        .partition
        .parse()
        .map_err(|e| PyValueError::new_err(format!("partition: {e}")))?;
    let keywords = |n_nodes: usize| {
        request(
            n_nodes,
            k.motion.clone(),
            k.displacements.as_ref(),
            k.slide.clone(),
            k.fixed.clone(),
            [&k.solver, &k.stiffness],
            k.rotation,
            k.tolerance,
            k.allow_inverted,
        )
    };
    if let Some(ids) = global_ids {
        let m = mesh
            .and_then(|m| m.cast::<PyMesh>().ok())
            .ok_or_else(|| PyValueError::new_err("mesh: a given part is a Mesh on every rank"))?
            .borrow()
            .inner
            .clone();
        let ids = arrays::read_ids(ids, "global_ids")?;
        let n_owned = n_owned.ok_or_else(|| {
            PyValueError::new_err("n_owned: a given part needs its number of owned nodes")
        })?;
        let req = keywords(m.n_nodes())?;
        let bc = req.boundary_conditions(&m, None);
        let (given, n_nodes) = (bc.displacements.len(), m.n_nodes());
        let grid = LocalGrid {
            mesh: m,
            global_ids: ids,
            n_owned,
        };
        Ok(Read {
            prescribed: bc.displacements.clone(),
            input: Input::Given(grid, bc),
            opts: req.options(),
            by,
            given,
            n_nodes,
        })
    } else if root {
        let m = whole_grid(mesh.ok_or_else(|| {
            PyValueError::new_err("mesh: rank 0 needs the grid (a Mesh or a grid file)")
        })?)?;
        let mut req = keywords(m.n_nodes())?;
        let given = req.displacements.len();
        // as `aeroshape deform`: a fixed marker's node never moves where it meets a
        // sliding one
        aeroshape::precedence::hold_fixed_nodes(&m, &mut req);
        let bc = req.boundary_conditions(&m, None);
        Ok(Read {
            prescribed: bc.displacements.clone(),
            n_nodes: m.n_nodes(),
            input: Input::Root(Some((m, bc))),
            opts: req.options(),
            by,
            given,
        })
    } else {
        // Displacements name nodes of rank 0's grid: only rank 0 checks them.
        let req = keywords(usize::MAX)?;
        Ok(Read {
            input: Input::Root(None),
            opts: req.options(),
            by,
            prescribed: Vec::new(),
            given: 0,
            n_nodes: 0,
        })
    }
}

/// The set-up on `comm` of what the ranks read (collective).
fn set_up<'c>(comm: &'c Comm, read: &Read, coarse_parts: usize) -> Result<Deformer<'c>, String> {
    match &read.input {
        Input::Root(whole) => Deformer::from_root_with(
            comm,
            whole.as_ref().map(|(m, bc)| (m, bc)),
            &read.opts,
            read.by,
        ),
        Input::Given(grid, bc) => Deformer::new(comm, grid.clone(), bc, &read.opts),
    }
    .map(|d| d.coarse_parts(coarse_parts))
    .map_err(|e| errors::one_line(&e))
}

/// The error of a rank whose arguments some rank refused: its own, or why it refused none.
fn refusal(py: Python<'_>, own: Option<PyErr>, same_way: bool) -> PyErr {
    match own {
        Some(e) => e,
        None if !same_way => PyValueError::new_err(
            "global_ids: given on some ranks and not on others (a given part needs them on \
             every rank, the grid on rank 0 none)",
        ),
        None => errors::raise(py, Kind::Deform, "another rank refused its arguments"),
    }
}

/// The Python result of the deformation `out` of `d`, the whole grid gathered on rank 0
/// (collective).
fn result(
    py: Python<'_>,
    d: &Deformer<'_>,
    out: &distributed::DistDeformed,
) -> PyResult<PyDistributedDeformation> {
    let whole = d.gather(&out.coords);
    Ok(PyDistributedDeformation {
        coordinates: whole.map(|x| arrays::coords(py, &x).into_any().unbind()),
        local_coordinates: arrays::coords(py, &out.coords).into_any().unbind(),
        global_ids: arrays::ids(py, &d.local_ids())?.into_any().unbind(),
        n_owned: d.partition().grid().n_owned,
        report: arrays::to_python(py, &out.report)?.unbind(),
    })
}

self_cell!(
    /// A communicator and the deformation set up on it.
    struct Kept {
        owner: Comm,
        #[covariant]
        dependent: Deformer,
    }
);

/// A distributed deformation set up once and deformed for new displacements as often as
/// asked (`aeroshape.distributed.Deformer`): the partition, the nodes' roles, the unknowns,
/// their halos, the coarse space and the baseline grid's operator are kept
/// (`deform::distributed::Deformer::deform_with`).
///
/// It holds its communicator (made from the world ranks as for `deform`) and runs its MPI
/// calls with the GIL held (the communicator is tied to the thread that made it: the class
/// is `unsendable`). Dropped after MPI was finalised (an object alive at the interpreter's
/// exit, after mpi4py's own exit handler), it leaves the communicator unfreed rather than
/// call MPI then.
#[pyclass(unsendable, module = "aeroshape._native", name = "DistributedDeformer")]
pub struct PyDistributedDeformer {
    /// Always `Some` until dropped.
    kept: Option<Kept>,
    /// The set-up's prescribed nodes and displacements (see [`Read`]).
    prescribed: Vec<(u32, [f64; 3])>,
    /// How many of them the caller gave (the first ones).
    given: usize,
    /// Nodes of this rank's grid (rank 0's whole grid, or a given part; 0 elsewhere).
    n_nodes: usize,
    /// The grid came whole on rank 0 and this is not rank 0: displacements are ignored.
    ignored: bool,
    /// This rank's result of the last deformation, the warm start of the next.
    last: std::cell::RefCell<Option<distributed::DistDeformed>>,
}

impl Drop for PyDistributedDeformer {
    fn drop(&mut self) {
        if mpi::environment::is_finalized() {
            std::mem::forget(self.kept.take());
        }
    }
}

/// The list of the set-up's displacements with the caller's new ones in place, from
/// `obj` (the `displacements` argument): the same nodes as the caller gave the set-up.
fn new_values(d: &PyDistributedDeformer, obj: &Bound<'_, PyAny>) -> PyResult<Vec<[f64; 3]>> {
    let new = crate::deformation::displacements(obj, d.n_nodes)?;
    if new.len() != d.given {
        return Err(PyValueError::new_err(format!(
            "displacements: {} nodes, the set-up was given {} (the same nodes are needed)",
            new.len(),
            d.given
        )));
    }
    let at: std::collections::HashMap<u32, [f64; 3]> = new.into_iter().collect();
    d.prescribed
        .iter()
        .enumerate()
        .map(|(k, &(v, d0))| match at.get(&v) {
            Some(&x) => Ok(x),
            None if k >= d.given => Ok(d0),
            None => Err(PyValueError::new_err(format!(
                "displacements: node {v} of the set-up is not given (the same nodes are needed)"
            ))),
        })
        .collect()
}

#[pymethods]
impl PyDistributedDeformer {
    /// Sets up the distributed deformation on the communicator of `world_ranks` (collective);
    /// called by `aeroshape.distributed.Deformer` and `deform`, which document the keywords.
    #[new]
    #[pyo3(signature = (
        world_ranks, rank, mesh, global_ids=None, n_owned=None, *, rigid=Vec::new(),
        rotate_deg=0.0, axis_point=[0.0, 0.0, 0.0], axis_dir=[0.0, 0.0, 1.0],
        translate=[0.0, 0.0, 0.0], displacements=None, slide=Vec::new(), fixed=Vec::new(),
        solver="pcg", stiffness="inverse-length2", no_rotation=false, rotation_reach=None,
        tolerance=1e-8, allow_inverted=false, partition="metis",
        coarse_parts=distributed::COARSE_PARTS
    ))]
    fn new(
        py: Python<'_>,
        world_ranks: Vec<i32>,
        rank: i32,
        mesh: Option<Bound<'_, PyAny>>,
        global_ids: Option<Bound<'_, PyAny>>,
        n_owned: Option<usize>,
        rigid: Vec<String>,
        rotate_deg: f64,
        axis_point: [f64; 3],
        axis_dir: [f64; 3],
        translate: [f64; 3],
        displacements: Option<Bound<'_, PyAny>>,
        slide: Vec<String>,
        fixed: Vec<String>,
        solver: &str,
        stiffness: &str,
        no_rotation: bool,
        rotation_reach: Option<f64>,
        tolerance: f64,
        allow_inverted: bool,
        partition: &str,
        coarse_parts: usize,
    ) -> PyResult<Self> {
        let given = global_ids.is_some();
        let keywords = Keywords {
            motion: Motion {
                rigid,
                rotate_deg,
                axis_point,
                axis_dir,
                translate,
            },
            displacements,
            slide,
            fixed,
            solver: solver.into(),
            stiffness: stiffness.into(),
            rotation: Rotation {
                off: no_rotation,
                reach: rotation_reach,
            },
            tolerance,
            allow_inverted,
            partition: partition.into(),
        };
        let read = read(
            rank == 0,
            mesh.as_ref(),
            global_ids.as_ref(),
            n_owned,
            keywords,
        );
        let comm =
            communicator(&world_ranks, rank).map_err(|e| errors::raise(py, Kind::Deform, e))?;
        let same_way = all_ok(&comm, given) || all_ok(&comm, !given);
        if !all_ok(&comm, same_way && read.is_ok()) {
            return Err(refusal(py, read.err(), same_way));
        }
        let read = read?;
        let kept = Kept::try_new(comm, |c| set_up(c, &read, coarse_parts))
            .map_err(|e| errors::raise(py, Kind::Deform, e))?;
        Ok(Self {
            kept: Some(kept),
            ignored: !given && rank != 0,
            prescribed: read.prescribed,
            given: read.given,
            n_nodes: read.n_nodes,
            last: std::cell::RefCell::new(None),
        })
    }

    /// Deforms for new values of the set-up's displacements (`(nodes, d)` or
    /// `{node: (dx, dy, dz)}`, the same nodes as the set-up's; `None`: the set-up's own),
    /// with `warm_start` from the last deformation's solutions
    /// (`deform::distributed::Deformer::deform_from`); collective. See
    /// `aeroshape.distributed.Deformer.deform`.
    #[pyo3(signature = (displacements=None, warm_start=false))]
    fn deform(
        &self,
        py: Python<'_>,
        displacements: Option<Bound<'_, PyAny>>,
        warm_start: bool,
    ) -> PyResult<PyDistributedDeformation> {
        let Some(kept) = &self.kept else {
            return Err(errors::raise(py, Kind::Deform, "the deformer was dropped"));
        };
        let values = match (&displacements, self.ignored) {
            (Some(obj), false) => new_values(self, obj).map(Some),
            _ => Ok(None),
        };
        let comm = kept.borrow_owner();
        if !all_ok(comm, values.is_ok()) {
            return Err(refusal(py, values.err(), true));
        }
        let values = values?;
        let d = kept.borrow_dependent();
        let mut last = self.last.borrow_mut();
        let out = d
            .deform_from(values.as_deref(), last.as_ref().filter(|_| warm_start))
            .map_err(|e| errors::raise(py, Kind::Deform, errors::one_line(&e)))?;
        let r = result(py, d, &out);
        *last = Some(out);
        r
    }

    fn __repr__(&self) -> String {
        match &self.kept {
            Some(k) => format!(
                "DistributedDeformer({} ranks, {} local nodes here, {} deformations)",
                k.borrow_owner().size(),
                k.borrow_dependent().partition().grid().mesh.n_nodes(),
                k.borrow_dependent().deformations()
            ),
            None => "DistributedDeformer(dropped)".into(),
        }
    }
}
