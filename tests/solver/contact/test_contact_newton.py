"""Generalized Newton on a sliding step: the Jacobian against finite differences of the
residual, and the convergence rate it gives.

The Jacobian drops the variation of the master normal and of the projection point with u
(docs/contact.md). With the base undeformed (its surface a fixed plane) these terms vanish
for perturbations of the sliding block, so there the Jacobian must match finite
differences to truncation error in the block's rows, including slip and the d mu / d|v|
term of the velocity law (the base's rows carry the dropped shift of the master basis
functions with the projection point). At the real sliding state, with the base deformed and perturbed too, the
dropped terms appear, with a relative size of the order of the interface strain p / E.

Convergence rate: on a deformable base Newton ends linearly with a contraction of order
p / E (the dropped terms). On a rigid base (all base dofs clamped, so the master surface can
neither move nor rotate) nothing is dropped, and once the stick/slip/open sets settle the
residual must fall quadratically, ||F_k+1|| <= C ||F_k||^2, down to round-off; without the
d mu / d|v| term of the velocity law the same case converges only linearly (control).
"""

from mpi4py import MPI

import numpy as np
import pytest

import dolfinx
from petsc4py import PETSc
from contact_cases import gathered, sliding_block
from solver.contact import FrictionLaw, NitscheContact, Status

pytestmark = pytest.mark.mpi


def _jacobian_error(contact, u, w, eps, rows=None):
    """|| (r(u + eps w) - r(u - eps w)) / (2 eps) - J w || / || J w || (on the owned ``rows``
    of the local arrays if given)."""
    u0 = u.x.array.copy()
    contact.update(u)
    J = contact.jacobian()
    Jw = J.createVecLeft()
    J.mult(w.x.petsc_vec, Jw)
    residuals = []
    for sign in (1.0, -1.0):
        u.x.array[:] = u0 + sign * eps * w.x.array
        contact.update(u)
        residuals.append(contact.residual().copy())
    u.x.array[:] = u0
    contact.update(u)
    fd = residuals[0]
    fd.axpy(-1.0, residuals[1])
    fd.scale(0.5 / eps)
    fd.axpy(-1.0, Jw)
    if rows is None:
        return fd.norm() / Jw.norm()
    comm = u.function_space.mesh.comm
    error = comm.allreduce(np.sum(fd.array[rows] ** 2), op=MPI.SUM)
    reference = comm.allreduce(np.sum(Jw.array[rows] ** 2), op=MPI.SUM)
    return np.sqrt(error / reference)


@pytest.fixture()
def sliding_state():
    friction = FrictionLaw(mu_s=0.5, mu_d=0.4, d_c=5000.0)
    # a tight Newton tolerance, so that the last step shows enough iterations for its rate
    history, contact, results, u = sliding_block(
        MPI.COMM_WORLD, friction, steps=6, slide_per_step=2e-4, dt=1.0, rtol=1e-9
    )
    assert all(r.converged for r in results)
    return contact, u, results


