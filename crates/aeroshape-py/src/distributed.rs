//! `deform_distributed(...)` (cargo feature `mpi`): the distributed deformation
//! (`deform::distributed::Deformer`) on the processes of an mpi4py communicator; the Python
//! half is `aeroshape.distributed.deform(comm, ...)`, which passes the communicator as the
//! `MPI_COMM_WORLD` ranks of its processes (docs/python.md, "MPI").
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

use crate::arrays;
use crate::deformation::{Motion, request};
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

/// How the deformation ended on this rank (inside the GIL-free part).
enum Outcome {
    /// Deformed: the result, the whole grid on rank 0, the local nodes' global ids.
    Done {
        out: Box<distributed::DistDeformed>,
        whole: Option<Vec<[f64; 3]>>,
        ids: Vec<u64>,
        n_owned: usize,
    },
    /// A rank refused its arguments (`same_way`: the ranks agreed on the way in).
    Refused { same_way: bool },
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

/// Runs the distributed deformation on the communicator of `world_ranks` (see the module
/// doc); called by `aeroshape.distributed.deform`, which documents the keywords.
#[pyfunction]
#[pyo3(signature = (
    world_ranks, rank, mesh, global_ids=None, n_owned=None, *, rigid=Vec::new(),
    rotate_deg=0.0, axis_point=[0.0, 0.0, 0.0], axis_dir=[0.0, 0.0, 1.0],
    translate=[0.0, 0.0, 0.0], displacements=None, slide=Vec::new(), fixed=Vec::new(),
    solver="pcg", stiffness="inverse-length2", no_rotation=false, tolerance=1e-8,
    allow_inverted=false, partition="metis", coarse_parts=distributed::COARSE_PARTS
))]
pub fn deform_distributed(
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
    tolerance: f64,
    allow_inverted: bool,
    partition: &str,
    coarse_parts: usize,
) -> PyResult<PyDistributedDeformation> {
    let root = rank == 0;
    let given = global_ids.is_some();
    // Every rank reads its own arguments; the ranks agree on the outcome before any exchange.
    let read = (|| -> PyResult<(Input, ::deform::DeformOptions, Partitioner)> {
        let by: Partitioner = partition
            .parse()
            .map_err(|e| PyValueError::new_err(format!("partition: {e}")))?;
        let motion = Motion {
            rigid,
            rotate_deg,
            axis_point,
            axis_dir,
            translate,
        };
        let keywords = |n_nodes: usize, motion: Motion| {
            request(
                n_nodes,
                motion,
                displacements.as_ref(),
                slide.clone(),
                fixed.clone(),
                [solver, stiffness],
                no_rotation,
                tolerance,
                allow_inverted,
            )
        };
        if let Some(ids) = &global_ids {
            let m = mesh
                .as_ref()
                .and_then(|m| m.cast::<PyMesh>().ok())
                .ok_or_else(|| PyValueError::new_err("mesh: a given part is a Mesh on every rank"))?
                .borrow()
                .inner
                .clone();
            let ids = arrays::read_ids(ids, "global_ids")?;
            let n_owned = n_owned.ok_or_else(|| {
                PyValueError::new_err("n_owned: a given part needs its number of owned nodes")
            })?;
            let req = keywords(m.n_nodes(), motion)?;
            let bc = req.boundary_conditions(&m, None);
            let grid = LocalGrid {
                mesh: m,
                global_ids: ids,
                n_owned,
            };
            Ok((Input::Given(grid, bc), req.options(), by))
        } else if root {
            let m = whole_grid(mesh.as_ref().ok_or_else(|| {
                PyValueError::new_err("mesh: rank 0 needs the grid (a Mesh or a grid file)")
            })?)?;
            let mut req = keywords(m.n_nodes(), motion)?;
            // as `aeroshape deform`: a fixed marker's node never moves where it meets a
            // sliding one
            aeroshape::precedence::hold_fixed_nodes(&m, &mut req);
            let bc = req.boundary_conditions(&m, None);
            Ok((Input::Root(Some((m, bc))), req.options(), by))
        } else {
            // Displacements name nodes of rank 0's grid: only rank 0 checks them.
            let req = keywords(usize::MAX, motion)?;
            Ok((Input::Root(None), req.options(), by))
        }
    })();
    let (input, refused) = match read {
        Ok(v) => (Some(v), None),
        Err(e) => (None, Some(e)),
    };
    // MPI runs without the GIL: the communicator is made, used and freed in here.
    let outcome = py.detach(move || -> Result<Outcome, String> {
        let comm = communicator(&world_ranks, rank)?;
        // The ranks agree on the way in (a part on every rank, or none), then on the
        // arguments.
        let same_way = all_ok(&comm, given) || all_ok(&comm, !given);
        let ok = all_ok(&comm, same_way && input.is_some());
        let Some((input, opts, by)) = input.filter(|_| ok) else {
            return Ok(Outcome::Refused { same_way });
        };
        let d = match &input {
            Input::Root(whole) => {
                Deformer::from_root_with(&comm, whole.as_ref().map(|(m, bc)| (m, bc)), &opts, by)
            }
            Input::Given(grid, bc) => Deformer::new(&comm, grid.clone(), bc, &opts),
        }
        .map_err(|e| errors::one_line(&e))?
        .coarse_parts(coarse_parts);
        let out = d.deform().map_err(|e| errors::one_line(&e))?;
        let whole = d.gather(&out.coords);
        Ok(Outcome::Done {
            ids: d.local_ids(),
            n_owned: d.partition().grid().n_owned,
            whole,
            out: Box::new(out),
        })
    });
    let (out, whole, ids, n_owned) = match outcome {
        Ok(Outcome::Done {
            out,
            whole,
            ids,
            n_owned,
        }) => (out, whole, ids, n_owned),
        Ok(Outcome::Refused { same_way }) => {
            return Err(match refused {
                Some(e) => e,
                None if !same_way => PyValueError::new_err(
                    "global_ids: given on some ranks and not on others (a given part needs \
                     them on every rank, the grid on rank 0 none)",
                ),
                None => errors::raise(py, Kind::Deform, "another rank refused its arguments"),
            });
        }
        Err(e) => return Err(errors::raise(py, Kind::Deform, e)),
    };
    Ok(PyDistributedDeformation {
        coordinates: whole.map(|x| arrays::coords(py, &x).into_any().unbind()),
        local_coordinates: arrays::coords(py, &out.coords).into_any().unbind(),
        global_ids: arrays::ids(py, &ids)?.into_any().unbind(),
        n_owned,
        report: arrays::to_python(py, &out.report)?.unbind(),
    })
}
