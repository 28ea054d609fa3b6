"""Report of the wall time per phase of the contact time step (benchmarks only).

The solver names its phases with ``common.timing.timed`` and counts inner iterations with
``common.timing.count``; ``PhaseTimer`` is the ``common.timing.PhaseTimes`` the benchmarks
record into (``with recording(timer): ...``) and prints what it holds. The phases, each
*exclusive* of the phases nested in it:

    pairing            solver.contact.pairing.pair (closest-point projection)
    contact update     NitscheContact.update without the pairing (state at the iterate)
    contact residual   NitscheContact.residual
    contact jacobian   NitscheContact.jacobian
    factorisation      FactorStore.factorise (A + J_c copy and LU); with the contact-point solver
                       the LU of A' (PointNewtonSolver)
    triangular solves  one forward and back solve with the contact zone's LU factors:
                       BlockLU.apply (of A + J_c), ContactCompliance.solve (of A')
    linear solves      the zone Newton's corrections without factorisation and triangular
                       solves (GMRES, products with the interface matrices)
    compliance         ContactCompliance.extend (the columns A'^-1 [F^T W, E^T, I_b] of new
                       contact points and master dofs, on several ranks with the sequential
                       factorisation of each rank's copy of A' at a stage's first extension) and
                       ContactCompliance.matrix (G per pairing)
    tractions          solve_tractions: the semismooth Newton of the contact points' tractions
    condensation       solver.dynamics.condensation.BulkCondensation: building and updating it (once
                       per step size), the condensed load and the recovery of the bulk (one bulk solve
                       each per step)
    bulk vectors       Elastodynamics: effective load, load evaluation, operator assembly
    other              the rest of Elastodynamics.step

Times are this rank's; ``report`` prints rank 0's, with the number of calls of each phase
(e.g. factorisations, pairings), and what the tractions phase did
(``solver.dynamics.traction_jacobian``): single-precision factorisations of the active points'
Jacobian (reduced by the kernel of the law's derivative) and their mean rows, Woodbury updates
of the kept factors and FGMRES iterations.
"""

import resource

from common.timing import PhaseTimes

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


def peak_memory_mb() -> float:
    """This process's peak resident memory [MB] so far (Linux ru_maxrss)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


class PhaseTimer(PhaseTimes):
    """The phase times of Elastodynamics.step and the inner iteration counts (module docstring)."""

    @property
    def gmres(self) -> int:
        """GMRES iterations of the zone Newton's corrections."""
        return self.counts.get("gmres", 0)

    @property
    def traction_iterations(self) -> int:
        """Semismooth iterations of the contact points' tractions."""
        return self.counts.get("traction iterations", 0)

    @property
    def inner(self) -> dict[str, int]:
        """The traction Jacobian's factorisations, their rows in all, Woodbury updates and FGMRES
        iterations."""
        return {
            key: self.counts.get(f"traction {key}", 0)
            for key in ("factorisations", "factor rows", "updates", "krylov")
        }

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
                f"    tractions: {inner['factorisations'] / n:.2f} single-precision factorisations "
                f"({inner['factor rows'] / max(inner['factorisations'], 1):.0f} rows on average), "
                f"{inner['updates'] / n:.2f} Woodbury updates and {inner['krylov'] / n:.1f} FGMRES "
                f"iterations per step ({inner['krylov'] / self.traction_iterations:.1f} per "
                "traction iteration)"
            )
