"""Axisymmetric statics of thin conical shells (Soedel, ch. 3; all theta-derivatives zero).

The shell is a shell of revolution whose mid-surface meridian is piecewise straight
(cones and cylinders joined at kinks), coaxial with the z axis (up). On each straight
piece Soedel's equations with A1 = 1 (arc length s along the meridian, upward),
A2 = r(s), 1/R1 = 0 and 1/R2 = cos(phi)/r reduce to six first-order ODEs:

* kinematics: eps_s = u', eps_theta = (r' u + z' w)/r, beta = -w',
  kappa_s = beta', kappa_theta = r' beta / r
* Hooke: N_s = K (eps_s + nu eps_theta), N_theta = K (eps_theta + nu eps_s),
  M_s = D (kappa_s + nu kappa_theta), M_theta = D (kappa_theta + nu kappa_s),
  K = E h / (1 - nu^2), D = E h^3 / (12 (1 - nu^2))
* equilibrium: (r N_s)' - r' N_theta = 0, (r Q)' - z' N_theta = 0, (r M_s)' - r' M_theta - r Q = 0

with u the meridional displacement (along +s), w the normal displacement (outward
normal n = (z', -r') in (r, z)), r' = dr/ds, z' = dz/ds. The state carried by the
solver is global: y = [u_r, u_z, beta, H, V, M] (radial and axial displacement [m],
meridional rotation [rad], radial and axial force and meridional moment per unit
circumference [N/m, N/m, N m/m] acting on the part above a cut from the part below),
so that it is continuous across kinks and ring loads enter as jumps.

Ring loads (H, V, M) are per unit length of the loaded circle: H radial (outward),
V axial (up), M conjugate to beta (beta = -dw/ds). Flexibilities are in m^2/N,
m/N, 1/N; totals (force = 2 pi r x line load) are used for the lumped model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
import numpy.typing as npt
from scipy.integrate import solve_bvp

from common.material import Material
from geometry.parameters import ConePart, JointGeometry

#: default relative tolerance of the collocation solver
BVP_TOL = 1e-8


@dataclass(frozen=True)
class Meridian:
    """Piecewise-straight mid-surface meridian: vertices (r_i, z_i) [m], z strictly increasing."""

    r: tuple[float, ...]
    z: tuple[float, ...]

    def __post_init__(self) -> None:
        if len(self.r) != len(self.z) or len(self.r) < 2:
            raise ValueError("a meridian needs at least two (r, z) vertices, with as many r as z")
        if not all(r > 0 for r in self.r):
            raise ValueError(f"meridian radii must be positive, got {self.r}")
        if not all(b > a for a, b in pairwise(self.z)):
            raise ValueError(f"meridian heights must increase strictly, got {self.z}")

    @property
    def lengths(self) -> npt.NDArray[np.float64]:
        """Arc length of each straight piece [m]."""
        return np.hypot(np.diff(self.r), np.diff(self.z))

    def split(self, z: float) -> Meridian:
        """The same meridian with an extra vertex at height ``z`` (no-op at a vertex)."""
        if not self.z[0] <= z <= self.z[-1]:
            raise ValueError(
                f"height {z} m lies outside the meridian [{self.z[0]}, {self.z[-1]}] m"
            )
        if np.isclose(self.z, z, rtol=0, atol=1e-12).any():
            return self
        i = int(np.searchsorted(self.z, z))
        ri = float(np.interp(z, self.z, self.r))
        return Meridian(self.r[:i] + (ri,) + self.r[i:], self.z[:i] + (z,) + self.z[i:])

    def radius(self, z: float) -> float:
        """Mid-surface radius at height ``z`` [m]."""
        return float(np.interp(z, self.z, self.r))


@dataclass(frozen=True)
class Shell:
    """Thin elastic shell of revolution: meridian, thickness h [m], material."""

    meridian: Meridian
    thickness: float
    material: Material

    def __post_init__(self) -> None:
        if not self.thickness > 0:
            raise ValueError(f"shell thickness must be positive, got {self.thickness} m")
        if not self.thickness < 0.1 * min(self.meridian.r):
            raise ValueError(
                f"thickness {self.thickness} m is not thin against the smallest radius "
                f"{min(self.meridian.r)} m (need h < r/10)"
            )

    @property
    def membrane_stiffness(self) -> float:
        """K = E h / (1 - nu^2) [N/m]."""
        m = self.material
        return m.E * self.thickness / (1 - m.nu**2)

    @property
    def bending_stiffness(self) -> float:
        """D = E h^3 / (12 (1 - nu^2)) [N m]."""
        m = self.material
        return m.E * self.thickness**3 / (12 * (1 - m.nu**2))


def _piece_rhs(shell: Shell, r0: float, dr: float, dz: float, length: float):
    """dy/dt on one straight piece mapped to t in [0, 1] (y global, see module doc)."""
    K, D = shell.membrane_stiffness, shell.bending_stiffness
    nu, Eh = shell.material.nu, shell.material.E * shell.thickness
    rp, zp = dr / length, dz / length  # r', z'

    def rhs(t: npt.NDArray, y: npt.NDArray) -> npt.NDArray:
        r = r0 + dr * t
        ur, uz, beta, H, V, M = y
        u, w = ur * rp + uz * zp, ur * zp - uz * rp  # local displacements
        N, Q = H * rp + V * zp, H * zp - V * rp  # local resultants
        eps_t = (rp * u + zp * w) / r
        kap_t = rp * beta / r
        N_t = Eh * eps_t + nu * N
        M_t = D * (1 - nu**2) * kap_t + nu * M
        du = N / K - nu * eps_t
        dw = -beta
        dbeta = M / D - nu * kap_t
        dN = rp * (N_t - N) / r
        dQ = (zp * N_t - rp * Q) / r
        dM = rp * (M_t - M) / r + Q
        out = np.array(
            [du * rp + dw * zp, du * zp - dw * rp, dbeta, dN * rp + dQ * zp, dN * zp - dQ * rp, dM]
        )
        return length * out

    return rhs


@dataclass(frozen=True)
class _Piece:
    """Unscaled state y(t) of piece ``index`` from the collocation solution."""

    interpolant: object
    scale: npt.NDArray[np.float64]
    index: int

    def __call__(self, t: npt.ArrayLike) -> npt.NDArray[np.float64]:
        x = self.interpolant(t)[6 * self.index : 6 * self.index + 6]
        return x * (self.scale[:, None] if x.ndim == 2 else self.scale)


@dataclass(frozen=True)
class RingLoadSolution:
    """Solution of one ring-load problem: callable state along the meridian."""

    meridian: Meridian
    pieces: tuple[_Piece, ...]  #: state y(t) of each straight piece, t in [0, 1]
    load_z: float

    def state_at(self, z: float) -> npt.NDArray[np.float64]:
        """y = [u_r, u_z, beta, H, V, M] at height z (lower piece at a vertex)."""
        zs = self.meridian.z
        i = min(max(int(np.searchsorted(zs, z)) - 1, 0), len(zs) - 2)
        t = (z - zs[i]) / (zs[i + 1] - zs[i])
        return self.pieces[i](t)

    def displacement_samples(self, n: int = 400) -> tuple[npt.NDArray, npt.NDArray, npt.NDArray]:
        """(r [m], ds [m] quadrature weights, (u_r, u_z) [m]) on Gauss points of every piece."""
        x, wq = np.polynomial.legendre.leggauss(n)
        t, wq = 0.5 * (x + 1), 0.5 * wq
        rs, ws, us = [], [], []
        m = self.meridian
        for i, sol in enumerate(self.pieces):
            L = m.lengths[i]
            rs.append(m.r[i] + (m.r[i + 1] - m.r[i]) * t)
            ws.append(wq * L)
            us.append(sol(t)[:2])
        return np.concatenate(rs), np.concatenate(ws), np.concatenate(us, axis=1)


def solve_ring_load(
    shell: Shell,
    load_z: float,
    load: tuple[float, float, float],
    clamped: str,
    tol: float = BVP_TOL,
    nodes: int = 60,
) -> RingLoadSolution:
    """Static response to a ring load (H, V, M) [N/m, N/m, N m/m] at height ``load_z`` [m].

    ``clamped`` is ``"top"`` or ``"bottom"``: that end has u_r = u_z = beta = 0, the
    other end is free. The load may sit at the free end or anywhere in between.
    Solved by scipy's collocation solver ``solve_bvp`` (relative tolerance ``tol``).
    """
    if clamped not in ("top", "bottom"):
        raise ValueError(f"clamped must be 'top' or 'bottom', got {clamped!r}")
    mer = shell.meridian.split(load_z)
    n = len(mer.z) - 1
    k = int(np.argmin(np.abs(np.asarray(mer.z) - load_z)))  # vertex index of the load
    P = np.asarray(load, dtype=float)
    rhss = [
        _piece_rhs(
            shell, mer.r[i], mer.r[i + 1] - mer.r[i], mer.z[i + 1] - mer.z[i], mer.lengths[i]
        )
        for i in range(n)
    ]

    # unknowns scaled to O(1): bending length l = sqrt(r h), resultants ~ 1 N/m
    ell = math.sqrt(min(mer.r) * shell.thickness)
    D = shell.bending_stiffness
    scale = np.array([ell**3 / D, ell**3 / D, ell**2 / D, 1.0, 1.0, ell])
    S = np.tile(scale, n)

    def fun(t, X):
        Y = X * S[:, None]
        return np.concatenate([rhss[i](t, Y[6 * i : 6 * i + 6]) for i in range(n)]) / S[:, None]

    def bc(Xa, Xb):
        Ya, Yb = Xa * S, Xb * S
        ud, fd = scale[:3], scale[3:]  # residuals in scaled units
        res = []
        # lower end (vertex 0): clamped, or free with (minus) the load if it sits there
        lo = Ya[0:6]
        res.append(lo[:3] / ud if clamped == "bottom" else (lo[3:] + (P if k == 0 else 0.0)) / fd)
        # interior vertices: displacement continuity, resultant jump by -P at the load
        for i in range(1, n):
            below, above = Yb[6 * (i - 1) : 6 * i], Ya[6 * i : 6 * i + 6]
            res.append((above[:3] - below[:3]) / ud)
            res.append((above[3:] - below[3:] + (P if k == i else 0.0)) / fd)
        hi = Yb[6 * (n - 1) :]
        res.append(hi[:3] / ud if clamped == "top" else (hi[3:] - (P if k == n else 0.0)) / fd)
        return np.concatenate(res)

    # initial mesh clustered towards both ends of every piece (edge boundary layers)
    t = 0.5 * (1 - np.cos(np.linspace(0.0, np.pi, nodes)))
    sol = solve_bvp(fun, bc, t, np.zeros((6 * n, t.size)), tol=tol, max_nodes=200000)
    if not sol.success:
        raise RuntimeError(f"shell collocation did not converge: {sol.message}")
    pieces = tuple(_Piece(sol.sol, scale, i) for i in range(n))
    return RingLoadSolution(mer, pieces, load_z)


def ring_flexibility(
    shell: Shell, load_z: float, clamped: str, tol: float = BVP_TOL
) -> tuple[npt.NDArray[np.float64], list[RingLoadSolution]]:
    """3x3 flexibility [u_r, u_z, beta] per unit ring load [H, V, M] at height ``load_z``.

    Entries in m^2/N (u per H, V), m/N (u per M, beta per H, V) and 1/N (beta per M),
    for loads per unit circumference. Returns also the three unit-load solutions.
    """
    F = np.empty((3, 3))
    sols = []
    for j in range(3):
        sol = solve_ring_load(shell, load_z, tuple(np.eye(3)[j]), clamped, tol)
        F[:, j] = sol.state_at(load_z)[:3]
        sols.append(sol)
    return F, sols


def generalized_mass(shell: Shell, sols: list[RingLoadSolution], weights: npt.ArrayLike) -> float:
    """Rayleigh mass [kg] of the shape sum_j weights_j * sols_j: 2 pi rho h int |u|^2 r ds.

    With ``weights`` the ring loads [N/m] that produce a unit generalized displacement
    at the loaded circle, this is the (consistent) mass to lump at that displacement.
    """
    weights = np.asarray(weights, dtype=float)
    r, ds, _ = sols[0].displacement_samples()
    shape = sum(wj * s.displacement_samples()[2] for wj, s in zip(weights, sols))
    rho_h = shell.material.rho * shell.thickness
    return float(2 * math.pi * rho_h * np.sum((shape**2).sum(axis=0) * r * ds))


def part_meridian(part: ConePart, z_low: float = 0.0) -> Meridian:
    """Mid-surface meridian of a cone part (part-local heights), from ``z_low`` to its top.

    The mid-surface radius is the outer radius minus half the (radial) wall
    thickness. Below the part's lower end (``z_low`` < 0) the lowest section is
    continued as a cylinder.
    """
    if not z_low < part.total_length:
        raise ValueError(f"z_low = {z_low} m must lie below the part's top ({part.total_length} m)")
    zs = sorted({z for z in part.profile_heights() if z > z_low} | {z_low})
    r = [float(part.outer_radius(max(z, 0.0))) - 0.5 * part.thickness for z in zs]
    return Meridian(tuple(r), tuple(float(z) for z in zs))


@dataclass(frozen=True)
class JointStiffness:
    """Springs and masses of the reduced model, from axisymmetric shell statics (docs/physics.md §7).

    Totals over the circumference (force = 2 pi r x line load). TP: 3x3 edge
    flexibility (clamped top, ring loads H, V, M at the free lower edge), inverted,
    diagonal kept. MP: 2x2 flexibility in the MP surface's normal/tangential
    directions at the first-contact circle (free top, clamped at twice its cone
    length below the top), inverted, diagonal kept. Masses: Rayleigh masses of
    the static shapes that give a unit generalized displacement (same constraint
    as the stiffness).
    """

    K_r: float  #: TP lower edge, radial [N/m]
    K_rot: float  #: TP lower edge, meridional rotation [N m/rad]
    K_N: float  #: MP at contact circle, normal to its surface [N/m]
    K_T: float  #: MP at contact circle, along its meridian [N/m]
    m_r: float  #: generalized mass of the TP edge's radial shape [kg]
    J_rot: float  #: generalized inertia of the TP edge's rotation shape [kg m^2]
    m_T: float  #: generalized mass of the MP's tangential shape [kg]
    K_r_free: float  #: TP radial edge stiffness with V = M = 0 (a ring-load test) [N/m]
    tp_flexibility: npt.NDArray[np.float64]  #: 3x3 [u_r, u_z, beta] per [H, V, M] line loads
    mp_flexibility: npt.NDArray[np.float64]  #: 2x2 [normal, tangential] per line loads


def tp_edge_shell(joint: JointGeometry, material: Material) -> Shell:
    """The TP as a shell: clamped top, free lower edge at part-local z = 0."""
    return Shell(part_meridian(joint.tp), joint.tp.thickness, material)


def mp_contact_shell(joint: JointGeometry, material: Material) -> tuple[Shell, float]:
    """The MP as a shell clamped twice its cone length below its top; contact height [m]."""
    mp = joint.mp
    return Shell(part_meridian(mp, mp.total_length - 2 * mp.cone_length), mp.thickness, material), (
        joint.first_contact_height
    )


def joint_stiffness(
    joint: JointGeometry, material: Material, tol: float = BVP_TOL
) -> JointStiffness:
    """Shell-theory springs and masses of the reduced model for any slip-joint geometry."""
    tp = tp_edge_shell(joint, material)
    F_tp, tp_sols = ring_flexibility(tp, 0.0, "top", tol)
    r_tp = tp.meridian.r[0]
    K_tp = np.linalg.inv(F_tp)  # line stiffness, [H, V, M] per [u_r, u_z, beta]

    mp, z_c = mp_contact_shell(joint, material)
    F_mp3, mp_sols = ring_flexibility(mp, z_c, "bottom", tol)
    r_mp = mp.meridian.radius(z_c)
    a = joint.mp.half_angle
    # rows: outward surface normal n = (cos a, sin a), tangent down the meridian (sin a, -cos a)
    A = np.array([[math.cos(a), math.sin(a)], [math.sin(a), -math.cos(a)]])
    F_mp = A @ F_mp3[:2, :2] @ A.T
    K_mp = np.linalg.inv(F_mp)
    # MP unit-displacement shapes: loads (H, V) = A^T K_mp[:, j]; moment 0
    mp_weights = [np.append(A.T @ K_mp[:, j], 0.0) for j in range(2)]

    two_pi = 2 * math.pi
    return JointStiffness(
        K_r=two_pi * r_tp * K_tp[0, 0],
        K_rot=two_pi * r_tp * K_tp[2, 2],
        K_N=two_pi * r_mp * K_mp[0, 0],
        K_T=two_pi * r_mp * K_mp[1, 1],
        m_r=generalized_mass(tp, tp_sols, K_tp[:, 0]),
        J_rot=generalized_mass(tp, tp_sols, K_tp[:, 2]),
        m_T=generalized_mass(mp, mp_sols, mp_weights[1]),
        K_r_free=two_pi * r_tp / F_tp[0, 0],
        tp_flexibility=F_tp,
        mp_flexibility=F_mp,
    )
