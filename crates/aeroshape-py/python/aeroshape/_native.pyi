"""Type stubs of aeroshape._native, the Rust extension module (crates/aeroshape-py/src)."""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Literal, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "__version__",
    "Constraints",
    "Deformation",
    "DesignVariable",
    "Evaluation",
    "Mesh",
    "SectionFit",
    "Study",
    "deform",
    "read_mesh",
    "section_build",
    "section_fit",
    "write_mesh",
    "write_section",
]

__version__: str

_StrPath = str | os.PathLike[str]
_Float64Array = npt.NDArray[np.float64]
_Int64Array = npt.NDArray[np.int64]
_ArrayLike = npt.ArrayLike
_Progress = Callable[[str, int, int], object]
"""``progress(phase, done, total)``: called as each phase starts."""

_ElementKind = Literal["line", "triangle", "quad", "tetra", "pyramid", "prism", "hexa"]
_Format = Literal["su2", "msh", "vtu", "baseline", "geometry", "report"]

@final
class DesignVariable:
    """One design variable of a study (physical units, as in the case file)."""

    @property
    def name(self) -> str:
        """Unique name."""
    @property
    def lower(self) -> float:
        """Lower bound."""
    @property
    def upper(self) -> float:
        """Upper bound."""
    @property
    def scale(self) -> float:
        """Scale for the optimiser: ``scaled = value / scale``."""
    @property
    def initial(self) -> float:
        """The value at which the study gives the baseline shape."""
    @property
    def group(self) -> str:
        """Group label of the case file (may be empty)."""
    @property
    def modifier(self) -> str:
        """The modifier the variable belongs to."""

@final
class Constraints:
    """The linear inequality constraints ``a @ x <= b`` of a study (x in physical units)."""

    @property
    def names(self) -> list[str]:
        """Constraint names (the rows of ``a``)."""
    @property
    def variables(self) -> list[str]:
        """Design-variable names (the columns of ``a``)."""
    @property
    def a(self) -> _Float64Array:
        """The matrix ``a``, constraints × design variables (a new array at each access)."""
    @property
    def b(self) -> _Float64Array:
        """The right-hand sides ``b`` (a new array at each access)."""
    def __len__(self) -> int: ...
    def violations(self, x: _ArrayLike) -> list[tuple[str, float, float]]:
        """The constraints violated at ``x`` beyond round-off, as ``(name, a·x, b)``."""

