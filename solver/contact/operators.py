"""Pointwise operators of the contact terms on the dofs of a point's slave cell (and paired
master facet): arrays over points q, with the vector dofs unrolled as (node a, component c)
-> gdim a + c, the layout of ``NitscheContact``'s point blocks."""

import numpy as np
import numpy.typing as npt

from common.material import Material

__all__ = ["traction_operator", "unrolled_dofs", "vector_basis"]


def traction_operator(
    material: Material, normal: npt.NDArray, gradients: npt.NDArray
) -> npt.NDArray:
    """Slave traction T[q, i, (a, c)] = (sigma(phi_a e_c) n)_i from the unit normals n (q, gdim)
    and the shape-function gradients (q, nodes, gdim) [1/m]; shape (q, gdim, gdim nodes) [Pa m]."""
    gdim = normal.shape[1]
    gn = gradients @ normal[:, :, None]  # (q, nodes, 1)
    T = material.mu * (
        gn[:, None, :, :] * np.eye(gdim)[None, :, None, :]
        + gradients.transpose(0, 2, 1)[:, :, :, None] * normal[:, None, None, :]
    )
    T += material.lmbda * normal[:, :, None, None] * gradients[:, None, :, :]
    return T.reshape(len(normal), gdim, gdim * gradients.shape[1])


def vector_basis(values: npt.NDArray, gdim: int) -> npt.NDArray:
    """The vector field sum_a values[q, a] v_(a, c) e_c as an operator on the unrolled dofs:
    shape (q, gdim, gdim nodes), from the scalar basis values (q, nodes)."""
    q, nodes = values.shape
    return (values[:, None, :, None] * np.eye(gdim)[None, :, None, :]).reshape(
        q, gdim, gdim * nodes
    )


def unrolled_dofs(blocks: npt.NDArray, gdim: int) -> npt.NDArray:
    """Global dof indices (q, gdim nodes) of the node blocks (q, nodes)."""
    q, nodes = blocks.shape
    return (blocks[:, :, None] * gdim + np.arange(gdim)).reshape(q, gdim * nodes)
