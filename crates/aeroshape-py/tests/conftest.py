"""Shared fixtures of the aeroshape Python tests: the repository, the command-line program
and the data files the project did not make (``../shared/data`` beside the repository).

``AEROSHAPE_CLI`` names the ``aeroshape`` program to compare with (default: the newest of
``target/debug/aeroshape`` and ``target/release/aeroshape``). With ``AEROSHAPE_STRICT=1``
(CI) a missing program or data file is an error instead of a skip.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[3]
DATA = ROOT.parent / "shared" / "data"
DEFAULT = ROOT / "fixtures" / "cases" / "default"
SPHERE = ROOT / "fixtures" / "cases" / "sphere"


def _missing(what: str) -> None:
    if os.environ.get("AEROSHAPE_STRICT") == "1":
        pytest.fail(f"{what} is missing (AEROSHAPE_STRICT=1)")
    pytest.skip(f"{what} is missing")


@pytest.fixture(scope="session")
def cli() -> Path:
    """The ``aeroshape`` program."""
    named = os.environ.get("AEROSHAPE_CLI")
    if named:
        p = Path(named)
        if not p.is_file():
            pytest.fail(f"AEROSHAPE_CLI={named} does not exist")
        return p
    found = [p for p in (ROOT / "target" / d / "aeroshape" for d in ("debug", "release")) if p.is_file()]
    if not found:
        _missing("the aeroshape program (cargo build -p aeroshape-cli)")
    return max(found, key=lambda p: p.stat().st_mtime)


@pytest.fixture(scope="session")
def data() -> Path:
    """``../shared/data``: files the project did not make."""
    if not DATA.is_dir():
        _missing(f"{DATA}")
    return DATA


def run_cli(cli: Path, *args: object, ok: bool = True) -> subprocess.CompletedProcess[str]:
    """Runs the program; with ``ok`` it must succeed."""
    r = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True, cwd=ROOT)
    if ok and r.returncode != 0:
        raise AssertionError(f"aeroshape {' '.join(map(str, args))} failed:\n{r.stderr}")
    return r


def cli_error(r: subprocess.CompletedProcess[str]) -> str:
    """The one-line message of a failed run (stderr after ``error: ``)."""
    assert r.returncode == 1, r.stderr
    lines = [l for l in r.stderr.splitlines() if l.startswith("error: ")]
    assert len(lines) == 1, r.stderr
    return lines[0][len("error: "):]


def released(call, repeat: int):
    """Runs ``call`` ``repeat`` times in a worker thread while this thread spins, and checks
    that this thread ran Python code in the middle half of at least one call: impossible if
    the call held the GIL throughout. Returns the last call's result."""
    import sys
    import threading
    import time

    windows, result, done = [], [], threading.Event()

    def work():
        for _ in range(repeat):
            t0 = time.perf_counter()
            result.append(call())
            windows.append((t0, time.perf_counter()))
        done.set()

    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-4)
    try:
        stamps, last = [], 0.0
        t = threading.Thread(target=work)
        t.start()
        while not done.is_set():
            now = time.perf_counter()
            if now - last > 5e-5:
                stamps.append(now)
                last = now
        t.join()
    finally:
        sys.setswitchinterval(old)
    stamps = np.asarray(stamps)
    inside = [
        int(np.count_nonzero((stamps > a + (b - a) / 4) & (stamps < b - (b - a) / 4)))
        for a, b in windows
    ]
    assert max(inside) > 0, f"no Python ran during the calls: the GIL was held ({inside})"
    return result[-1]


def constrained_case(tmp: Path, constraints: str) -> Path:
    """A copy of the sphere case (absolute paths) with the given ``constraints: [...]``."""
    text = (SPHERE / "case.ron").read_text()
    text = text.replace('"../../geom/sphere.ron"', f'"{(ROOT / "fixtures" / "geom" / "sphere.ron").as_posix()}"')
    text = text.replace('grid: "grid.msh"', f'grid: "{(SPHERE / "grid.msh").as_posix()}"')
    marker = "    ],\n  ),\n)"
    assert text.rstrip().endswith(marker), "layout of fixtures/cases/sphere/case.ron changed"
    text = text.rstrip()[: -len(marker)] + "    ],\n    constraints: " + constraints + ",\n  ),\n)\n"
    p = tmp / "case.ron"
    p.write_text(text)
    return p


def tight_case(tmp: Path) -> Path:
    """A copy of the sphere case (absolute paths) whose deformation solves run to 1e-12, so
    that products and differences of the volume grid are not limited by the solver's 1e-8."""
    text = (SPHERE / "case.ron").read_text()
    text = text.replace('"../../geom/sphere.ron"', f'"{(ROOT / "fixtures" / "geom" / "sphere.ron").as_posix()}"')
    text = text.replace('grid: "grid.msh"', f'grid: "{(SPHERE / "grid.msh").as_posix()}"')
    anchor = '  fixed: ["farfield"],\n'
    assert anchor in text, "layout of fixtures/cases/sphere/case.ron changed"
    text = text.replace(anchor, anchor + "  deform: (rel_tol: 1e-12),\n")
    p = tmp / "case.ron"
    p.write_text(text)
    return p


__all__ = ["ROOT", "DATA", "DEFAULT", "SPHERE", "run_cli", "cli_error", "constrained_case",
           "released", "tight_case"]
