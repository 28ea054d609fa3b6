"""The benchmark of the inner problem's factorisation on the ranks of a node
(benchmarks/node_factors.py): bad input is refused with ``error:``, a small run prints both
ways' times."""

import pytest
from mpi4py import MPI

from benchmarks.node_factors import main

pytestmark = pytest.mark.mpi


def test_bad_input_is_refused(capsys):
    assert main(["--rows", "0"]) == 2
    assert "error:" in capsys.readouterr().err


def test_a_small_run_prints_both_ways(capsys):
    assert main(["--rows", "40", "--repeats", "1", "--rounds", "1"]) == 0
    out = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:
        assert "every rank alike" in out and "once per node" in out
