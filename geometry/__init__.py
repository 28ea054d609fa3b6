"""Geometry of the slip-joint cones: parameters, gmsh meshes, imperfections."""

from common import backend  # noqa: F401  (must precede dolfinx/petsc4py/slepc4py)
