"""Closest-point pairing of slave-surface quadrature points with the deformed master surface.

The slave surface is sampled at quadrature points of its (owned) facets; each rank
keeps its own slave points. The master surface is small compared with the volume,
so its facets (reference node coordinates, displacement dofs) are gathered onto
every rank and each slave point is projected onto the *deformed* master surface
(large sliding): candidates from a k-d tree of facet centroids, then a vectorised
Gauss-Newton iteration on the facet's reference coordinates ``s``. The result does
not depend on how the mesh is distributed.

Conventions: coordinates and displacements in m; the master normal ``n_m`` is the
unit outward normal of the master body at the projection ``y``; the gap is
``g = (x - y) . n_m`` [m] with ``x`` the deformed slave point, positive when the
surfaces are apart, negative on penetration.
"""

from dataclasses import dataclass

from mpi4py import MPI

import basix
import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree

import dolfinx

__all__ = ["MasterSurface", "Pairing", "SlaveQuadrature", "pair"]


def _facet_maps(cell: basix.CellType) -> tuple[npt.NDArray, npt.NDArray, basix.CellType]:
    """Affine maps X = origin[lf] + axes[lf] @ s from reference facet lf to the reference cell."""
    geom = basix.geometry(cell)
    facets = basix.topology(cell)[-2]
    origin = np.array([geom[f[0]] for f in facets])
    axes = np.array([np.column_stack([geom[f[1]] - geom[f[0]], geom[f[2]] - geom[f[0]]]) for f in facets])
    facet_cell = basix.CellType.quadrilateral if len(facets[0]) == 4 else basix.CellType.triangle
    return origin, axes, facet_cell


def _combine(N: npt.NDArray, X: npt.NDArray) -> npt.NDArray:
    """sum_n N[p, n] X[p, n, i] (batched matrix product)."""
    return (N[:, None, :] @ X)[:, 0, :]


def _gradient(dN: npt.NDArray, X: npt.NDArray) -> npt.NDArray:
    """sum_n dN[d, p, n] X[p, n, i] -> [p, i, d] (batched matrix product)."""
    return (dN.transpose(1, 0, 2) @ X).transpose(0, 2, 1)


def _clip_to_facet(s: npt.NDArray, facet_cell: basix.CellType) -> npt.NDArray:
    """Clip reference facet coordinates into the unit square / unit triangle."""
    s = np.clip(s, 0.0, 1.0)
    if facet_cell == basix.CellType.triangle:
        total = s.sum(axis=1)
        over = total > 1.0
        s[over] /= total[over, None]
    return s


class _CellElements:
    """Scalar coordinate and displacement elements of a single-cell-type mesh, per-facet closures."""

    def __init__(self, V: dolfinx.fem.FunctionSpace):
        mesh = V.mesh
        if len(mesh.topology.entity_types[-1]) != 1:
            raise ValueError("contact needs a mesh with a single cell type")
        if V.dofmap.bs != mesh.geometry.dim or V.element.needs_dof_transformations:
            raise ValueError("contact needs a blocked vector Lagrange space with one component per space dimension")
        self.cell = mesh.basix_cell()
        self.gdim = mesh.geometry.dim
        self.tdim = mesh.topology.dim
        cmap = mesh.geometry.cmaps[0]
        self.coord_element = basix.create_element(
            basix.ElementFamily.P, self.cell, cmap.degree, basix.LagrangeVariant(cmap.variant)
        )
        self.element = V.element.basix_element
        self.origin, self.axes, self.facet_cell = _facet_maps(self.cell)
        nlf = len(self.origin)
        clayout = cmap.create_dof_layout()
        vlayout = V.dofmap.dof_layout
        self.coord_closure = np.array([clayout.entity_closure_dofs(self.tdim - 1, i) for i in range(nlf)])
        self.closure = np.array([vlayout.entity_closure_dofs(self.tdim - 1, i) for i in range(nlf)])

    def reference_points(self, lf: npt.NDArray, s: npt.NDArray) -> npt.NDArray:
        """Reference-cell coordinates of facet points (lf[i], s[i])."""
        return self.origin[lf] + np.einsum("pij,pj->pi", self.axes[lf], s)

    def tabulate(self, element: basix.finite_element.FiniteElement, X: npt.NDArray, nderiv: int):
        """Values and reference gradients of all cell basis functions, shape (1+tdim, npts, ndofs)."""
        if len(X) == 0:  # a rank without points: basix built with assertions (Debian) aborts on none
            return np.zeros((1 + self.tdim if nderiv else 1, 0, element.dim))
        tab = element.tabulate(nderiv, X)[..., 0]
        return tab[: 1 + self.tdim] if nderiv else tab


