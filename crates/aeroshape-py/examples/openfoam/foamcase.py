"""The OpenFOAM side of the M6 optimisation: case files, runs, and the files read back.

ESI OpenFOAM v1912 (Debian's `openfoam`): `gmshToFoam` converts the hybrid grid of
fixtures/openfoam/make_grid.py, `simpleFoam` solves the steady incompressible laminar flow,
`adjointOptimisationFoam` (optimisationManager `singleRun`) solves the continuous adjoint of
one force objective and writes its sensitivity maps, `checkMesh` judges every grid.

Flow: U∞ = 1 m/s at the angle of attack α in the x–z plane (z up, y spanwise), kinematic
viscosity ν = U∞ c̄ / Re with c̄ = 0.64607 m the M6's mean aerodynamic chord, laminar.
Objectives: C_D and C_L of the half wing, F·d / (½ U∞² S_ref), S_ref = 0.7530 m² (the half
wing's planform area), d the drag (cos α, 0, sin α) or lift (−sin α, 0, cos α) direction;
F the pressure and viscous force of the fluid on the wall patch (objectiveForce).

Every function raises `FoamError` (one line naming the case, the program and its log) when a
program fails, diverges or does not converge; the optimiser turns it into an AnalysisError.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

FOAM_ENV = {"WM_PROJECT_DIR": "/usr/share/openfoam"}  # where v1912 finds its etc/ files
MAC = 0.64607  # the ONERA M6's mean aerodynamic chord (m)
S_REF = 0.7530  # half-wing planform area (m^2): ½ (0.8059 + 0.4531) × 1.1963
PATCH_TYPES = {"wing": "wall", "symmetry": "symmetryPlane", "farfield": "patch"}


class FoamError(RuntimeError):
    """An OpenFOAM program failed, diverged or did not converge."""


@dataclass
class Flow:
    """The flow condition and the solver controls."""

    alpha_deg: float = 4.0
    reynolds: float = 1000.0  # on the mean aerodynamic chord
    u_inf: float = 1.0
    primal_iters: int = 3000
    primal_tol: float = 1e-8  # initial residuals of p and U (SIMPLE residualControl)
    adjoint_iters: int = 3000
    adjoint_tol: float = 1e-8
    accept_tol: float = 1e-5  # a run stopped at its iteration limit is accepted below this

    @property
    def nu(self) -> float:
        return self.u_inf * MAC / self.reynolds

    def direction(self, objective: str) -> tuple[float, float, float]:
        a = math.radians(self.alpha_deg)
        return {"drag": (math.cos(a), 0.0, math.sin(a)),
                "lift": (-math.sin(a), 0.0, math.cos(a))}[objective]

    def u_vector(self) -> tuple[float, float, float]:
        d = self.direction("drag")
        return tuple(self.u_inf * c for c in d)


@dataclass
class Sensitivity:
    """What adjointOptimisationFoam writes for one objective."""

    objective: str
    value: float  # J of the adjoint run's primal (its objective file)
    wall_points: np.ndarray  # polyMesh point index of each wall-patch point
    normal: np.ndarray  # pointSensNormal…ESI on those points
    vector: np.ndarray  # pointSensVec…ESI (k × 3)
    normal_vector: np.ndarray  # pointSensNormalVec…ESI (k × 3)
    area: np.ndarray  # Σ |S_f| of the wall faces around each point (the v1912 divisor)
    iterations: int
    seconds: float
    log: Path


# ---------------------------------------------------------------- dictionaries

def _header(cls: str, obj: str, location: str | None = None) -> str:
    loc = f'    location    "{location}";\n' if location else ""
    return ("FoamFile\n{\n    version     2.0;\n    format      ascii;\n"
            f"    class       {cls};\n{loc}    object      {obj};\n}}\n\n")


def _vec(v) -> str:
    return "(" + " ".join(repr(float(c)) for c in v) + ")"


def control_dict(app: str, end: int) -> str:
    return _header("dictionary", "controlDict") + f"""application     {app};
