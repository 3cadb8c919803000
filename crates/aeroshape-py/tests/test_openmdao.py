"""aeroshape.openmdao: inputs by name, outputs in MPhys's layout; the exact matrix-free
products against OpenMDAO's own finite differences (check_partials in both modes on the
default case, check_totals on the sphere); the finite-difference component consistent with
differences of Study.evaluate; design variables and linear constraints offered to the
driver; inverse design with exact gradients."""

from __future__ import annotations

import numpy as np
import openmdao.api as om
import pytest
from openmdao.utils.assert_utils import assert_check_partials, assert_check_totals

import aeroshape
from aeroshape.openmdao import Component, FdComponent, add_design_vars, add_linear_constraints
from conftest import DEFAULT, SPHERE, constrained_case, tight_case

CASE = SPHERE / "case.ron"
X = np.array([0.05, -0.03, 0.02, 0.04, -0.02, 0.03, 0.01, -0.04])


@pytest.fixture(scope="module")
def study() -> aeroshape.Study:
    return aeroshape.Study(CASE)


def problem(comp: Component) -> om.Problem:
    p = om.Problem(reports=False)
    p.model.add_subsystem("shape", comp, promotes_inputs=["*"])
    return p


def test_inputs_by_name_outputs_in_mphys_layout(study):
    p = problem(Component(case=str(CASE)))
    p.setup()
    p.run_model()
    assert np.array_equal(p.get_val("shape.x_aero0"), study.baseline_coordinates[study.wall_nodes].ravel())
    assert np.array_equal(p.get_val("shape.aero_vol_coords"), study.baseline_coordinates.ravel())
    for name, v in zip(study.names, X):
        p.set_val(name, v)
    p.run_model()
    study.forget_warm_start()
    ev = study.evaluate(X)
    wall = p.get_val("shape.x_aero0")
    assert wall.shape == (3 * len(study.wall_nodes),)
    assert np.array_equal(wall.reshape(-1, 3), ev.wall_coordinates)  # C order: x y z per node
    assert np.array_equal(p.get_val("shape.aero_vol_coords").reshape(-1, 3), ev.volume_coordinates)
    meta = p.model.shape.get_io_metadata(metadata_keys=["tags"])
    assert "mphys_coordinates" in meta["x_aero0"]["tags"]
    assert "mphys_coupling" in meta["aero_vol_coords"]["tags"]


def test_component_options(study):
    with pytest.raises(ValueError, match="exactly one of case=PATH or study=STUDY"):
        problem(Component()).setup()
    with pytest.raises(ValueError, match="exactly one"):
        problem(Component(case=str(CASE), study=study)).setup()
    p = problem(Component(study=study, wall_output="x_aero0_geometry_output", volume_output=None))
    p.setup()
    p.run_model()
    outs = [m["prom_name"] for _, m in p.model.list_outputs(out_stream=None, prom_name=True)]
    assert outs == ["shape.x_aero0_geometry_output"]


def test_fd_partials_are_differences_of_evaluate(study):
    """Column j of the finite-difference component's Jacobian is the central difference of
    Study.evaluate in variable j: the inputs reach the design vector by name, in the study's
    order."""
    p = problem(FdComponent(study=study, volume_output=None))
    p.setup()
    for name, v in zip(study.names, X):
        p.set_val(name, v)
    p.run_model()
    jac = p.compute_totals(of=["shape.x_aero0"], wrt=study.names)
    for j, (name, dv) in enumerate(zip(study.names, study.design_variables)):
        h = 1e-3 * dv.scale
        up, down = X.copy(), X.copy()
        up[j] += h
        down[j] -= h
        study.forget_warm_start()
        a = study.evaluate(up).wall_coordinates.ravel()
        study.forget_warm_start()
        b = study.evaluate(down).wall_coordinates.ravel()
        col = jac["shape.x_aero0", name].ravel()
        assert np.abs(col).max() > 0.1, name  # every variable moves the wall
        assert np.allclose(col, (a - b) / (2 * h), rtol=0, atol=1e-12), name


def test_check_partials_fd(study):
    p = problem(FdComponent(study=study))
    p.setup()
    for name, v in zip(study.names, X):
        p.set_val(name, v)
    p.run_model()
    # The declared partials (central differences, step 1e-4 here) against OpenMDAO's check
    # (central differences, step 3e-5): finite differences both, so this checks that the
    # outputs are smooth in the inputs down to the partials' accuracy.
    data = p.check_partials(out_stream=None, method="fd", form="central", step=3e-5,
                            step_calc="abs")
    assert_check_partials(data, atol=1e-5, rtol=1e-4)


