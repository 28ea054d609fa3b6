"""Nitsche frictional contact between two deformable bodies of one mesh (docs/contact.md).

Slave points x (quadrature points of the slave facets, deformed) are paired with their
closest points y on the deformed master surface (solver/contact/pairing.py). With n = -n_m
(n_m: master outward normal at y; n approximates the slave outward normal):

    gap             g   = (x - y) . n_m                               [m]
    slip increment  ds  = (I - n n)[(u_s - u_s_old)(x) - (u_m - u_m_old)(y)]   [m]
    slip velocity   v   = ds / dt                                     [m/s]
    slave traction  sigma_n = n . sigma(u_s) n, sigma_t = (I - n n) sigma(u_s) n   [Pa]
    Nitsche         P_n = sigma_n + gamma g,  P_t = sigma_t - gamma ds,  gamma = gamma0 E / h  [Pa]
    multipliers     lambda_n = min(P_n, 0), pressure p = -lambda_n >= 0,
                    lambda_t = proj onto the disk of radius mu(|v|) p of P_t   [Pa]

Residual (added to the bulk a(u, v) - L(v)), theta in {1, 0, -1}:

    r(v) = sum_q w_q [ -theta/gamma (sigma_n(u) sigma_n(v) + sigma_t(u) . sigma_t(v))
                       + 1/gamma lambda_n (theta sigma_n(v) + gamma dg(v))
                       + 1/gamma lambda_t . (theta sigma_t(v) - gamma ds(v)) ]

with dg(v) = (v_s - v_m(y)) . n_m and ds(v) = (I - n n)(v_s - v_m(y)). The Jacobian is
the generalized (semismooth) Newton derivative of r, including d mu / d|v|; the variations
of the normal n_m and of the projection y with u (curvature/geometric terms of order
lambda x rotation) are dropped.
"""

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import numpy.typing as npt

import dolfinx
import dolfinx.fem.petsc

from common.material import Material
from common.timing import timed
from solver.contact.assembly import PointMatrices, assemble_point_vector, grouped_products
from solver.contact.friction import FrictionLaw
from solver.contact.law import derivative, multipliers
from solver.contact.model import ContactState, PointOperators, Status, TrialTractions
from solver.contact.operators import traction_operator, unrolled_dofs, vector_basis
from solver.contact.pairing import Pairing, pair
from solver.contact.surfaces import MasterSurface, SlaveQuadrature

__all__ = ["NitscheContact"]