startFrom       latestTime;
startTime       0;
stopAt          endTime;
endTime         {end};
deltaT          1;
writeControl    timeStep;
writeInterval   {end};
purgeWrite      0;
writeFormat     ascii;
writePrecision  16;
writeCompression off;
timeFormat      general;
timePrecision   8;
runTimeModifiable false;
"""


FV_SCHEMES = _header("dictionary", "fvSchemes") + """ddtSchemes { default steadyState; }
gradSchemes
{
    default         Gauss linear;
    gradUConv       Gauss linear;
    gradUaConv      Gauss linear;
}
divSchemes
{
    default         Gauss linear;
    div(phi,U)      bounded Gauss linearUpwind gradUConv;
    div(-phi,Ua)    bounded Gauss linearUpwind gradUaConv;
}
laplacianSchemes { default Gauss linear limited corrected 0.5; }
interpolationSchemes { default linear; }
snGradSchemes { default limited corrected 0.5; }
"""

FV_SOLUTION = _header("dictionary", "fvSolution") + """SIMPLE
{
    nNonOrthogonalCorrectors 1;
    consistent      no;
}
solvers
{
    "p.*|pa.*" { solver GAMG; smoother GaussSeidel; tolerance 1e-10; relTol 0.05; }
    "m|ma" { solver PCG; preconditioner DIC; tolerance 1e-10; relTol 0.01; }
    "U.*|Ua.*" { solver smoothSolver; smoother symGaussSeidel; tolerance 1e-10; relTol 0.1; }
}
relaxationFactors
{
    fields { "p.*" 0.3; "pa.*" 0.3; }
    equations { "U.*" 0.7; "Ua.*" 0.7; }
}
"""


def transport(flow: Flow) -> str:
    return (_header("dictionary", "transportProperties")
            + f"transportModel  Newtonian;\nnu              [0 2 -1 0 0 0 0] {flow.nu!r};\n")


TURBULENCE = _header("dictionary", "turbulenceProperties") + "simulationType  laminar;\n"
ADJOINT_RAS = (_header("dictionary", "adjointRASProperties")
               + "adjointRASModel adjointLaminar;\nadjointTurbulence on;\nprintCoeffs off;\n")


def field_file(cls: str, name: str, dims: str, internal: str, patches: dict[str, str]) -> str:
    body = "".join(f"    {p}\n    {{\n{b}    }}\n" for p, b in patches.items())
    return (_header(cls, name, "0") + f"dimensions      {dims};\ninternalField   {internal};\n"
            f"boundaryField\n{{\n{body}}}\n")


def initial_fields(flow: Flow) -> dict[str, str]:
    u = _vec(flow.u_vector())
    sym = "        type            symmetryPlane;\n"
    return {
        "U": field_file("volVectorField", "U", "[0 1 -1 0 0 0 0]", f"uniform {u}", {
            "wing": "        type            noSlip;\n",
            "symmetry": sym,
            "farfield": ("        type            freestream;\n"
                         f"        freestreamValue uniform {u};\n        value uniform {u};\n")}),
        "p": field_file("volScalarField", "p", "[0 2 -2 0 0 0 0]", "uniform 0", {
            "wing": "        type            zeroGradient;\n",
            "symmetry": sym,
            "farfield": ("        type            outletInlet;\n"
                         "        outletValue     uniform 0;\n        value uniform 0;\n")}),
        "Ua": field_file("volVectorField", "Ua", "[0 1 -1 0 0 0 0]", "uniform (0 0 0)", {
            "wing": "        type            adjointWallVelocity;\n        value uniform (0 0 0);\n",
            "symmetry": sym,
            "farfield": ("        type            adjointFarFieldVelocity;\n"
                         "        value uniform (0 0 0);\n")}),
        "pa": field_file("volScalarField", "pa", "[0 2 -2 0 0 0 0]", "uniform 0", {
            "wing": "        type            zeroGradient;\n",
            "symmetry": sym,
            "farfield": "        type            adjointFarFieldPressure;\n        value uniform 0;\n"}),
    }


def force_coeffs(flow: Flow) -> str:
    """simpleFoam's forceCoeffs function object (C_D, C_L as the objectives define them)."""
    return f"""functions
{{
    forceCoeffs
    {{
        type            forceCoeffs;
        libs            ("libforces.so");
        writeControl    timeStep;
        writeInterval   1;
        log             false;
        patches         (wing);
        rho             rhoInf;
        rhoInf          1;
        CofR            (0.25 0 0);
        liftDir         {_vec(flow.direction("lift"))};
        dragDir         {_vec(flow.direction("drag"))};
        pitchAxis       (0 1 0);
        magUInf         {flow.u_inf!r};
        lRef            {MAC!r};
        Aref            {S_REF!r};
    }}
}}
"""


