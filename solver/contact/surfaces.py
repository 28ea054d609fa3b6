"""Master and slave contact surfaces of a mesh: facet elements, closures, quadrature points.

The slave surface is sampled at quadrature points of its (owned) facets, with the basis
values and gradients of the slave cells there (:class:`SlaveQuadrature`); each rank keeps
its own slave points. The master surface is small compared with the volume, so its facets
(reference node coordinates, displacement dofs, outward orientation) are gathered onto
every rank (:class:`MasterSurface`), where ``solver.contact.pairing`` projects the slave
points onto it. On a facet, the cell basis functions of the facet's closure dofs are
evaluated through the (cheaper) facet Lagrange element of the same degree.

Conventions: coordinates and displacements in m, quantities in the reference
(undeformed) configuration unless named deformed.
"""

from mpi4py import MPI

import basix
import numpy as np
import numpy.typing as npt

import dolfinx

__all__ = ["MasterSurface", "SlaveQuadrature", "clip_to_facet"]


def _facet_maps(cell: basix.CellType) -> tuple[npt.NDArray, npt.NDArray, basix.CellType]:
    """Affine maps X = origin[lf] + axes[lf] @ s from reference facet lf to the reference cell."""
    geom = basix.geometry(cell)
    facets = basix.topology(cell)[-2]
    origin = np.array([geom[f[0]] for f in facets])
    axes = np.array(
        [np.column_stack([geom[f[1]] - geom[f[0]], geom[f[2]] - geom[f[0]]]) for f in facets]
    )
    facet_cell = basix.CellType.quadrilateral if len(facets[0]) == 4 else basix.CellType.triangle
    return origin, axes, facet_cell


def _combine(N: npt.NDArray, X: npt.NDArray) -> npt.NDArray:
    """sum_n N[p, n] X[p, n, i] (batched matrix product)."""
    return (N[:, None, :] @ X)[:, 0, :]


def _gradient(dN: npt.NDArray, X: npt.NDArray) -> npt.NDArray:
    """sum_n dN[d, p, n] X[p, n, i] -> [p, i, d] (batched matrix product)."""
    return (dN.transpose(1, 0, 2) @ X).transpose(0, 2, 1)


def clip_to_facet(s: npt.NDArray, facet_cell: basix.CellType) -> npt.NDArray:
    """Clip reference facet coordinates into the unit square / unit triangle."""
    s = np.clip(s, 0.0, 1.0)
    if facet_cell == basix.CellType.triangle:
        total = s.sum(axis=1)
        over = total > 1.0
        s[over] /= total[over, None]
    return s


def _box_data(
    element: basix.finite_element.FiniteElement,
) -> tuple[npt.NDArray, npt.NDArray, float]:
    """(vertex dofs, (bi)linear vertex interpolation at the nodes (nodes, vertices),
    Lebesgue constant max_s sum_j |N_j(s)| sampled on a fine grid with a 5 % margin)."""
    vertices = np.array([dofs[0] for dofs in element.entity_dofs[0]])
    linear = basix.create_element(basix.ElementFamily.P, element.cell_type, 1)
    interpolation = np.asarray(linear.tabulate(0, element.points))[0, :, :, 0]
    t = np.linspace(0.0, 1.0, 101)
    s = np.array(
        [
            (a, b)
            for a in t
            for b in t
            if element.cell_type == basix.CellType.quadrilateral or a + b <= 1
        ]
    )
    tabulated = np.asarray(element.tabulate(0, s))[0, :, :, 0]
    lebesgue = 1.05 * float(np.abs(tabulated).sum(axis=1).max())
    return vertices, interpolation, lebesgue


