"""Observers of the installation's time loop (``solver.dynamics.time_loop.run``): the
settlement of the TP on the MP, and the guard that stops a run whose contact band reaches the
top of the contact zone."""

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from geometry import tags
from solver.contact import Status
from solver.dynamics.elastodynamics import Elastodynamics
from solver.probes import PointProbe


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
                "rerun with a larger mesh.contact_zone_above"
            )
        return {}