def optimisation_dict(flow: Flow, objective: str, sens: dict[str, object]) -> str:
    """singleRun: the primal (already converged by simpleFoam: it stops at once), one
    adjoint solver `adj` for `objective`, then the sensitivities `sens`."""
    extra = "".join(f"        {k} {('true' if v else 'false') if isinstance(v, bool) else v};\n"
                    for k, v in sens.items())
    return _header("dictionary", "optimisationDict") + f"""optimisationManager singleRun;
primalSolvers
{{
    op1
    {{
        active          true;
        type            incompressible;
        solver          simple;
        solutionControls
        {{
            nIters          {flow.primal_iters};
            residualControl {{ "p.*" {flow.primal_tol!r}; "U.*" {flow.primal_tol!r}; }}
        }}
    }}
}}
adjointManagers
{{
    adjManager1
    {{
        primalSolver    op1;
        adjointSolvers
        {{
            adj
            {{
                active          true;
                type            incompressible;
                solver          adjointSimple;
                objectives
                {{
                    type            incompressible;
                    objectiveNames
                    {{
                        {objective}
                        {{
                            weight          1;
                            type            force;
                            patches         (wing);
                            direction       {_vec(flow.direction(objective))};
                            Aref            {S_REF!r};
                            rhoInf          1;
                            UInf            {flow.u_inf!r};
                        }}
                    }}
                }}
                ATCModel
                {{
                    ATCModel        standard;
                    extraConvection 0;
                    nSmooth         0;
                    zeroATCPatchTypes (wall patch);
                    maskType        pointCells;
                }}
                solutionControls
                {{
                    nIters          {flow.adjoint_iters};
                            residualControl {{ "pa.*" {flow.adjoint_tol!r}; "Ua.*" {flow.adjoint_tol!r}; }}
                }}
            }}
        }}
    }}
}}
optimisation
{{
    sensitivities
    {{
        patches         (wing);
{extra}    }}
}}
"""


def write(path: Path, text: str) -> None:
    tmp = path.with_name(path.name + ".part")
    tmp.write_text(text)
    os.replace(tmp, path)


# ---------------------------------------------------------------- runs

def run(app: str, case: Path, *args: str, log: str | None = None, nproc: int = 1,
        timeout: float = 3600) -> tuple[str, float]:
    """Runs an OpenFOAM program in `case`; its output goes to case/log.<name>. Returns the
    log text and the seconds taken."""
    log_path = case / (log or f"log.{app}")
    cmd = [app, "-case", str(case), *args]
    if nproc > 1:
        cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(nproc), *cmd,
               "-parallel"]
    env = dict(os.environ, **FOAM_ENV)
    t0 = time.perf_counter()
    with open(log_path, "w") as out:
        try:
            r = subprocess.run(cmd, stdout=out, stderr=subprocess.STDOUT, env=env,
                               timeout=timeout)
        except subprocess.TimeoutExpired as e:
            raise FoamError(f"{case}: {app} took over {timeout:.0f} s ({log_path})") from e
        except FileNotFoundError as e:
            raise FoamError(f"{app}: not found (is Debian's openfoam installed?)") from e
    seconds = time.perf_counter() - t0
    text = log_path.read_text(errors="replace")
    if r.returncode != 0 or "FOAM FATAL" in text:
        last = [ln for ln in text.splitlines() if ln.strip()][-8:]
        raise FoamError(f"{case}: {app} failed (exit {r.returncode}; {log_path}): "
                        + " | ".join(s.strip() for s in last))
    return text, seconds


