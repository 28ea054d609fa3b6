"""benchmarks/vibration_stage.py: one vibration stage from the state an installation run kept,
with settings of the stage alone (the tiny joint)."""

import pytest
from mpi4py import MPI

from benchmarks.vibration_stage import main

pytestmark = pytest.mark.mpi


def test_stage_settings_apply_to_the_installed_state(installed, capsys):
    argv = ["--case", "tiny", "--installed", str(installed), "--frequency", "50"]
    argv += ["--amplitude", "100", "--steps", "2"]
    assert main([*argv, "--stage-set", "time.steps_per_period=10"]) == 0
    out = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:  # the benchmark prints on rank 0
        assert "dt = 2.000e-03 s" in out  # 1 / (50 Hz x 10)
        assert "steps:" in out and "step / solve" in out  # the stage ran to its end


def test_a_run_of_another_case_is_refused(installed, capsys):
    argv = ["--case", "tiny", "--installed", str(installed), "--set", "friction.mu_s=0.6"]
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    assert "of another case" in capsys.readouterr().err
