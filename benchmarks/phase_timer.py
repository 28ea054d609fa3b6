"""Wall time per phase of the contact time step, by instrumenting solver methods (benchmarks only).

``PhaseTimer.install()`` wraps, at class level, the methods that make up a step of
``solver.dynamics.elastodynamics.Elastodynamics`` with contact and accumulates *exclusive* wall
time (a phase nested in another is not counted twice) per phase:

    pairing            solver.contact.pairing.pair (closest-point projection)
    contact update     NitscheContact.update without the pairing (state at the iterate)
    contact residual   NitscheContact.residual
    contact jacobian   NitscheContact.jacobian (+ Dirichlet row zeroing, copy into A + J)
    factorisation      FactorStore.factorise (A + J_c copy and LU); with the contact-point solver
                       PointNewtonSolver._factorise (the LU of A')
    triangular solves  one forward and back solve with the contact zone's LU factors:
                       BlockLU.apply (of A + J_c), ContactCompliance.solve (of A')
    linear solves      ContactNewtonSolver._correction without factorisation and triangular solves
                       (GMRES, products with the interface matrices)
    compliance         ContactCompliance.extend (the columns A'^-1 [F^T W, E^T, I_b] of new
                       contact points and master dofs) and ContactCompliance.matrix (G per pairing)
    tractions          solve_tractions: the semismooth Newton of the contact points' tractions
    condensation       solver.dynamics.condensation.BulkCondensation: building and updating it (once
                       per step size), the condensed load and the recovery of the bulk (one bulk solve
                       each per step)
    bulk vectors       Elastodynamics._effective_load, load evaluation, Newmark update, A u
    other              the rest of Elastodynamics.step

Times are this rank's; ``report`` prints rank 0's, with the number of calls of each phase
(e.g. factorisations, pairings), and what the tractions phase did
(``solver.dynamics.traction_jacobian``): single-precision factorisations of the active points'
Jacobian, Woodbury updates of the kept factors and FGMRES iterations.
"""

import functools
import time
from collections import defaultdict

import solver.contact.nitsche
import solver.dynamics.condensation
import solver.dynamics.elastodynamics
import solver.dynamics.factor_store
import solver.dynamics.linear_algebra
import solver.dynamics.newton
import solver.dynamics.point_newton
import solver.dynamics.traction_jacobian

PHASES = [
    "pairing",
    "contact update",
    "contact residual",
    "contact jacobian",
    "factorisation",
    "triangular solves",
    "linear solves",
    "compliance",
    "tractions",
    "condensation",
    "bulk vectors",
    "other",
]