def available() -> bool:
    """True when the OpenFOAM programs this module runs are on the PATH."""
    return all(shutil.which(p) for p in
               ("gmshToFoam", "simpleFoam", "adjointOptimisationFoam", "checkMesh"))


def make_case(case: Path, msh: Path, flow: Flow) -> None:
    """A new case folder: the grid converted by gmshToFoam, patch types set, dictionaries."""
    if case.exists():
        shutil.rmtree(case)
    (case / "system").mkdir(parents=True)
    (case / "constant").mkdir()
    write(case / "system" / "controlDict", control_dict("simpleFoam", flow.primal_iters))
    write(case / "system" / "fvSchemes", FV_SCHEMES)
    write(case / "system" / "fvSolution", FV_SOLUTION)
    run("gmshToFoam", case, str(msh))
    set_patch_types(case)
    for extra in ("cellZones", "faceZones", "pointZones"):
        (case / "constant" / "polyMesh" / extra).unlink(missing_ok=True)
    shutil.rmtree(case / "constant" / "polyMesh" / "sets", ignore_errors=True)
    write(case / "constant" / "transportProperties", transport(flow))
    write(case / "constant" / "turbulenceProperties", TURBULENCE)
    write(case / "constant" / "adjointRASProperties", ADJOINT_RAS)


def set_patch_types(case: Path) -> None:
    """gmshToFoam makes every patch a `patch`: the wing becomes a wall, the symmetry plane a
    symmetryPlane."""
    path = case / "constant" / "polyMesh" / "boundary"
    text = path.read_text()
    for name, kind in PATCH_TYPES.items():
        pat = re.compile(r"(\n\s*%s\s*\{[^}]*?)type\s+\w+;(\s*physicalType\s+\w+;)?" % name)
        text, n = pat.subn(r"\1type            %s;\n        inGroups        List<word> 1(%s);"
                           % (kind, kind), text)
        if n != 1:
            raise FoamError(f"{path}: no patch `{name}` (the grid's markers must be "
                            f"{', '.join(PATCH_TYPES)})")
    write(path, text)


def reset_fields(case: Path, flow: Flow) -> None:
    """Removes every time folder and writes the initial fields into 0/."""
    for d in case.iterdir():
        if d.is_dir() and _is_time(d.name):
            shutil.rmtree(d)
    shutil.rmtree(case / "postProcessing", ignore_errors=True)
    shutil.rmtree(case / "optimisation", ignore_errors=True)
    (case / "0").mkdir()
    for name, text in initial_fields(flow).items():
        write(case / "0" / name, text)


def _is_time(name: str) -> bool:
    try:
        float(name)
        return True
    except ValueError:
        return False


def latest_time(case: Path) -> str:
    times = [d.name for d in case.iterdir() if d.is_dir() and _is_time(d.name)]
    if not times:
        raise FoamError(f"{case}: no time folder")
    return max(times, key=float)


@dataclass
class CheckMesh:
    ok: bool
    failed: list[str]
    max_non_orthogonality: float
    max_skewness: float
    min_volume: float
    log: Path
    seconds: float
    cells: dict[str, int] = field(default_factory=dict)


def check_mesh(case: Path) -> CheckMesh:
    """checkMesh's verdict and figures; `ok` is its "Mesh OK"."""
    text, s = run("checkMesh", case, "-constant")

    def num(pat, default=float("nan")):
        m = re.search(pat, text)
        return float(m.group(1).rstrip(".")) if m else default
    failed = [m.group(1).strip() for m in re.finditer(r"\*\*\*(.*)", text)]
    cells = {k: int(v) for k, v in re.findall(r"\n\s+(tetrahedra|prisms|hexahedra|"
                                              r"polyhedra|pyramids):\s+(\d+)", text)}
    return CheckMesh(ok="Mesh OK." in text, failed=failed,
                     max_non_orthogonality=num(r"Mesh non-orthogonality Max: ([\d.eE+-]+)"),
                     max_skewness=num(r"Max skewness = ([\d.eE+-]+)"),
                     min_volume=num(r"Min volume = ([\d.eE+-]+)"),
                     log=case / "log.checkMesh", seconds=s, cells=cells)