def _facets_with_cells(mesh: dolfinx.mesh.Mesh, facet_tags: dolfinx.mesh.MeshTags, tag: int):
    """Owned facets with the tag, their cells and local facet indices."""
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    mesh.topology.create_connectivity(tdim, tdim - 1)
    facets = facet_tags.find(tag)
    facets = np.sort(facets[facets < mesh.topology.index_map(tdim - 1).size_local])
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    c2f = mesh.topology.connectivity(tdim, tdim - 1)
    cells = f2c.array[f2c.offsets[facets]]
    nfpc = c2f.offsets[1] - c2f.offsets[0]
    c2f_table = c2f.array.reshape(-1, nfpc)
    local_facet = np.argmax(c2f_table[cells] == facets[:, None], axis=1).astype(np.int32)
    return facets, cells, local_facet


def _check_tag(comm: MPI.Comm, count: int, tag: int, what: str) -> None:
    if comm.allreduce(count, op=MPI.SUM) == 0:
        raise ValueError(f"{what} facet tag {tag} marks no exterior facet of the mesh")


def _gather(comm: MPI.Comm, a: npt.NDArray) -> npt.NDArray:
    return np.concatenate(comm.allgather(np.ascontiguousarray(a)))


class MasterSurface:
    """The master facets, gathered on every rank (reference geometry, dofs, outward orientation)."""

    def __init__(self, V: dolfinx.fem.FunctionSpace, facet_tags: dolfinx.mesh.MeshTags, tag: int):
        mesh = V.mesh
        comm = mesh.comm
        self.elements = el = _CellElements(V)
        facets, cells, lf = _facets_with_cells(mesh, facet_tags, tag)
        _check_tag(comm, len(facets), tag, "master")
        rows = np.arange(len(cells))[:, None]
        gnodes = mesh.geometry.dofmaps[0][cells]
        x = mesh.geometry.x[:, : el.gdim]
        coords = x[gnodes[rows, el.coord_closure[lf]]]
        # Orientation: sign that turns d(y)/ds0 x d(y)/ds1 into the outward normal, fixed in the
        # reference configuration (small strains cannot flip a facet).
        Xc = el.reference_points(lf, np.full((len(lf), 2), 0.5 if el.facet_cell == basix.CellType.quadrilateral else 1 / 3))
        dN = el.tabulate(el.coord_element, Xc, 1)[1:]
        J = np.einsum("dpn,pni->pid", dN, x[gnodes])
        t = np.einsum("pid,pdk->pik", J, el.axes[lf])
        normal = np.cross(t[:, :, 0], t[:, :, 1])
        outward = coords.mean(axis=1) - x[gnodes].mean(axis=1)
        orientation = np.sign(np.einsum("pi,pi->p", normal, outward))
        self._nodes = V.dofmap.list[cells][rows, el.closure[lf]]  # local block indices (nf, ncl)
        imap = V.dofmap.index_map
        blocks = imap.local_to_global(self._nodes.ravel()).reshape(self._nodes.shape)
        self.comm = comm
        self.coords = _gather(comm, coords)  #: reference node coordinates (nF, ncg, gdim) [m]
        self.local_facet = _gather(comm, lf)  #: local facet index of each gathered facet
        self.blocks = _gather(comm, blocks.astype(np.int64))  #: global block (node) indices (nF, ncl)
        self.orientation = _gather(comm, orientation)
        self.num_local = len(facets)

    @property
    def num_facets(self) -> int:
        return len(self.local_facet)

    def displacement(self, u: dolfinx.fem.Function) -> npt.NDArray:
        """Gathered nodal displacements of all master facets, shape (nF, ncl, gdim) [m]."""
        values = u.x.array.reshape(-1, self.elements.gdim)[self._nodes]
        return _gather(self.comm, values)

    def evaluate(self, facet: npt.NDArray, s: npt.NDArray, disp: npt.NDArray):
        """Deformed position y, tangents dy/ds (npts, gdim, 2) and displacement basis values at (facet, s)."""
        el = self.elements
        lf = self.local_facet[facet]
        X = el.reference_points(lf, s)
        rows = np.arange(len(facet))[:, None]
        cg = el.tabulate(el.coord_element, X, 1)[:, rows, el.coord_closure[lf]]
        cv = el.tabulate(el.element, X, 1)[:, rows, el.closure[lf]]
        y = _combine(cg[0], self.coords[facet]) + _combine(cv[0], disp[facet])
        dydX = _gradient(cg[1:], self.coords[facet]) + _gradient(cv[1:], disp[facet])
        dyds = dydX @ el.axes[lf]
        return y, dyds, cv[0]

    def centroids(self, disp: npt.NDArray) -> npt.NDArray:
        """Approximate deformed facet centres (mean of closure nodes) [m]."""
        return self.coords.mean(axis=1) + disp.mean(axis=1)

    def sizes(self) -> npt.NDArray:
        """Facet sizes (largest node distance from the centre) [m], used as search scales."""
        c = self.coords.mean(axis=1)
        return np.linalg.norm(self.coords - c[:, None, :], axis=2).max(axis=1)


