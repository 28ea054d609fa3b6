"""Rigid contact map: overlay the TP's inner and the MP's outer surface without deformation.

The TP is lowered rigidly onto the MP; its position is given by the *overlap*
o = (MP top) - (TP lower edge) [m]. On a grid over the TP contact surface (its
inner cone: angle theta, TP-local height zeta) the radial gap is

    gap = [R_i,TP(zeta) + dr_TP(theta, zeta)] - [R_o,MP(z) + dr_MP(theta, z)],
    z = H_MP - o + zeta,

(+inf where z lies above the MP top). A point is in contact where gap <= 0 (rigid
overlay: interpenetration stands for contact). Reported: the first-contact
overlap, the area fraction of the TP contact surface in contact as a function of
the overlap, and, per point, the overlap at which it first touches.
Angles in rad (plots in deg), lengths in m; analytic surfaces, vectorised numpy.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from geometry.imperfections import RadialDeviation, check_imperfections
from geometry.parameters import JointGeometry


@dataclass(frozen=True)
class ContactMap:
    """Result of :func:`rigid_contact_map` (SI units)."""

    overlaps: npt.NDArray[np.float64]  #: swept overlaps [m], increasing
    contact_fraction: npt.NDArray[np.float64]  #: area fraction in contact at each overlap [-]
    first_contact_overlap: float  #: overlap at first contact [m]
    theta: npt.NDArray[np.float64]  #: grid angles [rad], shape (n_theta,)
    zeta: npt.NDArray[np.float64]  #: TP-local grid heights on the TP cone [m], shape (n_zeta,)
    onset_overlap: npt.NDArray[
        np.float64
    ]  #: overlap at which each point first touches [m] (nan: never), (n_zeta, n_theta)


def _gap(
    joint: JointGeometry,
    r_tp: np.ndarray,
    theta: np.ndarray,
    zeta: np.ndarray,
    overlap: float,
    dr_mp: RadialDeviation | None,
) -> np.ndarray:
    z = joint.mp.total_length - overlap + zeta
    r_mp = np.broadcast_to(joint.mp.outer_radius(z), r_tp.shape)
    if dr_mp is not None:
        r_mp = r_mp + dr_mp(theta, np.broadcast_to(z, theta.shape))
    return np.where((z <= joint.mp.total_length) & (z >= 0.0), r_tp - r_mp, np.inf)


@dataclass(frozen=True)
class _Surfaces:
    """The TP contact surface on a (zeta, theta) grid and the gap to the MP at an overlap."""

    joint: JointGeometry
    theta: np.ndarray  # (n_zeta + 1, n_theta)
    zeta: np.ndarray
    r_tp: np.ndarray
    dr_mp: RadialDeviation | None

    @classmethod
    def on_grid(
        cls,
        joint: JointGeometry,
        imperfections: dict[str, RadialDeviation],
        n_theta: int,
        n_zeta: int,
    ) -> _Surfaces:
        tp = joint.tp
        theta = np.arange(n_theta) * 2 * np.pi / n_theta
        zeta = np.linspace(tp.cone_bottom_z, tp.cone_top_z, n_zeta + 1)
        th, ze = np.meshgrid(theta, zeta)
        r_tp = tp.inner_radius(ze)
        if "tp" in imperfections:
            r_tp = r_tp + imperfections["tp"](th, ze)
        return cls(joint, th, ze, r_tp, imperfections.get("mp"))

    def gap(self, overlap: float) -> np.ndarray:
        return _gap(self.joint, self.r_tp, self.theta, self.zeta, overlap, self.dr_mp)

    def first_contact(self, lo: float, hi: float) -> float:
        """Overlap of first contact in [lo, hi] by bisection on the minimum gap [m]."""
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if self.gap(mid).min() > 0 else (lo, mid)
        return 0.5 * (lo + hi)


def first_contact_overlap(
    joint: JointGeometry,
    imperfections: Mapping[str, RadialDeviation] | None = None,
    n_theta: int = 360,
    n_zeta: int = 400,
) -> float:
    """Overlap [m] at which the (possibly imperfect) TP first touches the MP when lowered rigidly.

    Without imperfections this is ``joint.overlap``; with them the contact is searched
    within the largest sampled deviation, converted to height by the MP cone slope.
    """
    imperfections = check_imperfections(imperfections)
    if not imperfections:
        return joint.overlap
    surfaces = _Surfaces.on_grid(joint, imperfections, n_theta, n_zeta)
    largest = np.abs(surfaces.r_tp - joint.tp.inner_radius(surfaces.zeta)).max()
    if surfaces.dr_mp is not None:
        z_mp = np.linspace(0.0, joint.mp.total_length, n_zeta + 1)[:, None]
        largest += np.abs(surfaces.dr_mp(surfaces.theta[:1], z_mp)).max()
    reach = 2.0 * largest / np.tan(joint.mp.half_angle) + 1e-3 * joint.tp.cone_length
    lo, hi = joint.overlap - reach, joint.overlap + reach
    if surfaces.gap(lo).min() <= 0 or surfaces.gap(hi).min() > 0:
        raise ValueError(
            f"no first contact found between overlaps {lo:.6g} m and {hi:.6g} m "
            "(imperfections too large for the joint?)"
        )
    return surfaces.first_contact(lo, hi)


def tp_placement(
    joint: JointGeometry, imperfections: Mapping[str, RadialDeviation] | None = None
) -> float:
    """Global z [m] of the TP's lower end at first contact; ``joint.tp_offset`` if perfect."""
    return joint.mp.total_length - first_contact_overlap(joint, imperfections)


