"""aeroshape: CAD-linked shape parametrisation and CFD grid deformation, from Python.

The computations are aeroshape's Rust crates (the same code as the ``aeroshape`` command
line); they run with the GIL released (but for ``aeroshape.distributed``'s MPI calls, which
hold it). Numpy arrays returned by this package are copies in numpy's own memory. Progress
goes to a ``progress`` callback where a function takes one, or else to the ``logging``
logger ``"aeroshape"`` (DEBUG for progress, INFO for summaries, WARNING for reader remarks
and violated constraints); nothing is printed.

- :class:`Study` -- a case file built once; ``evaluate(x)`` gives the deformed grid,
  ``linearise(x)`` its exact ``jvp``/``vjp`` products.
- :func:`read_mesh`, :func:`write_mesh`, :class:`Mesh` -- grids as numpy arrays.
- :func:`deform` -- the volume deformation of ``aeroshape deform``.
- :func:`section_fit`, :func:`section_build`, :func:`write_section` -- wing sections.
- ``aeroshape.openmdao`` -- the OpenMDAO component (needs ``openmdao``).

See ``docs/python.md`` in the repository.
"""

from __future__ import annotations

import logging as _logging

from ._errors import (
    AeroshapeError,
    CaseError,
    DeformError,
    DesignVectorError,
    EvaluationError,
    GeometryError,
    MeshError,
    OutputError,
    SectionError,
)
from ._native import (
    Constraints,
    Deformation,
    DesignVariable,
    Evaluation,
    Linearisation,
    Mesh,
    SectionFit,
    Study,
    __version__,
    deform,
    read_mesh,
    section_build,
    section_fit,
    write_mesh,
    write_section,
)

# A library's logger: silent unless the application configures logging.
_logging.getLogger("aeroshape").addHandler(_logging.NullHandler())

__all__ = [
    "AeroshapeError",
    "CaseError",
    "Constraints",
    "DeformError",
    "Deformation",
    "DesignVariable",
    "DesignVectorError",
    "Evaluation",
    "EvaluationError",
    "GeometryError",
    "Linearisation",
    "Mesh",
    "MeshError",
    "OutputError",
    "SectionError",
    "SectionFit",
    "Study",
    "__version__",
    "deform",
    "read_mesh",
    "section_build",
    "section_fit",
    "write_mesh",
    "write_section",
]
