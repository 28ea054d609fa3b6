"""Generalized Newton for a linear bulk operator plus Nitsche contact: A u + r_c(u) = b.

A is constant during the solve (stiffness K in quasi-static steps, the Newmark effective
stiffness K + c_M M + c_C C in dynamics), assembled with the Dirichlet conditions
(``assemble_matrix(a, bcs=bcs)``: identity rows/columns), and b is the load with lifting
and boundary values applied (``apply_lifting``, ``set_bc``), as for a linear solve.

Linear solves reuse one LU factorisation: each Newton correction solves
(A + J_c(u_k)) du = -F(u_k) by GMRES (right preconditioning, true residual; as flexible
GMRES, which with a fixed preconditioner makes the same iterates and keeps the
preconditioned basis vectors, so building the correction needs no extra LU solve) with the
LU factors of A + J_c at an earlier iterate as preconditioner. J_c only touches the
interface dofs and changes mostly where contact states change, so GMRES often needs
few iterations; when it fails within ``refactor_after`` iterations the current A + J_c
is factorised, and after a solve that needed more than ``refactor_after // 2`` GMRES
iterations the next correction refactorises. The policy uses iteration counts, not
timings, so a run's results do not depend on the machine's load. GMRES multiplies the
operator only with preconditioned vectors z = P^-1 v, P = A + J_P the factorised matrix, and
(A + J) z = v + (J - J_P) z needs products with the interface matrices only, not with A.
With a ``zone`` (the condensed system of ``solver.dynamics.condensation``, identity rows off the zone)
only the zone block of A + J is factorised.

The corrections are inexact Newton steps: GMRES stops at ||F + (A + J_c) du|| <= eta_k ||F||
with the Eisenstat-Walker forcing term of ``solver.dynamics.linear_algebra.forcing_term``. The
workspace (and its factorisation) can be kept across steps while A is unchanged.
"""

from dataclasses import dataclass, field

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx

from common.timing import count, timed
from solver.contact.model import ContactModel
from solver.dynamics.factor_store import Factors, FactorStore
from solver.dynamics.linear_algebra import BlockLU, SumOperator, forcing_term
from solver.dynamics.residual import contact_residual, dirichlet_rows

__all__ = ["ContactNewtonSolver", "NewtonResult", "newton_stop", "solve_contact_problem"]


@dataclass
class _Step:
    """Work vectors of a Newton step: the correction du, the iterate x0 it starts from, A du,
    and A x - b at x0 and at the current trial point (A u is linear along the step: one
    product with A per iteration)."""

    du: PETSc.Vec
    x0: PETSc.Vec
    A_du: PETSc.Vec
    linear0: PETSc.Vec
    linear: PETSc.Vec


@dataclass
class NewtonResult:
    """Outcome of a Newton solve (residual norms in N, the l2 norm of the nodal residual)."""

    converged: bool
    iterations: int
    residual_norms: list[float]
    linear_iterations: list[int] = field(default_factory=list)
    factorizations: int = 0
    message: str = ""


def newton_stop(
    norms: list[float],
    tol: float,
    max_iterations: int,
    linear: list[int] | None = None,
    step_small: bool = False,
) -> NewtonResult | None:
    """Where a Newton loop at the residual norms ``norms`` [N] (the last one its iterate's) stops:
    not converged if the last is not finite or the iterations are used up, converged at or below
    ``tol`` [N] (or when the correction was negligible, ``step_small``); None to go on."""
    k, norm = len(norms) - 1, norms[-1]
    linear = [] if linear is None else linear
    if not np.isfinite(norm):
        return NewtonResult(
            False, k, norms, linear, message=f"residual is not finite at iteration {k}"
        )
    if norm <= tol or step_small:
        return NewtonResult(True, k, norms, linear)
    if k == max_iterations:
        message = f"no convergence in {k} Newton iterations (||F|| = {norm:.3e} N)"
        return NewtonResult(False, k, norms, linear, message=message)
    return None


