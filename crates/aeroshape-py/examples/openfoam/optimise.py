#!/usr/bin/env python3
"""Drag at fixed lift of the ONERA M6 half wing, with OpenFOAM's flow and adjoint in the loop.

usage: python optimise.py [--work DIR] [--maxiter N] [--vars NAME,…] [--bound-fraction F]
                          [--no-volume] [--kind normal|vector] [--gradient adjoint|fd]

An OpenMDAO problem (docs/optimisation.md): the design variables are the wing master's
eight variables of `aeroshape case init` on fixtures/openfoam/m6_coarse/m6_coarse.su2
(bounds: `--bound-fraction` of case init's, which it checked valid one at a time) and the
angle of attack α (2° to 6°); minimise C_D subject to C_L = C_L0 (the initial design's
lift) and V ≥ V0 (the wing's volume from the wall grid, wingloop.py), with ScipyOptimizeDriver
SLSQP. One component, `FoamWing`, runs wingloop.Loop: compute = the grid and simpleFoam,
compute_partials = the two adjoints and aeroshape's reverse product.

A design whose grid or flow fails raises openmdao's AnalysisError. ScipyOptimizeDriver
stops on any exception; `SurvivingSLSQP` instead hands SLSQP a rejected point (the worst
objective seen plus one scaled unit, the constraints of the last good point), so its line
search steps back and the run goes on (counted in the log).

Every evaluation is logged (stdout and WORK/history.jsonl: x, α, C_D, C_L, V, aeroshape's
cell quality, checkMesh's figures, seconds per step; gradients where computed) and kept
in WORK/designs/NNN (the OpenFOAM case). `plots.py WORK` draws the results.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import openmdao.api as om

sys.path.insert(0, str(Path(__file__).resolve().parent))
import wingloop  # noqa: E402


class FoamWing(om.ExplicitComponent):
    """Inputs x (the study's design vector) and alpha (degrees); outputs CD, CL and
    volume_ratio = V / V0, with their partials from the adjoints."""

    def initialize(self):
        self.options.declare("loop", types=wingloop.Loop, recordable=False)
        self.options.declare("gradient", default="adjoint", values=("adjoint", "fd"))
        self.options.declare("fd_variables", default=[], types=list)
        self.options.declare("fd_step", default=0.2, types=float)

    def setup(self):
        loop = self.options["loop"]
        self.add_input("x", val=loop.study.initial)
        self.add_input("alpha", val=loop.flow.alpha_deg)
        for name in ("CD", "CL", "volume_ratio"):
            self.add_output(name, val=0.0)
        self.declare_partials("*", ["x", "alpha"])
        self.current: wingloop.Design | None = None
        self.gradient_designs: list[int] = []

    def _design(self, inputs) -> wingloop.Design:
        x, alpha = np.array(inputs["x"]), float(inputs["alpha"][0])
        c = self.current
        if c is not None and np.array_equal(c.x, x) and c.alpha == alpha:
            return c
        loop = self.options["loop"]
        try:
            d = loop.design(x, alpha)
        except wingloop.DesignError as e:
            loop.log(f"AnalysisError: {e}")
            with open(loop.history_path, "a") as f:
                f.write(json.dumps({"index": loop.count, "x": x.tolist(), "alpha": alpha,
                                    "failed": str(e)}) + "\n")
            raise om.AnalysisError(str(e)) from e
        self.current = d
        return d

    def compute(self, inputs, outputs):
        d = self._design(inputs)
        loop = self.options["loop"]
        outputs["CD"] = d.cd
        outputs["CL"] = d.cl
        outputs["volume_ratio"] = d.volume / loop.v0
        loop.record(d)

    def compute_partials(self, inputs, partials):
        d = self._design(inputs)
        loop = self.options["loop"]
        try:
            if self.options["gradient"] == "adjoint":
                g = loop.gradients(d)
            else:
                g = loop.fd_gradients(d, self.options["fd_variables"], self.options["fd_step"])
        except wingloop.DesignError as e:
            raise om.AnalysisError(str(e)) from e
        for out, key, s in (("CD", "cd", 1.0), ("CL", "cl", 1.0),
                            ("volume_ratio", "volume", 1.0 / loop.v0)):
            partials[out, "x"] = s * g[key][0][None, :]
            partials[out, "alpha"] = s * g[key][1]
        self.gradient_designs.append(d.index)
        loop.record(d, gradient=True)


class SurvivingSLSQP(om.ScipyOptimizeDriver):
    """ScipyOptimizeDriver whose objective survives an AnalysisError (module doc)."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.failed_points = 0
        self._worst = None

    def _objfunc(self, x_new):
        f = super()._objfunc(x_new)
        info = self._exc_info
        if info is not None and issubclass(info[0], om.AnalysisError):
            self._exc_info = None
            self.failed_points += 1
            return (self._worst if self._worst is not None else 0.0) + 1.0
        if info is None:
            self._worst = f if self._worst is None else max(self._worst, f)
        return f


def build(loop: wingloop.Loop, *, variables: list[str], bound_fraction: float,
          volume: bool, cl0: float, cd0: float, maxiter: int, gradient: str = "adjoint",
          fd_step: float = 0.2) -> om.Problem:
    study = loop.study
    prob = om.Problem(reports=False)
    prob.model.add_subsystem("wing", FoamWing(loop=loop, gradient=gradient,
                                              fd_variables=variables + ["alpha"],
                                              fd_step=fd_step), promotes=["*"])
    idx = [study.names.index(v) for v in variables]
    dvs = study.design_variables
    x0 = study.initial
    lower = np.array([x0[i] + bound_fraction * (dvs[i].lower - x0[i]) for i in idx])
    upper = np.array([x0[i] + bound_fraction * (dvs[i].upper - x0[i]) for i in idx])
    # Scaling: a variable's unit is half its range, the objective's 1 % of C_D0, so that
    # SLSQP's first step (its Hessian starts as the identity) is a fraction of the range
    # (with the variables' own scales and ref C_D0 the gradient was ~1e-3 and SLSQP stopped
    # after one step of 1e-5 rad, its change of f below its tolerance).
    ref = (upper - lower) / 2
    prob.model.add_design_var("x", indices=idx, lower=lower, upper=upper, ref=ref)
    prob.model.add_design_var("alpha", lower=2.0, upper=6.0, ref=1.0)
    prob.model.add_objective("CD", ref=0.01 * cd0)
    prob.model.add_constraint("CL", equals=cl0, ref=0.01 * cl0)
    if volume:
        prob.model.add_constraint("volume_ratio", lower=1.0, ref=0.01)
    c = study.constraints
    if len(c):
        raise SystemExit("the case has linear constraints; this script does not add them")
    prob.driver = SurvivingSLSQP(optimizer="SLSQP", maxiter=maxiter, tol=1e-6, disp=True)
    prob.setup()
    return prob


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", type=Path,
                    default=wingloop.ROOT / "target" / "openfoam" / "optimise")
    ap.add_argument("--maxiter", type=int, default=12)
    ap.add_argument("--vars", default="", help="comma-separated variables (default: all)")
    ap.add_argument("--bound-fraction", type=float, default=0.5)
    ap.add_argument("--no-volume", action="store_true")
    ap.add_argument("--kind", choices=("normal", "vector"), default="vector",
                    help="the adjoint's wall seed: the whole E-SI vector or its normal part")
    ap.add_argument("--gradient", choices=("adjoint", "fd"), default="adjoint",
                    help="the adjoint, or forward differences of the flow (one solve a variable)")
    ap.add_argument("--fd-step", type=float, default=0.2,
                    help="forward-difference step, in units of each variable's scale (α: °)")
    a = ap.parse_args()
    if not wingloop.fc.available():
        raise SystemExit("OpenFOAM (simpleFoam, adjointOptimisationFoam, checkMesh) not found")
    a.work.mkdir(parents=True, exist_ok=True)
    (a.work / "history.jsonl").unlink(missing_ok=True)
    logf = open(a.work / "optimise.log", "w")

    def log(msg):
        line = f"[{time.strftime('%H:%M:%S')}] {msg}"
        print(line, flush=True)
        logf.write(line + "\n")
        logf.flush()

    t0 = time.perf_counter()
    loop = wingloop.Loop(a.work, kind=a.kind, log=log)
    variables = [v for v in a.vars.split(",") if v] or loop.study.names
    log(f"variables {variables}; V0 = {loop.v0:.6e} m^3")
    d0 = loop.design(loop.study.initial, loop.flow.alpha_deg)
    prob = build(loop, variables=variables, bound_fraction=a.bound_fraction,
                 volume=not a.no_volume, cl0=d0.cl, cd0=d0.cd, maxiter=a.maxiter,
                 gradient=a.gradient, fd_step=a.fd_step)
    prob.model.wing.current = d0  # the driver's first evaluation is this design
    log(f"initial: CD {d0.cd:.8f} CL {d0.cl:.8f}")
    prob.run_driver()
    d = prob.model.wing.current
    summary = {
        "variables": variables, "names": loop.study.names, "bound_fraction": a.bound_fraction,
        "volume_constraint": not a.no_volume, "kind": a.kind, "gradient": a.gradient,
        "initial": {"cd": d0.cd, "cl": d0.cl, "volume": d0.volume, "x": d0.x.tolist(),
                    "alpha": d0.alpha, "index": d0.index},
        "final": {"cd": float(prob["CD"][0]), "cl": float(prob["CL"][0]),
                  "volume_ratio": float(prob["volume_ratio"][0]),
                  "x": prob["x"].tolist(), "alpha": float(prob["alpha"][0]),
                  "index": d.index if d else None},
        "driver": {"iterations": prob.driver.iter_count, "success": not prob.driver.fail,
                   "message": getattr(prob.driver._scipy_optimize_result, "message", None),
                   "failed_points": prob.driver.failed_points,
                   "gradient_designs": prob.model.wing.gradient_designs},
        "designs": loop.count, "seconds": time.perf_counter() - t0,
    }
    wingloop.fc.write(a.work / "summary.json", json.dumps(summary, indent=1) + "\n")
    log(f"final: CD {summary['final']['cd']:.8f} CL {summary['final']['cl']:.8f} "
        f"V/V0 {summary['final']['volume_ratio']:.6f}; {loop.count} designs, "
        f"{len(prob.model.wing.gradient_designs)} gradients, "
        f"{summary['seconds']:.0f} s")


if __name__ == "__main__":
    main()
