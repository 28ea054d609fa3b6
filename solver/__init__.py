"""Elastodynamics, frictional contact and modal analysis of the slip-joint.

Sub-packages, each importing only those before it (``common`` and ``geometry`` below all):

=================  ================================================================
``elasticity``     strain and stress in UFL
``probes``         point evaluation in a distributed mesh
``contact``        friction law, contact surfaces, pairing, Nitsche terms
``dynamics``       Newmark schemes, the time step and loop, Newton, loads, damping
``post``           CSV tables, reports, pictures, ParaView files
``modal``          eigen-solve, mode classification and ranking
``reduced``        shell-theory springs and the lumped stick-slip model
``installation``   the installation run: case, model, stages, checkpoints, demos' CLI
=================  ================================================================
"""

from common import backend  # noqa: F401  (must precede dolfinx/petsc4py/slepc4py)
