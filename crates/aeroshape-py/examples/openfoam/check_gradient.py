#!/usr/bin/env python3
"""The adjoint gradient against central differences of the whole flow solution, at the
initial design of the M6 optimisation (issue 47, item 4; docs/optimisation.md).

usage: python check_gradient.py [--work DIR] [--vars NAME,…] [--step S [S …]]

For each variable v (a design variable of the study, or `alpha`) and each relative step s:
h = s × (scale of v) (α: s × 1°), the designs x ± h e_v each through the whole chain
(aeroshape's grid from a cold start, checkMesh, simpleFoam to residuals 1e-8), and
(J(x + h) − J(x − h)) / 2h for C_D and C_L, beside the adjoint's dJ/dv at x from the
normal part of the E-SI wall sensitivity and from the whole vector (wingloop.Loop.gradients),
and dV/dv from the wall grid beside its central difference (an exact derivative: checks the
chain and the volume's formula). Writes WORK/gradient_check.json and prints a table.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import wingloop  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", type=Path,
                    default=wingloop.ROOT / "target" / "openfoam" / "gradient")
    ap.add_argument("--vars", default="", help="comma-separated (default: all and alpha)")
    ap.add_argument("--step", type=float, nargs="+", default=[1e-2])
    a = ap.parse_args()
    t0 = time.perf_counter()
    loop = wingloop.Loop(a.work, kind="normal")
    names = loop.study.names
    variables = [v for v in a.vars.split(",") if v] or names + ["alpha"]
    x0, al0 = loop.study.initial, loop.flow.alpha_deg
    d0 = loop.design(x0, al0)
    g = loop.gradients(d0, kinds=("normal", "vector"))
    out = {"initial": {"cd": d0.cd, "cl": d0.cl, "volume": d0.volume, "x": x0.tolist(),
                       "alpha": al0}, "steps": a.step, "rows": []}
    scales = {dv.name: dv.scale for dv in loop.study.design_variables}
    for v in variables:
        for s in a.step:
            h = s * (1.0 if v == "alpha" else scales[v])
            res = []
            for sign in (1, -1):
                x, al = x0.copy(), al0
                if v == "alpha":
                    al += sign * h
                else:
                    x[names.index(v)] += sign * h
                res.append(loop.design(x, al))
            j = names.index(v) if v != "alpha" else None

            def adj(kind, key):
                gk = g["by_kind"][kind][key] if key != "volume" else g["volume"]
                return float(gk[1] if j is None else gk[0][j])
            row = {"variable": v, "step": h, "relative_step": s}
            for key, attr in (("cd", "cd"), ("cl", "cl"), ("volume", "volume")):
                fd = (getattr(res[0], attr) - getattr(res[1], attr)) / (2 * h)
                row[key] = {"fd": fd, "normal": adj("normal", key),
                            "vector": adj("vector", key) if key != "volume" else None}
            out["rows"].append(row)
            print(f"{v:18s} h={h:.3g}  dCD: fd {row['cd']['fd']:+.6e} normal "
                  f"{row['cd']['normal']:+.6e} vector {row['cd']['vector']:+.6e} | dCL: fd "
                  f"{row['cl']['fd']:+.6e} normal {row['cl']['normal']:+.6e} vector "
                  f"{row['cl']['vector']:+.6e} | dV: fd {row['volume']['fd']:+.6e} exact "
                  f"{row['volume']['normal']:+.6e}", flush=True)
            wingloop.fc.write(a.work / "gradient_check.json", json.dumps(out, indent=1) + "\n")
    out["seconds"] = time.perf_counter() - t0
    out["designs"] = loop.count
    wingloop.fc.write(a.work / "gradient_check.json", json.dumps(out, indent=1) + "\n")
    print(f"{loop.count} designs, {out['seconds']:.0f} s")


if __name__ == "__main__":
    main()
