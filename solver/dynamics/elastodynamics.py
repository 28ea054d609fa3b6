"""Time loop of the linear structure with (optional) frictional contact.

Semi-discrete balance (SI units: u in m, forces in N, t in s)

    M a + C v + K u + r_c(u) = f(t),

integrated by a scheme of ``solver.dynamics.schemes`` (Newmark average acceleration by default,
generalised-alpha, or quasi-static). Each step solves the effective system

    A u_{n+1} + r_c(u_{n+1}) = b,    A = K + c_M M + c_C C_Rayleigh,

with a reused LU factorisation of A when there is no contact, and with
``solver.dynamics.newton.solve_contact_problem`` (generalised Newton, LU of A + J_c reused
across iterations and steps while dt is unchanged) when there is. The contact object
is ``solver.contact.nitsche.NitscheContact`` (two bodies) or ``solver.contact.RigidPlaneContact``.
Modal damping is low rank and enters b explicitly through the Newmark-predicted
velocity v_n + (1 - alpha_f) dt a_n (error O(dt^2), see ``solver.dynamics.damping``).
Dirichlet conditions must be homogeneous (clamped boundaries).
"""

import csv
import pathlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc

from solver.dynamics.condensation import BulkCondensation
from solver.contact import Status
from solver.dynamics.damping import ModalDamping, RayleighDamping
from common.material import Material
from solver.elasticity import epsilon, sigma
from solver.dynamics.schemes import GeneralisedAlpha, Scheme
from solver.dynamics.newton import ContactNewtonSolver

Load = Callable[[float, PETSc.Vec], None]  #: load(t, out): write the load vector f(t) [N] into out


def assemble_structure(V: fem.FunctionSpace, material: Material, bcs: Sequence[fem.DirichletBC],
                       extra_stiffness: ufl.Form | None = None) -> tuple[PETSc.Mat, PETSc.Mat]:
    """Mass M [kg] and stiffness K [N/m] of linear elasticity on V (bc rows: identity)."""
    u, w = ufl.TrialFunction(V), ufl.TestFunction(V)
    k = ufl.inner(sigma(u, material), epsilon(w)) * ufl.dx
    if extra_stiffness is not None:
        k = k + extra_stiffness
    m = material.rho * ufl.inner(u, w) * ufl.dx
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


def _lu_solver(comm: MPI.Comm, A: PETSc.Mat, prefix: str) -> PETSc.KSP:
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("lu")
    pc.setFactorSolverType("mumps")
    ksp.setFromOptions()
    ksp.setOperators(A)
    return ksp