@dataclass
class Primal:
    cd: float
    cl: float
    iterations: int
    converged: bool
    residual: float  # the largest initial residual of the last iteration
    seconds: float


def _residuals(text: str, fields: tuple[str, ...]) -> tuple[int, float]:
    """(iterations, largest initial residual of `fields` in the last iteration)."""
    blocks = re.split(r"\nTime = ", text)
    last = {}
    for f in fields:
        m = re.findall(r"Solving for %s, Initial residual = ([\d.eE+-]+)" % f, blocks[-1])
        if m:
            last[f] = float(m[0])
    res = max(last.values()) if last else float("nan")
    if math.isnan(res) or not math.isfinite(res):
        raise FoamError("no residual in the log")
    return len(blocks) - 1, res


def solve_primal(case: Path, flow: Flow, nproc: int = 1) -> Primal:
    """simpleFoam from 0/ (laminar, SIMPLE) until the residuals of p and U are below
    flow.primal_tol; C_D, C_L from its forceCoeffs."""
    ctrl = control_dict("simpleFoam", flow.primal_iters) + force_coeffs(flow)
    write(case / "system" / "controlDict", ctrl)
    write(case / "system" / "fvSolution", FV_SOLUTION.replace(
        "SIMPLE\n{", "SIMPLE\n{\n    residualControl { p %r; U %r; }" % (flow.primal_tol,
                                                                      flow.primal_tol)))
    if nproc > 1:
        decompose(case, nproc)
    text, s = run("simpleFoam", case, nproc=nproc)
    if nproc > 1:
        run("reconstructPar", case, "-latestTime")
        for d in case.glob("processor*"):
            shutil.rmtree(d)
    if re.search(r"\bnan\b", text, re.IGNORECASE):
        raise FoamError(f"{case}: simpleFoam diverged (NaN; {case / 'log.simpleFoam'})")
    iters, res = _residuals(text, ("Ux", "Uy", "Uz", "p"))
    converged = "SIMPLE solution converged" in text
    if not converged and res > flow.accept_tol:
        raise FoamError(f"{case}: simpleFoam not converged after {iters} iterations "
                        f"(residual {res:.2e} > {flow.accept_tol:.0e}; {case / 'log.simpleFoam'})")
    cd, cl = read_force_coeffs(case)
    return Primal(cd=cd, cl=cl, iterations=iters, converged=converged, residual=res, seconds=s)


def decompose(case: Path, nproc: int) -> None:
    write(case / "system" / "decomposeParDict", _header("dictionary", "decomposeParDict")
          + f"numberOfSubdomains {nproc};\nmethod scotch;\n")
    for d in case.glob("processor*"):
        shutil.rmtree(d)
    run("decomposePar", case, "-force")


def read_force_coeffs(case: Path) -> tuple[float, float]:
    """(C_D, C_L) of the last iteration in postProcessing/forceCoeffs."""
    files = sorted((case / "postProcessing" / "forceCoeffs").glob("*/*.dat"))
    files = [f for f in files if f.name.startswith(("coefficient", "forceCoeffs"))]
    if not files:
        raise FoamError(f"{case}: no forceCoeffs output")
    lines = files[-1].read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")][-1].lstrip("#").split()
    last = [ln for ln in lines if ln.strip() and not ln.startswith("#")][-1].split()
    row = dict(zip(head, last))
    return float(row["Cd"]), float(row["Cl"])