class SlaveQuadrature:
    """Quadrature points on the owned slave facets with the slave cells' basis data.

    All quantities are in the reference (undeformed) configuration (small strains):
    ``points`` (np, gdim) [m], ``weights`` (np,) surface quadrature weights [m^2],
    ``values`` (np, ndofs) basis values, ``gradients`` (np, ndofs, gdim) physical basis
    gradients [1/m], ``dofs`` (np, ndofs) local block indices of the slave cell,
    ``h`` (np,) cell height normal to the facet, cell volume / facet area [m].
    """

    def __init__(self, V: dolfinx.fem.FunctionSpace, facet_tags: dolfinx.mesh.MeshTags, tag: int, degree: int):
        mesh = V.mesh
        el = _CellElements(V)
        facets, cells, lf = _facets_with_cells(mesh, facet_tags, tag)
        _check_tag(mesh.comm, len(facets), tag, "slave")
        s_q, w_q = basix.make_quadrature(el.facet_cell, degree)
        nq = len(w_q)
        nf = len(facets)
        lf_p = np.repeat(lf, nq)
        cells_p = np.repeat(cells, nq)
        X = el.reference_points(lf_p, np.tile(s_q, (nf, 1)))
        x = mesh.geometry.x[:, : el.gdim]
        xg = x[mesh.geometry.dofmaps[0][cells_p]]  # (np, ncg, gdim)
        cg = el.tabulate(el.coord_element, X, 1)
        J = np.einsum("dpn,pni->pid", cg[1:], xg)
        Jinv = np.linalg.inv(J)
        cv = el.tabulate(el.element, X, 1)
        t = np.einsum("pid,pdk->pik", J, el.axes[lf_p])
        da = np.linalg.norm(np.cross(t[:, :, 0], t[:, :, 1]), axis=1)
        self.points = np.einsum("pn,pni->pi", cg[0], xg)
        self.weights = np.tile(w_q, nf) * da
        self.values = cv[0]
        self.gradients = np.einsum("dpn,pdi->pni", cv[1:], Jinv)
        self.dofs = V.dofmap.list[cells_p]
        # Cell height normal to the facet: cell volume / facet area (stable for thin cells).
        X_c, w_c = basix.make_quadrature(el.cell, 2 * el.coord_element.degree)
        dN_c = el.tabulate(el.coord_element, X_c, 1)[1:]
        Jc = np.einsum("dqn,cni->cqid", dN_c, x[mesh.geometry.dofmaps[0][cells]])
        volume = np.abs(np.linalg.det(Jc)) @ w_c
        area = self.weights.reshape(nf, nq).sum(axis=1)
        self.h = np.repeat(volume / area, nq)
        self.num_points = nf * nq
        self.points_per_facet = nq
        self.gdim = el.gdim

    def displacement(self, u: dolfinx.fem.Function) -> npt.NDArray:
        """Displacement at the slave points, shape (np, gdim) [m]."""
        values = u.x.array.reshape(-1, self.gdim)[self.dofs]
        return _combine(self.values, values)


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


