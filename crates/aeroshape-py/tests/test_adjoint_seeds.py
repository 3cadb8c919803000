"""Reverse products that converge for any seed (issue 44) on the default case: the seeds
OpenMDAO's ``check_partials`` asks for in reverse mode (one output entry each, in a row, each
adjoint solve warm-started from the previous one's solution, the case's default), a dense
seed and a wall-only seed; each passes the dot-product test against the forward product.
Before the fix, a single-entry seed on a symmetry-plane node's normal component (zero once
projected) after any other seed stopped with "adjoint of Eq. 21: solver pcg-amg did not
converge in 30 iterations (relative residual 1.7e-2)"; one seed in seven of a random draw
failed so.
"""

from __future__ import annotations

import os

import numpy as np
import openmdao.api as om
import pytest
from openmdao.utils.assert_utils import assert_check_partials

import aeroshape
from aeroshape.openmdao import Component
from conftest import DEFAULT, ROOT


def default_case(tmp, deform: str | None = None):
    """A copy of the default case (absolute paths), with ``deform: (...)`` if given."""
    text = (DEFAULT / "case.ron").read_text()
    text = text.replace('geometry: "wing_body.ron"', f'geometry: "{(DEFAULT / "wing_body.ron").as_posix()}"')
    text = text.replace('grid: "grid.msh"', f'grid: "{(DEFAULT / "grid.msh").as_posix()}"')
    anchor = '  fixed: ["farfield"],\n'
    assert anchor in text, "layout of fixtures/cases/default/case.ron changed"
    if deform is not None:
        text = text.replace(anchor, anchor + f"  deform: ({deform}),\n")
    p = tmp / "case.ron"
    p.write_text(text)
    return p


@pytest.fixture(scope="module")
def tight(tmp_path_factory) -> aeroshape.Study:
    """The default case with its deformation and products solved to 1e-12."""
    return aeroshape.Study(default_case(tmp_path_factory.mktemp("tight"), "rel_tol: 1e-12"))


def test_any_seed_converges_and_passes_the_dot_product_test(tight):
    study = tight
    x = study.read_design_vector(DEFAULT / "dv.ron")
    lin = study.linearise(x)
    n = study.n_nodes
    rng = np.random.default_rng(44)
    v = rng.standard_normal(len(x))
    jv = lin.jvp(v)
    wall = np.zeros(n, dtype=bool)
    wall[study.wall_nodes] = True
    x0 = study.baseline_coordinates
    sym = np.flatnonzero((np.abs(x0[:, 1]) < 1e-12) & ~wall)
    inner = np.flatnonzero((np.abs(x0[:, 1]) > 1e-9) & ~wall)
    assert len(sym) > 10 and len(inner) > 100
    seeds = [("dense", np.sin(x0 * [2.0, 1.0, 3.0]))]
    wall_only = np.zeros((n, 3))
    wall_only[wall] = [1.0, -0.5, 0.25]
    seeds.append(("wall only, as a volume seed", wall_only))
    for k, i in enumerate(rng.choice(inner, 12, replace=False)):
        s = np.zeros((n, 3))
        s[i, k % 3] = 1.0
        seeds.append((f"single {'xyz'[k % 3]} at node {i}", s))
        j = sym[k % len(sym)]
        s = np.zeros((n, 3))
        s[j, 1] = 1.0  # the symmetry plane's normal: zero once projected
        seeds.append((f"symmetry normal at node {j}", s))
    for name, s in seeds:
        g = lin.vjp(s)  # raised before the fix
        lhs, rhs = g @ v, np.sum(s * jv)
        scale = np.linalg.norm(v) * np.linalg.norm(g) + np.linalg.norm(s) * np.linalg.norm(jv)
        assert abs(lhs - rhs) <= 1e-10 * scale, (name, lhs, rhs)
    # The wall-only seed given as a wall seed: the same gradient, no deformation solve.
    g_vol = lin.vjp(wall_only)
    g_wall = lin.vjp(wall_bar=wall_only[study.wall_nodes])
    assert np.allclose(g_vol, g_wall, rtol=1e-9, atol=1e-12 * np.abs(g_wall).max())


@pytest.mark.skipif(os.environ.get("AEROSHAPE_SLOW") != "1",
                    reason="one adjoint solve per volume output entry (12k): AEROSHAPE_SLOW=1")
def test_check_partials_volume_both_modes_default_case(tight):
    """OpenMDAO's check_partials on the default case's full volume output, forward and
    reverse (one reverse product per output entry, warm-started in a row), at 1e-6."""
    study = tight
    comp = Component(study=study)
    p = om.Problem(reports=False)
    p.model.add_subsystem("shape", comp, promotes_inputs=["*"])
    p.setup()
    # Steps per column. At 0.01 × scale the thickness columns' differences carry the
    # chain's round-off (measured: 4.7e-6 and 2.8e-6 absolute off the products), so they
    # take 0.1 × scale. The others take 0.01 × scale: at 0.1 the differences' truncation
    # error (h²) is above 1e-6 (measured, max abs off the forward product at 0.1 / 0.03 /
    # 0.01 × scale: taper 4.0e-6 / 3.6e-7 / 4.3e-8, droop_bottom 3.5e-6 / 3.1e-7 / 3.6e-8).
    for dv in study.design_variables:
        frac = 0.1 if dv.name.startswith("thick") else 0.01
        comp.set_check_partial_options(wrt=dv.name, method="fd", form="central",
                                       step=frac * dv.scale, step_calc="abs")
    for name, val in zip(study.names, study.read_design_vector(DEFAULT / "dv.ron")):
        p.set_val(name, val)
    p.run_model()
    data = p.check_partials(out_stream=None)
    assert_check_partials(data, atol=1e-6, rtol=1e-6)
