"""aeroshape.openmdao: a :class:`aeroshape.Study` as an OpenMDAO component.

``Component(case=PATH)`` or ``Component(study=STUDY)``:

- inputs: the study's design variables, one scalar input per variable, by name (physical
  units), initialised at their initial values; :func:`add_design_vars` offers their bounds
  and scales to ``add_design_var``;
- outputs, in MPhys's naming and layout (flattened, C order: x, y, z of node 0, then node 1,
  ...):

  - ``x_aero0`` -- the wall-node coordinates, ``3 · n_wall`` values, tag
    ``mphys_coordinates`` (``MPhysVariables.Aerodynamics.Surface.COORDINATES_INITIAL``: the
    jig shape a geometry component hands to the aerodynamic solver);
  - ``aero_vol_coords`` -- the volume-grid coordinates, ``3 · n_nodes`` values, tag
    ``mphys_coupling`` (MPhys names no volume variable; this is DAFoam's MPhys name, ADflow
    calls its own ``adflow_vol_coords``: rename with the ``volume_output`` option).

  The wall nodes are ``study.wall_nodes`` in increasing order.

Derivatives: :class:`Component` is matrix-free: ``compute_jacvec_product`` takes the chain's
exact products (:meth:`aeroshape.Study.linearise`, kept for the current inputs), forward
(``jvp``) and reverse (``vjp``; a seed on the wall output alone needs no deformation solve).
:class:`FdComponent` is the same component with finite-difference partials instead, for
comparison or for a case whose products fail.

Failures: an :class:`aeroshape.EvaluationError` of an evaluation, a linearisation or a
product (inverted cells, a failed model update or solve) is raised as
``openmdao.api.AnalysisError``, so that drivers that handle it (pyOptSparse backtracks,
``DOEDriver`` records the case as failed and goes on) treat the point as a failed analysis
instead of stopping; the original error is its ``__cause__``.

:func:`add_linear_constraints` adds the study's linear inequalities ``a @ x <= b`` to a
group as one linear constraint with exact (constant) partials.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import openmdao.api as om  # type: ignore[import-untyped]

from ._errors import EvaluationError
from ._native import Evaluation, Linearisation, Study

__all__ = [
    "WALL_OUTPUT",
    "VOLUME_OUTPUT",
    "Component",
    "FdComponent",
    "LinearConstraints",
    "add_design_vars",
    "add_linear_constraints",
]

#: MPhys's name of the aerodynamic surface coordinates (jig shape).
WALL_OUTPUT = "x_aero0"
#: The volume-grid coordinates (DAFoam's MPhys name; MPhys defines none).
VOLUME_OUTPUT = "aero_vol_coords"


def _study(case: str | os.PathLike[str] | None, study: Study | None) -> Study:
    if study is not None and case is None:
        return study
    if case is not None and study is None:
        return Study(case)
    raise ValueError("give exactly one of case=PATH or study=STUDY")


class _StudyComponent(om.ExplicitComponent):  # type: ignore[misc]
    """A study as an explicit component (see the module doc); its subclasses give the
    derivatives.

    Options: ``case`` or ``study`` (exactly one); ``wall_output`` and ``volume_output``
    (output names; ``volume_output=None`` leaves the volume grid out); ``warm_start``
    (default False: every evaluation starts its solves from the baseline, so outputs are a
    function of the inputs alone, as derivatives need).

    Evaluations accept infeasible and out-of-bounds design vectors (a finite-difference
    step at a bound leaves it): the driver enforces bounds and constraints.
    """

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._aeroshape: Study | None = None
        #: The last evaluation made by ``compute``.
        self.last_evaluation: Evaluation | None = None

    def initialize(self) -> None:
        self.options.declare("case", default=None, types=(str, os.PathLike), allow_none=True,
                             desc="case file (CASE.ron) of the study")
        self.options.declare("study", default=None, types=Study, allow_none=True,
                             recordable=False, desc="an aeroshape.Study built already")
        self.options.declare("wall_output", default=WALL_OUTPUT, types=str,
                             desc="name of the flattened wall-node coordinates")
        self.options.declare("volume_output", default=VOLUME_OUTPUT, types=str,
                             allow_none=True,
                             desc="name of the flattened volume-grid coordinates (None: none)")
        self.options.declare("warm_start", default=False, types=bool,
                             desc="start each evaluation's solves from the previous solution")

    @property
    def study(self) -> Study:
        """The study (built from ``case`` at set-up)."""
        if self._aeroshape is None:
            self._aeroshape = _study(self.options["case"], self.options["study"])
        return self._aeroshape

    def setup(self) -> None:
        study = self.study
        self._names = study.names
        for dv in study.design_variables:
            self.add_input(dv.name, val=dv.initial, desc=f"design variable ({dv.modifier})")
        wall = study.baseline_coordinates[study.wall_nodes]
        self.add_output(self.options["wall_output"], val=wall.ravel(),
                        desc="wall-node coordinates, x y z per node", tags=["mphys_coordinates"])
        if self.options["volume_output"] is not None:
            self.add_output(self.options["volume_output"], val=study.baseline_coordinates.ravel(),
                            desc="volume-grid coordinates, x y z per node", tags=["mphys_coupling"])

    def design_vector(self, inputs: Any) -> np.ndarray:
        """The design vector (study order) from the component's inputs."""
        return np.array([inputs[n][0] for n in self._names], dtype=np.float64)

    def compute(self, inputs: Any, outputs: Any) -> None:
        study = self.study
        if not self.options["warm_start"]:
            study.forget_warm_start()
        x = self.design_vector(inputs)
        try:
            ev = study.evaluate(x, allow_infeasible=True, allow_out_of_bounds=True)
        except EvaluationError as e:
            raise _analysis_error(self, x, e) from e
        outputs[self.options["wall_output"]] = ev.wall_coordinates.ravel()
        if self.options["volume_output"] is not None:
            outputs[self.options["volume_output"]] = ev.volume_coordinates.ravel()
        self.last_evaluation = ev


