"""Bad options of the sweep, dismount, imperfection and parameter-study demos end with exit
code 2 and a message naming the problem, before anything is computed or written."""

from pathlib import Path

import pytest
from mpi4py import MPI

pytestmark = pytest.mark.mpi

@pytest.mark.parametrize(
    "demo, options, words",
    [
        ("sweep", ["--sweep", "ramp", "--f-step", "5"], ["--f-step", "ramp"]),
        ("sweep", ["--f-start", "50", "--f-stop", "20"], ["f_start <= f_stop"]),
        ("sweep", ["--amplitude", "loud"], ["--amplitude", "eccentric"]),
        ("sweep", ["--dwell=-0.1"], ["duration_s"]),
        ("sweep", ["--set", "friction.mu_d=0.9"], ["mu_d", "mu_s"]),
        ("dismount", ["--pull=-1e4"], ["positive (upward)"]),
        ("dismount", ["--n-frequencies", "-1"], ["n_frequencies"]),
        ("dismount", ["--pull-hold", "0"], ["positive"]),
        ("dismount", ["--damping", "viscous"], ["model", "rayleigh"]),
        ("imperfections", ["--scan", "no_such_scan.csv"], ["no such file"]),
        ("imperfections", ["--ovality-mm", "5"], ["--ovality-mm"]),
        ("parameter_study", ["--variants", "wet_friction"], ["unknown variant", "wet_friction"]),
        ("parameter_study", ["--set", "mesh.n_circumferential=10"], ["multiple of 4"]),
    ],
)
def test_bad_options_exit_2_before_computing(demo, options, words, demo_main, tmp_path_factory, capsys):
    comm = MPI.COMM_WORLD
    root = Path(comm.bcast(str(tmp_path_factory.mktemp("demo")) if comm.rank == 0 else None))
    out = root / "out"
    code = demo_main(demo)(options + ["--output", str(out), "--no-progress"])
    assert code == 2
    assert not out.exists()  # nothing written
    if comm.rank == 0:
        message = capsys.readouterr().err
        assert message.startswith("error: ")
        for w in words:
            assert w in message, message
