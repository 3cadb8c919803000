"""Between aeroshape's grid and OpenFOAM's polyMesh: the point mapping, the points file of a
design, and the adjoint's wall sensitivities as the seed of aeroshape's reverse product.

ESI v1912's E-SI point sensitivities (`surfacePoints`) on a wall point p, with S_p = Σ |S_f|
over the wall faces around p (all of each face, not a share of it):
- includeSurfaceArea false (v1912's default): pointSensVec_p = (dJ/dx_p) / S_p;
- includeSurfaceArea true: pointSensVec_p = dJ/dx_p;
and pointSensNormal_p = pointSensVec_p · n_p (n_p the normalised sum of the unit face normals,
out of the fluid), pointSensNormalVec_p = pointSensNormal_p n_p (`sensitivitySurfacePoints`
in src/optimisation/adjointOptimisation). The seed of aeroshape's vjp is dJ/dx_p per wall
node: `kind="normal"` takes the normal part only (what continuous-adjoint theory says
matters: tangential motion does not change the shape), `kind="vector"` the whole vector.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


class MappingError(RuntimeError):
    """The polyMesh and the aeroshape grid do not hold the same points."""


def point_mapping(grid_xyz: np.ndarray, foam_xyz: np.ndarray, tol: float) -> np.ndarray:
    """foam_index[node]: the polyMesh point at each grid node, within `tol` (a bijection)."""
    if len(grid_xyz) != len(foam_xyz):
        raise MappingError(f"{len(grid_xyz)} grid nodes but {len(foam_xyz)} polyMesh points")
    d, idx = cKDTree(foam_xyz).query(grid_xyz)
    worst = int(np.argmax(d))
    if d[worst] > tol:
        raise MappingError(f"grid node {worst} is {d[worst]:.3e} from every polyMesh point "
                           f"(tolerance {tol:.1e})")
    if len(np.unique(idx)) != len(idx):
        raise MappingError("two grid nodes map to one polyMesh point")
    return idx


def foam_points(volume_xyz: np.ndarray, foam_index: np.ndarray) -> np.ndarray:
    """The polyMesh `points` of a deformed grid."""
    out = np.empty_like(volume_xyz)
    out[foam_index] = volume_xyz
    return out


def wall_bar(study, sens, *, kind: str = "normal", area_included: bool = False,
             foam_index: np.ndarray | None = None) -> np.ndarray:
    """dJ/dx of every wall node of `study` (n_wall × 3, `study.wall_nodes` order) from the
    point sensitivities `sens` (foamcase.Sensitivity)."""
    per_area = {"normal": sens.normal_vector, "vector": sens.vector}[kind]
    d = per_area if area_included else per_area * sens.area[:, None]
    wall = np.asarray(study.wall_nodes)
    foam = wall if foam_index is None else foam_index[wall]
    row = {int(p): i for i, p in enumerate(sens.wall_points)}
    missing = [int(n) for n, p in zip(wall, foam) if int(p) not in row]
    if missing:
        raise MappingError(f"wall node {missing[0]} is not on the OpenFOAM wall patch "
                           f"({len(missing)} such nodes)")
    return d[[row[int(p)] for p in foam]]
