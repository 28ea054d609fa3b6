"""The scenario atlas (benchmarks/scenarios.py) on the tiny joint: it runs a list of scenarios,
makes the runs they share once, and rebuilds its page from every outcome in its output folder;
bad requests are refused before anything runs. (The tiny joint's verdicts say nothing about the
physics; docs/scenarios.md has the converged joint's.)"""

import json

import pytest
from mpi4py import MPI

from benchmarks.atlas.catalogue import SCENARIOS
from benchmarks.scenarios import main

pytestmark = pytest.mark.mpi


def test_atlas_runs_scenarios_and_rebuilds_its_page(shared_dir):
    out = shared_dir("atlas")
    page = out / "page.md"
    common = ["--case", "tiny", "--output", str(out / "runs_of"), "--docs", str(page)]
    assert main(["S1", *common]) == 0
    reference = out / "runs_of" / "runs" / "reference" / "run.json"
    made = reference.stat().st_mtime_ns
    assert main(["S8", *common]) == 0
    assert reference.stat().st_mtime_ns == made  # S8 reads S1's reference run
    assert main(["S5", *common]) == 0
    MPI.COMM_WORLD.Barrier()
    text = page.read_text()
    run = json.loads(reference.read_text())
    assert f"settlement {run['settlement_mm'][-1]:.4f} mm" in text  # S1's row, from its run
    assert "| S8: stiffening |" in text
    dismount = json.loads((out / "runs_of" / "runs" / "dismount" / "run.json").read_text())
    branches = dismount["branches"]
    vibrated = not branches["pull 1 x"]["separated"]  # the tiny joint is frictionless: released
    assert set(branches) == {"pull 1 x", "pull 1.25 x"} | (
        {"modal", "control"} if vibrated else set()
    )
    assert "| S5: dismount |" in text
    assert (out / "figures" / "scenarios" / "S5_dismount.png").exists()
    assert "(figures/scenarios/S1_settlement.png)" in text
    assert (out / "figures" / "scenarios" / "S8_frequencies.png").exists()
    not_yet = text.split("## Not in the atlas yet")[1]
    assert all(f"| {k}:" in not_yet for k, s in SCENARIOS.items() if s.run is None)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["S9"], "unknown scenario(s) S9"),
        ([], "no scenario given"),
        (["S2"], "S2 not in the atlas yet"),
        (["S1", "--case", "no_such_case"], "error:"),
    ],
)
def test_atlas_refuses_bad_requests(argv, message, capsys, shared_dir):
    out = shared_dir("atlas_refused")
    assert main([*argv, "--output", str(out), "--docs", str(out / "page.md")]) == 2
    if MPI.COMM_WORLD.rank == 0:
        assert message in capsys.readouterr().err
    assert not (out / "page.md").exists()