def _direction(contact, u, slave_only: bool):
    rng = np.random.default_rng(1 + u.function_space.mesh.comm.rank)
    w = dolfinx.fem.Function(u.function_space)
    w.x.array[:] = rng.uniform(-1.0, 1.0, w.x.array.size)
    if slave_only:
        mask = np.zeros(w.x.array.size // 3, dtype=bool)
        mask[contact.slave.dofs.ravel()] = True
        w.x.array.reshape(-1, 3)[~mask] = 0.0
    w.x.scatter_forward()
    return w


def _block_on_flat_base(
    contact, u: dolfinx.fem.Function
) -> tuple[dolfinx.fem.Function, np.ndarray]:
    """The sliding state with the block's displacement kept and the base reset to its undeformed
    (flat) shape, now and at the step's start (the block then 0.2 mm further back), with the
    contact updated there. Returns that state and the mask of the block's nodes."""
    V = u.function_space
    mesh = V.mesh
    cells = np.arange(
        mesh.topology.index_map(3).size_local + mesh.topology.index_map(3).num_ghosts,
        dtype=np.int32,
    )
    block = cells[dolfinx.mesh.compute_midpoints(mesh, 3, cells)[:, 2] > 0]
    on_block = np.zeros(u.x.array.size // 3, dtype=bool)
    on_block[V.dofmap.list[block].ravel()] = True
    state = u.copy()
    state.x.array.reshape(-1, 3)[~on_block] = 0.0
    reference = state.copy()
    reference.x.array.reshape(-1, 3)[on_block, 0] -= 2e-4
    contact.set_reference(reference, 1.0)
    contact.update(state)
    return state, on_block


def test_jacobian_is_consistent_for_slave_motion(sliding_state):
    contact, u, _ = sliding_state
    V = u.function_space
    state, on_block = _block_on_flat_base(contact, u)
    status = np.concatenate(MPI.COMM_WORLD.allgather(contact.state.status))
    assert np.any(status == Status.SLIP)
    w = _direction(contact, u, slave_only=True)
    n_owned = V.dofmap.index_map.size_local
    block_rows = np.flatnonzero(np.repeat(on_block[:n_owned], 3))
    error = _jacobian_error(contact, state, w, eps=1e-11, rows=block_rows)
    assert error < 1e-6


def test_jacobian_at_the_step_start_ignores_round_off(sliding_state):
    """At the first iterate of a step the slip increment ds is 0 or round-off (1e-19 m). The
    velocity-law term of the slip tangent needs a direction e of ds; it must come from the
    traction (e = -q), not from the round-off, or the first Newton step, and with it the 1-
    and 2-rank results, depend on noise (docs/contact.md section 4)."""
    contact, u, _ = sliding_state
    friction = contact.friction
    # lower friction: the traction of the sliding state then exceeds mu_s p and the points slip at ds = 0
    contact.friction = FrictionLaw(mu_s=0.3, mu_d=0.2, d_c=friction.d_c)
    contact.set_reference(u, 1.0)
    contact.update(u)
    slipping = MPI.COMM_WORLD.allreduce(
        int(np.sum(contact.state.status == Status.SLIP)), op=MPI.SUM
    )
    assert slipping > 0
    exact = contact.jacobian().copy()
    noisy = u.copy()
    rng = np.random.default_rng(7 + MPI.COMM_WORLD.rank)
    noisy.x.array[:] += (
        4 * np.finfo(float).eps * np.abs(u.x.array).max() * rng.uniform(-1, 1, u.x.array.size)
    )
    noisy.x.scatter_forward()
    contact.update(noisy)
    perturbed = contact.jacobian()
    # dt = 1 s: the slip velocity [m/s] is the slip increment ds [m]
    ds_max = MPI.COMM_WORLD.allreduce(
        float(np.abs(contact.state.slip_velocity).max(initial=0.0)), op=MPI.MAX
    )
    assert 0.0 < ds_max < 1e-17  # ds is round-off (both times; 0 or 1e-19 m without the noise)
    perturbed.axpy(-1.0, exact, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    assert perturbed.norm() < 1e-9 * exact.norm()
    contact.friction = friction


def test_dropped_terms_are_of_order_strain(sliding_state):
    contact, u, _ = sliding_state
    w = _direction(contact, u, slave_only=False)
    error = _jacobian_error(contact, u, w, eps=1e-11)
    strain = 1e6 / contact.material.E  # q / E
    assert error < 10 * strain


def test_convergence_rate(sliding_state):
    """Once the stick/slip/open sets settle, each iteration cuts ||F|| by a factor of order p / E."""
    _, _, results = sliding_state
    norms = np.array(results[-1].residual_norms)
    assert results[-1].converged and results[-1].iterations <= 12
    rates = norms[-2:] / norms[-3:-1]
    assert np.all(rates < 1e-2), rates


class _RecordedContact(NitscheContact):
    """NitscheContact that keeps the stick/slip/open status (all ranks) of every update and
    reports no round-off floor, so that Newton iterates on into its round-off stagnation,
    whose level is then measured."""

    def update(self, u):
        super().update(u)
        self.__dict__.setdefault("statuses", []).append(
            gathered(self.V.mesh.comm, self.state.status)
        )

    def residual_floor(self) -> float:
        return 0.0


class _WithoutSlope(FrictionLaw):
    """The velocity law with its derivative d mu / d|v| reported as zero (an inconsistent Jacobian)."""

    def derivative(self, slip_speed):
        return np.zeros_like(np.asarray(slip_speed, dtype=float))


def _rigid_base_step(
    theta: int, friction: FrictionLaw, **newton
) -> tuple[np.ndarray, list[np.ndarray], np.ndarray]:
    """Residual norms [N] and statuses of every iterate of the last of 6 sliding steps on a rigid
    base, and the final displacement (local array).

    Slip of 0.2 mm per 20 ms step (v = 1e-2 m/s, d_c |v| = 1 with d_c = 100 s/m: mu' v / mu = -8 %),
    exact Newton (fresh LU at every iteration, unless ``newton`` says otherwise), no convergence
    test (12 iterations).
    """
    _, contact, results, u = sliding_block(
        MPI.COMM_WORLD,
        friction,
        steps=6,
        slide_per_step=2e-4,
        dt=0.02,
        theta=theta,
        rigid_base=True,
        contact_type=_RecordedContact,
        **({"rtol": 1e-30, "atol": 0.0, "stol": 0.0, "max_iterations": 12} | newton),
    )
    norms = np.array(results[-1].residual_norms)
    return norms, contact.statuses[-len(norms) :], u.x.array.copy()


def _settled(norms: np.ndarray, statuses: list[np.ndarray], roundoff: float) -> np.ndarray:
    """The norms from the last change of the stick/slip/open sets on, up to the last one above ``roundoff``."""
    changes = [k for k in range(1, len(statuses)) if np.any(statuses[k] != statuses[k - 1])]
    F = norms[changes[-1] if changes else 0 :]
    return F[: np.argmax(F <= roundoff)] if np.any(F <= roundoff) else F


def _orders(F: np.ndarray) -> np.ndarray:
    """Estimated convergence orders log(F_k+1 / F_k) / log(F_k / F_k-1)."""
    return np.log(F[2:] / F[1:-1]) / np.log(F[1:-1] / F[:-2])


@pytest.mark.parametrize("theta", [1, -1])
def test_quadratic_rate_on_rigid_base(theta):
    """Sliding with mu(v) on a clamped base: sets settle, then ||F|| falls quadratically to round-off."""
    norms, statuses, _ = _rigid_base_step(theta, FrictionLaw(mu_s=0.5, mu_d=0.4, d_c=100.0))
    assert np.all(statuses[-1][statuses[-1] != Status.OPEN] == Status.SLIP)  # gross sliding
    noise = norms[-4:].max()  # the stagnated tail
    assert noise < 1e-13 * norms[0], norms
    F = _settled(norms, statuses, roundoff=2 * noise)
    assert len(F) >= 3, (norms, noise)  # at least two steps with a fixed active set above round-off
    assert _orders(F)[-1] >= 1.8, (F, _orders(F))
    # ||F_k+1|| <= C ||F_k||^2 with C = 10 / ||F_0|| at every settled iterate
    assert np.all(F[1:] * norms[0] / F[:-1] ** 2 <= 10.0), F


def test_linear_rate_without_velocity_slope():
    """Control: the same step with d mu / d|v| left out of the Jacobian converges only linearly."""
    norms, statuses, _ = _rigid_base_step(1, _WithoutSlope(mu_s=0.5, mu_d=0.4, d_c=100.0))
    F = _settled(norms, statuses, roundoff=0.0)
    assert len(F) >= 5, norms
    assert np.all(np.abs(_orders(F)[-3:] - 1.0) < 0.2), (F, _orders(F))


def test_inexact_newton_with_reused_factors():
    """The solver's default linear algebra (LU factors of an earlier iterate reused as GMRES
    preconditioner, Eisenstat-Walker tolerances) reaches the same state as exact Newton, and its
    rate stays superlinear once the sets settle (order >= 1.5; the forcing term is O(||F||))."""
    friction = FrictionLaw(mu_s=0.5, mu_d=0.4, d_c=100.0)
    exact_norms, _, exact = _rigid_base_step(1, friction)
    norms, statuses, u = _rigid_base_step(
        1, friction, refactor_after=25, forcing_max=1e-3, max_iterations=20
    )
    comm = MPI.COMM_WORLD
    difference = np.sqrt(comm.allreduce(float(np.sum((u - exact) ** 2)), op=MPI.SUM))
    size = np.sqrt(comm.allreduce(float(np.sum(exact**2)), op=MPI.SUM))
    assert difference < 1e-10 * size, difference / size
    noise = max(norms[-4:].max(), exact_norms[-4:].max())
    F = _settled(norms, statuses, roundoff=2 * noise)
    assert len(F) >= 3, (norms, noise)
    assert _orders(F)[-1] >= 1.5, (F, _orders(F))


def test_distributed_newton_follows_the_serial_one():
    """The Newton iterates of a sliding sequence on 2 ranks are those of the serial run to
    round-off: same residual norms at every iteration above round-off, in every step (the first
    iterate of a step takes the slip direction of the trial traction, not one of round-off)."""
    comm = MPI.COMM_WORLD
    if comm.size == 1:
        pytest.skip("compares a distributed run with a serial one (runs under mpiexec -n 2)")
    friction = FrictionLaw(mu_s=0.5, mu_d=0.4, d_c=100.0)
    newton = {"rtol": 1e-30, "atol": 0.0, "stol": 0.0, "max_iterations": 12}
    runs = [
        sliding_block(
            c, friction, steps=6, slide_per_step=2e-4, dt=0.02, rigid_base=True, **newton
        )[2]
        for c in (MPI.COMM_SELF, comm)
    ]
    for serial, distributed in zip(*runs):
        a, b = np.array(serial.residual_norms), np.array(distributed.residual_norms)
        k = (
            int(np.argmax(a < 1e-7 * a[0])) if np.any(a < 1e-7 * a[0]) else len(a)
        )  # iterates above round-off
        assert len(b) >= k, (a, b)  # (round-off is at 1e-14 - 1e-13 of F_0)
        assert np.allclose(b[:k], a[:k], rtol=1e-8, atol=0.0), (a, b)


def test_reversal_limit_stops_where_the_friction_would_reverse(sliding_state):
    """Dragging the slipping block back by a rigid translation: the trial traction P_t is then
    affine along the step (flat base, no strain change), P_t(alpha) = P_t0 + alpha gamma d e_x,
    so the fraction at which a slipping point's P_t . q0 vanishes is |P_t0| / (-gamma d e_x . q0),
    and the step limit is the smallest such fraction over the points that slip the other way at
    the full step."""
    contact, u, _ = sliding_state
    comm = u.function_space.mesh.comm
    state, on_block = _block_on_flat_base(contact, u)
    slipping, P_t0 = contact.slip_directions()
    assert comm.allreduce(int(slipping.sum()), op=MPI.SUM) > 0
    d = 3e-4  # [m]: back beyond the step's start (the last step slid 2e-4 m), against the friction
    back = state.copy()
    back.x.array.reshape(-1, 3)[on_block, 0] -= d
    contact.update(back)
    limit = comm.allreduce(contact.reversal_limit(slipping, P_t0), op=MPI.MIN)
    size = np.linalg.norm(P_t0, axis=1)
    rate = (
        contact.gamma * d * P_t0[:, 0] / np.where(size > 0, size, 1.0)
    )  # d(P_t . q0) / d alpha [Pa]
    mu = contact.friction.coefficient(np.linalg.norm(contact.state.slip_velocity, axis=1))
    reversing = slipping & (size + rate < -mu * contact.state.pressure)
    assert comm.allreduce(int(reversing.sum()), op=MPI.SUM) > 0
    expected = comm.allreduce(
        float((size[reversing] / -rate[reversing]).min(initial=np.inf)), op=MPI.MIN
    )
    assert 0.0 < expected < 1.0
    assert limit == pytest.approx(expected, rel=1e-9)
    # a step that goes no further than that reverses nothing
    contact.update(state)
    half = state.copy()
    half.x.array.reshape(-1, 3)[on_block, 0] -= 0.5 * expected * d
    contact.update(half)
    assert comm.allreduce(contact.reversal_limit(slipping, P_t0), op=MPI.MIN) == 1.0


def test_reversal_limit_changes_the_path_not_the_solution():
    """Dragging the block forth and back (its friction reverses twice) with backtracking Newton:
    with and without the reversal limit every step converges, to the same displacements and
    friction forces (to the Newton tolerance); only the iterations differ."""
    friction = FrictionLaw(mu_s=0.5, mu_d=0.4, d_c=100.0)
    drags = [2e-4, 4e-4, 6e-4, 5e-4, 4e-4, 3e-4, 4e-4, 5e-4]  # top face x displacement per step [m]
    comm = MPI.COMM_WORLD
    runs = [
        sliding_block(
            comm,
            friction,
            steps=0,
            slide_per_step=0.0,
            dt=0.02,
            drags=drags,
            rtol=1e-10,
            max_backtracks=4,
            limit_reversal=limit,
        )
        for limit in (True, False)
    ]
    (history, _, results, u), (history_free, _, results_free, u_free) = runs
    assert all(r.converged for r in results + results_free)
    assert [r.iterations for r in results] != [
        r.iterations for r in results_free
    ]  # the limit acted
    difference = np.sqrt(
        comm.allreduce(float(np.sum((u.x.array - u_free.x.array) ** 2)), op=MPI.SUM)
    )
    size = np.sqrt(comm.allreduce(float(np.sum(u_free.x.array**2)), op=MPI.SUM))
    print(
        f"\nreversal limit: Newton iterations {[r.iterations for r in results]} against "
        f"{[r.iterations for r in results_free]}; displacement difference {difference / size:.1e} relative"
    )
    assert difference < 1e-8 * size
    assert np.allclose(history, history_free, rtol=1e-8, atol=1e-10)
    assert (
        np.min(np.diff(history[:, 0])) < 0 < np.max(np.diff(history[:, 0]))
    )  # the friction force reversed