@final
class Study:
    """The chain of the paper's Figure 5 built once from a case file: geometry, grid,
    parametrisation, model-update seeds, wall classification, volume-deformation set-up.

    Raises :class:`aeroshape.CaseError` when the case file or a file it names is missing
    or bad, with the command line's message.
    """

    def __new__(cls, case_path: _StrPath) -> Study: ...
    @property
    def case_path(self) -> str:
        """The case file, as given."""
    @property
    def design_variables(self) -> list[DesignVariable]:
        """The design variables, in design-vector order."""
    @property
    def names(self) -> list[str]:
        """The design-variable names, in design-vector order."""
    @property
    def initial(self) -> _Float64Array:
        """The initial design vector (the baseline shape)."""
    @property
    def constraints(self) -> Constraints:
        """The linear inequality constraints ``a @ x <= b``."""
    @property
    def n_nodes(self) -> int:
        """Number of grid nodes."""
    @property
    def wall_nodes(self) -> _Int64Array:
        """Indices of the wall nodes, increasing: the rows of ``volume_coordinates`` that
        ``wall_coordinates`` holds."""
    @property
    def baseline_coordinates(self) -> _Float64Array:
        """The baseline grid's node coordinates, ``n_nodes × 3``."""
    @property
    def baseline(self) -> Mesh:
        """The baseline grid (a copy)."""
    @property
    def setup_report(self) -> dict[str, Any]:
        """Timings and sizes of the set-up (the ``setup`` object of ``report.json``)."""
    def vector(self, values: Mapping[str, float]) -> _Float64Array:
        """The design vector from named values; unnamed variables keep their initial value.
        Unknown names and values outside the bounds raise :class:`DesignVectorError`."""
    def read_design_vector(self, path: _StrPath) -> _Float64Array:
        """The design vector of a ``DV.ron`` file, as ``aeroshape run --dv`` reads it."""
    def evaluate(
        self,
        x: _ArrayLike,
        *,
        progress: _Progress | None = None,
        allow_infeasible: bool = False,
        allow_out_of_bounds: bool = False,
    ) -> Evaluation:
        """Runs the chain for the design vector ``x`` (physical units, design-vector order)
        with the GIL released.

        ``x`` is checked first, as ``aeroshape run`` checks a design vector: its length,
        finite values within the bounds (unless ``allow_out_of_bounds``), the linear
        constraints (unless ``allow_infeasible``; violations are then logged as warnings).
        Raises :class:`DesignVectorError` for a bad ``x`` and :class:`EvaluationError` when
        a phase fails. ``progress(phase, done, total)`` is called as each of the four
        phases (param, model update, surface grid, deform) starts; without it, progress goes
        to DEBUG records of the logger ``"aeroshape"``.
        """
    def failed_grid(
        self,
        x: _ArrayLike,
        *,
        max_cells: int = 20,
        allow_infeasible: bool = False,
        allow_out_of_bounds: bool = False,
    ) -> dict[str, Any]:
        """What a design that inverts cells did: ``count`` (cells inverted beyond the
        baseline's), ``cells`` (the ``max_cells`` worst: ``cell``, ``kind``, ``quality``
        [after, baseline], ``centroid``, ``nodes`` as [node, on the wall], ``moved_by``: the
        design variables' shares in the cell's distortion, largest first),
        ``volume_coordinates`` (the grid of the quality guard's last attempt) and
        ``cell_quality``. For the ``x`` that made :meth:`evaluate` raise
        :class:`EvaluationError` with inverted cells."""
    def forget_warm_start(self) -> None:
        """Makes the next evaluation start its solves from the baseline rather than from
        the previous solution."""
    def linearise(
        self,
        x: _ArrayLike,
        *,
        allow_infeasible: bool = False,
        allow_out_of_bounds: bool = False,
    ) -> Linearisation:
        """Evaluates the chain at ``x`` (checked as in :meth:`evaluate`; the deformation
        started cold) and linearises every phase there: exact ``jvp``/``vjp`` products at
        ``x``, as many as wanted, each for the price of the products alone."""
    def jvp(
        self,
        x: _ArrayLike,
        dx: _ArrayLike,
        *,
        wall: bool = False,
        allow_infeasible: bool = False,
        allow_out_of_bounds: bool = False,
    ) -> _Float64Array:
        """dX = J dx at ``x``: ``n_nodes × 3``, or the wall rows (``n_wall × 3``) with
        ``wall=True``. Linearises afresh: use :meth:`linearise` for several products."""
    def vjp(
        self,
        x: _ArrayLike,
        x_bar: _ArrayLike,
        *,
        wall: bool = False,
        allow_infeasible: bool = False,
        allow_out_of_bounds: bool = False,
    ) -> _Float64Array:
        """x̄ = Jᵀ X̄ at ``x``: one value per design variable, from the grid's cotangent
        ``x_bar`` (``n_nodes × 3``), or the wall rows' (``n_wall × 3``) with ``wall=True``.
        Linearises afresh: use :meth:`linearise` for several products."""
    def write(
        self,
        out_dir: _StrPath,
        evaluation: Evaluation,
        *,
        formats: Sequence[_Format] | None = None,
    ) -> list[str]:
        """Writes the files of ``aeroshape run --no-pictures`` for ``evaluation`` into
        ``out_dir`` (created if missing): "su2", "msh", "vtu" (``deformed.*``), "baseline"
        (``baseline.su2``), "geometry" (``geometry.ron``), "report" (``report.json``);
        default all. Each file is written to a temporary name and renamed; an output that
        would overwrite an input raises :class:`OutputError`. Returns the paths written."""

