"""Dense arrays kept from call to call, and their transposed copies. A fresh array of tens of MB
costs a page fault per 4 kB page at its first touch, on every call; the inner problem and the
compliance blocks of Newton on the contact points (``solver.dynamics.traction_jacobian``,
``solver.dynamics.compliance``) reuse their memory instead."""

import numpy as np
import numpy.typing as npt

__all__ = ["GrowingMatrix", "Workspace", "transpose"]

#: an array that must grow takes this much more room than asked for
ROOM = 1.25


def transpose(a: npt.NDArray, out: npt.NDArray | None = None, rows: int = 128) -> npt.NDArray:
    """a^T copied into ``out`` (a new C-order array where not given), ``rows`` rows of a at a
    time. numpy copies a transposed array element by element in the order of the copy, reading
    a from a new page at each element: the compliance's 3648 x 4536 products took 0.7 s so, and
    0.03 s in blocks of 128 rows."""
    if out is None:
        out = np.empty(a.shape[::-1], dtype=a.dtype)
    for start in range(0, a.shape[0], rows):
        out[:, start : start + rows] = a[start : start + rows].T
    return out


class Workspace:
    """Arrays by name, each in the memory of the last one of its name where it fits."""

    def __init__(self):
        self._arrays: dict[str, npt.NDArray] = {}

    def get(self, name: str, shape: tuple[int, ...], dtype: type = np.float64) -> npt.NDArray:
        """An uninitialised C-order array of this shape."""
        size = int(np.prod(shape))
        kept = self._arrays.get(name)
        if kept is None or kept.size < size or kept.dtype != dtype:
            kept = self._arrays[name] = np.empty(int(ROOM * size), dtype=dtype)
        return kept[:size].reshape(shape)


class GrowingMatrix:
    """A dense matrix that grows by rows and columns at its end, in a larger array (its rows
    strided by that array's width) that is replaced only when the matrix outgrows it."""

    def __init__(self):
        self._room = np.zeros((0, 0))
        self.array = self._room  #: the matrix: a view of the top-left corner of the room

    def set(self, matrix: npt.NDArray) -> None:
        """Replace the matrix (e.g. by its rows and columns kept)."""
        self._room = self.array = np.ascontiguousarray(matrix)

    def grow(self, rows: int, cols: int) -> npt.NDArray:
        """The matrix with ``rows`` x ``cols`` entries, its earlier entries kept in the top-left
        corner, the new ones zero."""
        old_rows, old_cols = self.array.shape
        if rows < old_rows or cols < old_cols:
            raise ValueError(f"a {old_rows} x {old_cols} matrix cannot grow to {rows} x {cols}")
        if rows > self._room.shape[0] or cols > self._room.shape[1]:
            room = np.empty((max(int(ROOM * rows), rows), max(int(ROOM * cols), cols)))
            room[:old_rows, :old_cols] = self.array
            self._room = room
        self.array = self._room[:rows, :cols]
        self.array[old_rows:, :] = 0.0
        self.array[:old_rows, old_cols:] = 0.0
        return self.array
