"""section_fit / section_build on UIUC airfoils: the same numbers and files as
``aeroshape section fit|build``, file and array input alike."""

from __future__ import annotations

import json

import numpy as np
import pytest

import aeroshape
from conftest import cli_error, run_cli


@pytest.mark.parametrize("name", ["naca2412", "rae2822"])
def test_fit_is_aeroshape_section_fit(cli, data, tmp_path, name):
    dat = data / "airfoils" / f"{name}.dat"
    r = run_cli(cli, "section", "fit", dat, "--json", "--out", tmp_path / "cli.dat",
                "--params", tmp_path / "params.ron")
    fit = aeroshape.section_fit(dat)
    assert fit.as_dict() == json.loads(r.stdout)
    assert fit.max_error < 2e-3 and fit.rms_error < fit.max_error
    assert fit.thickness["tmax"] == pytest.approx(0.12 if name == "naca2412" else 0.121, abs=3e-3)
    aeroshape.write_section(tmp_path / "py.dat", fit.coordinates(), fit.fitted_name)
    assert (tmp_path / "cli.dat").read_bytes() == (tmp_path / "py.dat").read_bytes()
    # section build from the PARAMS.ron the program wrote, from the fit and from its dict
    run_cli(cli, "section", "build", tmp_path / "params.ron", "-o", tmp_path / "built.dat")
    for params in (tmp_path / "params.ron", fit, fit.params()):
        pts = aeroshape.section_build(params)
        assert pts.shape == (241, 2)
        aeroshape.write_section(tmp_path / "b.dat", pts, fit.params()["name"] or "aeroshape section")
        assert (tmp_path / "b.dat").read_bytes() == (tmp_path / "built.dat").read_bytes()


def test_fit_of_points_equals_fit_of_file(data):
    dat = data / "airfoils" / "e387.dat"
    pts = np.loadtxt(dat, skiprows=1)
    a = aeroshape.section_fit(dat, camber_points=6, thickness_extra=1)
    b = aeroshape.section_fit(pts, camber_points=6, thickness_extra=1, name=a.name)
    da, db = a.as_dict(), b.as_dict()
    assert da == db
    assert a.thickness_extra.shape == (1, 2) and a.camber.shape == (6, 2)
    assert np.abs(a.distances).max() == pytest.approx(a.max_error)


def test_bad_input_raises(cli, tmp_path):
    bad = tmp_path / "bad.dat"
    bad.write_text("bad\n0 0\n1 nan\n")
    expected = cli_error(run_cli(cli, "section", "fit", bad, ok=False))
    with pytest.raises(aeroshape.SectionError) as e:
        aeroshape.section_fit(bad)
    assert str(e.value) == expected
    missing = tmp_path / "missing.dat"
    expected = cli_error(run_cli(cli, "section", "fit", missing, ok=False))
    with pytest.raises(aeroshape.SectionError) as e:
        aeroshape.section_fit(missing)
    assert str(e.value) == expected
    with pytest.raises(ValueError, match="at least 100 per surface"):
        aeroshape.section_build({"thickness": {}, "camber": []}, points=50)
    with pytest.raises(ValueError, match="missing field"):
        aeroshape.section_build({"camber": [[0, 0], [1, 0]]})
