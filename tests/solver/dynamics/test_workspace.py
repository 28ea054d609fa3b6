"""Kept arrays (``solver.dynamics.workspace``) and shares of a product among the ranks
(``solver.dynamics.shares``): a growing matrix keeps its entries and zeroes the new ones, within
its room and beyond it; a workspace array of a name reuses its memory while it fits; the blocked
transposed copy equals a^T, into a new array and into a strided part of another; the shares
of n entries cover them once, and gathered they give the whole product (or the rows of a matrix)
on every rank (serially and on 2 ranks)."""

import numpy as np
import pytest
from mpi4py import MPI

from solver.dynamics.shares import Shares
from solver.dynamics.workspace import GrowingMatrix, Workspace, transpose

pytestmark = pytest.mark.mpi


def test_growing_matrix_keeps_its_entries():
    rng = np.random.default_rng(5)
    matrix = GrowingMatrix()
    expected = np.zeros((0, 0))
    for rows, cols in [(3, 4), (5, 4), (5, 6), (40, 41), (41, 41)]:  # within room and beyond
        grown = matrix.grow(rows, cols)
        old_rows, old_cols = expected.shape
        assert np.array_equal(grown[:old_rows, :old_cols], expected)
        assert not grown[old_rows:].any() and not grown[:, old_cols:].any()
        grown[:] = rng.normal(size=grown.shape)
        expected = grown.copy()
    assert np.array_equal(matrix.array, expected)
    matrix.set(expected[::2, ::3])
    assert np.array_equal(matrix.array, expected[::2, ::3])
    with pytest.raises(ValueError, match="cannot grow"):
        matrix.grow(1, 1)


def test_workspace_reuses_its_memory():
    work = Workspace()
    first = work.get("a", (10, 10))
    smaller = work.get("a", (4, 5))
    assert np.shares_memory(first, smaller) and smaller.shape == (4, 5)
    assert not np.shares_memory(work.get("b", (4, 5)), first)
    assert work.get("a", (4, 5), np.float32).dtype == np.float32


@pytest.mark.parametrize("shape", [(0, 3), (1, 1), (127, 5), (300, 257)])
def test_transpose_copies_the_transposed_array(shape):
    a = np.random.default_rng(6).normal(size=shape)
    copy = transpose(a)
    assert copy.flags.c_contiguous and np.array_equal(copy, a.T)
    room = np.zeros((shape[1] + 2, shape[0] + 3))
    transpose(a.astype(np.float32), out=room[1:-1, 2:-1])  # a block of a larger matrix
    assert np.array_equal(room[1:-1, 2:-1], a.T.astype(np.float32))
    room[1:-1, 2:-1] = 0.0
    assert not room.any()  # nothing written outside the block


@pytest.mark.parametrize("n", [0, 1, 7, 100])
def test_shares_cover_the_entries_once(n):
    comm = MPI.COMM_WORLD
    shares = Shares(comm, n)
    sizes = comm.allgather(shares.stop - shares.start)
    assert sum(sizes) == n and shares.bounds[0] == 0 and shares.bounds[-1] == n
    G = np.arange(n * n, dtype=float).reshape(n, n)  # the same on every rank
    v = np.linspace(-1.0, 1.0, n)
    product = shares.gather(G[shares.part] @ v)
    assert np.allclose(product, G @ v, rtol=1e-14)
    assert np.array_equal(shares.gather(G[shares.part]), G)
    assert np.array_equal(shares.gather(G[shares.part, None, :]), G[:, None, :])
