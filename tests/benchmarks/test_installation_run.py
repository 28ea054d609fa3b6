"""The phase-timing benchmark of an installation run (benchmarks/installation_run.py): a bad case
is refused with ``error:`` before anything runs, as is a resume without a checkpoint; a run
that stops still prints its table."""

from benchmarks.installation_run import main
from solver.installation.runner import Installation


def test_a_bad_case_is_refused(capsys, tmp_path):
    assert main(["--case", "no_such_case", "--output", str(tmp_path)]) == 2
    assert "error:" in capsys.readouterr().err


def test_a_stopped_run_prints_the_table_of_its_stages(monkeypatch, capsys, tmp_path):
    def stop(self: Installation, resume: bool = False) -> None:
        raise RuntimeError("the contact band reached the top of the contact zone")

    monkeypatch.setattr(Installation, "run", stop)
    assert main(["--case", "tiny", "--output", str(tmp_path)]) == 1
    out = capsys.readouterr().out
    assert "| **total** |" in out
    assert out.rstrip().endswith(
        "run stopped: the contact band reached the top of the contact zone"
    )


def test_resume_without_a_checkpoint_is_refused(capsys, tmp_path):
    assert main(["--case", "tiny", "--output", str(tmp_path / "none"), "--resume"]) == 2
    assert "error:" in capsys.readouterr().err
