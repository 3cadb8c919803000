"""read_mesh / write_mesh on an SU2 grid the project did not make, checked against meshio;
Mesh built from arrays; bad grids raise."""

from __future__ import annotations

import meshio
import numpy as np
import pytest

import aeroshape
from conftest import DEFAULT, cli_error, run_cli


@pytest.fixture(scope="module")
def brick(data):
    return data / "su2" / "mesh_brick_tets_ffd.su2"


def meshio_markers(m: meshio.Mesh) -> list[np.ndarray]:
    """meshio's SU2 boundary triangles split by their tag (1, 2, ... in file order)."""
    blocks = [(c, t) for c, t in zip(m.cells, m.cell_data["su2:tag"]) if c.type == "triangle"]
    assert len(blocks) == 1
    tri, tags = blocks[0][0].data, blocks[0][1]
    return [tri[tags == k] for k in range(1, int(tags.max()) + 1)]


def test_read_su2_as_meshio_reads_it(brick):
    ours = aeroshape.read_mesh(brick)
    theirs = meshio.read(brick)
    assert ours.dim == 3 and ours.n_nodes == 11703 and ours.n_cells == 59156
    assert np.array_equal(ours.coordinates, theirs.points)
    assert np.array_equal(ours.cells["tetra"], theirs.cells_dict["tetra"])
    assert list(ours.markers) == ["x_m", "x_p", "y_m", "y_p", "z_m", "z_p"]
    for ours_tri, theirs_tri in zip(ours.markers.values(), meshio_markers(theirs)):
        assert list(ours_tri) == ["triangle"]
        assert np.array_equal(ours_tri["triangle"], theirs_tri)
    assert any("FFD" in w or "kept" in w for w in ours.warnings) or ours.warnings == []
    q = ours.cell_quality()
    assert q.shape == (59156,) and 0.56 < q.min() < 0.57  # docs/cli.md: min 0.5666


@pytest.mark.parametrize("ext", ["su2", "msh", "vtu"])
def test_round_trip_through_meshio(brick, tmp_path, ext):
    m = aeroshape.read_mesh(brick)
    out = tmp_path / f"brick.{ext}"
    aeroshape.write_mesh(out, m)
    back = aeroshape.read_mesh(out)
    assert np.array_equal(back.coordinates, m.coordinates)
    assert np.array_equal(back.cells["tetra"], m.cells["tetra"])
    assert {k: v["triangle"].tolist() for k, v in back.markers.items()} == {
        k: v["triangle"].tolist() for k, v in m.markers.items()}
    theirs = meshio.read(out)  # an independent reader of what we wrote
    assert np.array_equal(theirs.points, m.coordinates)
    assert np.array_equal(theirs.cells_dict["tetra"], m.cells["tetra"])


def test_write_mesh_is_mesh_convert(cli, brick, tmp_path):
    run_cli(cli, "mesh", "convert", brick, tmp_path / "cli.msh", "--binary")
    aeroshape.write_mesh(tmp_path / "py.msh", aeroshape.read_mesh(brick), binary=True)
    assert (tmp_path / "cli.msh").read_bytes() == (tmp_path / "py.msh").read_bytes()


def test_msh_classification_and_coordinates_setter():
    m = aeroshape.read_mesh(DEFAULT / "grid.msh")
    c = m.node_classes
    assert c is not None and m.parametric
    assert c["dim"].shape == (m.n_nodes,) and c["param"].shape == (m.n_nodes, 2)
    assert set(np.unique(c["dim"])) <= {0, 1, 2, 3}
    coords = m.coordinates
    with pytest.raises(ValueError, match="read-only"):
        coords[0, 0] = 1.0
    m2 = m.copy()
    m2.coordinates = coords + 1.0
    assert np.array_equal(m2.coordinates, coords + 1.0)
    assert np.array_equal(m.coordinates, coords)  # the copy is independent
    with pytest.raises(ValueError, match="rows for a grid of"):
        m2.coordinates = coords[:-1]
    bad = coords.copy()
    bad[7, 1] = np.inf
    with pytest.raises(ValueError, match="node 7 has a non-finite coordinate"):
        m2.coordinates = bad


def test_mesh_from_arrays_and_bad_grids(tmp_path):
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    m = aeroshape.Mesh(pts, {"tetra": [[0, 1, 2, 3]]}, {"wall": {"triangle": [[0, 2, 1]]}})
    assert m.n_nodes == 4 and m.cell_quality()[0] == pytest.approx(0.8399, abs=1e-4)
    aeroshape.write_mesh(tmp_path / "t.su2", m)
    assert aeroshape.read_mesh(tmp_path / "t.su2").markers["wall"]["triangle"].tolist() == [[0, 2, 1]]
    with pytest.raises(aeroshape.MeshError, match="refers to node 9"):
        aeroshape.Mesh(pts, {"tetra": [[0, 1, 2, 9]]})
    with pytest.raises(ValueError, match="unknown element kind 'tet'"):
        aeroshape.Mesh(pts, {"tet": [[0, 1, 2, 3]]})
    with pytest.raises(ValueError, match="3 nodes per element; a tetra has 4"):
        aeroshape.Mesh(pts, {"tetra": [[0, 1, 2]]})
    with pytest.raises(aeroshape.OutputError, match="unknown output format"):
        aeroshape.write_mesh(tmp_path / "t.txt", m)


def test_bad_file_raises_the_program_message(cli, tmp_path):
    bad = tmp_path / "bad.su2"
    bad.write_text("NDIME= 3\nNELEM= 1\n10 0 1 2\n")
    expected = cli_error(run_cli(cli, "mesh", "info", bad, ok=False))
    with pytest.raises(aeroshape.MeshError) as e:
        aeroshape.read_mesh(bad)
    assert str(e.value) == expected and str(bad) in expected
