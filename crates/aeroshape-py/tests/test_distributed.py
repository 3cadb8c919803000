"""aeroshape.distributed: the distributed deformation on an mpi4py communicator, run as
``mpirun -n N python mpi_deform.py`` (2 and 3 ranks) and compared there with the serial
``aeroshape.deform`` to 1e-8 of the largest displacement (see mpi_deform.py).

Skipped when mpi4py, mpirun or the package's cargo feature ``mpi`` is absent, unless
``AEROSHAPE_MPI=1`` (CI with MPI), which makes their absence an error.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from aeroshape import distributed
from conftest import ROOT

SCRIPT = Path(__file__).with_name("mpi_deform.py")
GRID = ROOT / "fixtures" / "grids" / "wing_body.su2"


def _absent(what: str) -> None:
    if os.environ.get("AEROSHAPE_MPI") == "1":
        pytest.fail(f"{what} (AEROSHAPE_MPI=1)")
    pytest.skip(what)


@pytest.fixture(scope="module")
def mpirun() -> list[str]:
    try:
        import mpi4py  # noqa: F401
    except ImportError:
        _absent("mpi4py is not installed")
    if not distributed.available():
        _absent("aeroshape was built without its cargo feature mpi")
    exe = shutil.which("mpirun")
    if exe is None:
        _absent("mpirun not found")
    cmd = [exe, "--oversubscribe"]
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    return cmd


@pytest.mark.parametrize("ranks", [2, 3])
def test_mpi4py_communicator_gives_the_serial_grid(mpirun, ranks):
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    r = subprocess.run(
        [*mpirun, "-n", str(ranks), sys.executable, str(SCRIPT), str(GRID)],
        capture_output=True, text=True, timeout=600, env=env, cwd=SCRIPT.parent,
    )
    results = [line for line in r.stdout.splitlines() if line.startswith("result ")]
    report = "\n".join(results) + "\n" + r.stdout[-2000:] + r.stderr[-3000:]
    assert r.returncode == 0, report
    names = [line.split(":")[0].split()[1] for line in results]
    assert names == ["file-metis", "file-metis-local", "mesh-rcb", "mesh-rcb-local", "given",
                     "given-reach", "bad-argument", "mixed-ways", "kept-made", "kept-refused",
                     "kept-warm", "kept-given"], report
    assert "partitioner metis" in results[0], report
