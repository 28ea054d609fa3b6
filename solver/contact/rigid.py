"""Nitsche contact with Coulomb friction against a rigid plane, in UFL.

The obstacle is the half-space behind the plane through ``plane_point`` with unit
normal ``n_o`` pointing from the obstacle towards the body. With n = -n_o (the
contact normal, out of the body) and for the facets tagged ``tag``:

    gap        g(u)   = (x + u - p_0) . n_o                       [m], >= 0 open
    stresses   s_n(u) = n . sigma(u) n,  s_t(u) = sigma(u) n - s_n n   [Pa]
    Nitsche    P_n(u) = s_n(u) + gamma g(u),   gamma = gamma0 E / h   [Pa]
               P_t(u) = s_t(u) - gamma (u - u_old)_t       (u_old: previous step)

Contact pressure p = -min(P_n, 0) >= 0; friction traction = projection of P_t onto
the disc of radius mu(|v_t|) p with the slip velocity v_t = (u - u_old)_t / dt and
mu(v) from ``solver.contact.friction.FrictionLaw``. The contact residual added to the bulk
equations (Chouly, Hild & Renard, theta-variant: 1 symmetric, 0 incomplete,
-1 skew-symmetric) is

    r_c(u; w) = - theta/gamma int s_n(u) s_n(w) + 1/gamma int min(P_n, 0) (theta s_n(w) - gamma w.n)
                - theta/gamma int s_t(u).s_t(w) + 1/gamma int [P_t]_{mu p} . (theta s_t(w) - gamma w_t),

and its Jacobian is the exact UFL Gateaux derivative (generalised Newton). The object
follows the contact interface of ``solver.contact.nitsche.NitscheContact``: set_reference,
update, residual, jacobian, state.
"""

from dataclasses import dataclass

import basix
import numpy as np
import numpy.typing as npt
import ufl
from petsc4py import PETSc

from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc

from common.material import Material
from solver.contact.friction import FrictionLaw
from solver.contact.model import Status
from solver.elasticity import sigma


@dataclass
class PlaneContactState:
    """Per quadrature point of the contact facets (owned facets of this rank)."""

    points: np.ndarray  #: reference positions (x) [m], (n, 3)
    status: np.ndarray  #: Status values (OPEN, STICK or SLIP)
    gap: np.ndarray  #: [m]
    pressure: np.ndarray  #: contact pressure, positive in compression [Pa]
    tangential_traction: np.ndarray  #: friction traction on the body [Pa], (n, gdim)
    slip_velocity: np.ndarray  #: (u - u_old)_t / dt [m/s], (n, gdim)


def _ball_projection(x, radius, eps: float):
    """Projection of the vector x onto the disc of the given radius (>= 0)."""
    norm = ufl.sqrt(ufl.dot(x, x) + eps**2)
    return ufl.conditional(ufl.le(norm, radius), x, radius * x / norm)


