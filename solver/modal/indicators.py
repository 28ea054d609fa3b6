"""How useful each mode is for settling the joint: energy shares, participation, slip.

All quantities refer to mass-normalised modes (phi^T M phi = 1):

* ``kinetic_share`` / ``strain_share``: fraction of the modal kinetic / strain
  energy in each part [-].
* ``modal_force``: phi^T f of a unit force (1 N), e.g. spread uniformly over the
  TP top face or applied at one point of its top edge (``solver.dynamics.loads``) [1/sqrt(kg)].
* ``interface_slip``: RMS of the relative tangential (meridional, i.e. slip
  direction) displacement between TP and MP over sample points of the contact
  interface [1/sqrt(kg), i.e. m per unit of the modal coordinate in m sqrt(kg)].
* ``resonant_slip``: the RMS interface slip amplitude at resonance for a harmonic
  force of amplitude F [N] with modal damping ratio zeta: |phi^T f| F /
  (2 zeta omega^2) times ``interface_slip`` [m] (single-mode response).
"""

from collections.abc import Callable, Sequence

from common import backend  # noqa: F401  (before dolfinx/petsc4py)

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from common.material import Material
from solver.elasticity import epsilon, sigma
from solver.probes import PointProbe


def energy_shares(
    u: fem.Function, material: Material, cell_tags, part_tags: Sequence[int]
) -> tuple[np.ndarray, np.ndarray]:
    """Kinetic and strain energy fractions of each part in ``part_tags`` (collective)."""
    dx = ufl.Measure("dx", domain=u.function_space.mesh, subdomain_data=cell_tags)
    kinetic, strain = [], []
    for tag in part_tags:
        kinetic.append(fem.assemble_scalar(fem.form(material.rho * ufl.inner(u, u) * dx(tag))))
        strain.append(
            fem.assemble_scalar(fem.form(ufl.inner(sigma(u, material), epsilon(u)) * dx(tag)))
        )
    comm = u.function_space.mesh.comm
    kinetic = np.array([comm.allreduce(k, op=MPI.SUM) for k in kinetic])
    strain = np.array([comm.allreduce(s, op=MPI.SUM) for s in strain])
    return kinetic / kinetic.sum(), strain / strain.sum()


def modal_force(u: fem.Function, load: PETSc.Vec) -> float:
    """phi^T f [N/sqrt(kg) per N of load]."""
    return u.x.petsc_vec.dot(load)


class InterfaceSampler:
    """Paired points across the contact interface and the slip direction there.

    Rings of points at heights ``z`` [m]: one just inside the TP wall (radius
    r_tp(z)), one just inside the MP wall (radius r_mp(z)) at the same (theta, z),
    and the unit meridional tangent of the MP surface (the settlement slip
    direction). Built on every rank with the same points (collective).
    """

    def __init__(
        self,
        V: fem.FunctionSpace,
        z: np.ndarray,
        r_tp: Callable[[np.ndarray], np.ndarray],
        r_mp: Callable[[np.ndarray], np.ndarray],
        n_theta: int = 36,
    ):
        theta = np.linspace(0.0, 2 * np.pi, n_theta, endpoint=False)
        zz, tt = (a.ravel() for a in np.meshgrid(np.asarray(z, dtype=float), theta, indexing="ij"))

        def ring(r: np.ndarray) -> np.ndarray:
            return np.column_stack([r * np.cos(tt), r * np.sin(tt), zz])

        dz = 1e-4
        slope = (r_mp(zz + dz) - r_mp(zz - dz)) / (2 * dz)  # dr/dz of the MP surface
        tangents = np.column_stack([slope * np.cos(tt), slope * np.sin(tt), np.ones_like(zz)])
        self.tangents = tangents / np.linalg.norm(tangents, axis=1)[:, None]
        self._phi = fem.Function(V)
        self._tp = PointProbe(self._phi, ring(r_tp(zz)))
        self._mp = PointProbe(self._phi, ring(r_mp(zz)))

    def slip(self, u: fem.Function) -> np.ndarray:
        """Relative meridional displacement TP - MP at each sample point [m]."""
        self._phi.x.array[:] = u.x.array
        return np.einsum("ij,ij->i", self._tp() - self._mp(), self.tangents)

    def rms_slip(self, u: fem.Function) -> float:
        """RMS of ``slip`` over the sample points [m]."""
        return float(np.sqrt(np.mean(self.slip(u) ** 2)))

    @classmethod
    def for_joint(
        cls, V: fem.FunctionSpace, joint, n_heights: int = 24, n_theta: int = 36
    ) -> "InterfaceSampler":
        """Sampler over the overlap of a ``geometry.parameters.JointGeometry`` at first contact:
        heights from the TP's lower edge to the MP's top, points a quarter wall inside each wall."""
        z_lo, z_hi = joint.tp_offset, joint.mp.total_length
        z = np.linspace(z_lo, z_hi, n_heights + 2)[1:-1]
        return cls(
            V,
            z,
            r_tp=lambda zz: joint.tp.inner_radius(zz - joint.tp_offset) + 0.25 * joint.tp.thickness,
            r_mp=lambda zz: joint.mp.outer_radius(zz) - 0.25 * joint.mp.thickness,
            n_theta=n_theta,
        )


def resonant_slip(
    participation: float, rms_slip: float, f_hz: float, force_n: float, zeta: float
) -> float:
    """Slip amplitude at resonance [m]: |phi^T f| F / (2 zeta omega^2) * slip_rms.

    A zero-frequency mode (a part not held, e.g. an imperfect TP resting on one point) has
    unbounded resonant slip: inf."""
    omega2 = (2 * np.pi * f_hz) ** 2
    if omega2 <= 0.0:
        return np.inf
    return abs(participation) * force_n / (2 * zeta * omega2) * rms_slip
