"""Newton on the contact points for A u + r_c(u) = b: the nonsmooth contact law is solved in the
trial tractions of the points that can touch, the linear rest held in fixed LU factors
(docs/dynamics.md, "Newton on the contact points").

With the pairing and the normals frozen at the iterate u_k, the
Nitsche residual (``solver.contact.nitsche``) is a linear part at every paired point plus, at
the candidate points C that can touch, F^T W lambda(P) with the multipliers lambda of the
pointwise law (``solver.contact.law``) of the trial tractions P = P_k + E (u - u_k). With A'
the linear operator (A and the linear Nitsche part, factorised once per A), the correction
delta from u_k solves

    R_k + A' delta + F^T W (lambda(P_k + E delta) - lambda_k) = 0,

with lambda_k and R_k at the coefficients mu(u_k) and lambda(.) at coefficients frozen for the
step's inner problem: mu(u_k) too, or with mu at the step's own slip speed their Aitken
relaxation (``solver.dynamics.relaxation``),
that is, in the candidates' trial tractions y = P_k + E delta (3 |C| unknowns),

    y - y_free + G lambda(y) = 0,   G = E A'^-1 F^T W,   y_free = P_k - E A'^-1 R_k + G lambda_k,

with the dense compliance G of ``solver.dynamics.compliance``. A semismooth Newton method with a
line search solves it (:func:`solve_tractions`); then delta = -A'^-1 (R_k + F^T W (lambda(y) -
lambda_k)). The outer iteration repeats with the true residual R (new pairing and normals)
until ||R|| meets the tolerance. The stick-slip-open transitions are resolved in the small
dense problem, so the outer iteration converges in two or three iterations (about four with mu
at the step's own slip speed, a fixed point in mu as well). A point outside C
that comes into contact, or a pairing that leaves the master band, extends C or the band and
recomputes the compliance blocks.
"""

from collections.abc import Sequence
from typing import cast

import numpy as np
import numpy.typing as npt
from mpi4py import MPI
from petsc4py import PETSc

import dolfinx

from common.timing import count, timed
from solver.contact.model import ContactModel, Status
from solver.contact.nitsche import NitscheContact
from solver.dynamics.compliance import ContactCompliance
from solver.dynamics.newton import NewtonResult, newton_stop
from solver.dynamics.relaxation import CoefficientRelaxation
from solver.dynamics.residual import contact_residual, dirichlet_rows
from solver.dynamics.traction_jacobian import TractionJacobian
from solver.dynamics.tractions import (
    Evaluation,
    pointwise_law,
    solve_tractions,
    traction_residual,
)

__all__ = ["PointNewtonSolver"]


