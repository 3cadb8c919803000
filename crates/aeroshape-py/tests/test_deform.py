"""deform: the same grid as ``aeroshape deform`` bit for bit (with a reach of R too), a rigid
motion of the whole boundary moving every node rigidly, displacements as arrays, bad options
raising."""

from __future__ import annotations

import numpy as np
import pytest

import aeroshape
from conftest import released, run_cli

MARKERS = ["x_m", "x_p", "y_m", "y_p", "z_m", "z_p"]


@pytest.fixture(scope="module")
def brick(data):
    return aeroshape.read_mesh(data / "su2" / "mesh_brick_tets_ffd.su2")


def test_deform_is_aeroshape_deform_bit_for_bit(cli, data, brick, tmp_path):
    src = data / "su2" / "mesh_brick_tets_ffd.su2"
    args = ["--rigid", "z_p", "--rotate-deg", "4", "--axis-point", "0.5,0.5,0.5",
            "--axis-dir", "1,0,0", "--translate", "0,0,0.02", "--slide", "x_m",
            "--fixed", "z_m", "--report", tmp_path / "r.json"]
    run_cli(cli, "deform", src, "-o", tmp_path / "cli.su2", *args)
    d = aeroshape.deform(brick, rigid=["z_p"], rotate_deg=4, axis_point=(0.5, 0.5, 0.5),
                         axis_dir=(1, 0, 0), translate=(0, 0, 0.02), slide=["x_m"],
                         fixed=["z_m"])
    aeroshape.write_mesh(tmp_path / "py.su2", d.mesh)
    assert (tmp_path / "cli.su2").read_bytes() == (tmp_path / "py.su2").read_bytes()
    assert np.array_equal(d.coordinates, d.mesh.coordinates)
    assert d.report["iterations"] > 0 and d.report["residual"] < 1e-8
    assert d.cell_quality.min() > 0


def test_rotation_reach_is_the_programs(cli, data, brick, tmp_path):
    """``rotation_reach=L`` is ``--rotation-reach L`` bit for bit; it changes the grid, and
    ``inf`` is the default (R everywhere) bit for bit."""
    src = data / "su2" / "mesh_brick_tets_ffd.su2"
    kw = dict(rigid=["z_p"], rotate_deg=2, axis_point=(0.5, 0.5, 0.5), axis_dir=(1, 0, 0),
              fixed=["z_m"])
    run_cli(cli, "deform", src, "-o", tmp_path / "cli.su2", "--rigid", "z_p", "--rotate-deg", "2",
            "--axis-point", "0.5,0.5,0.5", "--axis-dir", "1,0,0", "--fixed", "z_m",
            "--rotation-reach", "0.2")
    near = aeroshape.deform(brick, rotation_reach=0.2, **kw)
    aeroshape.write_mesh(tmp_path / "py.su2", near.mesh)
    assert (tmp_path / "cli.su2").read_bytes() == (tmp_path / "py.su2").read_bytes()
    full = aeroshape.deform(brick, **kw)
    assert np.array_equal(aeroshape.deform(brick, rotation_reach=np.inf, **kw).coordinates,
                          full.coordinates)
    moved = np.linalg.norm(full.coordinates - brick.coordinates, axis=1).max()
    assert np.linalg.norm(near.coordinates - full.coordinates, axis=1).max() > 1e-3 * moved


def test_rigid_motion_of_the_whole_boundary_moves_every_node_rigidly(brick):
    t = np.array([0.1, -0.05, 0.2])
    d = aeroshape.deform(brick, rigid=MARKERS, translate=t, tolerance=1e-12)
    assert np.allclose(d.coordinates, brick.coordinates + t, rtol=0, atol=1e-11)
    # rotation by 10° about z through the centre: every node rotates (R of Eq. 26 keeps it)
    c = np.array([0.5, 0.5, 0.5])
    a = np.radians(10)
    rot = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    d = aeroshape.deform(brick, rigid=MARKERS, rotate_deg=10, axis_point=c, tolerance=1e-12)
    expected = (brick.coordinates - c) @ rot.T + c
    assert np.allclose(d.coordinates, expected, rtol=0, atol=1e-11)
    assert np.allclose(d.cell_quality, brick.cell_quality(), rtol=0, atol=1e-11)


def test_displacements_as_arrays_or_mapping(brick):
    nodes = np.unique(np.concatenate([brick.markers[m]["triangle"].ravel() for m in MARKERS]))
    disp = np.tile([0.0, 0.0, 0.05], (len(nodes), 1))
    a = aeroshape.deform(brick, displacements=(nodes, disp))
    b = aeroshape.deform(brick, displacements={int(n): (0.0, 0.0, 0.05) for n in nodes})
    assert np.array_equal(a.coordinates, b.coordinates)
    assert np.allclose(a.coordinates, brick.coordinates + [0, 0, 0.05], rtol=0, atol=1e-9)


def test_bad_options_raise(brick):
    with pytest.raises(ValueError, match="need a marker to move"):
        aeroshape.deform(brick, translate=(1, 0, 0))
    with pytest.raises(ValueError, match='solver "cg"'):
        aeroshape.deform(brick, rigid=["z_p"], solver="cg")
    with pytest.raises(ValueError, match="node 99999 does not exist"):
        aeroshape.deform(brick, displacements={99999: (0, 0, 1)})
    with pytest.raises(ValueError, match="node 3 given twice"):
        aeroshape.deform(brick, displacements=([3, 3], [[0, 0, 1], [0, 0, 1]]))
    for bad in (-1.0, float("nan")):
        with pytest.raises(ValueError, match="rotation_reach"):
            aeroshape.deform(brick, rigid=["z_p"], rotate_deg=2, rotation_reach=bad)
    with pytest.raises(ValueError, match="no_rotation"):
        aeroshape.deform(brick, rigid=["z_p"], rotate_deg=2, no_rotation=True, rotation_reach=1.0)
    with pytest.raises(aeroshape.DeformError, match="nope"):
        aeroshape.deform(brick, rigid=["nope"], translate=(0, 0, 0.1))


def test_deform_releases_the_gil(brick):
    released(lambda: aeroshape.deform(brick, rigid=["z_p"], translate=(0, 0, 0.02)), repeat=3)