@final
class Evaluation:
    """The result of :meth:`Study.evaluate`; its arrays are its own (copies made at
    return)."""

    @property
    def study(self) -> Study:
        """The study evaluated."""
    @property
    def x(self) -> _Float64Array:
        """The design vector evaluated."""
    @property
    def volume_coordinates(self) -> _Float64Array:
        """Node coordinates of the deformed grid, ``n_nodes × 3``."""
    @property
    def wall_coordinates(self) -> _Float64Array:
        """Coordinates of the wall nodes (rows ``Study.wall_nodes`` of
        ``volume_coordinates``), ``n_wall × 3``."""
    @property
    def report(self) -> dict[str, Any]:
        """What the evaluation did (the ``evaluation`` object of ``report.json``)."""
    @property
    def cell_quality(self) -> _Float64Array:
        """Signed cell quality of the deformed grid, per cell."""
    @property
    def mesh(self) -> Mesh:
        """The deformed grid (a copy)."""
    def write(self, out_dir: _StrPath, *, formats: Sequence[_Format] | None = None) -> list[str]:
        """``Study.write(out_dir, self, formats=formats)``."""

@final
class Linearisation:
    """The chain linearised at one design vector (:meth:`Study.linearise`): the design
    variables → control nodes (param's exact Jacobian) → updated model (junctions by the
    implicit function theorem on Eqs. 12–13) → wall grid → volume grid (Eqs. 14–26)."""

    @property
    def x(self) -> _Float64Array:
        """The design vector linearised at."""
    @property
    def volume_coordinates(self) -> _Float64Array:
        """The volume grid's coordinates at ``x``, ``n_nodes × 3``."""
    def jvp(self, dx: _ArrayLike, *, wall: bool = False) -> _Float64Array:
        """dX = J dx for the design direction ``dx``: ``n_nodes × 3``, or the
        ``Study.wall_nodes`` rows (``n_wall × 3``, no volume solve) with ``wall=True``."""
    def vjp(self, x_bar: _ArrayLike | None = None, *,
            wall_bar: _ArrayLike | None = None) -> _Float64Array:
        """x̄ = Jᵀ X̄, one value per design variable, from the grid's cotangent ``x_bar``
        (``n_nodes × 3``, one adjoint deformation solve) and/or the wall rows' ``wall_bar``
        (``n_wall × 3``, no solve); both given: the sum."""

@final
class Mesh:
    """An unstructured grid: nodes, cells per element kind, boundary markers.

    The arrays a mesh hands out are read-only copies: assign ``mesh.coordinates = new`` to
    move the nodes. Element kinds: "line", "triangle", "quad", "tetra", "pyramid",
    "prism", "hexa" (meshio's "wedge" is "prism", "hexahedron" is "hexa"), with VTK's
    node orders. meshio lists a wedge in Gmsh's order: take its columns 0, 2, 1, 3, 5, 4.
    """

    def __new__(
        cls,
        coordinates: _ArrayLike,
        cells: Mapping[_ElementKind, _ArrayLike],
        markers: Mapping[str, Mapping[_ElementKind, _ArrayLike]] | None = None,
        dim: int = 3,
    ) -> Mesh:
        """A grid from arrays (node indices 0-based); validated, :class:`MeshError` if bad."""
    @property
    def dim(self) -> int:
        """Spatial dimension (2 or 3)."""
    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
    @property
    def n_cells(self) -> int:
        """Number of cells."""
    @property
    def coordinates(self) -> _Float64Array:
        """Node coordinates, ``n × 3`` float64 (read-only copy)."""
    @coordinates.setter
    def coordinates(self, value: _ArrayLike) -> None: ...
    @property
    def cells(self) -> dict[_ElementKind, _Int64Array]:
        """Cells by kind, ``m × k`` int64 node indices."""
    @property
    def markers(self) -> dict[str, dict[_ElementKind, _Int64Array]]:
        """Boundary markers by name, each ``{kind: m × k}``."""
    @property
    def node_classes(self) -> dict[str, npt.NDArray[Any]] | None:
        """Node classification of an MSH grid, or None: ``{"dim", "entity", "param"}``."""
    @property
    def parametric(self) -> bool:
        """True when curve and surface nodes carry parametric coordinates."""
    @property
    def warnings(self) -> list[str]:
        """Remarks of the reader."""
    def cell_quality(self) -> _Float64Array:
        """Signed cell quality (mean ratio of tetrahedra and triangles), per cell."""
    def copy(self) -> Mesh:
        """An independent copy."""

