"""Steady-state harmonic response of the linear structure, in the frequency domain.

For M u'' + C u' + K u = Re(F e^{i omega t}) with Rayleigh damping C = a M + b K the steady
state is u(t) = Re(U e^{i omega t}) with

    (K - omega^2 M + i omega C) U = F,

solved in real arithmetic as the block system

    [[D, -omega C], [omega C, D]] [U_re; U_im] = [F; 0],   D = K - omega^2 M,

with a direct solver. Units: omega in rad/s, F in N, U in m. Dirichlet rows of K and M (unit
diagonal, zero columns, as ``assemble_structure`` makes them) keep U = 0 there.
"""

import numpy as np
from petsc4py import PETSc

from solver.dynamics.damping import RayleighDamping
from solver.dynamics.linear_algebra import direct_solver

__all__ = ["harmonic_response"]


def harmonic_response(
    M: PETSc.Mat, K: PETSc.Mat, damping: RayleighDamping, force: PETSc.Vec, frequency_hz: float
) -> tuple[PETSc.Vec, PETSc.Vec]:
    """(U_re, U_im) [m] of the steady state under the load amplitude ``force`` [N] at ``frequency_hz``."""
    if not frequency_hz > 0:
        raise ValueError(f"frequency must be positive, got {frequency_hz} Hz")
    omega = 2 * np.pi * frequency_hz
    D = K.duplicate(copy=True)
    D.axpy(-(omega**2), M, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
    C = K.duplicate(copy=True)
    C.scale(omega * damping.b)
    C.axpy(omega * damping.a, M, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
    minus_C = C.duplicate(copy=True)
    minus_C.scale(-1.0)
    nest = PETSc.Mat().createNest([[D, minus_C], [C, D]], comm=K.getComm())
    A = nest.convert(PETSc.Mat.Type.AIJ)
    rhs, x = A.createVecs()
    zero = force.duplicate()
    zero.set(0.0)
    nest_rhs = PETSc.Vec().createNest([force, zero], comm=K.getComm())
    rhs.array[:] = np.concatenate([v.array_r for v in nest_rhs.getNestSubVecs()])
    ksp = direct_solver(K.getComm(), A)
    ksp.solve(rhs, x)
    if ksp.getConvergedReason() <= 0:
        raise RuntimeError(f"frequency-domain solve failed (KSP reason {ksp.getConvergedReason()})")
    n = force.getLocalSize()
    U_re, U_im = force.duplicate(), force.duplicate()
    U_re.array[:] = x.array_r[:n]
    U_im.array[:] = x.array_r[n:]
    for obj in (D, C, minus_C, nest, A, rhs, x, zero, nest_rhs, ksp):
        obj.destroy()
    return U_re, U_im