class _CellElements:
    """Scalar coordinate and displacement elements of a single-cell-type mesh, per-facet closures.

    On a facet, the cell basis functions of the facet's closure dofs restrict to the
    facet Lagrange element of the same degree and variant: N_closure(s) = R[lf] N_facet(s)
    with R[lf][i, j] = N_closure_i(s_j) at the facet element's points s_j. Facet points are
    therefore evaluated with the (cheaper) facet element.
    """

    def __init__(self, V: dolfinx.fem.FunctionSpace):
        mesh = V.mesh
        if len(mesh.topology.entity_types[-1]) != 1:
            raise ValueError("contact needs a mesh with a single cell type")
        if V.dofmap.bs != mesh.geometry.dim or V.element.needs_dof_transformations:
            raise ValueError(
                "contact needs a blocked vector Lagrange space with one component per space dimension"
            )
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
        self.coord_closure = np.array(
            [clayout.entity_closure_dofs(self.tdim - 1, i) for i in range(nlf)]
        )
        self.closure = np.array([vlayout.entity_closure_dofs(self.tdim - 1, i) for i in range(nlf)])
        self.facet_coord_element, self.coord_restriction = self._restriction(
            self.coord_element, self.coord_closure
        )
        self.facet_element, self.restriction = self._restriction(self.element, self.closure)
        same = (self.element.family, self.element.degree, self.element.lagrange_variant) == (
            self.coord_element.family,
            self.coord_element.degree,
            self.coord_element.lagrange_variant,
        )
        if same:  # one tabulation serves both
            self.facet_element = self.facet_coord_element
        self.coord_box = _box_data(self.facet_coord_element)  # for MasterSurface.distance_bound
        self.box = _box_data(self.facet_element)

    def _restriction(self, element, closure: npt.NDArray):
        """Facet element of ``element`` and the maps R[lf] (ncl, nfacet_dofs) onto the closure dofs."""
        facet = basix.create_element(
            element.family, self.facet_cell, element.degree, element.lagrange_variant
        )
        nlf = len(self.origin)
        s = facet.points
        R = np.array(
            [
                self.tabulate(element, self.reference_points(np.full(len(s), lf), s), 0)[0][
                    :, closure[lf]
                ].T
                for lf in range(nlf)
            ]
        )
        # check at points off the facet element's nodes that the restriction is exact
        s_check = np.array([[0.21, 0.13], [0.37, 0.52], [0.11, 0.71]])
        N_facet = facet.tabulate(0, s_check)[0, :, :, 0]
        for lf in range(nlf):
            N_cell = self.tabulate(
                element, self.reference_points(np.full(len(s_check), lf), s_check), 0
            )[0]
            if not np.allclose(N_cell[:, closure[lf]], N_facet @ R[lf].T, atol=1e-12):
                raise ValueError(
                    "contact needs Lagrange elements whose facet traces are facet Lagrange elements"
                )
        return facet, R

    def reference_points(self, lf: npt.NDArray, s: npt.NDArray) -> npt.NDArray:
        """Reference-cell coordinates of facet points (lf[i], s[i])."""
        return self.origin[lf] + np.einsum("pij,pj->pi", self.axes[lf], s)

    def tabulate(self, element: basix.finite_element.FiniteElement, X: npt.NDArray, nderiv: int):
        """Values and reference gradients of all cell basis functions, shape (1+tdim, npts, ndofs)."""
        if (
            len(X) == 0
        ):  # a rank without points: basix built with assertions (Debian) aborts on none
            return np.zeros((1 + self.tdim if nderiv else 1, 0, element.dim))
        tab = element.tabulate(nderiv, X)[..., 0]
        return tab[: 1 + self.tdim] if nderiv else tab

    def tabulate_facet(
        self, element: basix.finite_element.FiniteElement, s: npt.NDArray
    ) -> npt.NDArray:
        """Values and s-derivatives of a facet element's basis at facet points s, shape (3, npts, ndofs)."""
        if len(s) == 0:
            return np.zeros((3, 0, element.dim))
        return element.tabulate(1, s)[..., 0]


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
        self.cells = cells  #: local cells of this rank's master facets
        rows = np.arange(len(cells))[:, None]
        gnodes = mesh.geometry.dofmaps[0][cells]
        x = mesh.geometry.x[:, : el.gdim]
        coords = x[gnodes[rows, el.coord_closure[lf]]]
        # Orientation: sign that turns d(y)/ds0 x d(y)/ds1 into the outward normal, fixed in the
        # reference configuration (small strains cannot flip a facet).
        Xc = el.reference_points(
            lf,
            np.full((len(lf), 2), 0.5 if el.facet_cell == basix.CellType.quadrilateral else 1 / 3),
        )
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
        self.blocks = _gather(
            comm, blocks.astype(np.int64)
        )  #: global block (node) indices (nF, ncl)
        self.orientation = _gather(comm, orientation)
        #: deformation-free positions at the facet element's nodes (nF, nfc, gdim) [m]
        self.facet_coords = np.einsum(
            "fij,fid->fjd", el.coord_restriction[self.local_facet], self.coords
        )
        self.sizes = (
            self._sizes()
        )  #: facet sizes (largest node distance from the centre) [m], search scales
        centre = np.full(
            (self.num_facets, 2), 0.5 if el.facet_cell == basix.CellType.quadrilateral else 1 / 3
        )
        dN = el.tabulate_facet(el.facet_coord_element, centre)[1:]
        t = _gradient(dN, self.facet_coords)  # (nF, gdim, 2)
        t1 = t[:, :, 0] / np.linalg.norm(t[:, :, 0], axis=1)[:, None]
        nrm = np.cross(t[:, :, 0], t[:, :, 1])
        nrm /= np.linalg.norm(nrm, axis=1)[:, None]
        self.frames = np.stack(
            [t1, np.cross(nrm, t1), nrm], axis=1
        )  #: facet frames (nF, 3, 3), rows unit vectors
        self._reference_boxes = self._box(
            self.facet_coords, np.arange(self.num_facets), *el.coord_box
        )

    @property
    def num_facets(self) -> int:
        return len(self.local_facet)

    def displacement(self, u: dolfinx.fem.Function) -> npt.NDArray:
        """Gathered nodal displacements of all master facets, shape (nF, ncl, gdim) [m]."""
        values = u.x.array.reshape(-1, self.elements.gdim)[self._nodes]
        return _gather(self.comm, values)

    def facet_displacement(self, disp: npt.NDArray) -> npt.NDArray:
        """Displacement (nF, ncl, gdim) at the nodes of the facet element, shape (nF, nf, gdim) [m]."""
        return np.einsum("fij,fid->fjd", self.elements.restriction[self.local_facet], disp)

    def evaluate(self, facet: npt.NDArray, s: npt.NDArray, facet_disp: npt.NDArray):
        """Deformed position y, tangents dy/ds (npts, gdim, 2) and displacement basis values (closure
        dofs) at (facet, s); ``facet_disp`` from ``facet_displacement``."""
        el = self.elements
        cg = el.tabulate_facet(el.facet_coord_element, s)
        cv = (
            cg
            if el.facet_element is el.facet_coord_element
            else el.tabulate_facet(el.facet_element, s)
        )
        y = _combine(cg[0], self.facet_coords[facet]) + _combine(cv[0], facet_disp[facet])
        dyds = _gradient(cg[1:], self.facet_coords[facet]) + _gradient(cv[1:], facet_disp[facet])
        return y, dyds, cv[0]

    def closure_values(self, facet: npt.NDArray, facet_values: npt.NDArray) -> npt.NDArray:
        """Facet-element basis values (npts, nf) as values of the cell's closure basis (npts, ncl)."""
        return (self.elements.restriction[self.local_facet[facet]] @ facet_values[:, :, None])[
            :, :, 0
        ]

    def distance_bound(
        self, x: npt.NDArray, facet: npt.NDArray, facet_disp: npt.NDArray
    ) -> npt.NDArray:
        """Lower bound of the distance [m] from points x (n, gdim) to the deformed facets ``facet`` (n,).

        In each facet's frame (tangents and normal at its reference centre) a coordinate of a
        point of the facet is c(s) = l(s) + sum_j N_j(s) e_j, with l the (bi)linear interpolant
        of the vertex values (between their min and max) and e_j = c_j - l(s_j) at the nodes
        (|sum_j N_j e_j| <= Lambda max |e_j|, Lambda the Lebesgue constant of the facet
        element): the facet lies in that oriented box, and the distance to the box is the bound.
        """
        used, row = np.unique(facet, return_inverse=True)  # boxes once per facet, not per point
        hi_X, lo_X = (b[used][row] for b in self._reference_boxes)
        hi_d, lo_d = (b[row] for b in self._box(facet_disp, used, *self.elements.box))
        local = (self.frames[facet] @ x[:, :, None])[:, :, 0]
        excess = np.maximum(np.maximum(local - hi_X - hi_d, lo_X + lo_d - local), 0.0)
        return (1 - 1e-9) * np.linalg.norm(excess, axis=1)

    def _box(
        self,
        nodal: npt.NDArray,
        facet: npt.NDArray,
        vertices: npt.NDArray,
        linear: npt.NDArray,
        lebesgue: float,
    ) -> tuple[npt.NDArray, npt.NDArray]:
        """Upper and lower bounds (n, 3) of the facets' nodal fields ``nodal`` (nF, nodes, 3) along
        the rows of their frames (``distance_bound``)."""
        local = self.frames[facet] @ nodal[facet].transpose(0, 2, 1)  # (n, 3, nodes)
        corners = local[:, :, vertices]
        bulge = lebesgue * np.abs(local - corners @ linear.T).max(axis=2)
        return corners.max(axis=2) + bulge, corners.min(axis=2) - bulge

    def centroids(self, disp: npt.NDArray) -> npt.NDArray:
        """Approximate deformed facet centres (mean of closure nodes) [m]."""
        return self.coords.mean(axis=1) + disp.mean(axis=1)

    def _sizes(self) -> npt.NDArray:
        c = self.coords.mean(axis=1)
        return np.linalg.norm(self.coords - c[:, None, :], axis=2).max(axis=1)


class SlaveQuadrature:
    """Quadrature points on the owned slave facets with the slave cells' basis data.

    All quantities are in the reference (undeformed) configuration (small strains):
    ``points`` (np, gdim) [m], ``weights`` (np,) surface quadrature weights [m^2],
    ``values`` (np, ndofs) basis values, ``gradients`` (np, ndofs, gdim) physical basis
    gradients [1/m], ``dofs`` (np, ndofs) local block indices of the slave cell,
    ``h`` (np,) cell height normal to the facet, cell volume / facet area [m];
    ``cells`` the local cells of the slave facets.
    """

    def __init__(
        self, V: dolfinx.fem.FunctionSpace, facet_tags: dolfinx.mesh.MeshTags, tag: int, degree: int
    ):
        mesh = V.mesh
        el = _CellElements(V)
        facets, cells, lf = _facets_with_cells(mesh, facet_tags, tag)
        _check_tag(mesh.comm, len(facets), tag, "slave")
        self.cells = cells
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