class RigidPlaneContact:
    """Frictional Nitsche contact of the facets ``tag`` with a rigid plane.

    Implements ``solver.contact.model.ContactModel``; its UFL forms read the iterate directly,
    so it carries no memory between steps, no reversal limit and no round-off estimate.
    """

    def __init__(
        self,
        V: fem.FunctionSpace,
        facet_tags,
        tag: int,
        material: Material,
        friction: FrictionLaw | None,
        plane_point: npt.ArrayLike,
        plane_normal: npt.ArrayLike,
        gamma0: float = 10.0,
        theta: float = 1.0,
        quadrature_degree: int | None = None,
    ):
        mesh = V.mesh
        gdim = mesh.geometry.dim
        n_o = np.asarray(plane_normal, dtype=float)[:gdim]
        if n_o.shape != (gdim,) or not np.linalg.norm(n_o) > 0:
            raise ValueError(
                f"plane_normal must be a nonzero vector of length {gdim}, got {plane_normal}"
            )
        if theta not in (-1.0, 0.0, 1.0):
            raise ValueError(f"theta must be 1 (symmetric), 0 or -1 (skew-symmetric), got {theta}")
        if not gamma0 > 0:
            raise ValueError(f"gamma0 must be positive, got {gamma0}")
        if mesh.comm.allreduce(len(facet_tags.find(tag))) == 0:
            raise ValueError(f"RigidPlaneContact: no facets with tag {tag}")
        n_o = n_o / np.linalg.norm(n_o)
        self.V, self.material, self.friction = V, material, friction
        self.u = fem.Function(V, name="contact_displacement")
        self.u_old = fem.Function(V, name="contact_reference")
        self.dt = fem.Constant(mesh, 1.0)
        self._tag, self._facet_tags = tag, facet_tags
        tdim = mesh.topology.dim
        mesh.topology.create_connectivity(tdim - 1, tdim)
        f2c = mesh.topology.connectivity(tdim - 1, tdim)
        facets = facet_tags.find(tag)
        #: local cells with a contact facet: the only cells whose dofs r_c and J_c involve
        self.support_cells = np.unique(f2c.array[f2c.offsets[facets]]).astype(np.int32)

        x = ufl.SpatialCoordinate(mesh)
        n = ufl.as_vector(-n_o)
        p0 = ufl.as_vector(np.asarray(plane_point, dtype=float)[:gdim])
        h = ufl.CellDiameter(mesh)
        gamma = gamma0 * material.E / h
        metadata = {} if quadrature_degree is None else {"quadrature_degree": quadrature_degree}
        ds = ufl.Measure(
            "ds", domain=mesh, subdomain_data=facet_tags, subdomain_id=tag, metadata=metadata
        )
        w = ufl.TestFunction(V)
        u, u_old = self.u, self.u_old

        def s_n(v):
            return ufl.dot(n, ufl.dot(sigma(v, material), n))

        def s_t(v):
            return ufl.dot(sigma(v, material), n) - s_n(v) * n

        def tangential(v):
            return v - ufl.dot(v, n) * n

        gap = ufl.dot(x + u - p0, ufl.as_vector(n_o))
        P_n = s_n(u) + gamma * gap
        pressure = -ufl.conditional(ufl.le(P_n, 0.0), P_n, 0.0)  # the kink P_n = 0 counts as active
        F = (
            -theta / gamma * s_n(u) * s_n(w)
            - pressure / gamma * (theta * s_n(w) - gamma * ufl.dot(w, n))
        ) * ds
        slip = tangential(u - u_old)
        scale = float(material.E) * 1e-14  # regularisation of |.| at zero [Pa]
        slip_velocity = slip / self.dt
        P_t = s_t(u) - gamma * slip
        if friction is not None:
            speed = ufl.sqrt(ufl.dot(slip_velocity, slip_velocity) + 1e-30)
            limit = friction.coefficient(speed) * pressure
            traction_t = _ball_projection(P_t, limit, scale)
            F += (
                -theta / gamma * ufl.dot(s_t(u), s_t(w))
                + 1 / gamma * ufl.dot(traction_t, theta * s_t(w) - gamma * tangential(w))
            ) * ds
        self._forms = {
            "residual": fem.form(F),
            "jacobian": fem.form(ufl.derivative(F, u, ufl.TrialFunction(V))),
            "normal_force": fem.form(pressure * ds),
        }
        self._b = fem_petsc.create_vector(V)
        self._A = fem_petsc.create_matrix(self._forms["jacobian"])
        self._state_fields = [gap, pressure, slip_velocity, x]
        if friction is not None:
            self._state_fields += [traction_t, ufl.sqrt(ufl.dot(P_t, P_t)), limit]
        # one Expression per reference facet, compiled on every rank (JIT is collective)
        cell_type = mesh.basix_cell()
        degree = 2 * V.element.basix_element.degree
        self._state_expressions = []
        for lf in range(len(basix.topology(cell_type)[mesh.topology.dim - 1])):
            X = _facet_points_in_cell(cell_type, lf, degree)
            self._state_expressions.append(
                (X, [fem.Expression(e, X, comm=mesh.comm) for e in self._state_fields])
            )

    def set_reference(self, u_old: fem.Function, dt: float | None) -> None:
        """Displacement at the previous step (slip increments are measured from it) and dt [s]
        (``None``: a rate-free step, slip velocity 0)."""
        if dt is not None and not dt > 0:
            raise ValueError(f"time step must be positive, got {dt} s")
        self.u_old.x.array[:] = u_old.x.array
        self.dt.value = np.inf if dt is None else dt

    def update(self, u: fem.Function) -> None:
        """Set the current displacement iterate."""
        self.u.x.array[:] = u.x.array

    def updated_at(self, u: fem.Function) -> bool:
        """Always False: the forms evaluate at the iterate set by ``update`` (which is cheap)."""
        return False

    def residual_floor(self) -> float:
        """No round-off estimate: 0."""
        return 0.0

    def slip_directions(self) -> tuple[npt.NDArray, npt.NDArray]:
        """No reversal limit: no points."""
        return np.zeros(0, dtype=bool), np.zeros((0, self.V.mesh.geometry.dim))

    def reversal_limit(self, slipping: npt.NDArray, P_t0: npt.NDArray) -> float:
        """No reversal limit: 1."""
        return 1.0

    def memory(self) -> dict[str, npt.NDArray]:
        """No state carried between steps."""
        return {}

    def restore_memory(self, memory) -> None:
        """No state carried between steps."""

    def residual(self) -> PETSc.Vec:
        """Contact residual vector r_c(u) [N] (this object's vector, overwritten by the next call)."""
        with self._b.localForm() as loc:
            loc.set(0.0)
        fem_petsc.assemble_vector(self._b, self._forms["residual"])
        self._b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        return self._b

    def jacobian(self) -> PETSc.Mat:
        """Generalised derivative d r_c / d u [N/m], no boundary conditions (this object's matrix,
        overwritten by the next call)."""
        self._A.zeroEntries()
        fem_petsc.assemble_matrix(self._A, self._forms["jacobian"])
        self._A.assemble()
        return self._A

    def normal_force(self) -> float:
        """Total contact force int p ds [N] (per unit thickness in 2D), on every rank."""
        mesh = self.V.mesh
        return mesh.comm.allreduce(fem.assemble_scalar(self._forms["normal_force"]))

    @property
    def state(self) -> PlaneContactState:
        """Status, gap, pressure, friction traction and slip velocity at the facet quadrature points."""
        mesh = self.V.mesh
        tdim = mesh.topology.dim
        mesh.topology.create_connectivity(tdim - 1, tdim)
        facets = self._facet_tags.find(self._tag)
        facets = facets[facets < mesh.topology.index_map(tdim - 1).size_local]
        entities = fem.compute_integration_domains(
            fem.IntegralType.exterior_facet, mesh.topology, facets
        )
        entities = np.asarray(entities).reshape(-1, 2)
        values = [[] for _ in self._state_fields]
        for lf in np.unique(entities[:, 1]):
            X, expressions = self._state_expressions[lf]
            on_lf = entities[entities[:, 1] == lf, 0]
            for k, ex in enumerate(expressions):
                values[k].append(ex.eval(mesh, on_lf).reshape(len(on_lf) * X.shape[0], -1))
        gdim = mesh.geometry.dim
        gap, pressure, velocity, x, *friction = (
            np.concatenate(v) if v else np.zeros((0, c))
            for v, c in zip(values, (1, 1, gdim, gdim, gdim, 1, 1))
        )
        gap, pressure = gap[:, 0], pressure[:, 0]
        if friction:  # friction limit mu p versus the trial traction |P_t|
            traction, trial_norm, limit = friction[0], friction[1][:, 0], friction[2][:, 0]
            status = np.where(
                pressure > 0, np.where(trial_norm < limit, Status.STICK, Status.SLIP), Status.OPEN
            )
        else:
            traction, status = (
                np.zeros_like(velocity),
                np.where(pressure > 0, Status.SLIP, Status.OPEN),
            )
        return PlaneContactState(
            np.pad(x, ((0, 0), (0, 3 - gdim))), status, gap, pressure, traction, velocity
        )


def _facet_points_in_cell(cell_type: basix.CellType, local_facet: int, degree: int) -> np.ndarray:
    """Gauss points of one reference facet, in reference-cell coordinates."""
    tdim = basix.topology(cell_type).__len__() - 1
    vertices = basix.geometry(cell_type)[basix.topology(cell_type)[tdim - 1][local_facet]]
    if tdim == 1:
        return vertices.reshape(1, 1)
    facet_type = basix.cell.sub_entity_type(cell_type, tdim - 1, local_facet)
    s, _ = basix.make_quadrature(facet_type, degree)
    axes = vertices[1 : s.shape[1] + 1] - vertices[0]
    return vertices[0] + s @ axes