def pair(
    x: npt.NDArray,
    master: MasterSurface,
    disp: npt.NDArray,
    candidates: int = 4,
    search_radius: float | None = None,
    max_iterations: int = 30,
    tol: float = 1e-14,
    previous: npt.NDArray | None = None,
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
    the choice (and the normal) between Newton iterations.
    """
    el = master.elements
    npts = len(x)
    sizes = master.sizes()
    radius = float(sizes.max()) if search_radius is None else search_radius
    k = min(candidates, master.num_facets)
    if npts == 0:
        return Pairing(
            np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros((0, el.gdim)), np.zeros((0, el.gdim)),
            np.zeros(0), np.zeros((0, el.closure.shape[1])),
        )
    _, cand = cKDTree(master.centroids(disp)).query(x, k=k)
    cand = cand.reshape(npts, k).ravel()
    xp = np.repeat(x, k, axis=0)
    centre = 0.5 if el.facet_cell == basix.CellType.quadrilateral else 1 / 3
    s = np.full((len(cand), 2), centre)
    moving = np.arange(len(cand))
    for _ in range(max_iterations):
        y, dyds, _ = master.evaluate(cand[moving], s[moving], disp)
        r = xp[moving] - y
        dydsT = dyds.transpose(0, 2, 1)
        step = np.linalg.solve(dydsT @ dyds, dydsT @ r[:, :, None])[..., 0]
        s_new = _clip_to_facet(s[moving] + step, el.facet_cell)
        change = np.abs(s_new - s[moving]).max(axis=1)
        s[moving] = s_new
        moving = moving[change >= tol]
        if moving.size == 0:
            break
    y, dyds, _ = master.evaluate(cand, s, disp)
    dist = np.linalg.norm(xp - y, axis=1).reshape(npts, k)
    best = np.argmin(dist, axis=1)
    if previous is not None:
        cand_2d = cand.reshape(npts, k)
        match = cand_2d == previous[:, None]
        keep = match.any(axis=1)
        j = np.argmax(match, axis=1)
        rows = np.arange(npts)
        close = dist[rows, j] <= dist[rows, best] + 1e-6 * sizes[cand_2d[rows, j]]
        best = np.where(keep & close, j, best)
    pick = np.arange(npts) * k + best
    facet, s = cand[pick], s[pick]
    y, dyds, values = master.evaluate(facet, s, disp)
    normal = np.cross(dyds[:, :, 0], dyds[:, :, 1])
    normal *= (master.orientation[facet] / np.linalg.norm(normal, axis=1))[:, None]
    r = x - y
    gap = np.einsum("pi,pi->p", r, normal)
    tangential = np.linalg.norm(r - gap[:, None] * normal, axis=1)
    beyond_edge = tangential > np.maximum(0.5 * np.abs(gap), 1e-6 * sizes[facet])
    unpaired = beyond_edge | (np.linalg.norm(r, axis=1) > radius)
    facet = np.where(unpaired, -1, facet)
    return Pairing(facet, s, y, normal, gap, values)