@pytest.fixture(scope="module")
def default_study() -> aeroshape.Study:
    return aeroshape.Study(DEFAULT / "case.ron")


@pytest.fixture(scope="module")
def tight(tmp_path_factory) -> aeroshape.Study:
    """The sphere case with its deformation solved to 1e-12."""
    return aeroshape.Study(tight_case(tmp_path_factory.mktemp("tight")))


def steps(comp: Component, study: aeroshape.Study, fraction: float = 0.1) -> None:
    """check_partials' central differences with a step of ``fraction`` × scale per variable:
    above the chain's round-off (about 1e-10 m in the wall, so a step of 1e-5 scale would
    leave 1e-5 of noise in a thickness column) and below the curvature's scale (measured on
    the default case: 0.1 scale gives at most 4e-7 against the products, 0.3 scale 4e-6)."""
    for dv in study.design_variables:
        comp.set_check_partial_options(wrt=dv.name, method="fd", form="central",
                                       step=fraction * dv.scale, step_calc="abs")


def test_check_partials_exact_default_case(default_study):
    """The exact products, forward and reverse, against OpenMDAO's central differences on
    the default case at the design vector dv.ron, wall output (every reverse seed a wall
    row), at rel 1e-6; forward and reverse agree to round-off; every variable moves the
    wall."""
    study = default_study
    x = study.read_design_vector(DEFAULT / "dv.ron")
    comp = Component(study=study, volume_output=None)
    p = problem(comp)
    p.setup()
    steps(comp, study)
    for name, v in zip(study.names, x):
        p.set_val(name, v)
    p.run_model()
    data = p.check_partials(out_stream=None)
    assert_check_partials(data, atol=1e-6, rtol=1e-6)
    for (of, wrt), d in data["shape"].items():
        fwd, rev = d["J_fwd"], d["J_rev"]
        assert np.abs(fwd - rev).max() <= 1e-12 * np.abs(fwd).max(), wrt
        assert np.abs(fwd).max() > 0.1, f"{wrt} moves no wall node"


def test_check_partials_exact_volume(tight):
    """The volume output's products (one adjoint deformation per reverse seed) against
    central differences, both modes, on the sphere case solved to 1e-12."""
    comp = Component(study=tight)
    p = problem(comp)
    p.setup()
    steps(comp, tight, 0.01)  # the deformation curves more than the wall: measured, central
    # differences of the volume grid against the products at 0.1 / 0.03 / 0.01 / 0.003 scale:
    # 1.9e-5 / 1.7e-6 / 1.9e-7 / 5.4e-8 (truncation, h²)
    for name, v in zip(tight.names, X):
        p.set_val(name, v)
    p.run_model()
    data = p.check_partials(out_stream=None)
    assert_check_partials(data, atol=1e-6, rtol=1e-6)


