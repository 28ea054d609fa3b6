"""Time stepping of the linear structure with (optional) frictional contact: the step u_n -> u_{n+1}.

Semi-discrete balance (SI units: u in m, forces in N, t in s)

    M a + C v + K u + r_c(u) = f(t),

integrated by a scheme of ``solver.dynamics.schemes`` (Newmark average acceleration by default,
generalised-alpha, or quasi-static). Each step solves the effective system

    A u_{n+1} + r_c(u_{n+1}) = b,    A = K + c_M M + c_C C_Rayleigh,

with a reused LU factorisation of A when there is no contact, and with a contact Newton
solver (``CONTACT_SOLVERS``, its factorisations reused across iterations and steps) when there
is; A and its factorisations are kept for the last ``operators_kept`` step sizes. The
contact object is a ``solver.contact.model.ContactModel``: ``NitscheContact`` (two bodies)
or ``RigidPlaneContact``. Modal damping is low rank and enters b explicitly through the
Newmark-predicted velocity v_n + (1 - alpha_f) dt a_n (error O(dt^2), see
``solver.dynamics.damping``).
Dirichlet conditions must be homogeneous (clamped boundaries).
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc

from common.material import Material
from common.timing import timed
from solver.contact.model import ContactModel, Status
from solver.dynamics.condensation import BulkCondensation
from solver.dynamics.damping import ModalDamping, RayleighDamping
from solver.dynamics.linear_algebra import direct_solver
from solver.dynamics.newton import ContactNewtonSolver
from solver.dynamics.point_newton import PointNewtonSolver
from solver.dynamics.schemes import GeneralisedAlpha, Scheme
from solver.elasticity import elastic_forms

#: the Newton solvers of a contact step, by name
CONTACT_SOLVERS = {"zone": ContactNewtonSolver, "points": PointNewtonSolver}

Load = Callable[[float, PETSc.Vec], None]  #: load(t, out): write the load vector f(t) [N] into out


def assemble_structure(
    V: fem.FunctionSpace,
    material: Material,
    bcs: Sequence[fem.DirichletBC],
    extra_stiffness: ufl.Form | None = None,
) -> tuple[PETSc.Mat, PETSc.Mat]:
    """Mass M [kg] and stiffness K [N/m] of linear elasticity on V (bc rows: identity)."""
    k, m = elastic_forms(V, material)
    if extra_stiffness is not None:
        k = k + extra_stiffness
    K = fem_petsc.assemble_matrix(fem.form(k), bcs=bcs)
    K.assemble()
    M = fem_petsc.assemble_matrix(fem.form(m), bcs=bcs)
    M.assemble()
    return M, K


@dataclass
class StepResult:
    """Outcome of one attempted time step."""

    converged: bool
    iterations: int = 0  #: Newton iterations (0 for a linear step)
    residual_norms: list[float] = field(default_factory=list)
    message: str = ""


@dataclass
class _StepOperator:
    """A at one step size dt [s] (None: values to be set) with its direct solver and, in a
    contact problem, the bulk condensation and the contact Newton workspace built on it."""

    A: PETSc.Mat
    ksp: PETSc.KSP
    dt: float | None = None
    condensation: BulkCondensation | None = None
    newton: Any = None  #: a ``CONTACT_SOLVERS`` solver on A (or on the condensed A_hat)

    def destroy(self) -> None:
        for obj in (self.newton, self.condensation, self.ksp, self.A):
            if obj is not None:
                obj.destroy()


class Elastodynamics:
    """State (u, v, a) at time t and the step u_n -> u_{n+1} of a Newmark-family scheme.

    Besides ``step``: ``state_arrays()`` / ``restore_state(t, arrays)`` save and restore
    everything a step depends on (checkpoints), ``refresh_load()`` re-evaluates f(t) after
    the load object changed, ``set_scheme(scheme)`` switches the time scheme and
    ``reset_operator()`` drops the factorisations (the next step rebuilds them). ``last_result``
    is the outcome of the last step attempted.
    """

    def __init__(
        self,
        V: fem.FunctionSpace,
        M: PETSc.Mat,
        K: PETSc.Mat,
        bcs: Sequence[fem.DirichletBC],
        load: Load | None = None,
        scheme: Scheme = GeneralisedAlpha(),
        damping: RayleighDamping | ModalDamping | None = None,
        contact: ContactModel | None = None,
        newton_options: dict | None = None,
        condense_bulk: bool = False,
        contact_solver: str = "zone",
        operators_kept: int = 1,
    ):
        if operators_kept < 1:
            raise ValueError(f"operators_kept must be >= 1, got {operators_kept}")
        if condense_bulk and contact is None:
            raise ValueError(
                "condense_bulk needs a contact object (the bulk is condensed away from its cells)"
            )
        if contact_solver not in CONTACT_SOLVERS:
            raise ValueError(
                f"contact_solver must be one of {tuple(CONTACT_SOLVERS)}, got {contact_solver!r}"
            )
        #: Newton on the contact zone, the bulk condensed (solver.dynamics.condensation)
        self.condense_bulk = condense_bulk
        #: "zone": generalized Newton on the zone (solver.dynamics.newton); "points": Newton on
        #: the contact points' tractions (solver.dynamics.point_newton)
        self.contact_solver = contact_solver
        self.V, self.M, self.K, self.bcs = V, M, K, list(bcs)
        self.scheme, self.damping, self.contact = scheme, damping, contact
        self.load = load
        self.newton_options = dict(
            newton_options or {}
        )  #: options of solver.dynamics.newton.ContactNewtonSolver
        self.u, self.v, self.a = (
            fem.Function(V, name=n) for n in ("displacement", "velocity", "acceleration")
        )
        self.t = 0.0
        self._bc_dofs = self._homogeneous_bc_dofs()
        self._f_old, self._f_new = K.createVecLeft(), K.createVecLeft()
        self._b, self._work, self._b_hat = K.createVecLeft(), K.createVecLeft(), K.createVecLeft()
        self._r_contact_old = K.createVecLeft()  # r_c(u_n), used when alpha_f > 0
        self.failed_steps = 0  #: steps that did not converge (each one cut by ``run``)
        self.contact_status: np.ndarray | None = (
            None  #: contact status at the end of the last step (this rank's points)
        )
        self.last_result: StepResult | None = None  #: outcome of the last step attempted
        #: step sizes whose operators (A and its factorisations) are kept at once (>= 1): two
        #: let a loop alternate between a nominal and a finer step without refactorising
        self.operators_kept = operators_kept
        self._operators: list[_StepOperator] = []  # least recently used first
        self._operator = self._new_operator()
        self._evaluate_load(0.0, self._f_old)

    def _homogeneous_bc_dofs(self) -> np.ndarray:
        probe = self.K.createVecLeft()
        probe.set(0.0)
        fem_petsc.set_bc(probe, self.bcs)
        if probe.norm() > 0:
            raise ValueError(
                "Elastodynamics supports homogeneous Dirichlet conditions (clamped boundaries) only"
            )
        probe.set(1.0)
        fem_petsc.set_bc(probe, self.bcs, alpha=0.0)
        return np.flatnonzero(probe.array_r == 0.0).astype(np.int32)  # owned bc dofs

    @timed("bulk vectors")
    def _evaluate_load(self, t: float, out: PETSc.Vec) -> None:
        out.set(0.0)
        if self.load is not None:
            self.load(t, out)

    def _new_operator(self) -> _StepOperator:
        A = self.K.duplicate(copy=True)
        operator = _StepOperator(A, direct_solver(self.V.mesh.comm, A, prefix="dynamics_"))
        self._operators.append(operator)
        return operator

    @property
    def A(self) -> PETSc.Mat:
        """The effective operator A = K + c_M M + c_C C of the last step size [N/m]."""
        return self._operator.A

    @property
    def _condensation(self) -> BulkCondensation | None:
        return self._operator.condensation

    def condensation_at(self, dt: float) -> BulkCondensation:
        """The condensed bulk of the effective operator A(dt) at the step ``dt`` [s], assembled
        if it is not current (collective); ValueError for a problem without a condensed bulk."""
        self._assemble_operator(dt)
        if self._condensation is None:
            raise ValueError("the problem has no condensed bulk (contact.condense_bulk = false)")
        return self._condensation

    @timed("bulk vectors")
    def _assemble_operator(self, dt: float) -> None:
        """Make A(dt) = K + c_M M + c_C (a M + b K) current: a kept one, else new values in the
        least recently used (factorised lazily by the KSP and the contact solver)."""
        kept = [op for op in self._operators if op.dt == dt]
        unset = [op for op in self._operators if op.dt is None]
        if kept:
            operator = kept[0]
        elif unset:
            operator = unset[0]
        elif len(self._operators) < self.operators_kept:
            operator = self._new_operator()
        else:
            operator = self._operators[0]
        self._operators.remove(operator)
        self._operators.append(operator)
        self._operator = operator
        if operator.dt == dt:
            return
        c_M, c_C = self.scheme.coefficients(dt)
        a_R, b_R = (
            (self.damping.a, self.damping.b)
            if isinstance(self.damping, RayleighDamping)
            else (0.0, 0.0)
        )
        A = operator.A
        self.K.copy(A, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        A.scale(1.0 + c_C * b_R)
        A.axpy(c_M + c_C * a_R, self.M, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        operator.ksp.setOperators(A)
        operator.dt = dt
        if self.contact is None:
            return
        if operator.newton is not None:  # the Newton workspace (an LU of A + J_c), for the new A
            if operator.condensation is not None:
                operator.condensation.update(A)
                operator.newton.set_operator(operator.condensation.A_hat)
            else:
                operator.newton.set_operator(A)
            return
        solver = CONTACT_SOLVERS[self.contact_solver]
        if self.condense_bulk:
            operator.condensation = BulkCondensation(
                A,
                self.V,
                self.contact.support_cells,
                lu_solver=self.newton_options.get("lu_solver", "mumps"),
            )
            operator.newton = solver(
                operator.condensation.A_hat,
                self.bcs,
                zone=operator.condensation.zone,
                **self.newton_options,
            )
        else:
            operator.newton = solver(A, self.bcs, **self.newton_options)

    def initialise(self, t0: float = 0.0) -> None:
        """Set t = t0 and the consistent initial acceleration M a0 = f(t0) - K u0 - C v0 - r_c(u0)."""
        self.t = t0
        self._evaluate_load(t0, self._f_old)
        self.a.x.petsc_vec.set(0.0)
        if not self.scheme.dynamic:
            return
        rhs = self._f_old.copy()
        self._internal_force(self.u.x.petsc_vec, self.v.x.petsc_vec, rhs, scale=-1.0)
        if self.contact is not None:
            self.contact.set_reference(self.u, 1.0)
            self.contact.update(self.u)
            self.contact.residual().copy(self._r_contact_old)
            rhs.axpy(-1.0, self._r_contact_old)
        rhs.array_w[self._bc_dofs] = 0.0
        ksp = direct_solver(self.V.mesh.comm, self.M, prefix="dynamics_mass_")
        ksp.solve(rhs, self.a.x.petsc_vec)
        ksp.destroy()
        self.a.x.scatter_forward()

    def _internal_force(self, u: PETSc.Vec, v: PETSc.Vec, out: PETSc.Vec, scale: float) -> None:
        """out += scale (K u + C v)."""
        self.K.mult(u, self._work)
        out.axpy(scale, self._work)
        if isinstance(self.damping, RayleighDamping):
            self.M.mult(v, self._work)
            out.axpy(scale * self.damping.a, self._work)
            self.K.mult(v, self._work)
            out.axpy(scale * self.damping.b, self._work)
        elif isinstance(self.damping, ModalDamping):
            self._work.set(0.0)
            self.damping.mult(v, self._work)
            out.axpy(scale, self._work)

    @timed("bulk vectors")
    def _effective_load(self, dt: float) -> None:
        """b = (f_{n+1-alpha_f} - alpha_f r_c,n - M a_hat - C v_hat - K u_hat) / (1 - alpha_f).

        With Rayleigh damping C = a M + b K this takes two products: M (a_hat + a v_hat) and
        K (b v_hat + u_hat).
        """
        af = self.scheme.alpha_f
        u, v, a = (x.x.petsc_vec.array_r for x in (self.u, self.v, self.a))
        a_hat, v_hat, u_hat = self.scheme.history(u, v, a, dt)
        b = self._b
        b.set(0.0)
        b.axpy(1.0 - af, self._f_new)
        b.axpy(af, self._f_old)
        if af:
            b.axpy(-af, self._r_contact_old)
        rayleigh = isinstance(self.damping, RayleighDamping)
        on_mass = a_hat if self.scheme.dynamic else None
        on_stiffness = u_hat if af else None
        if self.scheme.dynamic and rayleigh:
            on_mass = a_hat + self.damping.a * v_hat
            if self.damping.b:
                on_stiffness = self.damping.b * v_hat + (u_hat if af else 0.0)
        hist = self.K.createVecRight()
        for matrix, values in ((self.M, on_mass), (self.K, on_stiffness)):
            if values is not None:
                hist.array_w[:] = values
                matrix.mult(hist, self._work)
                b.axpy(-1.0, self._work)
        if self.scheme.dynamic and isinstance(self.damping, ModalDamping):
            hist.array_w[:] = v + (1.0 - af) * dt * a  # predicted v_{n+1-alpha_f}
            self._work.set(0.0)
            self.damping.mult(hist, self._work)
            b.axpy(-1.0, self._work)
        hist.destroy()
        b.scale(1.0 / (1.0 - af))
        b.array_w[self._bc_dofs] = 0.0

    def initial_guesses(self, u_old: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """The two starts of a contact step's Newton solve, in order: the predictor and u_n.

        The predictor (constant acceleration; constant velocity when quasi-static) extrapolates
        the motion, and while the TP slides on (or flies free, or lands) it is the better start.
        Where it stops or reverses, the predictor slides it on, and with the slip direction
        fixed the linearised friction has a negative stiffness along it (about -mu gamma
        sin(alpha) per unit area on the cone): Newton cycles between stick and slip of the
        bearing points or leaves by centimetres. So where some point's status at the predictor
        changes between stick and slip against the last step's (open <-> contact changes do
        not count), u_n (no slip yet) comes first (docs/contact.md, section 6). The second
        start is the fallback before the caller cuts the step.
        """
        predictor = u_old + dt * self.v.x.array + 0.5 * dt**2 * self.a.x.array
        if self.contact_status is None:
            return predictor, u_old
        self.u.x.array[:] = predictor
        self.contact.update(self.u)
        old, new = self.contact_status, self.contact.state.status
        changed = np.count_nonzero((old != new) & (old != Status.OPEN) & (new != Status.OPEN))
        if self.V.mesh.comm.allreduce(changed, op=MPI.SUM):
            return u_old, predictor
        return predictor, u_old

    @timed("other")
    def step(self, dt: float) -> StepResult:
        """Advance by dt [s]; on Newton failure the state is left unchanged."""
        if isinstance(self.damping, ModalDamping):
            self.damping.check_step(dt)
        self._evaluate_load(self.t + dt, self._f_new)
        self._assemble_operator(dt)
        self._effective_load(dt)
        u_old = self.u.x.array.copy()
        memory = {}
        if self.contact is not None:
            memory = {key: value.copy() for key, value in self.contact.memory().items()}
        if self.contact is None:
            ksp = self._operator.ksp
            ksp.solve(self._b, self.u.x.petsc_vec)
            result = StepResult(converged=ksp.getConvergedReason() > 0)
        else:
            self.contact.set_reference(self.u, dt)
            starts = self.initial_guesses(u_old, dt)
            b, condensation = self._b, self._condensation  # the Newton workspace holds A (or A_hat)
            if condensation is not None:
                b = self._b_hat
                condensation.reduce_load(self._b, b)
            iterations = 0
            for start in starts:
                self.u.x.array[:] = start
                if condensation is not None:
                    condensation.hold_bulk(self.u, b)
                res = self._operator.newton.solve(b, self.contact, self.u, load_norm=self._b.norm())
                iterations += res.iterations
                if res.converged:
                    break
            if res.converged and condensation is not None:
                condensation.recover(self._b, self.u)
            result = StepResult(res.converged, iterations, res.residual_norms, res.message)
        self.last_result = result
        if not result.converged:
            self.failed_steps += 1
            self.u.x.array[:] = u_old
            if self.contact is not None:  # the contact state at u_n, not at the last iterate
                self.contact.update(self.u)
                self.contact.restore_memory(memory)
            return result
        self.u.x.scatter_forward()
        if self.contact is not None:  # the solver left the contact updated at u_{n+1}
            self.contact_status = self.contact.state.status.copy()
        v_new, a_new = self.scheme.update(self.u.x.array, u_old, self.v.x.array, self.a.x.array, dt)
        self.v.x.array[:], self.a.x.array[:] = v_new, a_new
        if (
            self.contact is not None
        ):  # kept whatever the scheme: a later one may weight it (alpha_f)
            self.contact.residual().copy(self._r_contact_old)
        self._f_new.copy(self._f_old)
        self.t += dt
        return result

    def refresh_load(self) -> None:
        """Re-evaluate the load f(t) at the current time (after the load object was changed)."""
        self._evaluate_load(self.t, self._f_old)

    def reset_operator(self) -> None:
        """Drop the factorisations and the Newton workspaces: the next step starts afresh."""
        for operator in self._operators:
            operator.dt = None

    @property
    def operators_held(self) -> int:
        """Step sizes whose operators (A and its factorisations) are held now."""
        return len(self._operators)

    def keep_operators(self, n: int) -> None:
        """From now on keep the operators of at most n >= 1 step sizes; the least recently used
        beyond n are destroyed (e.g. the second step size's after a stage that alternated two)."""
        if n < 1:
            raise ValueError(f"operators_kept must be >= 1, got {n}")
        self.operators_kept = n
        while len(self._operators) > n:
            self._operators.pop(0).destroy()

    def set_scheme(self, scheme: Scheme) -> None:
        """Integrate the following steps with ``scheme`` (the operator is rebuilt)."""
        self.scheme = scheme
        self.reset_operator()

    def state_arrays(self) -> dict[str, np.ndarray]:
        """This rank's local arrays (owned and ghost entries) of everything the next step's
        solution depends on besides t: u, v, a [m, m/s, m/s^2], the contact residual at u_n
        (generalised-alpha) [N], the contact model's memory and, after a contact step, the
        points' status (which chooses the next step's Newton start). The contact solver's warm
        starts (the points solver's last inner solution, candidates and their counters) are not
        in it: they change the Newton path, not its solution to the tolerance. Views, not
        copies."""
        arrays = {
            "u": self.u.x.array,
            "v": self.v.x.array,
            "a": self.a.x.array,
            "r_contact_old": self._r_contact_old.array_r,
        }
        if self.contact is not None:
            arrays.update(self.contact.memory())
            if self.contact_status is not None:
                arrays["contact_status"] = self.contact_status
        return arrays

    def restore_state(self, t: float, arrays) -> None:
        """Set the state at time t [s] from ``state_arrays()``'s arrays (same shapes; without
        ``contact_status`` the next step starts from the predictor)."""
        for key, f in (("u", self.u), ("v", self.v), ("a", self.a)):
            f.x.array[:] = arrays[key]
        self.t = float(t)
        self._evaluate_load(self.t, self._f_old)
        self._r_contact_old.array_w[:] = arrays["r_contact_old"]
        if self.contact is not None:
            self.contact.set_reference(self.u, None)
            self.contact.update(self.u)
            self.contact.restore_memory(arrays)
            self.contact_status = (
                arrays["contact_status"].copy() if "contact_status" in arrays else None
            )

    def energy(self) -> tuple[float, float]:
        """(kinetic 1/2 v.Mv, strain 1/2 u.Ku) [J]."""
        u, v = self.u.x.petsc_vec, self.v.x.petsc_vec
        self.M.mult(v, self._work)
        kinetic = 0.5 * v.dot(self._work)
        self.K.mult(u, self._work)
        return kinetic, 0.5 * u.dot(self._work)