def read_mesh(path: _StrPath) -> Mesh:
    """Reads ``.su2``, ``.msh`` (Gmsh 4.1) or ``.vtu``, by extension; :class:`MeshError` if
    the file is bad (naming the file and line)."""

def write_mesh(path: _StrPath, mesh: Mesh, *, binary: bool = False, base64: bool = False) -> None:
    """Writes ``.su2``, ``.msh`` or ``.vtu`` by extension, as ``aeroshape mesh convert``
    (``binary``: binary MSH; ``base64``: inline base64 VTU); atomically."""

@final
class Deformation:
    """The result of :func:`deform`."""

    @property
    def mesh(self) -> Mesh:
        """The deformed grid (the input's cells, markers and numbering)."""
    @property
    def coordinates(self) -> _Float64Array:
        """Node coordinates of the deformed grid, ``n × 3``."""
    @property
    def cell_quality(self) -> _Float64Array:
        """Signed quality of every cell of the deformed grid."""
    @property
    def report(self) -> dict[str, Any]:
        """The solver's report (iterations, residual, increments, quality, seconds...)."""

def deform(
    mesh: Mesh,
    *,
    rigid: Sequence[str] = (),
    rotate_deg: float = 0.0,
    axis_point: Sequence[float] = (0.0, 0.0, 0.0),
    axis_dir: Sequence[float] = (0.0, 0.0, 1.0),
    translate: Sequence[float] = (0.0, 0.0, 0.0),
    displacements: tuple[_ArrayLike, _ArrayLike] | Mapping[int, Sequence[float]] | None = None,
    slide: Sequence[str] = (),
    geometry: _StrPath | None = None,
    fixed: Sequence[str] = (),
    solver: Literal["pcg", "jacobi", "pcg-jacobi"] = "pcg",
    stiffness: Literal["inverse-length", "inverse-length2", "volume", "wall-distance"] = "inverse-length2",
    no_rotation: bool = False,
    rotation_reach: float | None = None,
    tolerance: float = 1e-8,
    allow_inverted: bool = False,
    find_planes: bool = False,
    progress: _Progress | None = None,
) -> Deformation:
    """Deforms a volume grid from prescribed boundary motion, as ``aeroshape deform``: each
    keyword is the flag of that name (``--rotate-deg`` → ``rotate_deg``). ``rigid`` markers
    move by the rotation (degrees about ``axis_dir`` through ``axis_point``) then the
    translation; ``displacements`` prescribes nodes (``(nodes, d)`` or ``{node: d}``);
    ``slide`` markers slide on the supports of ``geometry`` when all their nodes are
    classified, else on their plane; ``fixed`` and unnamed markers stay, except, with
    ``find_planes``, an unnamed marker that is a plane touching the moving markers, which
    slides on it (an INFO record of the logger ``"aeroshape"`` says so). The GIL is released
    while it runs. Raises :class:`DeformError` when the deformation fails."""

