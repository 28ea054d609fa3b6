"""Natural frequencies and mode shapes of the linear-elastic joint (SLEPc).

Generalised symmetric eigenproblem K x = omega^2 M x for vector Lagrange
displacements (SI units: K in N/m, M in kg, frequencies f = omega / (2 pi) in Hz).

Conventions:

* Clamped dofs are kept in the system: their rows and columns are zeroed, with
  1 on the diagonal of K and 0 on the diagonal of M, so they carry an infinite
  eigenvalue that shift-and-invert never returns (no spurious modes).
* Coupling through the contact interface enters as K_total = K_bulk + K_interface,
  where K_interface comes from any object with a ``stiffness(V) -> PETSc.Mat``
  method (a bonded band, or the tangent of a settled contact state). The matrix
  must have the row layout of V (as created by ``dolfinx.fem.petsc.create_matrix``
  for a bilinear form on V); clamped rows and columns are removed here.
* Eigenvectors are mass-normalised: x^T M x = 1 [1/sqrt(kg) scaling].
"""

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import count
from typing import Protocol

from common import backend  # noqa: F401  (before dolfinx/petsc4py/slepc4py)

import numpy as np
from dolfinx import fem
from dolfinx.fem.petsc import assemble_matrix
from mpi4py import MPI
from petsc4py import PETSc
from slepc4py import SLEPc

from common.material import Material
from solver.elasticity import elastic_forms

_solver_ids = count()


class InterfaceStiffness(Protocol):
    """Anything that adds the stiffness of the MP-TP interface to the bulk."""

    def stiffness(self, V: fem.FunctionSpace) -> PETSc.Mat:
        """Interface tangent stiffness [N/m] on V's dof layout."""
        ...


@dataclass(frozen=True)
class EigenOptions:
    """What part of the spectrum to compute.

    Either the ``n_modes`` eigenfrequencies nearest to ``target_hz`` (the lowest
    ones for the default target 0), or, if ``band_hz = (f_lo, f_hi)`` is given,
    every mode in that band (spectrum slicing with MUMPS inertia counts).
    """

    n_modes: int = 20  #: number of modes wanted (ignored with a band)
    target_hz: float = 0.0  #: shift of the spectral transformation [Hz]
    band_hz: tuple[float, float] | None = None  #: frequency band [Hz]
    tol: float = 1e-12  #: relative residual tolerance of SLEPc
    max_it: int = 500  #: maximum restarts of Krylov-Schur

    def __post_init__(self) -> None:
        if self.band_hz is None:
            if self.n_modes < 1:
                raise ValueError(f"n_modes must be >= 1, got {self.n_modes}")
            if self.target_hz < 0:
                raise ValueError(f"target_hz must be >= 0 Hz, got {self.target_hz}")
        else:
            f_lo, f_hi = self.band_hz
            if not 0 <= f_lo < f_hi:
                raise ValueError(f"band_hz must satisfy 0 <= f_lo < f_hi, got {self.band_hz}")
        if not 0 < self.tol < 1:
            raise ValueError(f"tol must lie in (0, 1), got {self.tol}")


@dataclass
class ModalResult:
    """Sorted natural frequencies [Hz] and mass-normalised mode shapes."""

    frequencies_hz: np.ndarray
    modes: list[fem.Function]
    M: PETSc.Mat  #: mass matrix with clamped rows zeroed [kg]
    K: PETSc.Mat  #: total stiffness (bulk + interface) [N/m]

    @property
    def V(self) -> fem.FunctionSpace:
        return self.modes[0].function_space


def clamp(V: fem.FunctionSpace, facet_tags, tags: Sequence[int]) -> fem.DirichletBC:
    """Zero displacement on the facets carrying any of ``tags``."""
    mesh = V.mesh
    fdim = mesh.topology.dim - 1
    present = np.unique(facet_tags.values)
    local_missing = [t for t in tags if t not in present]
    missing = [t for t in tags if mesh.comm.allreduce(t in local_missing, op=MPI.LAND)]
    if missing:
        raise ValueError(f"clamp: facet tag(s) {missing} not found in the mesh")
    facets = np.concatenate([facet_tags.find(t) for t in tags])
    dofs = fem.locate_dofs_topological(V, fdim, facets)
    zero = np.zeros(mesh.geometry.dim, dtype=PETSc.ScalarType)
    return fem.dirichletbc(zero, dofs, V)


def _owned_global_bc_rows(V: fem.FunctionSpace, bcs: Sequence[fem.DirichletBC]) -> np.ndarray:
    """Global (unrolled) indices of the owned clamped dofs."""
    bs = V.dofmap.index_map_bs
    rows = []
    for bc in bcs:
        dofs, n_owned = bc.dof_indices()
        rows.append(dofs[:n_owned])
    local = np.unique(np.concatenate(rows)) if rows else np.zeros(0, dtype=np.int32)
    offset = V.dofmap.index_map.local_range[0] * bs
    return (local + offset).astype(PETSc.IntType)


