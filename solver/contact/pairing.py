"""Closest-point pairing of slave-surface quadrature points with the deformed master surface.

The slave points and the master facets are those of ``solver.contact.surfaces`` (the
master facets gathered on every rank); each slave point is projected onto the *deformed*
master surface (large sliding): candidates from a k-d tree of facet centroids, then a
vectorised Gauss-Newton iteration on the facet's reference coordinates ``s``. The result
does not depend on how the mesh is distributed.

Conventions: coordinates and displacements in m; the master normal ``n_m`` is the
unit outward normal of the master body at the projection ``y``; the gap is
``g = (x - y) . n_m`` [m] with ``x`` the deformed slave point, positive when the
surfaces are apart, negative on penetration.
"""

from dataclasses import dataclass

import basix
import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree

from common.timing import timed
from solver.contact.surfaces import MasterSurface, clip_to_facet

__all__ = ["Pairing", "pair"]


def _closest_on_facets(
    x: npt.NDArray,
    facet: npt.NDArray,
    s: npt.NDArray,
    master: MasterSurface,
    facet_disp: npt.NDArray,
    max_iterations: int,
    tol: float,
) -> tuple[npt.NDArray, npt.NDArray]:
    """Closest points of x (n, gdim) on the given deformed facets: Gauss-Newton on the facet
    coordinates from s (n, 2) (modified), clipped to the facet. Returns s and |x - y| [m]."""
    moving = np.arange(len(x))
    for _ in range(max_iterations):
        y, dyds, _ = master.evaluate(facet[moving], s[moving], facet_disp)
        r = x[moving] - y
        dydsT = dyds.transpose(0, 2, 1)
        step = np.linalg.solve(dydsT @ dyds, dydsT @ r[:, :, None])[..., 0]
        s_new = clip_to_facet(s[moving] + step, master.elements.facet_cell)
        change = np.abs(s_new - s[moving]).max(axis=1)
        s[moving] = s_new
        moving = moving[change >= tol]
        if moving.size == 0:
            break
    y, _, _ = master.evaluate(facet, s, facet_disp)
    return s, np.linalg.norm(x - y, axis=1)


@dataclass
class Pairing:
    """Closest points of slave points on the deformed master surface (arrays over slave points).

    ``facet`` is the index into the gathered master facets, -1 where the point has no
    partner (beyond the master surface's edge or farther than the search radius).
    """

    facet: npt.NDArray  #: gathered master facet index, -1 if unpaired
    s: npt.NDArray  #: reference facet coordinates of the projection
    y: npt.NDArray  #: projection (closest point) on the deformed master surface [m]
    normal: npt.NDArray  #: outward unit normal of the master at y
    gap: npt.NDArray  #: (x - y) . normal [m], negative on penetration
    master_values: npt.NDArray  #: master displacement basis values at y, (np, ncl)

    @property
    def paired(self) -> npt.NDArray:
        return self.facet >= 0


@timed("pairing")
def pair(
    x: npt.NDArray,
    master: MasterSurface,
    disp: npt.NDArray,
    candidates: int = 4,
    search_radius: float | None = None,
    max_iterations: int = 30,
    tol: float = 1e-14,
    previous: npt.NDArray | None = None,
    previous_s: npt.NDArray | None = None,
) -> Pairing:
    """Project deformed slave points x (np, gdim) onto the deformed master surface.

    Candidates are the ``candidates`` facets with the nearest deformed centres; on each,
    Gauss-Newton on the facet coordinates (clipped to the facet) finds the closest point,
    and the nearest of them is kept. A point is unpaired when its closest point lies on
    the master surface's boundary with a tangential offset (it is beyond the edge), or
    when it is farther than ``search_radius`` [m] (default: the largest facet size).
    ``previous`` (facet per point from an earlier pairing) keeps a point on its facet while
    that facet is as close as the best candidate to within 1e-6 facet sizes: near a kink of
    the C0 master surface two facets are equally close and round-off would otherwise flip
    the choice (and the normal) between Newton iterations. With ``previous_s`` (the facet
    coordinates of that pairing), Gauss-Newton on the previous facet starts there instead of at
    the facet centre (a few iterations fewer; the same point to the tolerance ``tol``).
    Candidates other than the nearest centre's are only projected on when a lower bound of
    their distance (``MasterSurface.distance_bound``) does not rule them out.
    """
    el = master.elements
    npts = len(x)
    sizes = master.sizes
    radius = float(sizes.max()) if search_radius is None else search_radius
    k = min(candidates, master.num_facets)
    if npts == 0:
        return Pairing(
            np.zeros(0, np.int64),
            np.zeros((0, 2)),
            np.zeros((0, el.gdim)),
            np.zeros((0, el.gdim)),
            np.zeros(0),
            np.zeros((0, el.closure.shape[1])),
        )
    _, cand = cKDTree(master.centroids(disp)).query(x, k=k)
    cand = cand.reshape(npts, k)
    facet_disp = master.facet_displacement(disp)
    s = np.zeros((npts, k, 2))
    dist = np.full((npts, k), np.inf)
    s[:] = 0.5 if el.facet_cell == basix.CellType.quadrilateral else 1 / 3
    if previous is not None and previous_s is not None:  # warm start on the previous facet
        same = cand == previous[:, None]
        s[same] = np.repeat(previous_s[:, None, :], k, axis=1)[same]
    s[:, 0], dist[:, 0] = _closest_on_facets(
        x, cand[:, 0], s[:, 0], master, facet_disp, max_iterations, tol
    )
    if k > 1:
        # only candidates that can be as close as the nearest-centre facet (to the tolerance
        # of ``previous``), by a lower bound of the distance to a facet
        rows, cols = np.divmod(np.arange(npts * (k - 1)), k - 1)
        cols += 1
        lower = master.distance_bound(x[rows], cand[rows, cols], facet_disp)
        near = lower <= dist[rows, 0] + 1e-6 * sizes[cand[rows, cols]]
        rows, cols = rows[near], cols[near]
        s[rows, cols], dist[rows, cols] = _closest_on_facets(
            x[rows], cand[rows, cols], s[rows, cols], master, facet_disp, max_iterations, tol
        )
    best = np.argmin(dist, axis=1)
    if previous is not None:
        match = cand == previous[:, None]
        keep = match.any(axis=1)
        j = np.argmax(match, axis=1)
        rows = np.arange(npts)
        close = dist[rows, j] <= dist[rows, best] + 1e-6 * sizes[cand[rows, j]]
        best = np.where(keep & close, j, best)
    rows = np.arange(npts)
    facet, s = cand[rows, best], s[rows, best]
    y, dyds, values = master.evaluate(facet, s, facet_disp)
    values = master.closure_values(facet, values)
    normal = np.cross(dyds[:, :, 0], dyds[:, :, 1])
    normal *= (master.orientation[facet] / np.linalg.norm(normal, axis=1))[:, None]
    r = x - y
    gap = np.einsum("pi,pi->p", r, normal)
    tangential = np.linalg.norm(r - gap[:, None] * normal, axis=1)
    beyond_edge = tangential > np.maximum(0.5 * np.abs(gap), 1e-6 * sizes[facet])
    unpaired = beyond_edge | (np.linalg.norm(r, axis=1) > radius)
    facet = np.where(unpaired, -1, facet)
    return Pairing(facet, s, y, normal, gap, values)
