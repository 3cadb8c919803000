"""The exceptions of aeroshape: one base class, one subclass per domain.

Every exception carries the message the command line prints after ``error:`` for the same
fault (the file, line, entity or variable at fault, on one line).
"""

from __future__ import annotations

__all__ = [
    "AeroshapeError",
    "CaseError",
    "DesignVectorError",
    "MeshError",
    "GeometryError",
    "EvaluationError",
    "DeformError",
    "SectionError",
    "OutputError",
]


class AeroshapeError(Exception):
    """Base class of every error raised by aeroshape's Rust code."""


class CaseError(AeroshapeError):
    """The case file is missing or bad, or the case does not fit its grid or geometry (e.g. a
    wall marker missing from the grid); a bad grid or geometry file it names raises
    :class:`MeshError` or :class:`GeometryError`."""


class DesignVectorError(AeroshapeError, ValueError):
    """A design vector is wrong: its length, a non-finite value, a value outside its
    bounds, violated linear constraints, an unknown variable name."""


class MeshError(AeroshapeError):
    """A grid file cannot be read, or a grid is invalid."""


class GeometryError(AeroshapeError):
    """A geometric database (GEOM.ron) cannot be read or used."""


class EvaluationError(AeroshapeError):
    """A phase of the chain failed (param, model update, surface grid, deform); the message
    names the phase and the entity."""


class DeformError(AeroshapeError):
    """A volume deformation failed (unknown or non-planar marker, solver, inverted cells)."""


class SectionError(AeroshapeError):
    """An airfoil file, a section fit or section parameters are bad."""


class OutputError(AeroshapeError, OSError):
    """An output file cannot be written, or would overwrite an input."""
