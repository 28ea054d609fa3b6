"""Points in a distributed mesh: unique owning cell, basis values, point evaluation.

Every rank passes the same points; each point is assigned to exactly one rank
(the owner found by ``dolfinx.geometry.determine_point_ownership``), so sums over
ranks count each point once. Coordinates in m.
"""

import numpy as np
import numpy.typing as npt
from mpi4py import MPI

import basix
import dolfinx
from dolfinx import fem


class PointLocator:
    """Owning rank, cell and reference coordinates of a fixed set of points.

    ``cells`` (local indices) restricts the search, e.g. to one body of a mesh with two:
    the search tests convex hulls of the cells' nodes, which for curved cells reach
    beyond the cell and may claim points of a body close by.
    """

    def __init__(
        self,
        mesh: dolfinx.mesh.Mesh,
        points: npt.ArrayLike,
        padding: float = 1e-8,
        cells: npt.NDArray[np.int32] | None = None,
    ):
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        self.mesh = mesh
        self.num_points = points.shape[0]
        comm = mesh.comm
        sent = (
            points[:, : mesh.geometry.dim] if comm.rank == 0 else np.zeros((0, mesh.geometry.dim))
        )
        data = dolfinx.geometry.determine_point_ownership(
            mesh, np.ascontiguousarray(sent), padding, cells
        )
        found = comm.bcast(data.src_owner if comm.rank == 0 else None, root=0)
        if np.any(np.asarray(found) < 0):
            missing = points[np.asarray(found) < 0]
            raise ValueError(f"points outside the mesh: {missing.tolist()}")
        dest = np.asarray(data.dest_points).reshape(-1, 3)
        # index of each received point in the common list (all ranks know `points`)
        dist = (
            np.linalg.norm(dest[:, None, :] - points[None, :, :], axis=2)
            if len(dest)
            else np.zeros((0, 0))
        )
        self.local_index = (
            np.argmin(dist, axis=1).astype(np.int32) if len(dest) else np.zeros(0, np.int32)
        )
        self.cells = np.asarray(data.dest_cells, dtype=np.int32)
        self.points = dest
        cmap = mesh.geometry.cmaps[0]
        x_dofs = mesh.geometry.dofmaps[0]
        self.reference = np.array(
            [
                cmap.pull_back(p[None, :], mesh.geometry.x[x_dofs[c]])[0]
                for p, c in zip(dest, self.cells)
            ]
        ).reshape(-1, mesh.topology.dim)

    def gather(self, local_values: np.ndarray) -> np.ndarray:
        """Values of the owned points -> array over all points on every rank (sum over ranks)."""
        shape = (self.num_points,) + local_values.shape[1:]
        out = np.zeros(shape)
        out[self.local_index] = local_values
        return self.mesh.comm.allreduce(out, op=MPI.SUM)

    def basis_values(self, V: fem.FunctionSpace) -> np.ndarray:
        """Scalar basis functions of V's cells at the owned points, shape (num_owned, dofs_per_cell)."""
        element = V.element.basix_element
        if element.family != basix.ElementFamily.P:
            raise ValueError("point basis values need a Lagrange space")
        if len(self.cells) == 0:
            return np.zeros((0, element.dim))
        return np.array([element.tabulate(0, X[None, :])[0, 0, :, 0] for X in self.reference])


class PointProbe:
    """Values of a Function at fixed points, identical on every rank."""

    def __init__(
        self, u: fem.Function, points: npt.ArrayLike, cells: npt.NDArray[np.int32] | None = None
    ):
        self.u = u
        self.locator = PointLocator(u.function_space.mesh, points, cells=cells)

    def __call__(self) -> np.ndarray:
        """u at the points, shape (num_points, value_size)."""
        loc = self.locator
        size = int(np.prod(self.u.function_space.value_shape)) or 1
        local = (
            self.u.eval(loc.points, loc.cells).reshape(-1, size)
            if len(loc.cells)
            else np.zeros((0, size))
        )
        return loc.gather(local)
