"""The one place that loads the DOLFINx stack in the right order, and sets the PETSc
options every run needs.

With the PyPI wheel ``dolfinx-solver-real``, ``import dolfinx_solver`` must come
before mpi4py/dolfinx/petsc4py/slepc4py (it orders MPI ahead of the compiled
bindings). Debian's ``python3-dolfinx`` has no such module, so the import is
guarded. Every module that needs DOLFINx imports this module first (``solver``
and ``geometry`` do so in their ``__init__``; ``common`` itself does not, so that its
case files and material load without the DOLFINx stack).

Reproducibility: by default PETSc computes the Gram-Schmidt products of GMRES
(``VecMDot``/``VecMAXPY`` over the contiguous block of Krylov vectors) with BLAS gemv,
and OpenBLAS's gemv kernels sum in an order that depends on the memory alignment of
that block, which differs from one solver object to the next. Two runs of the same
input then differ at round-off (1e-18 m in a Newton correction), which stick-slip
amplifies to 5e-8 relative in the settlement, beyond the 1e-8 a resumed run must meet.
PETSc's plain loops are deterministic; they are used unless the user's PETSc options
say otherwise (docs/contact.md, section 6).

BLAS threads: one per rank, and OpenBLAS's idle threads asleep at once; freed memory: kept in
the process (all below).
"""

import ctypes
import ctypes.util
import os

# OpenBLAS threads that finish their work spin for about 0.1 s before they sleep. The inner
# problem's factorisations run on one rank with a thread per rank of the node
# (``solver.dynamics.node_memory``), and a thread spinning on after one would take the core from
# the next work of another rank. Read when OpenBLAS loads, so set before NumPy and SciPy load.
os.environ.setdefault("OPENBLAS_THREAD_TIMEOUT", "4")  # 2^4 cycles

try:  # PyPI wheel
    import dolfinx_solver  # noqa: F401
except ImportError:  # Debian / conda / source builds
    pass

from petsc4py import PETSc  # noqa: E402

_options = PETSc.Options()
for _name in ("vec_mdot_use_gemv", "vec_maxpy_use_gemv"):
    if not _options.hasName(_name):
        _options.setValue(_name, False)
    _options.getBool(_name)  # marked as used: no "unused option" warning from a run without vectors

# BLAS threads: one per rank. OpenBLAS (PETSc's, in the factorisations, and NumPy's and SciPy's,
# in the dense contact problems) starts one thread per core in every rank by default: the ranks
# of an MPI run then oversubscribe the cores (a 2-rank run on 2 cores runs severalfold slower),
# and the dense contact problems (matrices of a few hundred to a few thousand rows) run slower on
# two threads than on one even in a serial run. The limit applies to the libraries loaded when it
# is set: SciPy's own OpenBLAS is loaded first.
import scipy.linalg  # noqa: E402, F401
import threadpoolctl  # noqa: E402

threadpoolctl.threadpool_limits(1, "blas")


# Freed memory: kept in the process. glibc serves allocations above 32 MB with mmap and returns
# them to the kernel when freed; on virtual machines that hand freed guest pages back to the host
# (virtio free page reporting, as on the machines the docs' figures come from) the next first
# touch of such pages costs about 3.5-7 s per GB (docs/install.md, "Cost"). The contact
# solver's dense blocks and the factorisations of every stage (a new time step) are such
# allocations, so they are taken from the heap, which is not trimmed: later stages reuse its
# pages. Not with other C libraries, nor where the user set glibc's malloc options.
_M_TRIM_THRESHOLD, _M_MMAP_MAX = -1, -4


def _keep_freed_memory() -> bool:
    """Large allocations from the untrimmed heap (glibc's mallopt); False where not applied."""
    if any(name in os.environ for name in ("MALLOC_MMAP_MAX_", "MALLOC_TRIM_THRESHOLD_")):
        return False
    if "glibc.malloc." in os.environ.get("GLIBC_TUNABLES", ""):
        return False
    libc_name = ctypes.util.find_library("c")
    mallopt = getattr(ctypes.CDLL(libc_name), "mallopt", None) if libc_name else None
    if mallopt is None:
        return False
    return bool(mallopt(_M_MMAP_MAX, 0)) and bool(mallopt(_M_TRIM_THRESHOLD, 2**31 - 1))


KEEPS_FREED_MEMORY = _keep_freed_memory()  #: whether freed memory stays in the process
