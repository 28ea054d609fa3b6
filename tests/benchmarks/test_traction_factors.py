"""The benchmark of the inner problem's factors (benchmarks/traction_factors.py): bad input is
refused with ``error:``, a small run prints both ways' times and rows."""

import pytest
from mpi4py import MPI

from benchmarks.traction_factors import main

pytestmark = pytest.mark.mpi


@pytest.mark.parametrize("argv", [["--points", "0"], ["--slipping", "1.5"]])
def test_bad_input_is_refused(capsys, argv):
    assert main(argv) == 2
    assert "error:" in capsys.readouterr().err


def test_a_small_run_prints_both_ways(capsys):
    assert main(["--points", "20", "--slipping", "0.5", "--repeats", "1", "--rounds", "1"]) == 0
    out = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:
        assert "reduced by the kernel    50 rows" in out  # 10 stuck x 3 + 10 slipping x 2
        assert "whole block              60 rows" in out
