"""Elastodynamics, frictional contact and modal analysis of the slip-joint."""

from common import backend  # noqa: F401  (must precede dolfinx/petsc4py/slepc4py)