def _analysis_error(comp: om.ExplicitComponent, x: np.ndarray,
                    e: EvaluationError) -> om.AnalysisError:
    """The :class:`aeroshape.EvaluationError` of an evaluation, linearisation or product at
    ``x`` as OpenMDAO's ``AnalysisError``, the signal on which drivers that can (pyOptSparse,
    DOE, genetic) step back or record a failed case instead of stopping; the message names
    the component, the design vector by name and the original error."""
    names = getattr(comp, "_names", [])
    vector = ", ".join(f"{n} = {v:.6g}" for n, v in zip(names, x))
    return om.AnalysisError(f"{comp.pathname or 'aeroshape'}: {e} (at {vector})")


class Component(_StudyComponent):
    """A study as a matrix-free explicit component with the chain's exact products (see
    the module doc). The linearisation is made at the first product after the inputs
    change, and kept until they change again."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._lin: Linearisation | None = None

    def linearisation(self, inputs: Any) -> Linearisation:
        """The chain linearised at the current inputs (made once per design vector)."""
        x = self.design_vector(inputs)
        if self._lin is None or not np.array_equal(self._lin.x, x):
            self._lin = None  # the old one is dropped before the new one is made
            try:
                self._lin = self.study.linearise(x, allow_infeasible=True,
                                                 allow_out_of_bounds=True)
            except EvaluationError as e:
                raise _analysis_error(self, x, e) from e
        return self._lin

    def compute_jacvec_product(self, inputs: Any, d_inputs: Any, d_outputs: Any,
                               mode: str) -> None:
        lin = self.linearisation(inputs)
        wall_out, vol_out = self.options["wall_output"], self.options["volume_output"]
        outs = [o for o in (wall_out, vol_out) if o is not None and o in d_outputs]
        if mode == "fwd":
            dx = np.array([d_inputs[n][0] if n in d_inputs else 0.0 for n in self._names])
            if not outs or not dx.any():
                return
            if vol_out in outs:
                try:
                    dvol = lin.jvp(dx)
                except EvaluationError as e:
                    raise _analysis_error(self, lin.x, e) from e
                d_outputs[vol_out] += dvol.ravel()
                if wall_out in outs:
                    d_outputs[wall_out] += dvol[self.study.wall_nodes].ravel()
            else:
                d_outputs[wall_out] += lin.jvp(dx, wall=True).ravel()
        else:
            seeds = {o: np.asarray(d_outputs[o]).reshape(-1, 3) for o in outs}
            try:
                grad = lin.vjp(seeds.get(vol_out), wall_bar=seeds.get(wall_out))
            except EvaluationError as e:
                raise _analysis_error(self, lin.x, e) from e
            for n, g in zip(self._names, grad):
                if n in d_inputs:
                    d_inputs[n] += g


class FdComponent(_StudyComponent):
    """:class:`Component` with finite-difference partials instead of exact products.

    Extra options: ``fd_step`` and ``fd_form`` (the step of each variable is ``fd_step``
    times its scale; the default 1e-3 stays well above the chain's round-off, whose noise
    in the wall coordinates is about 1e-11 of the model size, and well below the
    curvature's scale)."""

    def initialize(self) -> None:
        super().initialize()
        self.options.declare("fd_step", default=1e-3, types=float,
                             desc="finite-difference step of each design variable, in units of "
                                  "its scale")
        self.options.declare("fd_form", default="central", values=("forward", "backward", "central"),
                             desc="form of the finite-difference partials")

    def setup_partials(self) -> None:
        for dv in self.study.design_variables:
            self.declare_partials(of="*", wrt=dv.name, method="fd",
                                  step=self.options["fd_step"] * dv.scale,
                                  form=self.options["fd_form"], step_calc="abs")


def add_design_vars(group: om.Group, study: Study, *, prefix: str = "",
                    scaled: bool = True) -> list[str]:
    """Adds every design variable of ``study`` to ``group`` as a design variable named
    ``prefix + name`` (its promoted input), with its bounds and, if ``scaled``,
    ``ref = scale`` (the driver sees ``value / scale``). Returns the names added."""
    names = []
    for dv in study.design_variables:
        name = prefix + dv.name
        group.add_design_var(name, lower=dv.lower, upper=dv.upper,
                             ref=dv.scale if scaled else None)
        names.append(name)
    return names


class LinearConstraints(om.ExplicitComponent):  # type: ignore[misc]
    """``g = a @ x`` for the linear constraints of a study (inputs: the design variables by
    name), with exact constant partials; :func:`add_linear_constraints` adds it."""

    def initialize(self) -> None:
        self.options.declare("study", types=Study, recordable=False)

    def setup(self) -> None:
        study = self.options["study"]
        c = study.constraints
        self._names = c.variables
        self._a = c.a
        for dv in study.design_variables:
            self.add_input(dv.name, val=dv.initial)
        self.add_output("g", val=self._a @ study.initial, desc="a @ x, one per constraint: "
                        + ", ".join(c.names))

    def setup_partials(self) -> None:
        for j, name in enumerate(self._names):
            rows = np.flatnonzero(self._a[:, j])
            if rows.size:  # sparse: only the non-zero coefficients
                self.declare_partials("g", name, rows=rows, cols=np.zeros_like(rows),
                                      val=self._a[rows, j])

    def compute(self, inputs: Any, outputs: Any) -> None:
        x = np.array([inputs[n][0] for n in self._names], dtype=np.float64)
        outputs["g"] = self._a @ x


def add_linear_constraints(group: om.Group, study: Study, *, name: str = "shape_constraints",
                           prefix: str = "") -> str | None:
    """Adds the linear constraints ``a @ x <= b`` of ``study`` to ``group``: a
    :class:`LinearConstraints` subsystem ``name`` whose inputs are promoted to
    ``prefix + variable`` (so they share the design variables' promoted inputs) and one
    constraint ``name + ".g"`` with ``upper = b`` and ``linear=True``. Call it before
    ``setup``. Returns the constraint's name, or None when the study has no constraint."""
    c = study.constraints
    if len(c) == 0:
        return None
    group.add_subsystem(name, LinearConstraints(study=study),
                        promotes_inputs=[(v, prefix + v) for v in c.variables])
    group.add_constraint(f"{name}.g", upper=c.b, linear=True)
    return f"{name}.g"
