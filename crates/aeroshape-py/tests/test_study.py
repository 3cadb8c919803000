"""Study: the same grid as ``aeroshape run`` bit for bit, bad input raising clearly, design
variables and constraints as the command line lists them, arrays of their own, the GIL
released, progress to a callback or the logger."""

from __future__ import annotations

import json
import logging
import threading

import numpy as np
import pytest

import aeroshape
from conftest import DEFAULT, SPHERE, cli_error, constrained_case, released, run_cli

CASE = DEFAULT / "case.ron"
DV = DEFAULT / "dv.ron"


@pytest.fixture(scope="module")
def study() -> aeroshape.Study:
    return aeroshape.Study(CASE)


def test_evaluate_is_aeroshape_run_bit_for_bit(cli, tmp_path):
    run_cli(cli, "run", CASE, "--dv", DV, "-o", tmp_path / "cli", "--no-pictures")
    study = aeroshape.Study(CASE)  # fresh, as the program: one evaluation, cold start
    x = study.read_design_vector(DV)
    ev = study.evaluate(x)
    written = ev.write(tmp_path / "py")
    names = {p.split("/")[-1] for p in written}
    assert names == {"deformed.su2", "deformed.msh", "deformed.vtu", "baseline.su2",
                     "geometry.ron", "report.json"}
    for name in ["deformed.su2", "deformed.msh", "deformed.vtu", "baseline.su2", "geometry.ron"]:
        a = (tmp_path / "cli" / name).read_bytes()
        b = (tmp_path / "py" / name).read_bytes()
        assert a == b, f"{name} differs from aeroshape run's"
    # The arrays are the grid the program wrote: exact equality with its binary VTU.
    cli_mesh = aeroshape.read_mesh(tmp_path / "cli" / "deformed.vtu")
    assert np.array_equal(ev.volume_coordinates, cli_mesh.coordinates)
    assert np.array_equal(ev.wall_coordinates, cli_mesh.coordinates[study.wall_nodes])
    # Something moved: the design vector is not the baseline.
    assert not np.array_equal(ev.volume_coordinates, study.baseline_coordinates)
    # The report is report.json's evaluation, timings aside.
    rep = json.loads((tmp_path / "cli" / "report.json").read_text())["evaluation"]
    assert ev.report["design"] == rep["design"]
    assert ev.report["quality_after"] == rep["quality_after"]
    assert ev.report["deform"]["report"]["iterations"] == rep["deform"]["report"]["iterations"] > 0
    assert ev.report is ev.report  # made once, on first access


def test_initial_vector_gives_the_baseline(study):
    ev = study.evaluate(study.initial)
    assert np.array_equal(ev.volume_coordinates, study.baseline_coordinates)
    assert ev.report["deform"]["skipped"] is True


def test_arrays_own_their_memory(study):
    x = study.initial.copy()
    x[study.names.index("twist")] = 0.02
    ev = study.evaluate(x)
    v, w = ev.volume_coordinates, ev.wall_coordinates
    for a in (v, w, ev.cell_quality, study.baseline_coordinates, study.wall_nodes):
        assert a.flags.owndata and a.base is None and a.flags.c_contiguous
    assert v.dtype == np.float64 and v.shape == (study.n_nodes, 3)
    assert w.shape == (len(study.wall_nodes), 3)
    kept = v.copy()
    v[:] = 0.0  # writing to the array changes nothing of the study's
    again = study.evaluate(x)
    assert np.allclose(again.volume_coordinates, kept, rtol=0, atol=1e-9)
    assert np.array_equal(ev.mesh.coordinates, kept)  # the evaluation's own grid is intact


def test_design_variables_as_param_list(cli, study):
    listed = json.loads(run_cli(cli, "param", "list", CASE, "--json").stdout)["variables"]
    records = study.design_variables
    assert [d.name for d in records] == [v["name"] for v in listed] == study.names
    for d, v in zip(records, listed):
        assert (d.lower, d.upper, d.scale, d.initial, d.group, d.modifier) == (
            v["lower"], v["upper"], v["scale"], v["value"], v["group"], v["modifier"])
    assert np.array_equal(study.initial, [v["value"] for v in listed])


def test_constraints_are_matrices(cli, tmp_path):
    case = constrained_case(tmp_path, '[(name: "px sum", coefficients: {"px_11": 1.0, "px_22": 2.0}, rhs: 0.1),'
                                      ' (name: "pz", coefficients: {"pz_12": -1.0}, rhs: 0.05)]')
    study = aeroshape.Study(case)
    c = study.constraints
    listed = json.loads(run_cli(cli, "param", "list", case, "--json").stdout)["constraints"]
    assert c.names == listed["names"] == ["px sum", "pz"]
    assert c.variables == study.names
    assert c.a.shape == (2, 8) and np.array_equal(c.a, listed["a"])
    assert np.array_equal(c.b, [0.1, 0.05])
    x = study.initial.copy()
    x[study.names.index("px_22")] = 0.1  # 2 × 0.1 > 0.1
    assert [v[0] for v in c.violations(x)] == ["px sum"]
    with pytest.raises(aeroshape.DesignVectorError, match=r"1 linear constraint\(s\) violated "
                       r"\(first: constraint 'px sum' violated: 0.2 > 0.1"):
        study.evaluate(x)
    ev = study.evaluate(x, allow_infeasible=True)
    assert ev.report["design"][study.names.index("px_22")] == ["px_22", 0.1]