class ContactNewtonSolver:
    """Newton solver for A u + r_c(u) = b that keeps an LU factorisation between iterations and calls.

    Args:
        A: bulk matrix (with Dirichlet rows/columns), constant while this solver is used.
        bcs: Dirichlet conditions of the problem.
        rtol, atol: convergence when ||F|| <= max(atol, rtol max(||F_0||, ||b||), floor) [N] (floor:
            the round-off level of the contact residual, ``ContactModel.residual_floor``; in a
            Newmark step A is dominated by M / (beta dt^2), so a residual of rtol ||b|| changes u
            by about rtol relative, and in slow steps the floor usually decides) ...
        stol: ... or when the Newton correction ||du||_inf <= stol ||u||_inf (the residual of a
            C0 faceted master surface can stagnate at the level lambda x kink angle).
        max_iterations: Newton iteration limit.
        stall_iterations: give up (converged=False) when the smallest ||F|| so far is this many
            iterations old: a generalized Newton that cycles between contact states (e.g. from a
            predictor that slides on where the TP stops) does not recover, and the caller's
            fallback (restart from u_n, step cut) is cheaper than the remaining iterations.
            0: no limit.
        refactor_after: refactorise when GMRES needs more iterations than this (and for the
            next correction after more than half of them); 0 factorises A + J_c at every
            Newton iteration (plain Newton with direct solves).
        krylov_rtol: tightest relative tolerance of the GMRES correction solves.
        forcing_max: largest GMRES relative tolerance (Eisenstat-Walker forcing term,
            ``forcing_term``); 0: every correction to krylov_rtol.
        lu_solver: PETSc factorisation package ("mumps", "superlu_dist", "petsc").
        max_backtracks: step halvings when a Newton step increases ||F|| (0: plain Newton).
        max_gap_change: if given [m], damp each Newton step so that no slave point's gap decreases
            by more than max(max_gap_change, g / 2) (g its gap at the current iterate): points
            approach the master at most halfway per iteration and move into penetration by at
            most max_gap_change per iteration (separation is not limited). Stops the open <->
            deeply penetrated cycling of a body that first flies free (docs/contact.md).
            None: full Newton steps.
        limit_reversal: with backtracking, when the (gap-limited) Newton step does not lower
            ||F||, first try the step shortened to where the first slipping point's trial
            friction traction would turn against its direction at the iterate
            (``ContactModel.reversal_limit``; a model without a limit returns 1: no effect), then
            halve from there. The slip tangent has no stiffness along the slip direction, so
            where the TP stops the Newton step slides it on until the friction reverses, and
            halving only approaches the stop linearly (docs/contact.md, section 6).
        zone: global dofs (this rank's part) off which A is the identity and J vanishes (the
            condensed system of ``solver.dynamics.condensation.BulkCondensation``): only the zone block
            of A + J is factorised. None: A + J is factorised whole.
        factorisations_kept: factorisations of A + J kept at once; each correction takes the one
            whose contact status is nearest the iterate's (``solver.dynamics.factor_store``).
    """

    def __init__(
        self,
        A: PETSc.Mat,
        bcs: list[dolfinx.fem.DirichletBC],
        rtol: float = 1e-7,
        atol: float = 1e-12,
        stol: float = 1e-10,
        max_iterations: int = 30,
        stall_iterations: int = 4,
        refactor_after: int = 25,
        krylov_rtol: float = 1e-11,
        forcing_max: float = 1e-3,
        lu_solver: str = "mumps",
        max_backtracks: int = 0,
        max_gap_change: float | None = None,
        limit_reversal: bool = True,
        zone: PETSc.IS | None = None,
        factorisations_kept: int = 3,
    ):
        if max_iterations < 1:
            raise ValueError(f"max_iterations must be >= 1, got {max_iterations}")
        if refactor_after < 0:
            raise ValueError(f"refactor_after must be >= 0, got {refactor_after}")
        if not (rtol > 0 and atol >= 0 and stol >= 0 and krylov_rtol > 0):
            raise ValueError("tolerances must be positive (atol, stol >= 0)")
        if not 0 <= forcing_max < 1:
            raise ValueError(f"forcing_max must lie in [0, 1), got {forcing_max}")
        self.krylov_rtol, self.forcing_max = krylov_rtol, forcing_max
        self.A = A
        self.rtol, self.atol, self.stol = rtol, atol, stol
        self.max_iterations = max_iterations
        if stall_iterations < 0:
            raise ValueError(f"stall_iterations must be >= 0, got {stall_iterations}")
        self.stall_iterations = stall_iterations
        self.refactor_after = refactor_after
        self.max_backtracks = max_backtracks
        self.limit_reversal = limit_reversal
        if max_gap_change is not None and not max_gap_change > 0:
            raise ValueError(f"max_gap_change must be positive [m] (or None), got {max_gap_change}")
        self.max_gap_change = max_gap_change
        self._bc_rows, self._bc_local = dirichlet_rows(bcs)
        self.bcs = bcs
        comm = A.getComm()
        self._comm = comm.tompi4py()
        self.ksp = PETSc.KSP().create(comm)
        self.ksp.setType(PETSc.KSP.Type.FGMRES)
        self.ksp.setGMRESRestart(max(refactor_after, 1) + 5)
        self.ksp.setPCSide(PETSc.PC.Side.RIGHT)
        self.ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
        self.ksp.setTolerances(rtol=krylov_rtol, atol=0.0, max_it=max(refactor_after, 5))
        self.ksp.setInitialGuessNonzero(False)
        self.zone = zone
        self._store = FactorStore(A, zone, lu_solver, factorisations_kept)
        pc = self.ksp.getPC()
        pc.setType(PETSc.PC.Type.PYTHON)
        self._preconditioner = BlockLU(
            None, None if zone is None else zone.getIndices() - A.getOwnershipRange()[0]
        )
        pc.setPythonContext(self._preconditioner)
        self._current: Factors | None = None  # the factors of the last correction
        self._bc_rows_hit: tuple | None = None  # (coo_pattern tag, whether J has Dirichlet rows)
        self._refactor_next = False

    def set_operator(self, A: PETSc.Mat) -> None:
        """A has new values in the same sparsity (e.g. another time step): the next correction
        factorises afresh (the solver objects, and the factorisation's ordering, are kept)."""
        self.A = A
        self._store.set_operator(A)
        self._current = None
        self._refactor_next = True

    @property
    def factorizations(self) -> int:
        """Numeric factorisations of A + J so far."""
        return self._store.factorizations

    def _use(self, factors: Factors) -> None:
        self._current = factors
        self._preconditioner.lu = factors.lu

    @timed("linear solves")
    def _correction(
        self,
        J: PETSc.Mat,
        status: np.ndarray,
        F: PETSc.Vec,
        du: PETSc.Vec,
        eta: float,
    ) -> int:
        """Solve (A + J) du = -F to GMRES relative tolerance eta, preconditioned by the kept factors
        nearest the contact ``status`` of J; returns GMRES iterations (refactorising when needed).

        The factors are reused until a solve needs more than ``refactor_after // 2`` GMRES
        iterations; the next correction then factorises anew.
        """
        rhs = F.copy()
        rhs.scale(-1.0)
        self._preconditioner.last = None
        fresh = self._store.empty or self.refactor_after == 0 or self._refactor_next
        self.ksp.setTolerances(rtol=eta)
        self._use(self._store.factorise(J, status) if fresh else self._store.nearest(status))
        operator = SumOperator(
            self.A, J, self._current.J_P, self._preconditioner, self._difference(J, fresh)
        )
        op = PETSc.Mat().createPython(self.A.getSizes(), operator, comm=self.A.getComm())
        op.setUp()
        self.ksp.setOperators(op)
        self.ksp.solve(rhs, du)
        its = self.ksp.getIterationNumber()
        if not fresh and self.ksp.getConvergedReason() <= 0:
            self._use(self._store.factorise(J, status))
            operator.J_P, operator.difference = self._current.J_P, SumOperator.ZERO
            self.ksp.solve(rhs, du)
            its += self.ksp.getIterationNumber()
            fresh = True
        # iteration counts, not timings, decide: the same on every rank (ranks that disagreed
        # would deadlock in the factorisation) and in every run, so that the reused factors,
        # and hence the results, do not depend on the machine's load
        self._refactor_next = not fresh and its > self.refactor_after // 2
        reason = self.ksp.getConvergedReason()
        op.destroy()
        rhs.destroy()
        if reason <= 0:
            raise RuntimeError(f"linear solve failed (KSP reason {reason})")
        return its

    def _difference(self, J: PETSc.Mat, fresh: bool) -> PETSc.Mat | str | None:
        """J - J_P for ``SumOperator``: ZERO right after factorising J; assembled in J_P's
        sparsity when J has the same ``coo_pattern`` (collective); else None."""
        if fresh:
            return SumOperator.ZERO
        factors = self._current
        pattern = J.getAttr("coo_pattern")
        same = pattern is not None and pattern == factors.pattern
        if not self._comm.allreduce(same, op=MPI.LAND):
            return None
        if factors.D is None:
            factors.D = factors.J_P.duplicate(copy=False)
        J.copy(factors.D, PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        factors.D.axpy(-1.0, factors.J_P, PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        return factors.D

    def _clear_bc_rows(self, J: PETSc.Mat) -> None:
        """Zero J's Dirichlet rows, if it has any (checked once per sparsity pattern)."""
        pattern = J.getAttr("coo_pattern")
        if pattern is None or self._bc_rows_hit is None or self._bc_rows_hit[0] != pattern:
            indptr = J.getValuesCSR()[0]
            start = J.getOwnershipRange()[0]
            rows = start + np.flatnonzero(np.diff(indptr))
            hit = self._comm.allreduce(bool(np.intersect1d(rows, self._bc_rows).size), op=MPI.LOR)
            self._bc_rows_hit = (pattern, hit)
        if self._bc_rows_hit[1]:
            J.setOption(
                PETSc.Mat.Option.KEEP_NONZERO_PATTERN, True
            )  # J's owner refills this pattern
            J.zeroRows(self._bc_rows, diag=0.0)

    def _residual(
        self,
        linear: PETSc.Vec,
        contact: ContactModel,
        u: dolfinx.fem.Function,
        F: PETSc.Vec,
        update: bool = True,
    ) -> float:
        """F = linear + r_c(u) (see :func:`contact_residual`); returns ||F||."""
        return contact_residual(linear, contact, u, F, self._bc_local, update)

    def _trial(self, step: "_Step", contact, u, alpha: float, F) -> float:
        """Move to u = x0 + alpha du; returns ||F|| there (contact updated at u)."""
        x = u.x.petsc_vec
        step.x0.copy(x)
        x.axpy(alpha, step.du)
        u.x.scatter_forward()
        step.linear0.copy(step.linear)
        step.linear.axpy(alpha, step.A_du)  # A u - b = (A x0 - b) + alpha A du
        return self._residual(step.linear, contact, u, F)

    def _newton_step(self, step: "_Step", contact, u, F, norm: float) -> tuple[float, float]:
        """Save u in x0 and take the Newton step, shortened by the gap limit; if that does not lower
        ||F|| (= norm at x0) and some slipping point's friction would reverse on the way, shortened
        to where the first one would. Returns (alpha, ||F||) of the step taken."""
        u.x.petsc_vec.copy(step.x0)
        step.linear.copy(step.linear0)
        self.A.mult(step.du, step.A_du)
        gap = contact.state.gap.copy() if self.max_gap_change is not None else None
        slip = contact.slip_directions() if self.limit_reversal and self.max_backtracks else None
        trial = self._trial(step, contact, u, 1.0, F)
        alpha = 1.0 if gap is None else self._gap_limited_step(gap, contact.state.gap)
        reversal = (
            1.0 if slip is None else self._comm.allreduce(contact.reversal_limit(*slip), op=MPI.MIN)
        )
        if alpha < 1.0:
            trial = self._trial(step, contact, u, alpha, F)
        if trial >= norm and reversal < alpha:
            alpha = reversal
            trial = self._trial(step, contact, u, alpha, F)
        return alpha, trial

    def _backtrack(
        self, step: "_Step", contact, u, F, norm: float, alpha: float, trial: float
    ) -> float:
        """From the step x0 + alpha du (||F|| = trial there), halve the step (up to ``max_backtracks``
        times) while ||F|| >= norm. Generalized Newton on stick/slip/open switches can cycle (e.g.
        with velocity-weakening friction); backtracking breaks such cycles. If no trial step
        lowers ||F||, the one with the smallest ||F|| is kept. Leaves u, F, A u - b and the contact
        state at the accepted point; returns its ||F||.
        """
        best = (trial, alpha)
        for _ in range(self.max_backtracks):
            if trial < norm:
                return trial
            alpha *= 0.5
            trial = self._trial(step, contact, u, alpha, F)
            best = min(best, (trial, alpha))
        if trial < norm or best[1] == alpha:
            return trial
        return self._trial(step, contact, u, best[1], F)

    def _gap_limited_step(self, gap: np.ndarray, trial_gap: np.ndarray) -> float:
        """Largest fraction (<= 1, the same on all ranks) of the step keeping each point's approach
        (gap decrease) within max(max_gap_change, g / 2), the gap assumed linear along the step."""
        approach = gap - trial_gap
        allowed = np.maximum(self.max_gap_change, 0.5 * gap)
        ratio = np.where(np.isfinite(approach) & (approach > 0), approach / allowed, 0.0)
        worst = self._comm.allreduce(float(ratio.max()) if ratio.size else 0.0, op=MPI.MAX)
        return 1.0 if worst <= 1.0 else 1.0 / worst

    def solve(
        self,
        b: PETSc.Vec,
        contact: ContactModel,
        u: dolfinx.fem.Function,
        load_norm: float | None = None,
    ) -> NewtonResult:
        """Solve A u + r_c(u) = b for u (initial guess: u on entry, Dirichlet values imposed).

        ``load_norm``: the ||b|| [N] of the relative tolerance (default: ||b||; the condensed
        system of ``solver.dynamics.condensation`` passes its uncondensed load's, so that both stop alike).
        """
        for bc in self.bcs:
            bc.set(u.x.array)
        u.x.scatter_forward()
        x = u.x.petsc_vec
        F = x.duplicate()
        step = _Step(*(x.duplicate() for _ in range(5)))
        self.A.mult(x, step.linear)
        step.linear.axpy(-1.0, b)
        norms, linear = [], []
        b_norm = b.norm() if load_norm is None else load_norm
        factorizations0 = self.factorizations
        result = None
        step_small = False
        eta = self.forcing_max
        # e.g. a time step's predictor, where the caller evaluated the contact status
        norm = self._residual(step.linear, contact, u, F, update=not contact.updated_at(u))
        for k in range(self.max_iterations + 1):
            norms.append(norm)
            tol = max(self.atol, self.rtol * max(norms[0], b_norm), contact.residual_floor())
            result = newton_stop(norms, tol, self.max_iterations, linear, step_small)
            if result is not None:
                break
            best = int(np.argmin(norms))
            if self.stall_iterations and k - best >= self.stall_iterations:
                result = NewtonResult(
                    False,
                    k,
                    norms,
                    linear,
                    message=f"||F|| not decreasing: smallest {norms[best]:.3e} N at "
                    f"iteration {best}, now {norm:.3e} N at iteration {k}",
                )
                break
            J = contact.jacobian()  # the contact's matrix: not ours to destroy
            self._clear_bc_rows(J)
            try:
                eta = forcing_term(norms, eta, tol, self.forcing_max, self.krylov_rtol)
                linear.append(self._correction(J, contact.state.status, F, step.du, eta))
            except (PETSc.Error, RuntimeError) as err:
                result = NewtonResult(
                    False,
                    k,
                    norms,
                    linear,
                    message=f"linear solve failed at Newton iteration {k}: {err}",
                )
                break
            alpha, trial = self._newton_step(step, contact, u, F, norm)
            norm = self._backtrack(step, contact, u, F, norm, alpha, trial)
            step_small = step.du.norm(PETSc.NormType.INFINITY) <= self.stol * x.norm(
                PETSc.NormType.INFINITY
            )
        for vec in (F, *step.__dict__.values()):
            vec.destroy()
        result.factorizations = self.factorizations - factorizations0
        count("gmres", sum(result.linear_iterations))
        return result

    def destroy(self) -> None:
        self.ksp.destroy()
        self._store.destroy()


def solve_contact_problem(
    A: PETSc.Mat,
    b: PETSc.Vec,
    contact: ContactModel,
    u: dolfinx.fem.Function,
    bcs: list[dolfinx.fem.DirichletBC],
    **options,
) -> NewtonResult:
    """Solve A u + r_c(u) = b once by generalized Newton with a solver made for it (see
    ContactNewtonSolver for ``options``); ``converged=False`` (with ``message``) lets the
    caller cut the step."""
    solver = ContactNewtonSolver(A, bcs, **options)
    try:
        return solver.solve(b, contact, u)
    finally:
        solver.destroy()