def rigid_contact_map(
    joint: JointGeometry,
    imperfections: Mapping[str, RadialDeviation] | None = None,
    overlaps: npt.ArrayLike | None = None,
    n_theta: int = 360,
    n_zeta: int = 400,
) -> ContactMap:
    """Sweep the TP down over ``overlaps`` [m] and map the rigid contact.

    ``imperfections`` maps ``"mp"``/``"tp"`` to radial deviations
    ``f(theta [rad], part-local z [m]) -> dr [m]``. Default sweep: from 10 % of the
    TP cone length above the first contact to twice the required slip below it.
    The first-contact overlap is refined by bisection between sweep samples.
    """
    imperfections = check_imperfections(imperfections)
    if overlaps is None:
        start = first_contact_overlap(joint, imperfections, n_theta, n_zeta)
        overlaps = np.linspace(
            start - 0.1 * joint.tp.cone_length, start + 2.0 * joint.required_slip, 201
        )
    overlaps = np.asarray(overlaps, dtype=np.float64)
    if overlaps.ndim != 1 or overlaps.size < 2 or np.any(np.diff(overlaps) <= 0):
        raise ValueError("overlaps must be an increasing 1D array of at least two values [m]")

    surfaces = _Surfaces.on_grid(joint, imperfections, n_theta, n_zeta)
    th, ze = surfaces.theta, surfaces.zeta
    zeta = ze[:, 0]
    weight = joint.tp.inner_radius(zeta)  # area element ~ r dtheta dzeta (trapezoid rule in zeta)
    weight[[0, -1]] *= 0.5
    weight = np.broadcast_to(weight[:, None], th.shape) / (n_theta * weight.sum())

    previous = surfaces.gap(overlaps[0])
    if np.any(previous <= 0.0):
        raise ValueError(
            f"already in contact at overlap {overlaps[0]:.6g} m: start the overlaps lower"
        )
    fraction = np.zeros(overlaps.size)
    onset = np.full(th.shape, np.nan)
    for k in range(1, overlaps.size):
        o, g = overlaps[k], surfaces.gap(overlaps[k])
        touching = g <= 0.0
        fraction[k] = weight[touching].sum()
        new = touching & np.isnan(onset)
        # onset by linear interpolation of the gap in o from the previous sample or, for
        # points that came below the MP top during this step, from where they did (o = zeta)
        o_start = np.full(g[new].shape, overlaps[k - 1])
        g_start = previous[new]
        entered = ~np.isfinite(g_start)
        o_start[entered] = ze[new][entered]
        g_start[entered] = _gap(
            joint,
            surfaces.r_tp[new][entered],
            th[new][entered],
            ze[new][entered],
            o_start[entered],
            surfaces.dr_mp,
        )
        t = np.divide(g_start, g_start - g[new], out=np.zeros_like(g_start), where=g_start > 0)
        onset[new] = o_start + t * (o - o_start)
        previous = g

    hits = np.flatnonzero(fraction > 0)
    if hits.size == 0:
        raise ValueError(f"no contact up to overlap {overlaps[-1]:.6g} m: extend the overlaps")
    first = surfaces.first_contact(overlaps[hits[0] - 1], overlaps[hits[0]])
    return ContactMap(overlaps, fraction, first, th[0], zeta, onset)


def plot_contact_map(result: ContactMap, path: str | Path) -> Path:
    """Write the unwrapped angle-height onset map and the contact-fraction curve (PNG)."""
    from matplotlib.figure import Figure

    path = Path(path).with_suffix(".png")
    fig = Figure(figsize=(11, 4.2), layout="constrained")
    ax_map, ax_curve = fig.subplots(1, 2, width_ratios=[1.6, 1])
    angles = np.degrees(np.append(result.theta, 2 * np.pi))
    onset = np.concatenate([result.onset_overlap, result.onset_overlap[:, :1]], axis=1)
    mesh = ax_map.pcolormesh(
        angles, result.zeta * 1e3, onset * 1e3, shading="gouraud", cmap="viridis"
    )
    fig.colorbar(mesh, ax=ax_map, label="overlap at first touch [mm] (blank: no contact)")
    ax_map.set(
        xlabel="angle [deg]",
        ylabel="height above TP lower edge [mm]",
        title="TP inner cone: rigid contact onset",
        xlim=(0, 360),
    )
    ax_curve.plot(result.overlaps * 1e3, result.contact_fraction * 100, "-")
    ax_curve.axvline(
        result.first_contact_overlap * 1e3,
        color="k",
        ls="--",
        label=f"first contact {result.first_contact_overlap * 1e3:.1f} mm",
    )
    ax_curve.set(
        xlabel="overlap [mm]", ylabel="TP contact surface in contact [%]", title="contact fraction"
    )
    ax_curve.legend()
    fig.savefig(path, dpi=120)
    return path