class PointNewtonSolver:
    """Newton on the contact points for A u + r_c(u) = b (module docstring).

    Args:
        A: bulk operator with Dirichlet rows/columns as identities (with a ``zone``: identity rows
            off it, ``solver.dynamics.condensation``), constant while this solver is used.
        bcs: Dirichlet conditions of the problem.
        zone: global dofs (this rank's part) of the block that the contact acts on; None: all.
        rtol, atol, max_iterations: convergence of the outer iteration, as in
            ``solver.dynamics.newton.ContactNewtonSolver``.
        lu_solver: PETSc factorisation package of A'.
        candidate_gap: points within this gap of the master [m] (and all points of their slave
            facets) are candidates; points outside that come into contact are added.
        traction_rtol, traction_iterations: tolerance and iteration limit of the inner problem.
        traction_forcing: the inner problem also stops where its residual, as forces on the
            points, is below this fraction of the outer residual ||R_k|| (an inexact outer
            Newton step; the outer test on the true residual decides convergence).
        pairing_rtol: G is recomputed when the candidates' master parts moved by more than this
            fraction since it was (or a candidate paired with another master facet).
        slow_contraction: G is also recomputed at the present pairing when the last outer
            iteration, with a kept G, reduced ||R|| by less than this factor, unless the friction
            coefficients moved (``CoefficientRelaxation.moving``: the slow rate is then that of
            the fixed point in mu, which a new G does not change).
        look_ahead: when candidates are added, the facets within this multiple of
            ``candidate_gap`` are added as well.
        drop_after: a candidate is dropped after this many solves in a row far from the master.
    """

    def __init__(
        self,
        A: PETSc.Mat,
        bcs: list[dolfinx.fem.DirichletBC],
        zone: PETSc.IS | None = None,
        rtol: float = 1e-7,
        atol: float = 1e-12,
        max_iterations: int = 12,
        lu_solver: str = "mumps",
        candidate_gap: float = 2e-6,
        traction_rtol: float = 1e-12,
        traction_iterations: int = 60,
        traction_forcing: float = 1e-3,
        pairing_rtol: float = 1e-2,
        slow_contraction: float = 0.03,
        look_ahead: float = 4.0,
        drop_after: int = 10,
    ):
        if max_iterations < 1:
            raise ValueError(f"max_iterations must be >= 1, got {max_iterations}")
        if not (rtol > 0 and atol >= 0 and traction_rtol > 0 and traction_forcing >= 0):
            raise ValueError("tolerances must be positive (atol, traction_forcing >= 0)")
        if not candidate_gap >= 0:
            raise ValueError(f"candidate_gap must be >= 0 m, got {candidate_gap}")
        if not look_ahead >= 1:
            raise ValueError(f"look_ahead must be >= 1, got {look_ahead}")
        if not drop_after >= 1:
            raise ValueError(f"drop_after must be >= 1, got {drop_after}")
        self.A, self.bcs = A, bcs
        self.rtol, self.atol, self.max_iterations = rtol, atol, max_iterations
        self.lu_solver = lu_solver
        self.candidate_gap = candidate_gap
        self.look_ahead, self.drop_after = look_ahead, drop_after
        self.traction_rtol, self.traction_iterations = traction_rtol, traction_iterations
        self.traction_forcing = traction_forcing
        self._comm: MPI.Comm = A.getComm().tompi4py()
        self._bc_rows, self._bc_local = dirichlet_rows(bcs)
        start, end = A.getOwnershipRange()
        self._zone = zone if zone is not None else PETSc.IS().createStride(end - start, start, 1)
        self._zone_local = self._zone.getIndices() - start
        self._compliance: ContactCompliance | None = None
        self._G: npt.NDArray | None = None  # the inner problem's G and the master parts it used
        self._G_master: tuple[npt.NDArray, npt.NDArray] | None = None
        #: the inner problem's linear solves; its factors are kept while the points are the same
        self.jacobian = TractionJacobian(self._comm)
        self._last_y: npt.NDArray | None = None  # the last inner solution, while its points stay
        self._relaxation: CoefficientRelaxation | None = None
        self.pairing_rtol, self.slow_contraction = pairing_rtol, slow_contraction
        self._candidates = np.zeros(0, dtype=np.int64)  # this rank's candidate points
        self._far_solves = np.zeros(0, dtype=np.int64)  # solves each candidate has been far
        self.factorizations = 0  #: LU factorisations of A'

    def set_operator(self, A: PETSc.Mat) -> None:
        """A has new values (another time step): A' is factorised and the blocks rebuilt at the
        next solve."""
        self.A = A
        self._drop()

    @property
    def compliance(self) -> ContactCompliance:
        """The factors of A' and the compliance blocks (after the first solve)."""
        if self._compliance is None:
            raise RuntimeError("PointNewtonSolver: no operator factorised yet")
        return self._compliance

    def _drop(self) -> None:
        if self._compliance is not None:
            self._compliance.A.destroy()
            self._compliance.destroy()
        self._compliance = None

    # -- the linear operator A' and the compliance blocks ------------------------------------------
    @timed("factorisation")
    def _factorise(self, contact: NitscheContact) -> None:
        """A' = A + the linear Nitsche part at every paired point, on the zone, factorised."""
        J = contact.interface_stiffness(Status.OPEN)
        J.zeroRows(cast(Sequence[int], self._bc_rows), diag=0.0)
        # summed at full size: PETSc's MatAXPY of two parallel submatrices whose off-process
        # columns differ fails ("Non conforming matrix add")
        full = self.A.copy()
        full.axpy(1.0, J, cast(PETSc.Mat.Structure, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN))
        A_prime = full.createSubMatrix(self._zone, self._zone)
        full.destroy()
        zone_dofs = np.concatenate(self._comm.allgather(self._zone.getIndices()))
        self._compliance = ContactCompliance(A_prime, zone_dofs, self.lu_solver)
        self._candidates = self._far_solves = np.zeros(0, dtype=np.int64)
        self._new_points()
        self.factorizations += 1

    def _new_points(self) -> None:
        """Other candidates: the inner problem's factors and last solution are dropped."""
        self.jacobian.reset()
        self._last_y = None
        if self._relaxation is not None:
            self._relaxation.reset()

    def _starts(
        self,
        y_k: npt.NDArray,
        y_free: npt.NDArray,
        normal: npt.NDArray,
        mu: npt.NDArray,
    ) -> list[tuple[npt.NDArray, Evaluation | None]]:
        """The inner problem's starts, in order, with the residual at each where it was evaluated
        (with the jacobian's G): of the iterate's tractions y_k and the last inner solution
        (points appended since then at y_k) the one with the smaller ||Phi|| first (within a
        step, y_k; at a new step's first iteration often the last solution, nearer in stick and
        slip than the predictor's), then the other, then y_free (the tractions if the
        multipliers kept their values: for every point open, where the first step from y_k
        closes them all at once)."""
        if self._last_y is None:
            return [(y_k, None), (y_free, None)]
        last = y_k.copy()
        last[: len(self._last_y)] = self._last_y
        at_k, at_last = (
            (y, traction_residual(self.jacobian, y, y_free, normal, mu)) for y in (y_k, last)
        )
        nearer = np.abs(at_last[1].phi).max(initial=0.0) < np.abs(at_k[1].phi).max(initial=0.0)
        return [at_last, at_k, (y_free, None)] if nearer else [at_k, at_last, (y_free, None)]

    def _update_points(self, contact: NitscheContact, first: bool) -> None:
        """Fit the candidates and the master band to the contact (collective).

        Candidates: the points of this rank's slave facets with a paired point in contact or
        within ``candidate_gap`` of the master; when some must be added, those within
        ``look_ahead`` times that gap come too (fewer, larger extensions); a facet stays a
        candidate until all of its points have been more than twice that far away at the
        first iteration (``first``) of ``drop_after`` solves in a row (hysteresis in space and
        in time: after a switch to longer steps an unresolved ringing brings points near and
        away in turns, each return costing an extension of the blocks). Band:
        the dofs of the master facets the candidates pair with. New points and dofs extend the
        compliance blocks, dropped ones are cut from them (when they are a tenth of the candidates
        or more); a candidate that lost its partner restarts the blocks.
        """
        trial = contact.trial_tractions()
        P_n = np.einsum("pi,pi->p", trial.traction, trial.normal)
        gap = trial.gap
        nq = contact.slave.points_per_facet
        compliance, comm = self.compliance, self._comm

        def facet_points(mask):
            facets = np.unique(np.flatnonzero(trial.paired & mask) // nq)
            points = (facets[:, None] * nq + np.arange(nq)).ravel()
            return points[trial.paired[points]]

        if comm.allreduce(bool(np.any(~trial.paired[self._candidates])), op=MPI.LOR):
            compliance.reset()
            self._candidates = self._far_solves = np.zeros(0, dtype=np.int64)
            self._new_points()
        near = facet_points((gap <= self.candidate_gap) | (P_n <= 0))
        kept = facet_points((gap <= 2 * self.look_ahead * self.candidate_gap) | (P_n <= 0))
        near_now = np.isin(self._candidates, kept)
        if first:
            self._far_solves = np.where(near_now, 0, self._far_solves + 1)
        keep = near_now | (self._far_solves < self.drop_after)
        dropped = comm.allreduce(int(np.count_nonzero(~keep)), op=MPI.SUM)
        if dropped and dropped >= 0.1 * compliance.points:
            self._candidates = self._candidates[keep]
            self._far_solves = self._far_solves[keep]
            ops = contact.point_operators(self._candidates)
            needed = self._band_dofs(ops.master_dofs)
            compliance.restrict(ops, keep, np.isin(compliance.band, needed))
            self._G_master = None
            self._new_points()
        new = np.setdiff1d(near, self._candidates)
        added = comm.allreduce(len(new), op=MPI.SUM)
        if added:  # those about to come near as well
            ahead = facet_points((gap <= self.look_ahead * self.candidate_gap) | (P_n <= 0))
            new = np.setdiff1d(ahead, self._candidates)
        candidates = np.concatenate([self._candidates, new])
        ops = contact.point_operators(candidates)
        band = np.setdiff1d(self._band_dofs(ops.master_dofs), compliance.band)
        if added or len(band):
            compliance.extend(ops, len(new), band)
            self._candidates = candidates
            self._far_solves = np.concatenate([self._far_solves, np.zeros(len(new), np.int64)])
            self._G_master = None  # the earlier points keep their places: the factors stay

    def _band_dofs(self, master_dofs: npt.NDArray) -> npt.NDArray:
        """The master dofs (``PointOperators.master_dofs``) of the points of every rank (sorted)."""
        return np.unique(np.concatenate(self._comm.allgather(np.unique(master_dofs))))

    def _gather_points(self, contact: NitscheContact):
        """The candidates' trial tractions, normals, friction coefficients, weights w / gamma and
        areas w [m^2] (in the compliance blocks' order), their master operator on the band and its
        dofs and values."""
        comm, points = self._comm, self._candidates
        ops = contact.point_operators(points)
        trial = contact.trial_tractions()

        def gather(a):
            return self.compliance.points_to_block(
                np.concatenate(comm.allgather(np.ascontiguousarray(a)))
            )

        master_dofs, master = gather(ops.master_dofs), gather(ops.master)
        return (
            gather(trial.traction[points]).ravel(),
            gather(trial.normal[points]),
            gather(trial.mu[points]),
            gather(ops.weight),
            gather(contact.slave.weights[points]),
            self.compliance.master_operator(master_dofs, master),
            (master_dofs, master),
        )

    def _compliance_matrix(self, M_b, weight, master, keep: bool) -> tuple[npt.NDArray, bool]:
        """G at the present pairing and whether it was built now: where ``keep``, the last one
        while no candidate changed its master facet and the master parts moved by at most
        ``pairing_rtol`` of their size (G is the Jacobian of the inner problem; the residuals
        use the present pairing)."""
        kept = self._G_master
        if keep and self._G is not None and kept is not None and np.array_equal(kept[0], master[0]):
            change = np.abs(master[1] - kept[1]).max(initial=0.0)
            if change <= self.pairing_rtol * np.abs(kept[1]).max(initial=0.0):
                return self._G, False
        G = self.compliance.matrix(M_b, weight)
        self._G, self._G_master = G, master
        return G, True

    def solve(
        self,
        b: PETSc.Vec,
        contact: NitscheContact,
        u: dolfinx.fem.Function,
        load_norm: float | None = None,
    ) -> NewtonResult:
        """Solve A u + r_c(u) = b for u (initial guess: u on entry, Dirichlet values imposed);
        ``load_norm`` as in ``ContactNewtonSolver.solve``."""
        for bc in self.bcs:
            bc.set(u.x.array)
        u.x.scatter_forward()
        x = u.x.petsc_vec
        F, linear, delta = x.duplicate(), x.duplicate(), x.duplicate()
        self.A.mult(x, linear)
        linear.axpy(-1.0, b)
        model = cast(ContactModel, contact)
        norm = contact_residual(
            linear, model, u, F, self._bc_local, update=not contact.updated_at(u)
        )
        if self._compliance is None:
            self._factorise(contact)
        compliance = self.compliance
        r_zone, d_zone, v_zone = (compliance.A.createVecLeft() for _ in range(3))
        b_norm = cast(float, b.norm()) if load_norm is None else load_norm
        norms: list[float] = []
        inner: list[int] = []
        result: NewtonResult | None = None
        factorizations0 = self.factorizations
        law = contact.friction  # its range now: the bounds of the relaxed coefficients
        relaxation = self._relaxation = CoefficientRelaxation(*sorted((law.mu_s, law.mu_d)))
        built = False
        for k in range(self.max_iterations + 1):
            norms.append(norm)
            tol = max(self.atol, self.rtol * max(norms[0], b_norm), contact.residual_floor())
            result = newton_stop(norms, tol, self.max_iterations)
            if result is not None:
                break
            self._update_points(contact, first=k == 0)
            y_k, normal, mu, weight, area, M_b, master = self._gather_points(contact)
            mu_inner = relaxation(mu)
            # a kept G that slowed the last iteration down is rebuilt at the present pairing,
            # unless the coefficients moved (the slow rate is then the fixed point's in mu)
            slow = k > 0 and not built and norm > self.slow_contraction * norms[-2]
            slow = slow and not relaxation.moving
            G, built = self._compliance_matrix(M_b, weight, master, keep=not slow)
            r_zone.array[:] = F.array_r[self._zone_local]
            compliance.solve(r_zone, d_zone)
            self.jacobian.set_compliance(G)
            # lambda_k: the multipliers of R_k; the inner problem at the relaxed coefficients
            _, law_k = pointwise_law(y_k, normal, mu)
            lam_k = law_k.vector(normal).ravel()
            y_free = (
                y_k
                - compliance.apply_E(d_zone, M_b)
                + self.jacobian.times(lam_k, np.flatnonzero(law_k.active))
            )
            for y0, evaluated in self._starts(y_k, y_free, normal, mu_inner):
                solution = solve_tractions(
                    G,
                    y_free,
                    y0,
                    normal,
                    mu_inner,
                    self.traction_rtol,
                    self.traction_iterations,
                    jacobian=self.jacobian,
                    evaluated=evaluated,
                    area=area,
                    force_tol=self.traction_forcing * norm,
                )
                if solution.converged:
                    self._last_y = solution.y
                    break
            inner.append(solution.iterations)
            if not solution.converged:
                result = NewtonResult(
                    False,
                    k,
                    norms,
                    message=f"contact tractions did not converge in {solution.iterations} "
                    f"iterations at Newton iteration {k}",
                )
                break
            compliance.load(solution.multipliers - lam_k, M_b, weight, v_zone)
            v_zone.axpy(1.0, r_zone)
            compliance.solve(v_zone, d_zone)
            delta.set(0.0)
            delta.array[self._zone_local] = -d_zone.array_r
            x.axpy(1.0, delta)
            u.x.scatter_forward()
            self.A.multAdd(delta, linear, linear)
            norm = contact_residual(linear, model, u, F, self._bc_local)
        for vec in (F, linear, delta, r_zone, d_zone, v_zone):
            vec.destroy()
        assert result is not None  # every way out of the loop sets it
        result.factorizations = self.factorizations - factorizations0
        result.linear_iterations = inner
        count("traction iterations", sum(inner))
        return result

    def destroy(self) -> None:
        self._drop()
        self.jacobian.free()
