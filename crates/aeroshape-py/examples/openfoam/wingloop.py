"""One design of the M6 optimisation: aeroshape's grid → OpenFOAM → C_D, C_L and their
gradients with respect to the design variables and the angle of attack.

`Loop.setup(work)` makes, once: the aeroshape case (`aeroshape case init` on the IGES and
fixtures/openfoam/m6_coarse/m6_coarse.su2), the study, an OpenFOAM base case holding the
fixture's polyMesh (gmshToFoam's conversion of the same grid, same point order), and the map
from grid nodes to polyMesh points (checked to 1e-7 of the model size: case init puts the wall nodes on the CAD, 3.5e-9 m from the fixture at most).

`Loop.design(x, alpha)`: `Study.evaluate(x)` (cold start: a function of x alone) → grid
checks (aeroshape's cell quality, checkMesh) → polyMesh points → simpleFoam → C_D, C_L, and
the wing's volume from the wall grid. `Loop.gradients(design)`: adjointOptimisationFoam for
C_D and for C_L (E-SI point sensitivities) → aeroshape's reverse product
(`Study.linearise(x).vjp(wall_bar=…)`) → dC_D/dx, dC_L/dx; the angle of attack's derivative
from the same wall sensitivities (a rigid rotation of the wing, below); dV/dx exactly from
the wall grid. Every failure raises `DesignError` (one line: which design, which step, the
log).

**Angle of attack.** Rotating the wing and the flow together changes nothing, so raising α
by δ is the same as turning the wing nose-down by δ about the y axis at the old α:
dJ/dα = Σ_p g_p · (z_p − z_c, 0, −(x_p − x_c)) per radian, g_p = dJ/dx_p the wall
sensitivity, c = (0.2015, 0, 0) the far field's centre (the whole grid turned about it is
the same domain). It needs no extra flow solve; check_gradient.py compares it with central
differences of the flow.

**Volume.** The wall triangles (marker `wing`) and the root plane y = 0 close the wing; a
tetrahedron on the origin over a triangle of that plane has zero volume, so the wing's
volume is V = Σ det(a, b, c) / 6 over the wall triangles alone (oriented consistently,
checked), exact for the grid's polyhedron (it differs from the CAD's volume by the
triangulation's O(h²) error), with dV/da = (b × c) / 6 and so on.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[3]
sys.path.insert(0, str(HERE))
import foamcase as fc  # noqa: E402
import vjp  # noqa: E402

FIXTURE = ROOT / "fixtures" / "openfoam" / "m6_coarse"
IGES = ROOT / "fixtures" / "iges" / "geom_oneram6.igs"
FAR_CENTRE = np.array([0.2015, 0.0, 0.0])
POLYMESH = ("boundary", "faces", "owner", "neighbour", "points")


class DesignError(RuntimeError):
    """A design whose grid or flow failed (the optimiser's AnalysisError)."""


def aeroshape_cli() -> str:
    env = os.environ.get("AEROSHAPE_CLI")
    if env:
        return env
    found = [p for p in (ROOT / "target" / "release" / "aeroshape",
                         ROOT / "target" / "debug" / "aeroshape") if p.exists()]
    if not found:
        raise SystemExit("no aeroshape program (cargo build -p aeroshape-cli, or AEROSHAPE_CLI)")
    return str(max(found, key=lambda p: p.stat().st_mtime))


@dataclass
class Design:
    """One evaluated design: its case folder and what the primal gave."""

    index: int
    x: np.ndarray
    alpha: float
    case: Path
    cd: float
    cl: float
    volume: float
    quality: dict  # aeroshape's quality_after (min, mean, p1, inverted) and inverted_before
    checkmesh: dict
    primal_iterations: int
    seconds: dict = field(default_factory=dict)
    wall_xyz: np.ndarray | None = None
    grad: dict | None = None  # "cd", "cl", "volume": (dx, dalpha)

    def record(self) -> dict:
        r = {"index": self.index, "x": self.x.tolist(), "alpha": self.alpha, "cd": self.cd,
             "cl": self.cl, "volume": self.volume, "quality": self.quality,
             "checkmesh": self.checkmesh, "primal_iterations": self.primal_iterations,
             "seconds": self.seconds, "case": str(self.case)}
        if self.grad:
            r["grad"] = {k: {"x": list(map(float, v[0])), "alpha": float(v[1])}
                         for k, v in self.grad.items()}
        return r


class Loop:
    """The chain from a design vector and α to C_D, C_L, V and their gradients."""

    def __init__(self, work: Path, *, kind: str = "normal", flow: fc.Flow | None = None,
                 keep: bool = True, log=print):
        import aeroshape
        self.work = Path(work)
        self.kind = kind
        self.flow = flow or fc.Flow()
        self.keep = keep
        self.log = log
        self.count = 0
        self.history_path = self.work / "history.jsonl"
        self.work.mkdir(parents=True, exist_ok=True)
        case = self.work / "case"
        if not (case / "case.ron").exists():
            subprocess.run([aeroshape_cli(), "case", "init", str(IGES),
                            str(FIXTURE / "m6_coarse.su2"), "-o", str(case)], check=True,
                           stdout=open(self.work / "case_init.log", "w"),
                           stderr=subprocess.STDOUT)
        self.study = aeroshape.Study(str(case / "case.ron"))
        self.base = self.work / "base"
        self._base_case()
        xyz0 = self.study.baseline_coordinates
        size = float(np.linalg.norm(np.ptp(xyz0[self.study.wall_nodes], axis=0)))
        self.foam_index = vjp.point_mapping(xyz0, fc.read_points(self.base), 1e-7 * size)
        self.wall_row = {int(n): i for i, n in enumerate(self.study.wall_nodes)}
        self.tris = self._wing_triangles()
        self.v0 = self.volume(xyz0)[0]

    @staticmethod
    def names_of(work: Path) -> list[str]:
        """The design variables' names of the case in `work` (without building a study)."""
        import aeroshape
        return aeroshape.Study(str(Path(work) / "case" / "case.ron")).names

    # ------------------------------------------------------------ set-up

    def _base_case(self) -> None:
        b = self.base
        if b.exists():
            shutil.rmtree(b)
        (b / "system").mkdir(parents=True)
        (b / "constant" / "polyMesh").mkdir(parents=True)
        for f in POLYMESH:
            shutil.copy(FIXTURE / "constant" / "polyMesh" / f, b / "constant" / "polyMesh" / f)
        fc.write(b / "system" / "controlDict", fc.control_dict("simpleFoam", 1))
        fc.write(b / "system" / "fvSchemes", fc.FV_SCHEMES)
        fc.write(b / "system" / "fvSolution", fc.FV_SOLUTION)
        fc.write(b / "constant" / "transportProperties", fc.transport(self.flow))
        fc.write(b / "constant" / "turbulenceProperties", fc.TURBULENCE)
        fc.write(b / "constant" / "adjointRASProperties", fc.ADJOINT_RAS)

    def _wing_triangles(self) -> np.ndarray:
        """The `wing` marker's triangles (grid node indices), oriented consistently."""
        markers = self.study.baseline.markers
        if "wing" not in markers or "triangle" not in markers["wing"]:
            raise SystemExit(f"the case's grid has no `wing` triangles (markers "
                             f"{sorted(markers)})")
        t = np.asarray(markers["wing"]["triangle"], dtype=np.int64)
        edges: dict[tuple[int, int], int] = {}
        for a, b, c in t:
            for e in ((a, b), (b, c), (c, a)):
                edges[e] = edges.get(e, 0) + 1
        bad = [e for e, n in edges.items() if n > 1]  # an edge twice the same way round
        if bad:
            raise SystemExit(f"the wing triangles are not oriented consistently (edge {bad[0]})")
        missing = [int(n) for n in np.unique(t) if int(n) not in self.wall_row]
        if missing:
            raise SystemExit(f"wing node {missing[0]} is not a wall node of the study")
        return t

    # ------------------------------------------------------------ geometry

    def volume(self, xyz: np.ndarray) -> tuple[float, np.ndarray]:
        """(V, dV/dx of the wall nodes, n_wall × 3) of the wing closed by y = 0."""
        a, b, c = (xyz[self.tris[:, k]] for k in range(3))
        det = np.einsum("ij,ij->i", a, np.cross(b, c))
        sign = 1.0 if det.sum() >= 0 else -1.0
        g = np.zeros((len(self.study.wall_nodes), 3))
        rows = np.array([[self.wall_row[int(n)] for n in tri] for tri in self.tris])
        for k, part in enumerate((np.cross(b, c), np.cross(c, a), np.cross(a, b))):
            np.add.at(g, rows[:, k], sign * part / 6)
        return sign * det.sum() / 6, g

    # ------------------------------------------------------------ one design

    def design(self, x: np.ndarray, alpha: float, warm: Design | None = None) -> Design:
        """Grid and flow of (x, α); raises DesignError when either fails. With `warm`
        (a design at the same α), simpleFoam starts from that design's converged U and p
        (same topology, same cells) instead of the uniform free stream."""
        import aeroshape
        x = np.asarray(x, dtype=float).copy()
        self.count += 1
        idx = self.count
        t0 = time.perf_counter()
        secs = {}
        case = self.work / "designs" / f"{idx:03d}"
        try:
            self.study.forget_warm_start()
            ev = self.study.evaluate(x, allow_infeasible=True, allow_out_of_bounds=True)
        except aeroshape.AeroshapeError as e:
            raise DesignError(f"design {idx}: aeroshape: {e}") from e
        secs["grid"] = time.perf_counter() - t0
        # The guard's rule: a design may not invert a cell the baseline grid has valid.
        # A grid that arrives with invalid cells (m6_coarse has two flat prisms at the
        # trailing edge) keeps them; checkMesh below judges the finite-volume grid.
        q0 = ev.report["quality_before"]
        q = ev.report.get("quality_after") or q0
        if q["inverted"] > q0["inverted"]:
            raise DesignError(f"design {idx}: {q['inverted']} inverted cells against "
                              f"{q0['inverted']} in the baseline (min quality {q['min']:.3g})")
        xyz = ev.volume_coordinates
        if case.exists():
            shutil.rmtree(case)
        shutil.copytree(self.base, case)
        fc.write_points(case, vjp.foam_points(xyz, self.foam_index))
        flow = self.flow_at(alpha)
        try:
            cm = fc.check_mesh(case)
            if not cm.ok:
                raise DesignError(f"design {idx}: checkMesh fails the grid: "
                                  f"{'; '.join(cm.failed)} ({cm.log})")
            fc.reset_fields(case, flow)
            if warm is not None:
                t = fc.latest_time(warm.case)
                for name in ("U", "p"):
                    shutil.copy(warm.case / t / name, case / "0" / name)
            p = fc.solve_primal(case, flow)
        except fc.FoamError as e:
            raise DesignError(f"design {idx}: {e}") from e
        secs["checkMesh"] = cm.seconds
        secs["simpleFoam"] = p.seconds
        vol, _ = self.volume(xyz)
        d = Design(index=idx, x=x, alpha=float(alpha), case=case, cd=p.cd, cl=p.cl,
                   volume=vol, quality={**{k: q[k] for k in ("min", "mean", "p1", "inverted")},
                            "inverted_before": q0["inverted"]},
                   checkmesh={"ok": cm.ok, "max_non_orthogonality": cm.max_non_orthogonality,
                              "max_skewness": cm.max_skewness, "min_volume": cm.min_volume},
                   primal_iterations=p.iterations, seconds=secs,
                   wall_xyz=xyz[self.study.wall_nodes])
        secs["total"] = time.perf_counter() - t0
        self.log(f"design {idx}: alpha {alpha:.4f} CD {p.cd:.8f} CL {p.cl:.8f} "
                 f"V/V0 {vol / self.v0:.6f} q_min {q['min']:.4f} "
                 f"non-orth {cm.max_non_orthogonality:.1f} ({secs['total']:.1f} s)")
        return d

    def flow_at(self, alpha: float) -> fc.Flow:
        f = fc.Flow(**{k: getattr(self.flow, k) for k in self.flow.__dataclass_fields__})
        f.alpha_deg = float(alpha)
        return f

    def gradients(self, d: Design, kinds: tuple[str, ...] | None = None) -> dict:
        """dC_D, dC_L, dV with respect to (x, α), from the adjoints in d's case. With
        `kinds`, also returns each kind's gradients under "by_kind"."""
        t0 = time.perf_counter()
        flow = self.flow_at(d.alpha)
        sens = {}
        try:
            for obj in ("drag", "lift"):
                sens[obj] = fc.solve_adjoint(d.case, flow, obj)
        except fc.FoamError as e:
            raise DesignError(f"design {d.index}: {e}") from e
        d.seconds["adjoints"] = time.perf_counter() - t0
        t1 = time.perf_counter()
        lin = self.study.linearise(d.x, allow_infeasible=True, allow_out_of_bounds=True)
        xyz = lin.volume_coordinates
        wall = xyz[self.study.wall_nodes]
        rot = np.stack([wall[:, 2] - FAR_CENTRE[2], np.zeros(len(wall)),
                        -(wall[:, 0] - FAR_CENTRE[0])], axis=1) * (math.pi / 180)
        out = {}
        by_kind = {}
        for kind in kinds or (self.kind,):
            g = {}
            for obj, key in (("drag", "cd"), ("lift", "cl")):
                w = vjp.wall_bar(self.study, sens[obj], kind=kind, foam_index=self.foam_index)
                g[key] = (np.asarray(lin.vjp(wall_bar=w)), float(np.sum(w * rot)))
            by_kind[kind] = g
        out.update(by_kind[self.kind] if self.kind in by_kind else by_kind[kinds[0]])
        _, gv = self.volume(xyz)
        out["volume"] = (np.asarray(lin.vjp(wall_bar=gv)), 0.0)
        d.seconds["vjp"] = time.perf_counter() - t1
        d.seconds["adjoint_iterations"] = {k: s.iterations for k, s in sens.items()}
        d.grad = out
        self.log(f"design {d.index}: gradients ({d.seconds['adjoints']:.1f} s adjoints, "
                 f"{d.seconds['vjp']:.1f} s aeroshape)")
        if kinds:
            out = dict(out, by_kind=by_kind)
        return out

    def fd_gradients(self, d: Design, variables: list[str], step: float) -> dict:
        """dC_D, dC_L by forward differences of the whole flow solution, one design per
        variable in `variables` (a study variable or "alpha"; the step is `step` × its scale,
        α: `step` degrees), the others zero; dV exactly (as in `gradients`). The
        reference when the adjoint's wall sensitivities are too coarse (docs/optimisation.md)."""
        t0 = time.perf_counter()
        names = self.study.names
        g = {"cd": [np.zeros(len(names)), 0.0], "cl": [np.zeros(len(names)), 0.0]}
        scales = {dv.name: dv.scale for dv in self.study.design_variables}
        for v in variables:
            x, al = d.x.copy(), d.alpha
            h = step * (1.0 if v == "alpha" else scales[v])
            if v == "alpha":
                al += h
            else:
                x[names.index(v)] += h
            # warm start from d's fields only at d's α: the U file carries d's far-field
            # velocity, which would override the new α's
            p = self.design(x, al, warm=d if v != "alpha" else None)
            for key in ("cd", "cl"):
                dj = (getattr(p, key) - getattr(d, key)) / h
                if v == "alpha":
                    g[key][1] = dj
                else:
                    g[key][0][names.index(v)] = dj
            if not self.keep:
                shutil.rmtree(p.case, ignore_errors=True)
        lin = self.study.linearise(d.x, allow_infeasible=True, allow_out_of_bounds=True)
        _, gv = self.volume(lin.volume_coordinates)
        out = {k: (v[0], float(v[1])) for k, v in g.items()}
        out["volume"] = (np.asarray(lin.vjp(wall_bar=gv)), 0.0)
        d.seconds["fd"] = time.perf_counter() - t0
        d.grad = out
        self.log(f"design {d.index}: finite-difference gradients ({len(variables)} designs, "
                 f"{d.seconds['fd']:.1f} s)")
        return out

    def record(self, d: Design, **extra) -> None:
        with open(self.history_path, "a") as f:
            f.write(json.dumps(dict(d.record(), **extra)) + "\n")
