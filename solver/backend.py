"""The one place that loads the DOLFINx stack in the right order.

With the PyPI wheel ``dolfinx-solver-real``, ``import dolfinx_solver`` must come
before mpi4py/dolfinx/petsc4py/slepc4py (it orders MPI ahead of the compiled
bindings). Debian's ``python3-dolfinx`` has no such module, so the import is
guarded. Every module that needs DOLFINx imports this module first (``solver``
and ``geometry`` do so in their ``__init__``).
"""

try:  # PyPI wheel
    import dolfinx_solver  # noqa: F401
except ImportError:  # Debian / conda / source builds
    pass