# Present only when the package is built with its cargo feature ``mpi``
# (``aeroshape.distributed``).
@final
class DistributedDeformation:
    """The result of ``aeroshape.distributed.deform`` on one rank."""

    @property
    def coordinates(self) -> _Float64Array | None:
        """The whole grid's new coordinates in global-id order (rank 0; ``None`` elsewhere)."""
    @property
    def local_coordinates(self) -> _Float64Array:
        """This rank's nodes (owned first, then ghosts) at their new positions, ``n × 3``."""
    @property
    def global_ids(self) -> _Int64Array:
        """Global id of every local node."""
    @property
    def n_owned(self) -> int:
        """Number of owned nodes (the first rows of ``local_coordinates``)."""
    @property
    def report(self) -> dict[str, Any]:
        """The distributed report (ranks, ghost nodes, partitioner, iterations, bytes...)."""

@final
class DistributedDeformer:
    """The Rust half of ``aeroshape.distributed.Deformer``: one distributed set-up."""

    def __init__(
        self,
        world_ranks: Sequence[int],
        rank: int,
        mesh: Mesh | _StrPath | None,
        global_ids: _ArrayLike | None = None,
        n_owned: int | None = None,
        **keywords: Any,
    ) -> None: ...
    def deform(
        self, displacements: Any = None, warm_start: bool = False
    ) -> DistributedDeformation:
        """Deforms for new values of the set-up's displacements (collective)."""

@final
class SectionFit:
    """A fitted wing section (Eq. 39 thickness parameters, B-spline camber)."""

    @property
    def name(self) -> str:
        """The airfoil's name."""
    @property
    def thickness(self) -> dict[str, float]:
        """The ten thickness parameters: r0, z1, z2, xtmax, tmax, crv4, x6, z6, phi_te, d78."""
    @property
    def camber(self) -> _Float64Array:
        """Camber control points Q_j, ``m × 2``."""
    @property
    def thickness_extra(self) -> _Float64Array:
        """Extra thickness control points, ``k × 2``."""
    @property
    def te_thickness(self) -> float:
        """Trailing-edge thickness in chords."""
    @property
    def max_error(self) -> float:
        """Largest normal distance of the input points from the fit, in chords."""
    @property
    def rms_error(self) -> float:
        """RMS normal distance, in chords."""
    @property
    def iterations(self) -> int:
        """Iterations of the fit."""
    @property
    def n_design_variables(self) -> int:
        """Number of fitted parameters."""
    @property
    def points(self) -> _Float64Array:
        """The input points in the chord frame, ``n × 2``."""
    @property
    def distances(self) -> _Float64Array:
        """Signed normal distance of each input point from the fit, in chords."""
    @property
    def warnings(self) -> list[str]:
        """Remarks of the airfoil reader."""
    @property
    def fitted_name(self) -> str:
        """The name line ``aeroshape section fit --out`` writes."""
    def params(self) -> dict[str, Any]:
        """The section parameters (the PARAMS.ron fields), input of :func:`section_build`."""
    def as_dict(self) -> dict[str, Any]:
        """The object ``aeroshape section fit --json`` prints."""
    def coordinates(self, points: int = 120) -> _Float64Array:
        """The fitted section in the input's coordinates, ``(2·points + 1) × 2``."""

def section_fit(
    airfoil: _StrPath | _ArrayLike,
    *,
    camber_points: int = 8,
    thickness_extra: int = 0,
    name: str | None = None,
) -> SectionFit:
    """Fits the section parametrisation to a Selig or Lednicer file, or to an ``n × 2``
    array of points in Selig order, as ``aeroshape section fit``."""

def section_build(params: Mapping[str, Any] | SectionFit | _StrPath, *, points: int = 120) -> _Float64Array:
    """A section's ``(2·points + 1) × 2`` points in Selig order, normalised, from its
    parameters (dict, ``SectionFit`` or PARAMS.ron path), as ``aeroshape section build``."""

def write_section(path: _StrPath, coordinates: _ArrayLike, name: str = "aeroshape section") -> None:
    """Writes points in Selig format, atomically, as ``aeroshape section build`` does."""