def test_bad_design_vectors_raise(study):
    n = len(study.names)
    with pytest.raises(aeroshape.DesignVectorError,
                       match=f"^design vector has 3 values, the parametrisation has {n} variables$"):
        study.evaluate([0.0, 0.0, 0.0])
    x = study.initial.copy()
    x[2] = np.nan
    with pytest.raises(aeroshape.DesignVectorError,
                       match=r"^design variable 'sweep' = NaN is outside its bounds \[-0.8, 0.8\]$"):
        study.evaluate(x)
    with pytest.raises(ValueError):  # DesignVectorError is a ValueError too
        study.evaluate(x, allow_out_of_bounds=True)
    x[2] = 0.9
    with pytest.raises(aeroshape.DesignVectorError, match="'sweep' = 0.9 is outside"):
        study.evaluate(x)
    assert study.evaluate(x, allow_out_of_bounds=True).report["design"][2] == ["sweep", 0.9]
    with pytest.raises(TypeError, match="one-dimensional"):
        study.evaluate(np.zeros((2, n)))
    with pytest.raises(aeroshape.DesignVectorError, match="unknown design variable 'nope'"):
        study.vector({"nope": 1.0})


def test_missing_case_file_raises_the_program_message(cli, tmp_path):
    missing = tmp_path / "missing.ron"
    expected = cli_error(run_cli(cli, "run", missing, "-o", tmp_path / "o", ok=False))
    with pytest.raises(aeroshape.CaseError) as e:
        aeroshape.Study(missing)
    assert str(e.value) == expected
    assert str(missing) in str(e.value)


def test_bad_case_file_raises_the_program_message(cli, tmp_path):
    bad = tmp_path / "bad.ron"
    bad.write_text("(format_version: 1,\n geometry: 3)")
    expected = cli_error(run_cli(cli, "run", bad, "-o", tmp_path / "o", ok=False))
    with pytest.raises(aeroshape.CaseError) as e:
        aeroshape.Study(bad)
    assert str(e.value) == expected and str(e.value).startswith(f"{bad}:2:")


def test_write_refuses_an_input_and_unknown_formats(tmp_path, study):
    ev = study.evaluate(study.initial)
    with pytest.raises(ValueError, match="unknown format 'png'"):
        ev.write(tmp_path, formats=["png"])
    assert ev.write(tmp_path, formats=["vtu"]) == [str(tmp_path / "deformed.vtu")]
    (tmp_path / "f").write_text("")
    with pytest.raises(aeroshape.OutputError, match="cannot create the output folder"):
        ev.write(tmp_path / "f" / "sub")
    # A case whose grid is named like an output: writing beside it is refused, untouched.
    grid = tmp_path / "in" / "deformed.msh"
    grid.parent.mkdir()
    grid.write_bytes((SPHERE / "grid.msh").read_bytes())
    case = constrained_case(tmp_path / "in", "[]")
    case.write_text(case.read_text().replace(str(SPHERE / "grid.msh"), str(grid)))
    s = aeroshape.Study(case)
    with pytest.raises(aeroshape.OutputError, match="output would overwrite an input"):
        s.evaluate(s.initial + 0.01).write(grid.parent)
    assert grid.read_bytes() == (SPHERE / "grid.msh").read_bytes()
    assert sorted(p.name for p in grid.parent.iterdir()) == ["case.ron", "deformed.msh"]


def test_study_and_evaluate_release_the_gil():
    study = released(lambda: aeroshape.Study(CASE), repeat=1)
    x = study.read_design_vector(DV)

    def evaluate():
        study.forget_warm_start()
        study.evaluate(x)

    released(evaluate, repeat=20)


def test_progress_to_callback_and_logger(study, caplog):
    x = study.initial.copy()
    x[0] = 0.01
    calls = []
    study.evaluate(x, progress=lambda *a: calls.append(a))
    assert calls == [("param", 0, 4), ("model update", 1, 4), ("surface grid", 2, 4),
                     ("deform", 3, 4)]
    with caplog.at_level(logging.DEBUG, logger="aeroshape"):
        study.evaluate(x)
    assert [r.getMessage() for r in caplog.records if r.name == "aeroshape"] == [
        "evaluate: param (0/4)", "evaluate: model update (1/4)",
        "evaluate: surface grid (2/4)", "evaluate: deform (3/4)"]

    def boom(*_):
        raise RuntimeError("stop")

    with pytest.raises(RuntimeError, match="stop"):
        study.evaluate(x, progress=boom)


def test_warm_start_forgotten_gives_the_cold_result(study):
    x = study.initial.copy()
    x[study.names.index("sweep")] = 0.2
    study.forget_warm_start()
    cold = study.evaluate(x).volume_coordinates
    y = x.copy()
    y[study.names.index("twist")] = 0.03
    study.evaluate(y)  # the next solve would start from this one
    study.forget_warm_start()
    assert np.array_equal(study.evaluate(x).volume_coordinates, cold)
