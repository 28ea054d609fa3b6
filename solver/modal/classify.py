"""Classification of mode shapes of thin-walled tubes: wave numbers (m, n).

Conventions (docs/physics.md §5): the tube axis is the z axis through the origin; m counts
circumferential waves (m = 0 axisymmetric, m = 1 beam-like); n counts nodal
circles along the part's axis, so n = 0 is the lowest axial shape (no node) and
n = 1 has one nodal circle.

Method: the displacement at the owned dof nodes of one part is written in
cylindrical components (u_r, u_theta, u_z) and sorted into axial stations. On
each station a least-squares Fourier series in theta (harmonics 0..m_max) is
fitted; the normal equations are summed over ranks, so the result does not
depend on the partition. m is the harmonic carrying most of the mean-square
displacement. n is the number of sign changes along the axis of the dominant
component of harmonic m (in its dominant circumferential orientation), with a
hysteresis of ``node_threshold`` times the peak amplitude so that numerical
noise near a clamp is not counted as a node.
"""

from dataclasses import dataclass

from common import backend  # noqa: F401  (before dolfinx)

import numpy as np
from dolfinx import fem
from mpi4py import MPI


@dataclass(frozen=True)
class WaveNumbers:
    """Circumferential (m) and axial (n) wave numbers of one part's motion."""

    m: int
    n: int
    m_share: float  #: fraction of mean-square displacement in harmonic m [-]
    component: str  #: cylindrical component that defines n: "r", "theta" or "z"


@dataclass(frozen=True)
class RingFourier:
    """Fourier coefficients of (u_r, u_theta, u_z) on axial stations.

    ``cos[s, c, k]`` and ``sin[s, c, k]`` are the coefficients of cos(k theta)
    and sin(k theta) of component c (0: r, 1: theta, 2: z) on station s at
    height ``z[s]`` [m]; stations with too few nodes are omitted.
    """

    z: np.ndarray
    cos: np.ndarray
    sin: np.ndarray


_COMPONENTS = ("r", "theta", "z")


def part_nodes(V: fem.FunctionSpace, cells: np.ndarray | None = None) -> np.ndarray:
    """Owned dof-node (block) indices of V, restricted to ``cells`` if given."""
    n_owned = V.dofmap.index_map.size_local
    if cells is None:
        return np.arange(n_owned, dtype=np.int32)
    tdim = V.mesh.topology.dim
    nodes = fem.locate_dofs_topological(V, tdim, np.asarray(cells, dtype=np.int32))
    return nodes[nodes < n_owned]


def ring_fourier(
    u: fem.Function, nodes: np.ndarray, n_stations: int = 24, m_max: int = 12
) -> RingFourier:
    """Least-squares Fourier coefficients of u on ``n_stations`` axial stations (collective)."""
    if n_stations < 2 or m_max < 0:
        raise ValueError(f"need n_stations >= 2 and m_max >= 0, got {n_stations}, {m_max}")
    V = u.function_space
    comm = V.mesh.comm
    x = V.tabulate_dof_coordinates()[nodes]
    values = u.x.array.reshape(-1, V.dofmap.index_map_bs)[nodes].real
    theta = np.arctan2(x[:, 1], x[:, 0])
    c, s = np.cos(theta), np.sin(theta)
    u_cyl = np.column_stack(
        [c * values[:, 0] + s * values[:, 1], -s * values[:, 0] + c * values[:, 1], values[:, 2]]
    )

    z_lo = comm.allreduce(x[:, 2].min() if len(x) else np.inf, op=MPI.MIN)
    z_hi = comm.allreduce(x[:, 2].max() if len(x) else -np.inf, op=MPI.MAX)
    if not z_hi > z_lo:
        raise ValueError("ring_fourier: the selected nodes span no axial length")
    station = np.minimum(
        ((x[:, 2] - z_lo) / (z_hi - z_lo) * n_stations).astype(int), n_stations - 1
    )

    k = np.arange(1, m_max + 1)
    basis = np.column_stack(
        [np.ones_like(theta), np.cos(np.outer(theta, k)), np.sin(np.outer(theta, k))]
    )
    n_basis = basis.shape[1]
    normal = np.zeros((n_stations, n_basis, n_basis))
    rhs = np.zeros((n_stations, n_basis, 3))
    z_sum = np.zeros(n_stations)
    n_pts = np.zeros(n_stations)
    np.add.at(normal, station, basis[:, :, None] * basis[:, None, :])
    np.add.at(rhs, station, basis[:, :, None] * u_cyl[:, None, :])
    np.add.at(z_sum, station, x[:, 2])
    np.add.at(n_pts, station, 1.0)
    for arr in (normal, rhs, z_sum, n_pts):
        comm.Allreduce(MPI.IN_PLACE, arr, op=MPI.SUM)

    keep = [
        i for i in range(n_stations) if n_pts[i] >= 2 * n_basis and np.linalg.cond(normal[i]) < 1e8
    ]
    if len(keep) < 2:
        raise ValueError(
            f"ring_fourier: fewer than 2 stations with enough nodes for m_max = {m_max}"
        )
    coef = np.array([np.linalg.solve(normal[i], rhs[i]) for i in keep])  # (s, basis, comp)
    cos = np.concatenate([coef[:, :1, :], coef[:, 1 : m_max + 1, :]], axis=1).transpose(0, 2, 1)
    sin = np.concatenate(
        [np.zeros_like(coef[:, :1, :]), coef[:, m_max + 1 :, :]], axis=1
    ).transpose(0, 2, 1)
    return RingFourier(z=z_sum[keep] / n_pts[keep], cos=cos, sin=sin)


def _sign_changes(w: np.ndarray, threshold: float) -> int:
    """Sign changes of w, counting only swings between +threshold and -threshold."""
    changes, sign = 0, 0
    for value in w:
        if abs(value) < threshold:
            continue
        s = 1 if value > 0 else -1
        if sign and s != sign:
            changes += 1
        sign = s
    return changes


def wave_numbers(fourier: RingFourier, node_threshold: float = 0.05) -> WaveNumbers:
    """(m, n) of one part from its ring Fourier coefficients."""
    # mean-square displacement of each harmonic: a0^2 for k = 0, (a^2 + b^2)/2 otherwise
    weight = np.full(fourier.cos.shape[2], 0.5)
    weight[0] = 1.0
    power = weight * (fourier.cos**2 + fourier.sin**2)  # (s, c, k)
    per_k = power.sum(axis=(0, 1))
    m = int(np.argmax(per_k))
    share = float(per_k[m] / per_k.sum()) if per_k.sum() > 0 else 0.0
    comp = int(np.argmax(power[:, :, m].sum(axis=0)))
    ab = np.column_stack([fourier.cos[:, comp, m], fourier.sin[:, comp, m]])
    # standing wave: project onto the dominant circumferential orientation
    _, vecs = np.linalg.eigh(ab.T @ ab)
    w = ab @ vecs[:, -1]
    peak = np.abs(w).max()
    n = _sign_changes(w, node_threshold * peak) if peak > 0 else 0
    return WaveNumbers(m=m, n=n, m_share=share, component=_COMPONENTS[comp])


def classify(
    u: fem.Function, cells: np.ndarray | None = None, n_stations: int = 24, m_max: int = 12
) -> WaveNumbers:
    """(m, n) of u on the part made of ``cells`` (all local cells if None). Collective."""
    return wave_numbers(ring_fourier(u, part_nodes(u.function_space, cells), n_stations, m_max))