def assemble_operators(
    V: fem.FunctionSpace,
    material: Material,
    bcs: Sequence[fem.DirichletBC],
    interfaces: Sequence[InterfaceStiffness] = (),
) -> tuple[PETSc.Mat, PETSc.Mat]:
    """Stiffness K = K_bulk + sum K_interface [N/m] and mass M [kg] with clamps applied."""
    k_form, m_form = (fem.form(a) for a in elastic_forms(V, material))
    K = assemble_matrix(k_form, bcs=bcs, diag=1.0)
    K.assemble()
    M = assemble_matrix(m_form, bcs=bcs, diag=0.0)
    M.assemble()
    clamped = _owned_global_bc_rows(V, bcs)
    for interface in interfaces:
        K_i = interface.stiffness(V)
        if K_i.getSizes() != K.getSizes():
            raise ValueError(
                f"interface stiffness has sizes {K_i.getSizes()}, "
                f"expected those of K {K.getSizes()}"
            )
        K_i.zeroRowsColumns(clamped, diag=0.0)
        K.axpy(1.0, K_i, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        K_i.destroy()
    K.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    M.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    return K, M


def _omega2(f_hz: float) -> float:
    return (2.0 * np.pi * f_hz) ** 2


def solve_eigenproblem(
    K: PETSc.Mat, M: PETSc.Mat, options: EigenOptions
) -> tuple[np.ndarray, list[PETSc.Vec]]:
    """Eigenpairs of K x = omega^2 M x: sorted frequencies [Hz] and M-normalised vectors."""
    comm = K.getComm()
    prefix = f"modal{next(_solver_ids)}_"
    opts = PETSc.Options()
    settings = {
        "st_type": "sinvert",
        "st_ksp_type": "preonly",
        "st_pc_type": "cholesky",
        "st_pc_factor_mat_solver_type": "mumps",
        "st_mat_mumps_icntl_13": 1,  # no ScaLAPACK root front: inertia (band) in parallel
        "st_mat_mumps_icntl_24": 1,  # null-pivot detection
    }
    for key, value in settings.items():
        opts[prefix + key] = value
    eps = SLEPc.EPS().create(comm)
    eps.setOptionsPrefix(prefix)
    eps.setOperators(K, M)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setTolerances(options.tol, options.max_it)
    if options.band_hz is None:
        # A slightly negative shift keeps K - sigma M definite at target 0
        # (and for unclamped structures with rigid-body modes).
        shift = _omega2(options.target_hz) if options.target_hz > 0 else -_omega2(1.0)
        eps.setTarget(shift)
        eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
        eps.setDimensions(options.n_modes)
    else:
        f_lo, f_hi = options.band_hz
        eps.setWhichEigenpairs(SLEPc.EPS.Which.ALL)
        eps.setInterval(_omega2(f_lo), _omega2(f_hi))
    eps.setFromOptions()
    eps.solve()
    for key in settings:
        opts.delValue(prefix + key)
    n_conv = eps.getConverged()
    if options.band_hz is None and n_conv < options.n_modes:
        raise RuntimeError(f"SLEPc converged {n_conv} of {options.n_modes} eigenpairs")
    n_take = n_conv if options.band_hz is not None else options.n_modes
    lam, vecs = [], []
    for i in range(n_conv):
        x = K.createVecRight()
        lam.append(eps.getEigenpair(i, x).real)
        vecs.append(x)
    eps.destroy()
    # SLEPc lists the pairs nearest to the target first; report them ascending.
    chosen = sorted(range(n_take), key=lambda i: lam[i])
    Mx = M.createVecLeft()
    out = []
    for i in chosen:
        x = vecs[i]
        M.mult(x, Mx)
        x.scale(1.0 / np.sqrt(x.dot(Mx)))
        out.append(x)
    freqs = np.sqrt(np.maximum(np.asarray([lam[i] for i in chosen]), 0.0)) / (2 * np.pi)
    return freqs, out


def modal_analysis(
    V: fem.FunctionSpace,
    material: Material,
    bcs: Sequence[fem.DirichletBC],
    interfaces: Sequence[InterfaceStiffness] = (),
    options: EigenOptions = EigenOptions(),
) -> ModalResult:
    """Natural frequencies [Hz] and mass-normalised mode shapes of the clamped body."""
    K, M = assemble_operators(V, material, bcs, interfaces)
    freqs, vectors = solve_eigenproblem(K, M, options)
    modes = []
    for i, x in enumerate(vectors):
        u = fem.Function(V, name=f"mode_{i + 1}")
        u.x.petsc_vec.array[:] = x.array_r
        u.x.scatter_forward()
        modes.append(u)
        x.destroy()
    return ModalResult(freqs, modes, M=M, K=K)
