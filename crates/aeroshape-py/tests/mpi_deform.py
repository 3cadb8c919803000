"""Run under ``mpirun -n N python mpi_deform.py GRID`` by ``test_distributed.py``: the
distributed deformation through mpi4py against the serial ``aeroshape.deform`` on rank 0.

1. The grid file on rank 0, partitioned by METIS; then the grid as a ``Mesh`` on rank 0,
   partitioned by coordinate bisection. Motion and flags of ``cargo xtask regress``'s MPI
   test (the wing and fuselage pitched 2°, the symmetry plane sliding).
2. Each rank's own part, cut here by slabs of x (owned nodes, then the ghosts of the cells
   around them, the boundary elements of its nodes), rigid and fixed markers only: the wing
   and fuselage lifted by 0.05 (without the sliding plane, the pitch above inverts a cell
   at the wing root even serially); then pitched by 1° with a reach of R, against the serial
   result with the same reach.
3. Bad arguments on one rank only: every rank raises, nobody hangs.
4. One set-up, two designs (``distributed.Deformer``): the wing and fuselage nodes displaced
   (a lift growing along x), first by one amount, then by another through ``deform`` on the
   same set-up; the second design must equal a new set-up's result bit for bit, differ from
   the first, and lie within 1e-8 of the serial result; with the grid on rank 0 (the
   symmetry plane sliding) and with given parts. A list naming other nodes raises on every
   rank, and the deformer still works after it.

Rank 0 prints one ``result`` line per check and exits 1 when one failed (after every
collective call, so no rank is left waiting); an unexpected exception aborts the job.
"""

from __future__ import annotations

import sys

import numpy as np
from mpi4py import MPI

import aeroshape
from aeroshape import distributed

REL = 1e-8
KW = dict(rigid=["wing", "fuselage"], rotate_deg=2.0, axis_point=(5, 0, 0), axis_dir=(0, 1, 0),
          tolerance=1e-11)


def deviation(x, serial, x0):
    return np.abs(np.linalg.norm(x - serial, axis=1)).max() / np.linalg.norm(serial - x0, axis=1).max()


def part(mesh, rank, size):
    """This rank's slab of x: owned nodes, ghosts, the cells with an owned node, the marker
    elements whose nodes are all local; global ids are the grid's node indices."""
    x = mesh.coordinates
    cuts = np.quantile(x[:, 0], np.linspace(0, 1, size + 1)[1:-1])
    owner = np.searchsorted(cuts, x[:, 0], side="right")
    owned = np.flatnonzero(owner == rank)
    cells = {}
    touched = []
    for kind, c in mesh.cells.items():
        keep = c[(owner[c] == rank).any(axis=1)]
        cells[kind] = keep
        touched.append(keep.ravel())
    ghosts = np.setdiff1d(np.unique(np.concatenate(touched)), owned)
    gids = np.concatenate([owned, ghosts])
    local = np.full(len(x), -1)
    local[gids] = np.arange(len(gids))
    markers = {}
    for name, sets in mesh.markers.items():
        markers[name] = {k: local[e[(local[e] >= 0).all(axis=1)]] for k, e in sets.items()}
    m = aeroshape.Mesh(x[gids], {k: local[c] for k, c in cells.items()}, markers)
    return m, gids, len(owned)