class NitscheContact:
    """Nitsche frictional contact of a slave surface against a master surface of the same mesh.

    Args:
        V: blocked vector Lagrange space of the displacement [m].
        facet_tags: facet tags holding both contact surfaces.
        slave_tag, master_tag: tags of the slave and master surfaces.
        material: elastic material of the slave body (its stress enters the Nitsche terms).
        friction: Coulomb law mu(|v|).
        gamma0: dimensionless Nitsche parameter; gamma = gamma0 E / h with h the slave cell
            height normal to the facet (cell volume / facet area) [m].
        theta: 1 symmetric, 0 non-symmetric (incomplete), -1 skew-symmetric variant.
        quadrature_degree: degree of the slave facet quadrature (default 2 p + 1 for degree p).
        lagged_friction: evaluate mu at each point's slip speed of the previous step (set at
            ``set_reference``) instead of the current one. The step is then a Coulomb problem
            with a fixed coefficient field: more robust generalized Newton when mu(v) decays
            steeply (velocity weakening can make the active set cycle), first-order lag in time.
        chunk: points processed at once in the Jacobian (bounds memory).

    Call ``set_reference(u_old, dt)`` at the start of each step and ``update(u)`` at each
    iterate, then ``residual()`` / ``jacobian()``. Both are in the layout of
    ``dolfinx.fem.petsc`` vectors/matrices of V (global indices, owned rows). The
    Jacobian is a separate AIJ matrix with its own sparsity (it couples slave and
    master dofs, which the bulk pattern lacks): add it as ``A.axpy(1, J,
    PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)`` or use ``solver.dynamics.newton``, which
    keeps A and J apart. Implements ``solver.contact.model.ContactModel``.
    """

    def __init__(
        self,
        V: dolfinx.fem.FunctionSpace,
        facet_tags: dolfinx.mesh.MeshTags,
        slave_tag: int,
        master_tag: int,
        material: Material,
        friction: FrictionLaw,
        gamma0: float = 100.0,
        theta: int = 1,
        quadrature_degree: int | None = None,
        lagged_friction: bool = False,
        chunk: int = 500,
    ):
        if theta not in (1, 0, -1):
            raise ValueError(
                f"theta must be 1 (symmetric), 0 (non-symmetric) or -1 (skew), got {theta}"
            )
        if not gamma0 > 0:
            raise ValueError(f"Nitsche parameter gamma0 must be positive, got {gamma0}")
        if slave_tag == master_tag:
            raise ValueError(f"slave and master tags must differ, got {slave_tag} for both")
        degree = V.element.basix_element.degree
        qdeg = 2 * degree + 1 if quadrature_degree is None else quadrature_degree
        if qdeg < 1:
            raise ValueError(f"quadrature_degree must be >= 1, got {qdeg}")
        self.V = V
        self.material = material
        self.friction = friction
        self.theta = theta
        self.gamma0 = gamma0
        self.chunk = chunk
        self.lagged_friction = lagged_friction
        self.slave = SlaveQuadrature(V, facet_tags, slave_tag, qdeg)
        self.master = MasterSurface(V, facet_tags, master_tag)
        self.gamma = gamma0 * material.E / self.slave.h  #: Nitsche parameter per point [Pa/m]
        #: local cells with a slave or master facet: the only cells whose dofs r_c and J_c involve
        self.support_cells = np.unique(np.concatenate([self.slave.cells, self.master.cells]))
        imap = V.dofmap.index_map
        self._slave_blocks = imap.local_to_global(self.slave.dofs.ravel()).reshape(
            self.slave.dofs.shape
        )
        self._sizes = (imap.size_local * 3, imap.size_global * 3)
        self._matrices = PointMatrices(
            V.mesh.comm, self._sizes
        )  # the Jacobian's COO pattern cached
        self._residual = dolfinx.fem.petsc.create_vector(V)  # returned by residual()
        u0 = dolfinx.fem.Function(V)
        self.dt: float | None = None
        self.state: ContactState | None = None  #: the contact state at the last update
        self.pairing: Pairing | None = None  #: the pairing of the last update
        self.set_reference(u0, None)
        self.update(u0)

    # -- state ---------------------------------------------------------------------------
    def set_reference(self, u_old: dolfinx.fem.Function, dt: float | None) -> None:
        """Start a step: slip increments are measured from u_old; slip velocity = increment / dt [s].

        ``dt=None`` marks a quasi-static step without a rate: the slip speed is taken as 0
        (static coefficient mu_s).
        """
        if dt is not None and not dt > 0:
            raise ValueError(
                f"time step dt must be positive (or None for rate-free steps), got {dt}"
            )
        self.dt = dt
        self._speed_old = (
            np.linalg.norm(self.state.slip_velocity, axis=1)
            if self.state is not None
            else np.zeros(self.slave.num_points)
        )
        self._u_old_slave = self.slave.displacement(u_old)
        self._u_old_master = self.master.displacement(u_old)
        self._updated_at = None

    @timed("contact update")
    def update(self, u: dolfinx.fem.Function) -> None:
        """Pair the slave points with the deformed master surface and evaluate the contact state at u."""
        u.x.scatter_forward()
        self._updated_at = u.x.array.copy()
        slave, gdim = self.slave, self.slave.gdim
        self._u_slave_nodes = u.x.array.reshape(-1, gdim)[slave.dofs]
        u_s = np.einsum("pn,pni->pi", slave.values, self._u_slave_nodes)
        disp = self.master.displacement(u)
        x = slave.points + u_s
        if self.pairing is not None:  # keep facets at kinks, warm-start the projection
            p = pair(x, self.master, disp, previous=self.pairing.facet, previous_s=self.pairing.s)
        else:
            p = pair(x, self.master, disp)
        self.pairing = p
        n = -p.normal
        grad_u = self._u_slave_nodes.transpose(0, 2, 1) @ slave.gradients
        eps = 0.5 * (grad_u + grad_u.transpose(0, 2, 1))
        mat = self.material
        sig = 2 * mat.mu * eps + mat.lmbda * np.trace(eps, axis1=1, axis2=2)[
            :, None, None
        ] * np.eye(gdim)
        traction = np.einsum("pij,pj->pi", sig, n)
        sigma_n = np.einsum("pi,pi->p", traction, n)
        sigma_t = traction - sigma_n[:, None] * n
        facet = np.maximum(p.facet, 0)
        old_m = np.einsum("pn,pni->pi", p.master_values, self._u_old_master[facet])
        new_m = np.einsum("pn,pni->pi", p.master_values, disp[facet])
        rel = (u_s - self._u_old_slave) - (new_m - old_m)
        ds = rel - np.einsum("pi,pi->p", rel, n)[:, None] * n
        # round-off level of ds [m]: below it the slip direction ds/|ds| is noise
        magnitude = sum(np.linalg.norm(a, axis=1) for a in (u_s, self._u_old_slave, new_m, old_m))
        self._ds_roundoff = 256 * np.finfo(float).eps * magnitude
        gamma = self.gamma
        P_n = sigma_n + gamma * p.gap
        P_t = sigma_t - gamma[:, None] * ds
        paired = p.paired
        speed = np.zeros(len(x)) if self.dt is None else np.linalg.norm(ds, axis=1) / self.dt
        mu = self.friction.coefficient(self._speed_old if self.lagged_friction else speed)
        lam = multipliers(np.where(paired, P_n, np.inf), P_t, mu)
        lam_n, lam_t, active, stick, slip = (
            lam.normal,
            lam.tangential,
            lam.active,
            lam.stick,
            lam.slip,
        )
        pressure = -lam_n
        status = np.full(len(x), Status.OPEN, dtype=np.int8)
        status[stick & (pressure > 0)] = Status.STICK
        status[slip] = Status.SLIP
        self._lam_n, self._lam_t = lam_n, lam_t
        self._sigma_n, self._sigma_t = sigma_n, sigma_t
        self._P_n, self._P_t, self._ds, self._speed, self._mu = P_n, P_t, ds, speed, mu
        self._active, self._stick, self._slip = active, stick, slip
        self._n = n
        velocity = ds / self.dt if self.dt is not None else np.zeros_like(ds)
        self.state = ContactState(
            status=status,
            gap=np.where(paired, p.gap, np.nan),
            pressure=pressure,
            tangential_traction=lam_t,
            slip_velocity=velocity,
            coordinates=x,
            weights=slave.weights,
            normal=n,
        )

    def trial_tractions(self) -> TrialTractions:
        """The points' trial tractions, normals, friction coefficients and pairing at the last
        update (this rank's points): the input of ``solver.contact.law``."""
        pairing = self._pairing()
        return TrialTractions(
            self._P_n[:, None] * self._n + self._P_t,
            self._n.copy(),
            np.asarray(self._mu, dtype=float).copy(),
            pairing.paired.copy(),
            np.where(pairing.paired, pairing.gap, np.nan),
        )

    def _pairing(self) -> Pairing:
        """The pairing of the last update."""
        if self.pairing is None:
            raise RuntimeError("NitscheContact: no update yet")
        return self.pairing

    def point_operators(self, idx: npt.NDArray) -> PointOperators:
        """The trial traction's derivative E = T - gamma jump and the test operator F = theta T -
        gamma jump of the points ``idx`` (this rank's, paired) at the last update, split into the
        slave part and the master part gamma psi (the same in both): the residual's contribution
        of these points is F^T (w / gamma) lambda(P), and dP = E du (pairing, normals and mu
        frozen)."""
        T = self._traction(idx)
        gdim = self.slave.gdim
        gam = self.gamma[idx]
        H = gam[:, None, None] * vector_basis(self.slave.values[idx], gdim)
        pairing = self._pairing()
        return PointOperators(
            slave_dofs=unrolled_dofs(self._slave_blocks[idx], gdim),
            E_slave=T - H,
            F_slave=self.theta * T - H,
            master_dofs=unrolled_dofs(self.master.blocks[pairing.facet[idx]], gdim),
            master=gam[:, None, None] * vector_basis(pairing.master_values[idx], gdim),
            weight=self.slave.weights[idx] / gam,
        )

    def slip_directions(self) -> tuple[npt.NDArray, npt.NDArray]:
        """The slipping points at the last update and their trial tangential tractions P_t [Pa]
        (this rank's points; the reference of ``reversal_limit``)."""
        return self._slip.copy(), self._P_t.copy()

    def reversal_limit(self, slipping: npt.NDArray, P_t0: npt.NDArray) -> float:
        """Largest fraction (<= 1, this rank) of the step from the iterate of ``slip_directions``
        (``slipping``, ``P_t0``) to the last update before a point that slipped there slips the
        other way at the last update: P_t . q0 = 0 with q0 = P_t0 / |P_t0|, P_t linear along the
        step. Points that come to stick (inside the friction disk) do not limit the step."""
        along = np.einsum("pi,pi->p", self._P_t, P_t0)
        start = np.einsum("pi,pi->p", P_t0, P_t0)
        radius = self._mu * -self._lam_n * np.sqrt(start)
        reversing = slipping & self._slip & (along < -radius)
        if not reversing.any():
            return 1.0
        return float((start[reversing] / (start[reversing] - along[reversing])).min())

    def updated_at(self, u: dolfinx.fem.Function) -> bool:
        """Whether the last ``update`` since ``set_reference`` was at u's present values (all ranks)."""
        same = self._updated_at is not None and np.array_equal(self._updated_at, u.x.array)
        return self.V.mesh.comm.allreduce(same, op=MPI.LAND)

    def memory(self) -> dict[str, npt.NDArray]:
        """This rank's contact memory: the slip velocity of the last step [m/s] (the lagged friction
        coefficient's speed), the paired master facet, which the pairing keeps while it is as close
        as any other, and the point's coordinates on that facet, from which the next projection
        starts."""
        return {
            "slip_velocity": self.state.slip_velocity,
            "paired_facet": self.pairing.facet,
            "paired_coordinates": self.pairing.s,
        }

    def restore_memory(self, memory) -> None:
        """Set the contact memory (the arrays of ``memory()``, same shapes) after an ``update`` at the
        restored u."""
        self.pairing.facet[:] = memory["paired_facet"]
        self.pairing.s[:] = memory["paired_coordinates"]
        self.state.slip_velocity[:] = memory["slip_velocity"]

    # -- per-point operators -------------------------------------------------------------
    def _traction(self, idx: npt.NDArray) -> npt.NDArray:
        """Slave traction operator of the points ``idx`` (``traction_operator``) [Pa m]."""
        return traction_operator(self.material, self._n[idx], self.slave.gradients[idx])

    def _jump(self, idx: npt.NDArray) -> npt.NDArray:
        """Jump operator v_s(x) - v_m(y) on [slave cell dofs, master facet dofs], shape (q, 3, nd)."""
        phi, psi = self.slave.values[idx], self.pairing.master_values[idx]
        return vector_basis(np.concatenate([phi, -psi], axis=1), self.slave.gdim)

    def _global_dofs(self, idx: npt.NDArray) -> npt.NDArray:
        blocks = np.concatenate(
            [self._slave_blocks[idx], self.master.blocks[self.pairing.facet[idx]]], axis=1
        )
        return unrolled_dofs(blocks, self.slave.gdim)

    def _chunks(self):
        paired = np.flatnonzero(self.pairing.paired)
        for start in range(0, len(paired), self.chunk):
            yield paired[start : start + self.chunk]

    # -- assembly ------------------------------------------------------------------------
    @timed("contact residual")
    def residual(self) -> PETSc.Vec:
        """Contact residual r(v) at the last update, a ghosted PETSc vector in V's layout [N]
        (this object's vector, overwritten by the next call: copy it to keep it).

        Evaluated as r(v) = sum_q w [T^T c + jump^T j] with the slave traction operator T
        (sigma_n(v) = n . T v, sigma_t(v) = (I - n n) T v), c = theta/gamma ((lambda_n - sigma_n) n
        + (I - n n)(lambda_t - sigma_t)) and j = -(lambda_n n + (I - n n) lambda_t) (n_m = -n).
        """
        th, mat = self.theta, self.material
        rows, vals = [], []
        for idx in self._chunks():
            n = self._n[idx]
            gam = self.gamma[idx]
            lam_n, lam_t = self._lam_n[idx], self._lam_t[idx]
            diff_t = lam_t - self._sigma_t[idx]
            diff_t -= np.sum(diff_t * n, axis=1)[:, None] * n
            c = (th / gam)[:, None] * ((lam_n - self._sigma_n[idx])[:, None] * n + diff_t)
            j = -(lam_n[:, None] * n + lam_t - np.sum(lam_t * n, axis=1)[:, None] * n)
            g = self.slave.gradients[idx]  # (q, ns, 3)
            gn, gc = (g @ n[:, :, None]), (g @ c[:, :, None])
            r_s = mat.mu * (gn * c[:, None, :] + gc * n[:, None, :])
            r_s += mat.lmbda * np.sum(n * c, axis=1)[:, None, None] * g
            r_s += self.slave.values[idx][:, :, None] * j[:, None, :]
            r_m = -self.pairing.master_values[idx][:, :, None] * j[:, None, :]
            r = np.concatenate([r_s.reshape(len(idx), -1), r_m.reshape(len(idx), -1)], axis=1)
            rows.append(self._global_dofs(idx).ravel())
            vals.append((self.slave.weights[idx][:, None] * r).ravel())
        assemble_point_vector(self._residual, self._sizes[1], rows, vals)
        return self._residual

    def _tangent_rows(self, idx, E, jump, stick, slip, consistent: bool) -> npt.NDArray:
        """n dlambda_n + dlambda_t (q, 3, nd) at normal-tied points, from E = T - gamma jump.

        d lambda = D E with D the derivative of ``solver.contact.law`` at stick and, when
        ``consistent``, slip points (else slip points are tied normally only), plus the
        coefficient's dependence on the slip speed when friction is not lagged.
        """
        n = self._n[idx]
        D = derivative(
            n, self._P_t[idx], self._mu[idx], -self._lam_n[idx], stick, slip & consistent
        )
        R = D @ E
        if consistent and slip.any() and self.dt is not None and not self.lagged_friction:
            # d|v| = e . d(ds) / dt with e = ds/|ds|; |ds| has no derivative at 0, where any unit
            # vector is a generalized gradient: take the slip direction of the trial traction,
            # -q, while ds is at round-off (the first iterate of a step), not a direction of noise
            s = np.flatnonzero(slip)
            P_t = self._P_t[idx[s]]
            q = P_t / np.linalg.norm(P_t, axis=1)[:, None]
            ds = self._ds[idx[s]]
            ds_norm = np.linalg.norm(ds, axis=1)
            moving = ds_norm > self._ds_roundoff[idx[s]]
            e = np.where(moving[:, None], ds / np.where(moving, ds_norm, 1.0)[:, None], -q)
            e -= np.sum(e * n[s], axis=1)[:, None] * n[s]  # e^T (I - n n) jump
            dmu = self.friction.derivative(self._speed[idx[s]])
            d_radius = (-self._lam_n[idx[s]] * dmu / self.dt)[:, None] * np.einsum(
                "pi,pik->pk", e, jump[s]
            )
            R[s] += q[:, :, None] * d_radius[:, None, :]
        return R

    def _assemble_matrix(
        self,
        tied,
        stick,
        slip,
        consistent: bool,
        theta: int | None = None,
        gamma=None,
        cache: str | None = None,
    ) -> PETSc.Mat:
        """Assemble sum_q w/gamma (-theta T^T T + [theta T - gamma jump]^T (n dlam_n + dlam_t)).

        (-theta T^T T = -theta (Sn Sn + St St), the slave-only Nitsche term, at every paired point;
        the tie term at the points ``tied``, with the states ``stick``/``slip`` per point.)
        Point matrices are summed per slave facet (slave-only term) and per (slave facet,
        master facet) pair (tie term) before the COO insertion (PETSc sums the remaining
        duplicates, also across ranks). With ``cache``, the matrix and its COO pattern are
        kept under that name and reused while the pattern is unchanged; a copy is returned.
        """
        th = self.theta if theta is None else theta
        gamma = self.gamma if gamma is None else gamma
        nq = self.slave.points_per_facet
        gdim = self.slave.gdim
        blocks, vals = [], []
        for idx in self._chunks():
            T = self._traction(idx)
            nsd = T.shape[2]
            gam = gamma[idx]
            w = self.slave.weights[idx] / gam
            slave_facet = idx // nq
            if th != 0:
                L = np.sqrt(w)[:, None, None] * T
                first, K = grouped_products(slave_facet, L, L)
                blocks.append(self._global_dofs(idx[first])[:, :nsd])
                vals.append((-th * K).ravel())
            t = np.flatnonzero(tied[idx])
            if t.size:
                it = idx[t]
                jump = self._jump(it)
                T_full = np.concatenate(
                    [T[t], np.zeros((len(t), gdim, jump.shape[2] - nsd))], axis=2
                )
                E = T_full - gam[t, None, None] * jump
                R = self._tangent_rows(it, E, jump, stick[it], slip[it], consistent)
                F = w[t, None, None] * (th * T_full - gam[t, None, None] * jump)
                key = slave_facet[t] * self.master.num_facets + self.pairing.facet[it]
                first, K = grouped_products(key, F, R)
                blocks.append(self._global_dofs(it[first]))
                vals.append(K.ravel())
        vals = np.concatenate(vals) if vals else np.zeros(0)
        return self._matrices.assemble(blocks, vals, cache)

    @timed("contact jacobian")
    def jacobian(self) -> PETSc.Mat:
        """Generalized-Newton Jacobian of the contact residual at the last update [N/m] (this
        object's matrix, overwritten by the next call: copy it to keep it)."""
        return self._assemble_matrix(
            self._active, self._stick, self._slip, consistent=True, cache="jacobian"
        )

    def interface_stiffness(
        self, status: npt.NDArray | Status, theta: int | None = None, gamma0: float | None = None
    ) -> PETSc.Mat:
        """Linear interface tangent for a given per-point status (this rank's slave points) [N/m].

        STICK ties normal and tangential relative motion, SLIP the normal motion only, OPEN
        nothing (for theta != 0 the Nitsche consistency term -theta/gamma sigma(u) sigma(v)
        remains at every paired point, as in the nonlinear operator). Uses the pairing of the
        last ``update`` (the reference configuration if none). Add to the bulk stiffness with
        ``K.axpy(1, S, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)``.

        ``theta``/``gamma0`` (default: this object's) assemble the tangent of another Nitsche
        variant at the same pairing, e.g. the symmetric theta = 1 with a large gamma0 for a
        modal analysis while the time stepping uses theta = -1 with a small gamma0.
        """
        if theta is not None and theta not in (1, 0, -1):
            raise ValueError(
                f"theta must be 1 (symmetric), 0 (non-symmetric) or -1 (skew), got {theta}"
            )
        if gamma0 is not None and not gamma0 > 0:
            raise ValueError(f"Nitsche parameter gamma0 must be positive, got {gamma0}")
        gamma = None if gamma0 is None else gamma0 * self.material.E / self.slave.h
        status = np.broadcast_to(np.asarray(status, dtype=np.int8), (self.slave.num_points,))
        if not np.isin(status, list(Status)).all():
            raise ValueError("status values must be Status.OPEN, Status.STICK or Status.SLIP")
        return self._assemble_matrix(
            status != Status.OPEN,
            status == Status.STICK,
            np.zeros(len(status), bool),
            consistent=False,
            theta=theta,
            gamma=gamma,
        )

    def residual_floor(self) -> float:
        """Round-off level of the contact residual's l2 norm at the last update [N] (all ranks).

        The gap is a difference of positions of size |x|, so it carries an absolute error of
        about eps |x| [m], which the Nitsche terms multiply by gamma w: the residual cannot be
        reduced below about eps (sum_q (w_q gamma_q |x_q|)^2)^(1/2) over the paired points
        (measured on the joint: the residual stagnates at 1-5 times this). Returns 10 times
        that estimate, for use as a floor of Newton's residual tolerance.
        """
        paired = self.pairing.paired
        scale = (
            self.slave.weights[paired]
            * self.gamma[paired]
            * np.linalg.norm(self.state.coordinates[paired], axis=1)
        )
        total = self.V.mesh.comm.allreduce(float(scale @ scale), op=MPI.SUM)
        return 10.0 * np.finfo(float).eps * np.sqrt(total)

    # -- output --------------------------------------------------------------------------
    def forces(self) -> tuple[float, npt.NDArray]:
        """Total normal force sum(w p) [N] and friction force sum(w lambda_t) (3,) [N] on the slave (all ranks)."""
        w = self.slave.weights
        comm = self.V.mesh.comm
        normal = comm.allreduce(float(w @ self.state.pressure), op=MPI.SUM)
        tangential = comm.allreduce(w @ self.state.tangential_traction, op=MPI.SUM)
        return normal, tangential
