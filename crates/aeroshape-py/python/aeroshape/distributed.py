"""The distributed deformation on the processes of an mpi4py communicator.

Needs the package built with its cargo feature ``mpi`` (``MATURIN_PEP517_ARGS="--features
mpi" pip install ./crates/aeroshape-py``) and mpi4py on the same MPI library (Debian's Open
MPI). Run under ``mpirun -n N python script.py``; every process of ``comm`` calls
:func:`deform` together. See ``docs/python.md``, "MPI", and ``docs/mpi.md``.

The communicator is handed to the Rust side as the ``MPI.COMM_WORLD`` ranks of its processes
(``Group.Translate_ranks``), from which a communicator over the same processes in the same
order is made there with safe MPI calls (``MPI_Comm_create_group``): no handle crosses the
language boundary as a raw pointer, and the deformation's messages never meet the caller's.
"""

from __future__ import annotations

from typing import Any

from . import _native

__all__ = ["Deformer", "available", "deform"]


def available() -> bool:
    """True when the package was built with the cargo feature ``mpi``."""
    return hasattr(_native, "DistributedDeformer")


def deform(
    comm: Any,
    mesh: Any = None,
    *,
    global_ids: Any = None,
    n_owned: int | None = None,
    **keywords: Any,
) -> _native.DistributedDeformation:
    """Deforms a grid over the processes of ``comm`` (an ``mpi4py.MPI.Intracomm``); collective.

    Two ways in:

    - the whole grid on rank 0: ``mesh`` is a :class:`aeroshape.Mesh` or the path of a grid
      file (read on rank 0) on rank 0 and ``None`` elsewhere. Rank 0 classifies the nodes as
      the serial :func:`aeroshape.deform` does, partitions the grid (``partition="metis"``,
      the default, or ``"rcb"``) and sends each rank its part;
    - each rank's own part: ``mesh`` is the rank's local grid (an :class:`aeroshape.Mesh` of
      its owned nodes first, then its ghosts, the cells around its owned nodes and the
      boundary elements of its nodes under the markers' global names), ``global_ids`` the
      global id of every local node (0..N over the ranks, each owned by one rank) and
      ``n_owned`` the number of owned nodes. Markers may be ``rigid`` or ``fixed``;
      ``displacements`` are in local numbering.

    The keywords are those of :func:`aeroshape.deform` (``rigid``, ``rotate_deg``,
    ``axis_point``, ``axis_dir``, ``translate``, ``displacements``, ``slide``, ``fixed``,
    ``solver``, ``stiffness``, ``no_rotation``, ``rotation_reach``, ``tolerance``,
    ``allow_inverted``; not
    ``geometry`` or ``progress``), with ``partition`` and ``coarse_parts`` (aggregates per rank
    of the coarse-grid correction) of ``aeroshape deform`` under mpirun.

    Returns a ``DistributedDeformation``: ``coordinates`` (the whole grid's new coordinates in
    global-id order on rank 0, ``None`` elsewhere), ``local_coordinates``, ``global_ids`` and
    ``n_owned`` of this rank's nodes, and ``report`` (the same on every rank). Raises
    :class:`aeroshape.DeformError` (or ``ValueError`` for a bad argument) on every rank alike.
    """
    return Deformer(comm, mesh, global_ids=global_ids, n_owned=n_owned, **keywords).deform()


def _world_ranks(comm: Any) -> list[int]:
    """The ``MPI.COMM_WORLD`` ranks of the processes of ``comm``, in its order."""
    if not available():
        raise ImportError(
            "aeroshape was built without its cargo feature 'mpi': "
            'MATURIN_PEP517_ARGS="--features mpi" pip install ./crates/aeroshape-py'
        )
    from mpi4py import MPI

    size = comm.Get_size()
    world = MPI.COMM_WORLD.Get_group()
    group = comm.Get_group()
    try:
        ranks = MPI.Group.Translate_ranks(group, list(range(size)), world)
    finally:
        group.Free()
        world.Free()
    if any(r == MPI.UNDEFINED for r in ranks):
        raise ValueError("comm: a process of the communicator is not in MPI.COMM_WORLD")
    return list(ranks)


class Deformer:
    """One distributed set-up deformed for new displacements as often as asked: an
    optimiser's loop, whose wall moves anew at each design, pays for the partition once.

    ``Deformer(comm, mesh, global_ids=None, n_owned=None, **keywords)`` takes the arguments of
    :func:`deform` (collective) and sets the deformation up; :meth:`deform` then deforms it.
    The partition, the nodes' roles, the unknowns, their halos, the coarse space and the
    baseline grid's operator with its block multigrids are kept (the increments after the
    first, on the moved grid, build theirs). Each deformation starts from the baseline grid;
    its solves start from zero, or with ``warm_start=True`` from the last deformation's
    solutions.

    The deformer holds its own communicator over ``comm``'s processes and calls MPI with the
    GIL held, from the thread that made it. MPI stays the caller's: a deformer still alive
    when mpi4py finalises MPI at exit leaves its communicator unfreed rather than call MPI
    after that.
    """

    def __init__(
        self,
        comm: Any,
        mesh: Any = None,
        *,
        global_ids: Any = None,
        n_owned: int | None = None,
        **keywords: Any,
    ) -> None:
        self._native = _native.DistributedDeformer(
            _world_ranks(comm), comm.Get_rank(), mesh, global_ids, n_owned, **keywords
        )

    def deform(
        self, displacements: Any = None, *, warm_start: bool = False
    ) -> _native.DistributedDeformation:
        """Deforms for new values of the set-up's ``displacements`` (collective).

        ``displacements`` takes the forms of :func:`aeroshape.deform`'s (``(nodes, d)`` or
        ``{node: (dx, dy, dz)}``) and must name the same nodes as the set-up's (in any
        order); ``None``: the set-up's own. With the grid on rank 0, rank 0's are used and
        the other ranks' ignored; with given parts, each rank passes its own (local
        numbering) and the ghosts take their owners' values. The rigid markers move as set
        up. A bad argument raises ``ValueError`` on its rank and :class:`aeroshape.DeformError`
        ("another rank refused its arguments") on the others; a failed deformation raises
        :class:`aeroshape.DeformError` on every rank, and the deformer stays usable.

        ``warm_start=True`` starts the solves (the R field's, the spring system's, the
        sliding's) from the solutions of this deformer's last deformation, as the serial
        ``warm_start`` does: the answer agrees with the cold one to the solver tolerance, in
        fewer iterations when the designs are close (the same design again takes none).
        Pass the same value on every rank; the first deformation starts cold either way.

        Returns a ``DistributedDeformation``, as :func:`deform`; its ``report["deformations"]``
        counts the deformations on this set-up.
        """
        return self._native.deform(displacements, warm_start)

    def __repr__(self) -> str:
        return repr(self._native)