class Elastodynamics:
    """State (u, v, a) at time t and the step u_n -> u_{n+1} of a Newmark-family scheme."""

    def __init__(self, V: fem.FunctionSpace, M: PETSc.Mat, K: PETSc.Mat, bcs: Sequence[fem.DirichletBC],
                 load: Load | None = None, scheme: Scheme = GeneralisedAlpha(),
                 damping: RayleighDamping | ModalDamping | None = None, contact=None,
                 newton_options: dict | None = None, condense_bulk: bool = False):
        if condense_bulk and not hasattr(contact, "support_cells"):
            raise ValueError("condense_bulk needs a contact object that names its cells (NitscheContact)")
        self.condense_bulk = condense_bulk  #: Newton on the contact zone, the bulk condensed (solver.dynamics.condensation)
        self._condensation: BulkCondensation | None = None
        self.V, self.M, self.K, self.bcs = V, M, K, list(bcs)
        self.scheme, self.damping, self.contact = scheme, damping, contact
        self.load = load
        self.newton_options = dict(newton_options or {})  #: options of solver.dynamics.newton.ContactNewtonSolver
        self._newton = None
        self.u, self.v, self.a = (fem.Function(V, name=n) for n in ("displacement", "velocity", "acceleration"))
        self.t = 0.0
        self._bc_dofs = self._homogeneous_bc_dofs()
        self._f_old, self._f_new = K.createVecLeft(), K.createVecLeft()
        self._b, self._work, self._b_hat = K.createVecLeft(), K.createVecLeft(), K.createVecLeft()
        self._r_contact_old = K.createVecLeft()  # r_c(u_n), used when alpha_f > 0
        self.contact_status: np.ndarray | None = None  #: contact status at the end of the last step (this rank's points)
        self.A = K.duplicate(copy=True)
        self._dt_of_A = None
        self._ksp = _lu_solver(V.mesh.comm, self.A, "dynamics_")
        self._evaluate_load(0.0, self._f_old)

    def _homogeneous_bc_dofs(self) -> np.ndarray:
        probe = self.K.createVecLeft()
        probe.set(0.0)
        fem_petsc.set_bc(probe, self.bcs)
        if probe.norm() > 0:
            raise ValueError("Elastodynamics supports homogeneous Dirichlet conditions (clamped boundaries) only")
        probe.set(1.0)
        fem_petsc.set_bc(probe, self.bcs, alpha=0.0)
        return np.flatnonzero(probe.array_r == 0.0).astype(np.int32)  # owned bc dofs

    def _evaluate_load(self, t: float, out: PETSc.Vec) -> None:
        out.set(0.0)
        if self.load is not None:
            self.load(t, out)

    def _assemble_operator(self, dt: float) -> None:
        """A = K + c_M M + c_C (a M + b K), factorised lazily by the KSP."""
        if self._dt_of_A == dt:
            return
        c_M, c_C = self.scheme.coefficients(dt)
        a_R, b_R = (self.damping.a, self.damping.b) if isinstance(self.damping, RayleighDamping) else (0.0, 0.0)
        self.K.copy(self.A, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        self.A.scale(1.0 + c_C * b_R)
        self.A.axpy(c_M + c_C * a_R, self.M, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        self._ksp.setOperators(self.A)
        self._dt_of_A = dt
        if self.contact is not None:  # Newton workspace (keeps an LU of A + J_c) for this A
            for workspace in (self._newton, self._condensation):
                if workspace is not None:
                    workspace.destroy()
            if self.condense_bulk:
                self._condensation = BulkCondensation(self.A, self.V, self.contact.support_cells,
                                                      lu_solver=self.newton_options.get("lu_solver", "mumps"))
                self._newton = ContactNewtonSolver(self._condensation.A_hat, self.bcs, zone=self._condensation.zone,
                                                   **self.newton_options)
            else:
                self._newton = ContactNewtonSolver(self.A, self.bcs, **self.newton_options)

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
            r = self.contact.residual()
            r.copy(self._r_contact_old)
            r.destroy()
            rhs.axpy(-1.0, self._r_contact_old)
        rhs.array_w[self._bc_dofs] = 0.0
        ksp = _lu_solver(self.V.mesh.comm, self.M, "dynamics_mass_")
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

    def _initial_guesses(self, u_old: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
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

    def step(self, dt: float) -> StepResult:
        """Advance by dt [s]; on Newton failure the state is left unchanged."""
        if isinstance(self.damping, ModalDamping):
            self.damping.check_step(dt)
        self._evaluate_load(self.t + dt, self._f_new)
        self._assemble_operator(dt)
        self._effective_load(dt)
        u_old = self.u.x.array.copy()
        if self.contact is None:
            self._ksp.solve(self._b, self.u.x.petsc_vec)
            result = StepResult(converged=self._ksp.getConvergedReason() > 0)
        else:
            self.contact.set_reference(self.u, dt)
            starts = self._initial_guesses(u_old, dt)
            A, b, condensation = self.A, self._b, self._condensation
            if condensation is not None:
                A, b = condensation.A_hat, self._b_hat
                condensation.reduce_load(self._b, b)
            iterations = 0
            for start in starts:
                self.u.x.array[:] = start
                if condensation is not None:
                    condensation.hold_bulk(self.u, b)
                res = self._newton.solve(b, self.contact, self.u, load_norm=self._b.norm())
                iterations += res.iterations
                if res.converged:
                    break
            if res.converged and condensation is not None:
                condensation.recover(self._b, self.u)
            result = StepResult(res.converged, iterations, res.residual_norms, res.message)
        if not result.converged:
            self.u.x.array[:] = u_old
            return result
        self.u.x.scatter_forward()
        if self.contact is not None:  # the solver left the contact updated at u_{n+1}
            self.contact_status = self.contact.state.status.copy()
        v_new, a_new = self.scheme.update(self.u.x.array, u_old, self.v.x.array, self.a.x.array, dt)
        self.v.x.array[:], self.a.x.array[:] = v_new, a_new
        if self.contact is not None and self.scheme.alpha_f:
            r = self.contact.residual()
            r.copy(self._r_contact_old)
            r.destroy()
        self._f_new.copy(self._f_old)
        self.t += dt
        return result

    def energy(self) -> tuple[float, float]:
        """(kinetic 1/2 v.Mv, strain 1/2 u.Ku) [J]."""
        u, v = self.u.x.petsc_vec, self.v.x.petsc_vec
        self.M.mult(v, self._work)
        kinetic = 0.5 * v.dot(self._work)
        self.K.mult(u, self._work)
        return kinetic, 0.5 * u.dot(self._work)


class CsvWriter:
    """History file written as the run goes (rank 0 only), flushed after every row."""

    def __init__(self, path: str | pathlib.Path, columns: Sequence[str], comm: MPI.Comm):
        self.columns = list(columns)
        self._file = None
        if comm.rank == 0:
            path = pathlib.Path(path)
            path.parent.mkdir(parents=True, exist_ok=True)
            self._file = open(path, "w", newline="")
            self._writer = csv.writer(self._file)
            self._writer.writerow(self.columns)
            self._file.flush()

    def write(self, row: dict[str, float]) -> None:
        if self._file is not None:
            self._writer.writerow([f"{row[c]:.10g}" for c in self.columns])
            self._file.flush()

    def close(self) -> None:
        if self._file is not None:
            self._file.close()


Observer = Callable[[Elastodynamics], dict[str, float]]


class Settlement:
    """Settlement of the TP on the MP [mm], positive downward (an observer for ``run``).

    s = mean_k u_z(MP, p_k) - mean_k u_z(TP, q_k), with q_k the points of the TP's lower
    edge on its mid-wall circle (height z_e = joint.tp_offset, radius halfway between
    the TP's inner and outer surface) and p_k the points of the MP's mid-wall circle at
    the same height z_e, both at ``n_points`` equally spaced angles, in the reference
    configuration. So s is the axial slide of the TP's lower edge relative to the MP
    wall next to it (rigid motions of the whole joint give s = 0); s > 0: the TP went down.
    ``cell_tags`` (MP_VOLUME, TP_VOLUME) keep each probe in its own part.
    """

    def __init__(self, u: fem.Function, joint, cell_tags, n_points: int = 16):
        from geometry import tags
        from solver.probes import PointProbe

        z_e = joint.tp_offset
        r_tp = 0.5 * (float(joint.tp.inner_radius(0.0)) + float(joint.tp.outer_radius(0.0)))
        r_mp = 0.5 * (float(joint.mp.inner_radius(z_e)) + float(joint.mp.outer_radius(z_e)))
        angles = 2 * np.pi * np.arange(n_points) / n_points
        ring = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(n_points)])
        lift = np.array([0.0, 0.0, z_e])
        self._tp = PointProbe(u, r_tp * ring + lift, cells=cell_tags.find(tags.TP_VOLUME))
        self._mp = PointProbe(u, r_mp * ring + lift, cells=cell_tags.find(tags.MP_VOLUME))

    def __call__(self, problem: Elastodynamics | None = None) -> dict[str, float]:
        s = self._mp()[:, 2].mean() - self._tp()[:, 2].mean()
        return {"settlement_mm": 1e3 * float(s)}


def touches_top(contact, margin: float, axis: int = 2) -> bool:
    """Whether a slave point of ``contact`` within ``margin`` [m] of the slave surface's highest
    point along ``axis`` (reference coordinates) is in contact, on any rank: the contact band
    has reached the upper end of the surface, above which no contact is modelled."""
    z = contact.slave.points[:, axis]
    comm = contact.V.mesh.comm
    z_max = comm.allreduce(z.max() if len(z) else -np.inf, op=MPI.MAX)
    touching = (z >= z_max - margin) & (contact.state.status != Status.OPEN)
    return comm.allreduce(bool(touching.any()), op=MPI.LOR)


class ContactZoneGuard:
    """Observer for ``run`` that stops the run (RuntimeError) when the contact band reaches the
    upper ``margin`` [m] of the slave surface (:func:`touches_top`): with a contact
    zone (``MeshOptions.contact_axial_size`` > 0) the contact surfaces end at its top, and
    contact beyond it would be missed. ``margin``: the zone's element height."""

    def __init__(self, contact, margin: float, zone_above: float):
        self.contact, self.margin, self.zone_above = contact, margin, zone_above

    def __call__(self, problem: Elastodynamics) -> dict[str, float]:
        if touches_top(self.contact, self.margin):
            raise RuntimeError(
                f"at t = {problem.t:.6g} s the contact band reached the top of the contact zone "
                f"({self.zone_above} m above the TP's lower edge), where the contact surfaces end: "
                "rerun with a larger mesh.contact_zone_above")
        return {}


def run(problem: Elastodynamics, t_end: float, dt: float, dt_min: float | None = None,
        observers: Sequence[Observer] = (), csv_path: str | pathlib.Path | None = None,
        progress: bool = True, growth_after: int = 4) -> list[dict[str, float]]:
    """Integrate from problem.t to t_end [s] with nominal step dt [s].

    On Newton failure the step is halved and retried; after ``growth_after`` accepted
    steps it doubles again (up to dt). Below dt_min (default dt/64) a RuntimeError
    names the time and step. Each accepted step records time_s, dt_s, newton_iterations
    and every observer's values (keys carry units, e.g. settlement_mm); rows go to the
    CSV file as they are produced. Returns the rows.
    """
    if not (t_end > problem.t and dt > 0):
        raise ValueError(f"need t_end > t = {problem.t} s and dt > 0, got t_end={t_end} s, dt={dt} s")
    dt_min = dt / 64 if dt_min is None else dt_min
    if not 0 < dt_min <= dt:
        raise ValueError(f"need 0 < dt_min <= dt, got dt_min={dt_min} s, dt={dt} s")
    comm = problem.V.mesh.comm
    bar = None
    if progress and comm.rank == 0:
        from tqdm import tqdm
        bar = tqdm(total=t_end - problem.t, unit="s", bar_format="{l_bar}{bar}| {n:.4g}/{total:.4g} s {postfix}")
    rows, writer, h, accepted = [], None, dt, 0
    try:
        while problem.t < t_end - 1e-12 * t_end:
            remaining = t_end - problem.t
            # a last step within round-off of h is taken as h: a new step size would mean a new
            # effective operator A(dt) and its factorisation
            step = h if abs(remaining - h) <= 1e-9 * h else min(h, remaining)
            result = problem.step(step)
            if not result.converged:
                h = step / 2
                accepted = 0
                if h < dt_min:
                    raise RuntimeError(f"Newton did not converge at t = {problem.t:.6g} s even with dt = {step:.3g} s "
                                       f"(minimum step {dt_min:.3g} s): {result.message or 'no message'}; "
                                       f"last residual norms {result.residual_norms[-3:]} N")
                continue
            row = {"time_s": problem.t, "dt_s": step, "newton_iterations": result.iterations}
            for observe in observers:
                row.update(observe(problem))
            rows.append(row)
            if writer is None and csv_path is not None:
                writer = CsvWriter(csv_path, list(row), comm)
            if writer is not None:
                writer.write(row)
            if bar is not None:
                bar.update(step)
                bar.set_postfix({k: f"{v:.4g}" for k, v in row.items() if k != "time_s"}, refresh=False)
            accepted += 1
            if h < dt and accepted >= growth_after:
                h, accepted = min(2 * h, dt), 0
    finally:
        if writer is not None:
            writer.close()
        if bar is not None:
            bar.close()
    return rows
