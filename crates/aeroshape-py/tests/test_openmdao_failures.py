"""A failed evaluation is a signal an optimiser can use (issue 44): in the OpenMDAO
component an :class:`aeroshape.EvaluationError` (here inverted cells, a point of the default
case's box that fails) is ``openmdao.api.AnalysisError``, so a driver that handles it records
the point as failed and goes on, and the next point evaluates as if nothing had failed."""

from __future__ import annotations

import numpy as np
import openmdao.api as om
import pytest

import aeroshape
from aeroshape.openmdao import Component, add_design_vars
from conftest import DEFAULT


@pytest.fixture(scope="module")
def study() -> aeroshape.Study:
    return aeroshape.Study(DEFAULT / "case.ron")


def failing_point(study: aeroshape.Study) -> np.ndarray:
    """The first of the uniform draws (seed 0) in the default case's box whose deformation
    inverts a cell (measured: "deform: 1 inverted cells after 16 increments")."""
    lo = np.array([d.lower for d in study.design_variables])
    hi = np.array([d.upper for d in study.design_variables])
    return lo + (hi - lo) * np.random.default_rng(0).random(len(lo))


def test_evaluation_error_is_an_analysis_error(study):
    x = failing_point(study)
    with pytest.raises(aeroshape.EvaluationError, match="inverted cells"):
        study.evaluate(x)
    p = om.Problem(reports=False)
    p.model.add_subsystem("shape", Component(study=study, volume_output=None),
                          promotes_inputs=["*"])
    p.setup()
    for name, v in zip(study.names, x):
        p.set_val(name, v)
    with pytest.raises(om.AnalysisError, match="inverted cells") as info:
        p.run_model()
    assert isinstance(info.value.__cause__, aeroshape.EvaluationError)
    assert "shape: deform:" in str(info.value) and f"twist = {x[0]:.6g}" in str(info.value)


def test_a_driver_survives_a_failing_point(study, tmp_path, capsys):
    x_bad = failing_point(study)
    x_ok = 0.3 * x_bad
    p = om.Problem(reports=False)
    p.model.add_subsystem("shape", Component(study=study, volume_output=None),
                          promotes_inputs=["*"], promotes_outputs=["x_aero0"])
    add_design_vars(p.model, study, scaled=False)
    p.model.add_objective("x_aero0", index=0)
    cases = [list(zip(study.names, x)) for x in (np.zeros(len(x_ok)), x_bad, x_ok)]
    p.driver = om.DOEDriver(om.ListGenerator(cases))
    rec = tmp_path / "cases.sql"
    p.driver.add_recorder(om.SqliteRecorder(str(rec)))
    p.setup()
    p.run_driver()
    p.cleanup()
    # DOEDriver prints the traceback of any other exception; an AnalysisError it takes as
    # a failed case, silently.
    assert "Traceback" not in capsys.readouterr().out
    reader = om.CaseReader(str(rec))
    got = [reader.get_case(c) for c in reader.list_cases("driver", out_stream=None)]
    assert len(got) == 3  # the driver went on after the failed point
    # The failed point left the outputs as they were (the baseline's).
    assert np.array_equal(got[1].get_val("x_aero0"), got[0].get_val("x_aero0"))
    assert np.array_equal(got[0].get_val("x_aero0"),
                          study.baseline_coordinates[study.wall_nodes].ravel())
    # The point after the failure is the study's own evaluation of it, bit for bit.
    study.forget_warm_start()
    ev = study.evaluate(x_ok)
    assert np.array_equal(got[2].get_val("x_aero0"), ev.wall_coordinates.ravel())