def solve_adjoint(case: Path, flow: Flow, objective: str) -> Sensitivity:
    """adjointOptimisationFoam in `case` (whose latest time holds the converged primal):
    the adjoint of `objective` ("drag" or "lift") and its E-SI point sensitivities
    (surfacePoints, v1912's default area convention: includeSurfaceArea false)."""
    iters, s = run_adjoint(case, flow, objective, {"type": "surfacePoints",
                                                    "includeSurfaceArea": False,
                                                    "writeAllSurfaceFiles": True})
    return read_sensitivity(case, objective, iters, s)


def run_adjoint(case: Path, flow: Flow, objective: str, opts: dict) -> tuple[int, float]:
    """adjointOptimisationFoam with the sensitivity options `opts` (the optimisationDict's
    `sensitivities` entries); returns its adjoint iterations and seconds."""
    write(case / "system" / "controlDict",
          control_dict("adjointOptimisationFoam", flow.primal_iters))
    write(case / "system" / "optimisationDict", optimisation_dict(flow, objective, opts))
    t = latest_time(case)
    if t != "0":
        for name in ("Ua", "pa"):
            shutil.copy(case / "0" / name, case / t / name)
    text, s = run("adjointOptimisationFoam", case, log=f"log.adjoint.{objective}")
    if re.search(r"\bnan\b", text, re.IGNORECASE):
        raise FoamError(f"{case}: the {objective} adjoint diverged (NaN; "
                        f"{case / ('log.adjoint.' + objective)})")
    m = re.search(r"adj solution converged in (\d+) iterations", text)
    start = text.index("op1 solution converged") if "op1 solution converged" in text else 0
    adj = text[start:].split("Adjoint Mesh Movement", 1)[0]
    iters, res = _residuals(adj, ("Uax", "Uay", "Uaz", "pa"))
    if not m and res > flow.accept_tol:
        raise FoamError(f"{case}: the {objective} adjoint not converged after {iters} "
                        f"iterations (residual {res:.2e}; {case / ('log.adjoint.' + objective)})")
    return iters, s


# ---------------------------------------------------------------- files

_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def _list_after(text: str, start: int, kind: str) -> tuple[np.ndarray, int]:
    """The OpenFOAM list `N ( … )` starting at text[start:], of scalars or vectors."""
    m = re.compile(r"\s*(\d+)\s*\(").match(text, start)
    if not m:
        raise FoamError("expected a list `N (`")
    n = int(m.group(1))
    end = text.index(")\n", m.end()) if kind == "scalar" else _vector_list_end(text, m.end(), n)
    body = text[m.end():end]
    vals = np.array(re.findall(_NUM, body), dtype=float)
    width = 1 if kind == "scalar" else 3
    if vals.size != n * width:
        raise FoamError(f"a list of {n} {kind}s holds {vals.size} numbers")
    return (vals if width == 1 else vals.reshape(n, 3)), end + 1


def _vector_list_end(text: str, pos: int, n: int) -> int:
    for _ in range(n):
        pos = text.index(")", pos) + 1
    return text.index(")", pos)


def read_points(case: Path) -> np.ndarray:
    text = (case / "constant" / "polyMesh" / "points").read_text()
    start = text.index("\n", text.index("}", text.index("FoamFile"))) + 1
    while not re.match(r"\s*\d+\s*\(", text[start:start + 40]) and start < len(text):
        start = text.index("\n", start) + 1
    pts, _ = _list_after(text, start, "vector")
    return pts


def write_points(case: Path, xyz: np.ndarray) -> None:
    """constant/polyMesh/points (ASCII, full precision), the only grid file a design changes."""
    body = "\n".join(f"({x!r} {y!r} {z!r})" for x, y, z in xyz.tolist())
    write(case / "constant" / "polyMesh" / "points",
          _header("vectorField", "points", "constant/polyMesh")
          + f"{len(xyz)}\n(\n{body}\n)\n")


def read_boundary(case: Path) -> dict[str, tuple[int, int]]:
    text = (case / "constant" / "polyMesh" / "boundary").read_text()
    out = {}
    for m in re.finditer(r"\n\s*(\w+)\s*\{([^}]*)\}", text):
        nf = re.search(r"nFaces\s+(\d+);", m.group(2))
        sf = re.search(r"startFace\s+(\d+);", m.group(2))
        if nf and sf:
            out[m.group(1)] = (int(sf.group(1)), int(nf.group(1)))
    return out


