"""Bad options of the demos end with exit code 2 and a message naming the problem, before
anything is computed or written: bad case entries and options, --quick with another --case,
an output folder that cannot be created or written."""

import pytest
from mpi4py import MPI

pytestmark = pytest.mark.mpi

DEMOS = (
    "install",
    "sweep",
    "dismount",
    "imperfections",
    "parameter_study",
    "joint_geometry",
    "modal",
    "lumped",
)
WITHOUT_PROGRESS_BAR = ("joint_geometry", "modal", "lumped")


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
        ("install", ["--quick", "--case", "scaled"], ["--quick is --case install_quick"]),
        ("install", ["--full", "--quick"], ["--full is --case scaled_full"]),
        ("sweep", ["--quick", "--case", "coarse"], ["--quick is --case sweep_quick"]),
        ("sweep", ["--set", "sweep.kind='chirp'"], ["[sweep]", "'steps' or 'ramp'"]),
        ("modal", ["--quick", "--case", "full_scale"], ["--quick is --case modal_quick"]),
        ("joint_geometry", ["--case", "no_such_case"], ["no_such_case", "presets"]),
        ("joint_geometry", ["--quick", "--tp-ovality-mm", "100"], ["imperfections too large"]),
        (
            "install",
            ["--quick", "--set", 'contact.lu_solver="superlu_dist"'],
            ["superlu_dist", "event_dt_s", "mumps"],
        ),
        ("modal", ["--set", "mesh.n_circumferential=10"], ["scaled.toml: [mesh]", "multiple of 4"]),
    ],
)
def test_bad_options_exit_2_before_computing(demo, options, words, demo_main, shared_tmp, capsys):
    comm = MPI.COMM_WORLD
    out = shared_tmp / "out"
    quiet = [] if demo in WITHOUT_PROGRESS_BAR else ["--no-progress"]
    code = demo_main(demo)(options + ["--output", str(out)] + quiet)
    assert code == 2
    assert not out.exists()  # nothing written
    if comm.rank == 0:
        message = capsys.readouterr().err
        assert message.startswith("error: ")
        for w in words:
            assert w in message, message


@pytest.mark.parametrize(
    "options, words",
    [
        (["--case", "no_such_case"], ["no_such_case", "presets"]),
        (["--set", "geometry.tp.thickness=-1"], ["lumped.toml", "thickness"]),
        (["--mu-d", "0.9"], ["lumped.toml", "[lumped]", "mu_d", "mu_s"]),
        (["--set", "lumped.n_frequencies=1"], ["[lumped]", "n_frequencies"]),
        (["--quick", "--case", "full_scale"], ["--quick is --case lumped_quick"]),
        (["--scaled-case", "no_such_case"], ["no_such_case"]),
        (["--set", "1"], ["section.key=value"]),
        (["--settle", "1"], ["unrecognized arguments: --settle"]),  # no abbreviations
    ],
)
def test_lumped_bad_case_exits_2_before_computing(options, words, demo_main, shared_tmp, capsys):
    """The lumped demo's argument parser (argparse's message and exit code 2) checks its case
    files and overrides before anything is computed or written."""
    out = shared_tmp / "out"
    with pytest.raises(SystemExit) as stop:
        demo_main("lumped")(options + ["--output", str(out)])
    assert stop.value.code == 2
    assert not out.exists()
    message = capsys.readouterr().err
    for w in words:
        assert w in message, message


@pytest.mark.parametrize("demo", DEMOS)
def test_unwritable_output_folder_exits_2_before_computing(demo, demo_main, shared_tmp, capsys):
    """An --output folder below a file cannot be created: error and exit code 2."""
    comm = MPI.COMM_WORLD
    blocker = shared_tmp / "a_file"
    if comm.rank == 0:
        blocker.write_text("not a folder\n")
    comm.barrier()
    options = ["--quick", "--output", str(blocker / "out")]
    quiet = [] if demo in WITHOUT_PROGRESS_BAR else ["--no-progress"]
    code = demo_main(demo)(options + quiet)
    assert code == 2
    if comm.rank == 0:
        message = capsys.readouterr().err
        assert message.startswith("error: ") and "cannot be created or written" in message, message
        assert str(blocker / "out") in message
