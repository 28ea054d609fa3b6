"""Ranking of the joint's modes by how useful each is for settling the joint.

One ``ModeRecord`` per mode: frequency, (m, n) of each part and of the part that
dominates the kinetic energy, and the settlement indicators of
:mod:`solver.modal.indicators` for two ways of loading the TP top:

* "face": a force spread uniformly over the TP top face (as in the dynamics,
  ``solver.dynamics.loads.TopFaceLoad``); on a perfectly axisymmetric joint it excites
  only m = 0 (axial) and m = 1 (lateral) modes;
* "point": a force at one point of the TP top edge (mid-wall, theta = 0, as an
  eccentric motor or shaker fixed to one side), which excites every m.

Modes are ranked by the resonant interface slip under the eccentric-motor force
amplitude 0.3632 f^2 N (docs/physics.md §3) applied at the point, axially or laterally (the
larger of the two), with modal damping ``zeta``: rank 1 is the most promising
excitation frequency. Members of a degenerate pair (equal frequencies, cos/sin
orientations) share the pair's combined indicator and rank.
"""

from dataclasses import dataclass

import numpy as np
from dolfinx import fem

from common.material import Material
from solver.dynamics.loads import PointLoad, TopFaceLoad, eccentric_amplitude, shaker_point
from solver.modal.classify import classify
from solver.modal.eigen import ModalResult
from solver.modal.indicators import InterfaceSampler, energy_shares, modal_force, resonant_slip


@dataclass(frozen=True)
class ModeRecord:
    """Classification and settlement indicators of one mode (units in the names)."""

    mode: int
    frequency_Hz: float
    m: int
    n: int
    dominant_part: str
    m_MP: int
    n_MP: int
    m_TP: int
    n_TP: int
    kinetic_share_TP: float
    strain_share_TP: float
    participation_axial_face_per_sqrtkg: float
    participation_lateral_face_per_sqrtkg: float
    participation_axial_point_per_sqrtkg: float
    participation_lateral_point_per_sqrtkg: float
    interface_slip_rms_per_sqrtkg: float
    resonant_slip_axial_um: float
    resonant_slip_lateral_um: float
    rank: int


@dataclass(frozen=True)
class JointParts:
    """Cell tags of the two parts, the unit loads on the TP top and the interface sampler."""

    cell_tags: object  #: dolfinx MeshTags of the cells
    mp_tag: int
    tp_tag: int
    face: TopFaceLoad  #: unit forces spread over the TP top face
    point: PointLoad  #: unit forces at one point of the TP top edge
    interface: InterfaceSampler

    @classmethod
    def for_joint(cls, V: fem.FunctionSpace, mesh_data, joint) -> "JointParts":
        """Standard set-up on a mesh from ``geometry.mesh.create_joint_mesh`` (collective)."""
        from geometry import tags

        top = shaker_point(joint.tp, joint.tp_offset, joint.tp.total_length, 0.0)
        top[2] -= 1e-6 * joint.tp.total_length  # just inside the top face
        return cls(
            mesh_data.cell_tags,
            tags.MP_VOLUME,
            tags.TP_VOLUME,
            TopFaceLoad(V, mesh_data.facet_tags, tags.TP_TOP),
            PointLoad(V, top),
            InterfaceSampler.for_joint(V, joint),
        )


def degenerate_groups(frequencies_hz: np.ndarray, rtol: float = 1e-6) -> list[list[int]]:
    """Indices of consecutive (sorted) frequencies equal to ``rtol``, grouped."""
    groups: list[list[int]] = []
    for i, f in enumerate(frequencies_hz):
        if groups and abs(f - frequencies_hz[groups[-1][-1]]) <= rtol * f:
            groups[-1].append(i)
        else:
            groups.append([i])
    return groups


def describe_modes(
    result: ModalResult,
    material: Material,
    parts: JointParts,
    zeta: float = 0.01,
    n_stations: int = 24,
    m_max: int = 12,
) -> list[ModeRecord]:
    """Classify every mode and compute its indicators (collective)."""
    if not 0 < zeta < 1:
        raise ValueError(f"damping ratio zeta must lie in (0, 1), got {zeta}")
    mp_cells = parts.cell_tags.find(parts.mp_tag)
    tp_cells = parts.cell_tags.find(parts.tp_tag)
    rows = []
    for i, (f, u) in enumerate(zip(result.frequencies_hz, result.modes)):
        w_mp = classify(u, mp_cells, n_stations, m_max)
        w_tp = classify(u, tp_cells, n_stations, m_max)
        kinetic, strain = energy_shares(u, material, parts.cell_tags, [parts.mp_tag, parts.tp_tag])
        dominant, w = ("TP", w_tp) if kinetic[1] >= 0.5 else ("MP", w_mp)
        g = {
            f"{d}_{kind}": modal_force(u, load.vectors[c])
            for kind, load in (("face", parts.face), ("point", parts.point))
            for d, c in (("axial", 2), ("lateral", 0))
        }
        rows.append(
            dict(
                mode=i + 1,
                frequency_Hz=float(f),
                m=w.m,
                n=w.n,
                dominant_part=dominant,
                m_MP=w_mp.m,
                n_MP=w_mp.n,
                m_TP=w_tp.m,
                n_TP=w_tp.n,
                kinetic_share_TP=float(kinetic[1]),
                strain_share_TP=float(strain[1]),
                **{f"participation_{k}_per_sqrtkg": abs(v) for k, v in g.items()},
                interface_slip_rms_per_sqrtkg=parts.interface.rms_slip(u),
            )
        )
    # The orientation of a degenerate pair (cos/sin of the same m) is arbitrary: a force
    # excites the pair's combination, so resonant slips use the group's root-sum-square.
    for group in degenerate_groups(result.frequencies_hz):
        f = float(np.mean(result.frequencies_hz[group]))
        force = float(eccentric_amplitude(f))
        slip = float(
            np.sqrt(np.mean([rows[k]["interface_slip_rms_per_sqrtkg"] ** 2 for k in group]))
        )
        for d in ("axial", "lateral"):
            g = float(
                np.sqrt(sum(rows[k][f"participation_{d}_point_per_sqrtkg"] ** 2 for k in group))
            )
            for k in group:
                rows[k][f"resonant_slip_{d}_um"] = 1e6 * resonant_slip(g, slip, f, force, zeta)
    score = np.array(
        [max(r["resonant_slip_axial_um"], r["resonant_slip_lateral_um"]) for r in rows]
    )
    distinct = np.unique(np.round(-score, 12))
    rank = 1 + np.searchsorted(distinct, np.round(-score, 12))
    return [ModeRecord(**r, rank=int(k)) for r, k in zip(rows, rank)]