def read_faces(case: Path, start: int, count: int) -> list[list[int]]:
    """Faces start..start+count of constant/polyMesh/faces (ASCII `n(a b c …)` lines)."""
    text = (case / "constant" / "polyMesh" / "faces").read_text()
    rows = re.findall(r"^\d+\(([\d ]+)\)$", text, re.MULTILINE)
    return [[int(v) for v in r.split()] for r in rows[start:start + count]]


def wall_patch(case: Path, patch: str = "wing") -> tuple[np.ndarray, list[list[int]]]:
    """The patch's points in OpenFOAM's patch order (first appearance in its faces, as
    PrimitivePatch::meshPoints) and its faces."""
    start, n = read_boundary(case)[patch]
    faces = read_faces(case, start, n)
    seen: dict[int, int] = {}
    for f in faces:
        for p in f:
            if p not in seen:
                seen[p] = len(seen)
    return np.array(list(seen), dtype=np.int64), faces


def read_point_field(path: Path, kind: str) -> np.ndarray:
    """The internalField of a pointScalarField / pointVectorField file: one value per mesh
    point (v1912 writes the wall sensitivities there, zero off the sensitivity patches)."""
    text = path.read_text()
    m = re.compile(r"internalField\s+nonuniform\s+List<(\w+)>").search(text)
    if not m:
        raise FoamError(f"{path}: no nonuniform internalField")
    vals, _ = _list_after(text, m.end(), kind)
    return vals


def read_patch_field(path: Path, patch: str, kind: str) -> np.ndarray:
    """The `value` of `patch` in a volScalarField / volVectorField file (patch face order)."""
    text = path.read_text()
    b = text.index("boundaryField")
    m = re.compile(r"\n\s*%s\s*\{" % patch).search(text, b)
    if not m:
        raise FoamError(f"{path}: no patch {patch}")
    v = re.compile(r"value\s+nonuniform\s+List<\w+>").search(text, m.end())
    if not v:
        raise FoamError(f"{path}: patch {patch} has no nonuniform value")
    vals, _ = _list_after(text, v.end(), kind)
    return vals


def read_sensitivity(case: Path, objective: str, iterations: int, seconds: float) -> Sensitivity:
    t = latest_time(case)
    d = case / t
    pts, faces = wall_patch(case)
    xyz = read_points(case)
    area = np.zeros(len(pts))
    local = {int(p): i for i, p in enumerate(pts)}
    for f in faces:
        a = _face_area(xyz[f])
        for p in f:
            area[local[p]] += a
    return Sensitivity(
        objective=objective, value=read_objective(case, objective), wall_points=pts,
        normal=read_point_field(d / "pointSensNormaladjESI", "scalar")[pts],
        vector=read_point_field(d / "pointSensVecadjESI", "vector")[pts],
        normal_vector=read_point_field(d / "pointSensNormalVecadjESI", "vector")[pts],
        area=area, iterations=iterations, seconds=seconds,
        log=case / f"log.adjoint.{objective}")


def read_objective(case: Path, objective: str) -> float:
    """J of the last adjointOptimisationFoam run (optimisation/objective/<t>/<name>adj)."""
    obj = sorted((case / "optimisation" / "objective").glob(f"*/{objective}adj*"))
    if not obj:
        raise FoamError(f"{case}: no objective file for {objective}")
    last = [ln.split() for ln in obj[-1].read_text().splitlines()
            if ln.strip() and not ln.lstrip().startswith("#")][-1]
    return float(last[1])


def _face_area(p: np.ndarray) -> float:
    """|S_f| as OpenFOAM's face::mag: triangles fanned from the face centre estimate."""
    c = p.mean(axis=0)
    s = np.zeros(3)
    for i in range(len(p)):
        s += np.cross(p[i] - c, p[(i + 1) % len(p)] - c) / 2
    return float(np.linalg.norm(s))
