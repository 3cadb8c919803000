"""Python's overhead over the Rust evaluate, for the default case (docs/python.md,
"Performance"). Build the package in release first (`pip install ./crates/aeroshape-py`).

In one process, alternating, each repetition times:

- **python**: `Study.evaluate(x)` from Python: conversion and checks of `x`, the chain, the
  numpy copies of the volume and wall coordinates and the report dict;
- **rust**: the library's `Study::evaluate(x)` alone, timed in Rust (`_rust_evaluate_seconds`).

It also prints the time each Python call spends outside the chain's own timer (the report's
`seconds`), which a loaded machine disturbs least.

Every evaluation starts cold (`forget_warm_start()`, not timed), so both do the same solver
work; the design vector alternates between dv.ron and a nearby vector. Prints the medians, the
overhead of the medians and the median of the per-pair ratios.

    python crates/aeroshape-py/benches/overhead.py [--reps 200]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import aeroshape

ROOT = Path(__file__).resolve().parents[3]
CASE = ROOT / "fixtures" / "cases" / "default" / "case.ron"
DV = ROOT / "fixtures" / "cases" / "default" / "dv.ron"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=200)
    args = ap.parse_args()
    study = aeroshape.Study(CASE)
    x1 = study.read_design_vector(DV)
    x2 = x1.copy()
    x2[study.names.index("twist")] += 0.01
    xs = [x1, x2]
    py_t, rs_t, inner_t = [], [], []
    for _ in range(5):  # warm-up: caches, lazily factorised re-maps
        study.forget_warm_start()
        study.evaluate(x1)
        study.forget_warm_start()
        study._rust_evaluate_seconds(list(x2))
    for k in range(args.reps):
        x = xs[k % 2]
        xl = list(x)
        order = ("py", "rs") if k % 2 == 0 else ("rs", "py")
        for what in order:
            study.forget_warm_start()
            if what == "py":
                t = time.perf_counter()
                ev = study.evaluate(x)
                py_t.append(time.perf_counter() - t)
                inner_t.append(ev.report["seconds"])
            else:
                rs_t.append(study._rust_evaluate_seconds(xl))
    mp, mr, mi = (statistics.median(v) for v in (py_t, rs_t, inner_t))
    ratios = sorted(p / r for p, r in zip(py_t, rs_t))
    print(f"default case, {study.n_nodes} nodes, {args.reps} alternated pairs, cold starts")
    print(f"python Study.evaluate   median {mp * 1e3:8.3f} ms  (min {min(py_t) * 1e3:.3f})")
    print(f"rust   Study::evaluate  median {mr * 1e3:8.3f} ms  (min {min(rs_t) * 1e3:.3f})")
    print(f"  (the chain's own time inside the python calls: median {mi * 1e3:.3f} ms)")
    extra = sorted(p - i for p, i in zip(py_t, inner_t))
    print(f"python-side time per call (call minus the chain's own timer): median "
          f"{statistics.median(extra) * 1e6:.1f} us, quartiles {extra[len(extra) // 4] * 1e6:.1f} "
          f".. {extra[3 * len(extra) // 4] * 1e6:.1f} us = {100 * statistics.median(extra) / mr:.2f} % "
          f"of the rust median")
    print(f"overhead of the medians: {100 * (mp / mr - 1):+.2f} %")
    print(f"per-pair ratio python/rust: median {statistics.median(ratios):.4f}, "
          f"quartiles {ratios[len(ratios) // 4]:.4f} .. {ratios[3 * len(ratios) // 4]:.4f}")


if __name__ == "__main__":
    main()
