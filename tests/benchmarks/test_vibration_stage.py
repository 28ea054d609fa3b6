"""benchmarks/vibration_stage.py: one vibration stage from the state an installation run kept,
with settings of the stage alone (the tiny joint)."""

import re

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
        # the phase breakdown: calls per phase, from the solver's ``common.timing`` phases
        calls = {
            m[1]: int(m[2])
            for m in re.finditer(r"^ {4}(\w[\w ]*?) +[\d.]+ s/step.*\((\d+) calls\)$", out, re.M)
        }
        # Elastodynamics.step: once per accepted step and once per failed attempt (step cut)
        steps, cuts = re.search(r"^(\d+) steps: .*, (\d+) step cuts;", out, re.M).groups()
        assert calls["other"] == int(steps) + int(cuts)
        steps_phases = ("pairing", "contact update", "contact residual", "triangular solves")
        stage_phases = ("factorisation", "compliance", "tractions", "condensation", "bulk vectors")
        assert all(calls[phase] > 0 for phase in steps_phases + stage_phases), calls
        # the zone Newton's phases: not the contact points' solver of this case
        assert calls["contact jacobian"] == calls["linear solves"] == 0


def test_a_run_of_another_case_is_refused(installed, capsys):
    argv = ["--case", "tiny", "--installed", str(installed), "--set", "friction.mu_s=0.6"]
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    assert "of another case" in capsys.readouterr().err