def main() -> int:
    comm = MPI.COMM_WORLD
    rank, size = comm.Get_rank(), comm.Get_size()
    grid = sys.argv[1]
    mesh = aeroshape.read_mesh(grid)
    x0 = mesh.coordinates
    failed = []

    def check(name, ok, text):
        if rank == 0:
            print(f"result {name}: {text}", flush=True)
            if not ok:
                failed.append(name)

    # 1. The grid on rank 0: METIS from the file, bisection from a Mesh.
    slide = dict(KW, slide=["symmetry"])
    s = aeroshape.deform(mesh, **slide) if rank == 0 else None
    serial = s.coordinates if rank == 0 else None
    for name, arg, how in [("file-metis", grid, "metis"), ("mesh-rcb", mesh, "rcb")]:
        d = distributed.deform(comm, arg if rank == 0 else None, partition=how, **slide)
        r = d.report
        if rank == 0:
            dev = deviation(d.coordinates, serial, x0)
            # The far field over the ranks: the serial one's nodes, node and distance.
            fs, fd = s.report["far_field"], r["far_field"]
            far = fd is not None and all(fs[k] == fd[k] for k in ("nodes", "node", "distance"))
            far = far and abs(fs["max_displacement"] - fd["max_displacement"]) <= REL * fs[
                "wall_max_displacement"]
            ok = dev <= REL and r["partitioner"] == how and r["ranks"] == size and far
            check(name, ok, f"deviation {dev:.2e}, partitioner {r['partitioner']}, "
                  f"{r['ghost_nodes']} ghost nodes, {r['iterations']} + {r['rotation_iterations']} iterations, "
                  f"far field {fd} (serial {fs})")
        # every rank's own nodes at the gathered grid's positions
        xs = comm.bcast(d.coordinates if rank == 0 else None)
        local_ok = np.array_equal(d.local_coordinates[: d.n_owned], xs[d.global_ids[: d.n_owned]])
        check(f"{name}-local", all(comm.allgather(local_ok)), "owned nodes as gathered")

    # 2. Each rank's own part (rigid and fixed markers only).
    lift = dict(rigid=["wing", "fuselage"], translate=(0, 0, 0.05), tolerance=1e-11)
    s = aeroshape.deform(mesh, **lift) if rank == 0 else None
    serial = s.coordinates if rank == 0 else None
    m, gids, n_owned = part(mesh, rank, size)
    d = distributed.deform(comm, m, global_ids=gids, n_owned=n_owned, **lift)
    if rank == 0:
        dev = deviation(d.coordinates, serial, x0)
        # The far field: each owner finds the moving boundary among its own nodes.
        fs, fd = s.report["far_field"], d.report["far_field"]
        far = fd is not None and fs["nodes"] > 0 and all(
            fs[k] == fd[k] for k in ("nodes", "node", "distance"))
        far = far and abs(fs["max_displacement"] - fd["max_displacement"]) <= REL * fs[
            "wall_max_displacement"]
        check("given", dev <= REL and d.report["partitioner"] == "given" and far,
              f"deviation {dev:.2e}, {d.report['ghost_nodes']} ghost nodes, "
              f"far field {fd} (serial {fs})")
    # The reach of R on the given part: each owner finds the moving boundary among its nodes.
    tilt = dict(rigid=["wing", "fuselage"], rotate_deg=1.0, axis_point=(5, 0, 0),
                axis_dir=(0, 1, 0), fixed=["symmetry"], tolerance=1e-11)
    reach = 2.0
    sn = aeroshape.deform(mesh, rotation_reach=reach, **tilt).coordinates if rank == 0 else None
    sf = aeroshape.deform(mesh, **tilt).coordinates if rank == 0 else None
    d = distributed.deform(comm, m, global_ids=gids, n_owned=n_owned, rotation_reach=reach, **tilt)
    if rank == 0:
        dev = deviation(d.coordinates, sn, x0)
        effect = deviation(sf, sn, x0)
        check("given-reach", dev <= REL and effect > 1e-4,
              f"deviation {dev:.2e} from serial with the reach {reach}, "
              f"which moves the serial grid by {effect:.2e}")

    # 3. Bad arguments on rank 0 alone: every rank raises.
    raised = None
    try:
        distributed.deform(comm, grid if rank == 0 else None,
                           partition="scotch" if rank == 0 else "metis", **KW)
    except (ValueError, aeroshape.DeformError) as e:
        raised = f"{type(e).__name__}: {e}"
    got = comm.gather(raised)
    if rank == 0:
        ok = got[0].startswith("ValueError") and "scotch" in got[0] and all(
            g and "another rank refused" in g for g in got[1:])
        check("bad-argument", ok, " | ".join(map(str, got)))
    raised = None
    try:
        if rank == 0:
            distributed.deform(comm, m, global_ids=gids, n_owned=n_owned, **KW)
        else:
            distributed.deform(comm, None, **KW)
    except (ValueError, aeroshape.DeformError) as e:
        raised = f"{type(e).__name__}: {e}"
    got = comm.gather(raised)
    if rank == 0:
        ok = all(g and "given on some ranks" in g for g in got)
        check("mixed-ways", ok, " | ".join(map(str, got)))
    # 4. One set-up, two designs.
    wall = np.unique(np.concatenate(
        [e.ravel() for name in ("wing", "fuselage") for e in mesh.markers[name].values()]))
    span = np.abs(x0[:, 0]).max()
    design = []
    for h in (0.02, 0.05):
        d = np.zeros((len(x0), 3))
        d[wall, 2] = h * (1.0 + 0.5 * x0[wall, 0] / span)
        design.append(d)
    root = mesh if rank == 0 else None
    slide = dict(slide=["symmetry"], tolerance=1e-11)
    kept = distributed.Deformer(comm, root, displacements=(wall, design[0][wall]), **slide)
    first = kept.deform()
    order = wall[::-1]  # the same nodes in another order
    second = kept.deform((order, design[1][order]))
    fresh = distributed.deform(comm, root, displacements=(wall, design[1][wall]), **slide)
    if rank == 0:
        serial = aeroshape.deform(mesh, displacements=(wall, design[1][wall]), **slide).coordinates
        dev = deviation(second.coordinates, serial, x0)
        same = np.array_equal(second.coordinates, fresh.coordinates)
        moved = np.abs(second.coordinates - first.coordinates).max()
        n = second.report["deformations"]
        check("kept-made", same and moved > 0 and dev <= REL and n == 2,
              f"a new set-up's grid {'exactly' if same else 'NOT'}, {moved:.2e} from the first "
              f"design, deviation {dev:.2e}, {n} deformations on the set-up")
    raised = None
    try:
        kept.deform((wall[1:], design[1][wall[1:]]))
    except (ValueError, aeroshape.DeformError) as e:
        raised = f"{type(e).__name__}: {e}"
    got = comm.gather(raised)
    again = kept.deform((wall, design[1][wall]))
    if rank == 0:
        ok = (got[0].startswith("ValueError") and "the set-up was given" in got[0]
              and all(g and "another rank refused" in g for g in got[1:])
              and np.array_equal(again.coordinates, second.coordinates))
        check("kept-refused", ok, " | ".join(map(str, got)))
    # A warm start: a design 2 % further from the last one's solutions, against cold.
    near = (wall, 1.02 * design[1][wall])
    warm = kept.deform(near, warm_start=True)
    cold = kept.deform(near)
    same = kept.deform(near, warm_start=True)
    if rank == 0:
        its = [r.report["iterations"] + r.report["rotation_iterations"]
               for r in (warm, cold, same)]
        dev = deviation(warm.coordinates, cold.coordinates, x0)
        check("kept-warm", dev <= REL and its[0] < its[1] and its[2] == 0,
              f"{dev:.2e} from the cold start, iterations warm {its[0]}, cold {its[1]}, "
              f"the same design again {its[2]}")
    # Given parts: each rank its owned wall nodes, in local numbering.
    serial = (aeroshape.deform(mesh, displacements=(wall, design[1][wall]), tolerance=1e-11)
              .coordinates if rank == 0 else None)
    local = np.flatnonzero(np.isin(gids[:n_owned], wall))
    kept = distributed.Deformer(comm, m, global_ids=gids, n_owned=n_owned,
                                displacements=(local, design[0][gids[local]]), tolerance=1e-11)
    second = kept.deform((local, design[1][gids[local]]))
    fresh = distributed.deform(comm, m, global_ids=gids, n_owned=n_owned,
                               displacements=(local, design[1][gids[local]]), tolerance=1e-11)
    if rank == 0:
        dev = deviation(second.coordinates, serial, x0)
        same = np.array_equal(second.coordinates, fresh.coordinates)
        check("kept-given", same and dev <= REL,
              f"a new set-up's grid {'exactly' if same else 'NOT'}, deviation {dev:.2e}")
    if rank == 0 and failed:
        print(f"failed: {', '.join(failed)}", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    try:
        code = main()
    except BaseException:
        import traceback

        traceback.print_exc()
        sys.stderr.flush()
        MPI.COMM_WORLD.Abort(2)
    sys.exit(code)