class PhaseTimer:
    """Exclusive wall time per phase of Elastodynamics.step (see module docstring)."""

    def __init__(self):
        self.totals: dict[str, float] = defaultdict(float)
        self.cpu: dict[str, float] = defaultdict(float)  #: process CPU time per phase [s]
        self.calls: dict[str, int] = defaultdict(int)
        self.gmres = 0  #: GMRES iterations (generalized Newton on the zone)
        self.traction_iterations = 0  #: semismooth iterations (Newton on the contact points)
        #: the traction Jacobian's factorisations, Woodbury updates and FGMRES iterations
        self.inner: dict[str, int] = defaultdict(int)
        self._stack: list[
            list
        ] = []  # [phase, start, cpu start, wall and cpu time spent in nested phases]
        self._undo: list = []

    def _enter(self, phase: str) -> None:
        self._stack.append([phase, time.perf_counter(), time.process_time(), 0.0, 0.0])

    def _exit(self) -> None:
        phase, start, cpu_start, nested, nested_cpu = self._stack.pop()
        elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu_start
        self.totals[phase] += elapsed - nested
        self.cpu[phase] += cpu - nested_cpu
        self.calls[phase] += 1
        if self._stack:
            self._stack[-1][3] += elapsed
            self._stack[-1][4] += cpu

    def _wrap(self, owner, name: str, phase: str) -> None:
        original = getattr(owner, name)

        @functools.wraps(original)
        def timed(*args, **kwargs):
            self._enter(phase)
            try:
                return original(*args, **kwargs)
            finally:
                self._exit()

        setattr(owner, name, timed)
        self._undo.append((owner, name, original))

    def install(self) -> "PhaseTimer":
        NC = solver.contact.nitsche.NitscheContact
        CN = solver.dynamics.newton.ContactNewtonSolver
        ED = solver.dynamics.elastodynamics.Elastodynamics
        self._wrap(ED, "step", "other")
        self._wrap(solver.contact.nitsche, "pair", "pairing")
        self._wrap(NC, "update", "contact update")
        self._wrap(NC, "residual", "contact residual")
        self._wrap(NC, "jacobian", "contact jacobian")
        self._wrap(solver.dynamics.factor_store.FactorStore, "factorise", "factorisation")
        self._wrap(CN, "_correction", "linear solves")
        self._wrap(solver.dynamics.linear_algebra.BlockLU, "apply", "triangular solves")
        PN = solver.dynamics.point_newton
        self._wrap(PN.PointNewtonSolver, "_factorise", "factorisation")
        self._wrap(PN.ContactCompliance, "solve", "triangular solves")
        for name in ("extend", "matrix"):
            self._wrap(PN.ContactCompliance, name, "compliance")
        self._wrap(PN, "solve_tractions", "tractions")  # the name point_newton calls it by
        for name in ("__init__", "update", "reduce_load", "recover"):
            self._wrap(solver.dynamics.condensation.BulkCondensation, name, "condensation")
        for name in ("_effective_load", "_evaluate_load", "_assemble_operator"):
            self._wrap(ED, name, "bulk vectors")
        self._count(CN, "gmres")
        self._count(PN.PointNewtonSolver, "traction_iterations")
        self._tally_inner(solver.dynamics.traction_jacobian.TractionJacobian)
        return self

    def _tally_inner(self, jacobian_class) -> None:
        """Add the growth of a traction Jacobian's counters over each of its solves to ``inner``."""
        original = jacobian_class.solve
        counters = {
            "factorisations": "factorizations",
            "updates": "updates",
            "krylov": "krylov_iterations",
        }

        @functools.wraps(original)
        def tallied(jacobian, *args, **kwargs):
            before = {key: getattr(jacobian, name) for key, name in counters.items()}
            result = original(jacobian, *args, **kwargs)
            for key, name in counters.items():
                self.inner[key] += getattr(jacobian, name) - before[key]
            return result

        jacobian_class.solve = tallied
        self._undo.append((jacobian_class, "solve", original))

    def _count(self, solver_class, counter: str) -> None:
        """Add the inner iterations of ``solver_class.solve`` (NewtonResult.linear_iterations:
        GMRES iterations, or the contact points' semismooth iterations) to ``counter``."""
        original = solver_class.solve

        @functools.wraps(original)
        def counted(*args, **kwargs):
            result = original(*args, **kwargs)
            setattr(self, counter, getattr(self, counter) + sum(result.linear_iterations))
            return result

        solver_class.solve = counted
        self._undo.append((solver_class, "solve", original))

    def uninstall(self) -> None:
        for owner, name, original in reversed(self._undo):
            setattr(owner, name, original)
        self._undo.clear()

    def reset(self) -> None:
        self.totals.clear()
        self.cpu.clear()
        self.calls.clear()
        self.gmres = 0
        self.traction_iterations = 0
        self.inner.clear()

    def triangular_solve_s(self) -> float:
        """Mean wall time of one application of the LU factors (forward and back solve) [s]."""
        calls = self.calls.get("triangular solves", 0)
        return self.totals.get("triangular solves", 0.0) / calls if calls else float("nan")

    def report(self, comm, steps: int, iterations: int, say=print) -> None:
        """Print wall s/step, s/Newton iteration and CPU s/step of each phase (rank 0's times) and,
        on several ranks, the largest wall time of each phase over the ranks. On a shared machine
        the CPU time is the load-independent figure (MPI waits count as CPU time: MPICH polls)."""
        per_rank = comm.allgather(dict(self.totals))
        total, total_cpu = sum(self.totals.values()), sum(self.cpu.values())
        n, its = max(steps, 1), max(iterations, 1)
        say(
            f"  phase breakdown (rank 0, {steps} steps, {iterations} Newton iterations, {self.gmres} GMRES "
            f"and {self.traction_iterations} traction iterations, {self.calls.get('factorisation', 0)} factorisations; "
            f"slowest rank {max(sum(t.values()) for t in per_rank) / n:.3f} s/step):"
        )
        for phase in PHASES:
            t = self.totals.get(phase, 0.0)
            line = (
                f"    {phase:17s} {t / n:8.3f} s/step {t / its:8.3f} s/iteration "
                f"{100 * t / total if total else 0:5.1f} %  CPU {self.cpu.get(phase, 0.0) / n:7.3f} s/step"
            )
            if comm.size > 1:
                line += (
                    f"  max over ranks {max(r.get(phase, 0.0) for r in per_rank) / n:7.3f} s/step"
                )
            say(line + f"  ({self.calls.get(phase, 0)} calls)")
        say(f"    {'total':17s} {total / n:8.3f} s/step{'':33s}CPU {total_cpu / n:7.3f} s/step")
        if self.traction_iterations:
            inner = self.inner
            say(
                f"    tractions: {inner['factorisations'] / n:.2f} single-precision factorisations, "
                f"{inner['updates'] / n:.2f} Woodbury updates and {inner['krylov'] / n:.1f} FGMRES "
                f"iterations per step ({inner['krylov'] / self.traction_iterations:.1f} per "
                "traction iteration)"
            )