def test_products_are_transposes_and_match_differences(tight):
    """<vjp(w), v> = <w, jvp(v)> for the volume and the wall; the products of Study and of a
    Linearisation agree; each column of the Jacobian is the central difference of evaluate;
    bad seeds raise."""
    study = tight
    rng = np.random.default_rng(7)
    lin = study.linearise(X)
    assert np.array_equal(lin.x, X)
    v = rng.standard_normal(len(X))
    w = rng.standard_normal((study.n_nodes, 3))
    jv = lin.jvp(v)
    assert jv.shape == (study.n_nodes, 3)
    lhs, rhs = lin.vjp(w) @ v, np.sum(w * jv)
    assert abs(lhs - rhs) <= 1e-10 * np.linalg.norm(w) * np.linalg.norm(jv)
    ww = rng.standard_normal((len(study.wall_nodes), 3))
    jvw = lin.jvp(v, wall=True)
    assert np.allclose(jvw, jv[study.wall_nodes], rtol=0, atol=1e-12)
    lhs, rhs = lin.vjp(wall_bar=ww) @ v, np.sum(ww * jvw)
    assert abs(lhs - rhs) <= 1e-12 * np.linalg.norm(ww) * np.linalg.norm(jvw)
    assert np.allclose(lin.vjp(w, wall_bar=ww), lin.vjp(w) + lin.vjp(wall_bar=ww), rtol=1e-12)
    assert np.array_equal(study.jvp(X, v), jv)
    assert np.array_equal(study.vjp(X, ww, wall=True), lin.vjp(wall_bar=ww))
    for j, dv in enumerate(study.design_variables):
        h = 0.01 * dv.scale
        e = np.zeros(len(X))
        e[j] = 1.0
        study.forget_warm_start()
        a = study.evaluate(X + h * e).volume_coordinates
        study.forget_warm_start()
        b = study.evaluate(X - h * e).volume_coordinates
        fd = (a - b) / (2 * h)
        col = lin.jvp(e)
        assert np.abs(col).max() > 0.1, dv.name  # the variable moves the grid
        assert np.linalg.norm(col - fd) <= 1e-6 * np.linalg.norm(fd), dv.name
    with pytest.raises(ValueError, match="dx has 3 values"):
        lin.jvp([1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="x_bar has 2 rows"):
        lin.vjp(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="wall_bar has"):
        lin.vjp(wall_bar=np.zeros((study.n_nodes + 1, 3)))
    with pytest.raises(aeroshape.DesignVectorError):
        study.linearise([np.nan] * len(X))


class Misfit(om.ExplicitComponent):
    """f = ½ |x_aero0 − target|² with exact partials."""

    def initialize(self):
        self.options.declare("target")

    def setup(self):
        t = self.options["target"]
        self.add_input("x_aero0", val=np.zeros_like(t))
        self.add_output("f")
        self.declare_partials("f", "x_aero0")

    def compute(self, inputs, outputs):
        r = inputs["x_aero0"] - self.options["target"]
        outputs["f"] = 0.5 * r @ r

    def compute_partials(self, inputs, partials):
        partials["f", "x_aero0"] = (inputs["x_aero0"] - self.options["target"]).reshape(1, -1)


def misfit_problem(study: aeroshape.Study) -> om.Problem:
    target = study.evaluate(X).wall_coordinates.ravel()
    p = om.Problem(reports=False)
    p.model.add_subsystem("shape", Component(study=study, volume_output=None),
                          promotes_inputs=["*"], promotes_outputs=["x_aero0"])
    p.model.add_subsystem("misfit", Misfit(target=target), promotes=["*"])
    add_design_vars(p.model, study)
    p.model.add_objective("f")
    return p


def test_check_totals_fd(study):
    p = misfit_problem(study)
    p.setup(mode="rev")
    for name, v in zip(study.names, 0.5 * X):
        p.set_val(name, v)
    p.run_model()
    data = p.check_totals(out_stream=None, method="fd", form="central", step=1e-6)
    assert_check_totals(data, atol=1e-8, rtol=1e-6)
    grad = p.compute_totals()
    assert all(abs(float(g.ravel()[0])) > 1e-6 for g in grad.values())


def test_design_vars_offered_with_bounds_and_scales(study):
    p = misfit_problem(study)
    p.setup()
    dvs = p.model.get_design_vars(use_prom_ivc=True)
    assert list(dvs) == study.names
    for d in study.design_variables:
        m = dvs[d.name]
        assert (m["lower"], m["upper"]) == (d.lower, d.upper)
        assert m["total_scaler"] == pytest.approx(1 / d.scale)  # the driver sees value / scale


def test_linear_constraints_helper(tmp_path):
    case = constrained_case(tmp_path, '[(name: "px sum", coefficients: {"px_11": 1.0, "px_22": 2.0}, rhs: 0.1),'
                                      ' (name: "pz", coefficients: {"pz_12": -1.0}, rhs: 0.05)]')
    study = aeroshape.Study(case)
    p = problem(Component(study=study))
    add_design_vars(p.model, study)
    assert add_linear_constraints(p.model, study) == "shape_constraints.g"
    p.setup()
    for name, v in zip(study.names, X):
        p.set_val(name, v)
    p.run_model()
    con = p.model.get_constraints()["shape_constraints.g"]
    assert con["linear"] is True and np.array_equal(con["upper"], study.constraints.b)
    assert np.allclose(p.get_val("shape_constraints.g"), study.constraints.a @ X, rtol=0, atol=1e-15)
    data = p.check_partials(out_stream=None, includes=["shape_constraints"], method="fd")
    assert_check_partials(data, atol=1e-9, rtol=1e-9)  # the partials are exact: a
    assert add_linear_constraints(om.Group(), aeroshape.Study(CASE)) is None


def test_inverse_design_recovers_a_hidden_vector(study):
    """SLSQP with the exact gradients recovers a hidden design vector of the sphere case
    from its wall shape (the default case's version is examples/inverse_design.py)."""
    p = misfit_problem(study)
    p.driver = om.ScipyOptimizeDriver(optimizer="SLSQP", tol=1e-14, maxiter=60, disp=False)
    p.setup()
    p.run_driver()
    x = np.array([p.get_val(n)[0] for n in study.names])
    assert np.abs(x - X).max() < 1e-6, x - X
