#!/usr/bin/env python3
"""Pictures and tables of an optimise.py run (docs/optimisation.md).

usage: python plots.py [WORK] [--out DIR] [--prefix NAME]

Reads WORK/history.jsonl and WORK/summary.json and the OpenFOAM cases of the initial and
the final design (WORK/designs/NNN), and writes into DIR (default docs/img):
  PREFIX_history.png   C_D, C_L, V/V0, aeroshape's smallest cell quality and checkMesh's
                       largest non-orthogonality per evaluation (gradient points marked)
  PREFIX_planform.png  the wing's wall grid seen from above, before and after
  PREFIX_sections.png  sections y = const (η = y / b: 0.2, 0.65, 0.9), before and after
  PREFIX_cp.png        C_p on the upper surface before and after, and C_p along the sections
and prints the history as a Markdown table (one row per gradient point).

C_p = p / (½ U∞²): p is simpleFoam's kinematic pressure (p∞ = 0 at the far field), on a wall
face the value of the cell next to it (the wall's `zeroGradient` condition), from the
latest time of the case's p file.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import foamcase as fc  # noqa: E402
import wingloop  # noqa: E402

ETAS = (0.2, 0.65, 0.9)
SPAN = 1.1963  # the M6's semi-span (m)


def read_labels(path: Path) -> np.ndarray:
    text = path.read_text()
    body = text[text.index("}", text.index("FoamFile")) + 1:]
    i = body.index("(")
    n = int(body[:i].split()[-1])
    vals = np.array(body[i + 1:body.index(")", i)].split(), dtype=np.int64)
    if vals.size != n:
        raise SystemExit(f"{path}: {vals.size} labels, header says {n}")
    return vals


class Wing:
    """The wing patch of a case: points, faces (triangles), face normals, C_p."""

    def __init__(self, case: Path, u_inf: float = 1.0):
        xyz = fc.read_points(case)
        start, n = fc.read_boundary(case)["wing"]
        faces = fc.read_faces(case, start, n)
        if any(len(f) != 3 for f in faces):
            raise SystemExit(f"{case}: the wing patch has non-triangular faces")
        self.tri = np.array(faces)
        self.xyz = xyz
        a, b, c = (xyz[self.tri[:, k]] for k in range(3))
        self.normal = np.cross(b - a, c - a)  # out of the fluid (into the wing)
        owner = read_labels(case / "constant" / "polyMesh" / "owner")[start:start + n]
        t = fc.latest_time(case)
        p = fc.read_point_field(case / t / "p", "scalar")  # the internalField (cells)
        self.cp = p[owner] / (0.5 * u_inf ** 2)
        used = xyz[np.unique(self.tri)]
        self.box = (used.min(axis=0), used.max(axis=0))

    def frame(self, ax, other: "Wing", pad: float = 0.03) -> None:
        """Limits the axes (x, y) to the two wings (the points list the whole grid)."""
        lo = np.minimum(self.box[0], other.box[0]) - pad
        hi = np.maximum(self.box[1], other.box[1]) + pad
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])

    def section(self, y0: float):
        """Segments of the plane y = y0 through the wing faces: (k × 2 × 3 points, face)."""
        segs, fidx = [], []
        for f, tri in enumerate(self.tri):
            p = self.xyz[tri]
            d = p[:, 1] - y0
            pts = []
            for i in range(3):
                j = (i + 1) % 3
                if (d[i] < 0) != (d[j] < 0):
                    s = d[i] / (d[i] - d[j])
                    pts.append(p[i] + s * (p[j] - p[i]))
            if len(pts) == 2:
                segs.append(pts)
                fidx.append(f)
        return np.array(segs), np.array(fidx, dtype=np.int64)


def history(work: Path):
    rows = [json.loads(ln) for ln in (work / "history.jsonl").read_text().splitlines()]
    evals, grads, seen = [], [], set()
    for r in rows:
        if r.get("gradient"):
            grads.append(r)
        elif "failed" in r or r["index"] not in seen:
            evals.append(r)
            seen.add(r.get("index"))
    return evals, grads


def plot_history(evals, grads, summary, out: Path):
    ok = [r for r in evals if "failed" not in r]
    gi = {r["index"] for r in grads}
    n = np.arange(1, len(ok) + 1)
    fig, ax = plt.subplots(2, 2, figsize=(9, 6), dpi=90)
    series = [("cd", "$C_D$", ax[0, 0]), ("cl", "$C_L$", ax[0, 1])]
    for key, label, a in series:
        v = [r[key] for r in ok]
        a.plot(n, v, ".-", color="0.5", label="every evaluation")
        m = [(k, r[key]) for k, r in zip(n, ok) if r["index"] in gi]
        if m:
            a.plot(*zip(*m), "o", color="C0", label="gradient points (iterates)")
        a.set_ylabel(label)
        a.grid(alpha=0.3)
    ax[0, 1].axhline(summary["initial"]["cl"], color="C3", lw=0.8, ls="--", label="$C_{L0}$")
    ax[0, 0].legend(fontsize=8, loc="upper right")
    ax[0, 1].legend(fontsize=8, loc="upper right")
    v0 = summary["initial"]["volume"]
    ax[1, 0].plot(n, [r["volume"] / v0 for r in ok], ".-", color="C2")
    ax[1, 0].axhline(1.0, color="C3", lw=0.8, ls="--")
    ax[1, 0].set_ylabel("$V / V_0$ (wall grid)")
    ax[1, 1].plot(n, [r["quality"]["min"] for r in ok], ".-", color="C1",
                  label="aeroshape min quality")
    ax[1, 1].set_ylabel("min cell quality")
    t = ax[1, 1].twinx()
    t.plot(n, [r["checkmesh"]["max_non_orthogonality"] for r in ok], ".-", color="C4")
    t.set_ylabel("checkMesh max non-orth. (°)", color="C4")
    for a in ax[1]:
        a.set_xlabel("evaluation")
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


def plot_planform(w0: Wing, w1: Wing, out: Path):
    fig, ax = plt.subplots(figsize=(7, 5), dpi=90)
    for w, col, lab in ((w0, "0.6", "initial"), (w1, "C0", "final")):
        up = w.normal[:, 2] < 0
        ax.triplot(w.xyz[:, 0], w.xyz[:, 1], w.tri[up], color=col, lw=0.4)
        ax.plot([], [], color=col, label=lab)
    w0.frame(ax, w1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend()
    ax.set_title("wing wall grid from above (upper surface)")
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


def plot_sections(w0: Wing, w1: Wing, out: Path):
    fig, ax = plt.subplots(len(ETAS), 1, figsize=(7, 6.5), dpi=90)
    for a, eta in zip(ax, ETAS):
        for w, col, lab in ((w0, "0.5", "initial"), (w1, "C0", "final")):
            segs, _ = w.section(eta * SPAN)
            for s in segs:
                a.plot(s[:, 0], s[:, 2], color=col, lw=1.2)
            a.plot([], [], color=col, label=lab)
        a.set_aspect("equal")
        a.set_title(f"y = {eta * SPAN:.3f} m (η = {eta})", fontsize=9)
        a.grid(alpha=0.3)
    ax[0].legend(fontsize=8)
    ax[-1].set_xlabel("x (m)")
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


def plot_cp(w0: Wing, w1: Wing, out: Path):
    fig = plt.figure(figsize=(10, 8.5), dpi=90)
    lo = min(w0.cp.min(), w1.cp.min())
    hi = max(w0.cp.max(), w1.cp.max())
    for k, (w, title) in enumerate(((w0, "initial"), (w1, "final"))):
        a = fig.add_subplot(2, 2, k + 1)
        up = w.normal[:, 2] < 0
        tc = a.tripcolor(w.xyz[:, 0], w.xyz[:, 1], w.tri[up], facecolors=w.cp[up],
                         cmap="viridis", vmin=lo, vmax=hi)
        w0.frame(a, w1)
        a.set_aspect("equal")
        a.set_title(f"$C_p$ upper surface, {title}", fontsize=9)
        a.set_xlabel("x (m)")
    fig.colorbar(tc, ax=fig.axes[:2], shrink=0.8)
    for k, eta in enumerate(ETAS):
        a = fig.add_subplot(2, 3, 4 + k)
        for w, col, lab in ((w0, "0.5", "initial"), (w1, "C0", "final")):
            segs, f = w.section(eta * SPAN)
            if not len(segs):
                continue
            xm = segs[:, :, 0].mean(axis=1)
            c = (xm - segs[:, :, 0].min()) / np.ptp(segs[:, :, 0])
            upper = w.normal[f, 2] < 0
            for m, mk in ((upper, "-"), (~upper, "--")):
                o = np.argsort(c[m])
                a.plot(c[m][o], w.cp[f][m][o], mk, color=col, lw=1, label=f"{lab}"
                       if mk == "-" else None)
        a.invert_yaxis()
        a.set_title(f"η = {eta} (— upper, -- lower)", fontsize=9)
        a.set_xlabel("x / c")
        a.grid(alpha=0.3)
        if k == 0:
            a.set_ylabel("$C_p$")
            a.legend(fontsize=8)
    fig.subplots_adjust(hspace=0.35)
    fig.savefig(out, bbox_inches="tight")
    plt.close(fig)


def table(evals, grads, summary) -> str:
    names = summary["names"]
    out = ["| iterate | evaluation | α (°) | C_D | C_L | V/V0 | min quality | inverted | "
           "checkMesh max non-orth. (°) | max skewness |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    v0 = summary["initial"]["volume"]
    for k, r in enumerate(grads):
        out.append(f"| {k} | {r['index']} | {r['alpha']:.4f} | {r['cd']:.6f} | "
                   f"{r['cl']:.6f} | {r['volume'] / v0:.5f} | {r['quality']['min']:.4f} | "
                   f"{r['quality']['inverted']} | "
                   f"{r['checkmesh']['max_non_orthogonality']:.2f} | "
                   f"{r['checkmesh']['max_skewness']:.3f} |")
    x0, x1 = summary["initial"]["x"], summary["final"]["x"]
    out += ["", "| variable | initial | final |", "|---|---|---|"]
    out += [f"| {n} | {a:.6g} | {b:.6g} |" for n, a, b in zip(names, x0, x1)]
    out.append(f"| alpha | {summary['initial']['alpha']:.6g} | "
               f"{summary['final']['alpha']:.6g} |")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("work", type=Path, nargs="?",
                    default=wingloop.ROOT / "target" / "openfoam" / "optimise")
    ap.add_argument("--out", type=Path, default=wingloop.ROOT / "docs" / "img")
    ap.add_argument("--prefix", default="optimisation")
    a = ap.parse_args()
    evals, grads = history(a.work)
    if (a.work / "summary.json").exists():
        summary = json.loads((a.work / "summary.json").read_text())
    else:  # a run stopped early: its first design and its last gradient point (an iterate)
        first, last = evals[0], grads[-1]
        names = wingloop.Loop.names_of(a.work)
        summary = {"names": names,
                   "initial": {k: first[k] for k in ("cd", "cl", "volume", "x", "alpha",
                                                     "index")},
                   "final": {k: last[k] for k in ("cd", "cl", "volume", "x", "alpha",
                                                  "index")}}
    a.out.mkdir(parents=True, exist_ok=True)
    cases = a.work / "designs"
    w0 = Wing(cases / f"{summary['initial']['index']:03d}")
    w1 = Wing(cases / f"{summary['final']['index']:03d}")
    plot_history(evals, grads, summary, a.out / f"{a.prefix}_history.png")
    plot_planform(w0, w1, a.out / f"{a.prefix}_planform.png")
    plot_sections(w0, w1, a.out / f"{a.prefix}_sections.png")
    plot_cp(w0, w1, a.out / f"{a.prefix}_cp.png")
    print(table(evals, grads, summary))


if __name__ == "__main__":
    main()
