"""--resume continues only the case that wrote the checkpoint: a case that would compute
something else (friction, an imperfection file's content, ...) is refused before anything is
computed, with exit code 2 and the dotted keys that differ; output-only keys and the dismount
plan (read after the installation) may differ."""

import json
import math

import pytest
from mpi4py import MPI

from common.case import read_case
from solver.installation import checkpoint
from solver.installation.runner import Installation

pytestmark = pytest.mark.mpi

#: the tiny joint without the modal stage: the self-weight stage and one 2 ms stage at 100 Hz
SHORT = [
    "vibration.modal_stage=false",
    "schedule=[{duration_s = 0.002, frequency_hz = 100.0, amplitude_N = 'eccentric'}]",
]


def _checkpoint_of(case, output) -> None:
    """A checkpoint manifest of ``case`` in ``output`` (no state arrays: a refused resume reads none)."""
    comm = MPI.COMM_WORLD
    folder = output / "checkpoint"
    if comm.rank == 0:
        folder.mkdir(parents=True)
        manifest = {"ranks": comm.size, "time_s": 0.006, "case": case.fingerprint()}
        (folder / checkpoint.MANIFEST).write_text(json.dumps(manifest))
    comm.barrier()


def _error(capsys) -> str:
    return capsys.readouterr().err if MPI.COMM_WORLD.rank == 0 else ""


def test_changed_friction_is_refused(tiny_case, demo_main, shared_tmp, capsys):
    _checkpoint_of(tiny_case(), shared_tmp)
    code = demo_main("install")(
        [
            "--case",
            "tiny",
            "--resume",
            "--mu-s",
            "0.9",
            "--mu-d",
            "0.8",
            "--output",
            str(shared_tmp),
            "--no-progress",
        ]
    )
    assert code == 2
    message = _error(capsys)
    if MPI.COMM_WORLD.rank == 0:
        print(message)
        assert message.startswith("error: ")
        assert "friction.mu_s: 0.0 -> 0.9" in message and "friction.mu_d: 0.0 -> 0.8" in message
        assert "output." not in message
    assert not (shared_tmp / "case.json").exists() and not (shared_tmp / "history.csv").exists()


def test_another_preset_and_a_changed_imperfection_file_are_refused(
    tiny_case, demo_main, shared_tmp, capsys
):
    comm = MPI.COMM_WORLD
    scan = shared_tmp / "map.csv"

    def write_map(amplitude: float) -> None:
        if comm.rank == 0:
            rows = ["z_m,angle_deg,radial_deviation_m"]
            rows += [
                f"{z},{a},{amplitude * math.cos(math.radians(2 * a)):.9e}"
                for z in (0.0, 1.4)
                for a in range(0, 360, 5)
            ]
            scan.write_text("\n".join(rows) + "\n")
        comm.barrier()

    write_map(0.1e-3)
    imperfect = f"imperfections.tp.file='{scan}'"
    _checkpoint_of(tiny_case(imperfect), shared_tmp)
    write_map(0.2e-3)
    code = demo_main("install")(
        [
            "--case",
            "tiny",
            "--set",
            imperfect,
            "--resume",
            "--output",
            str(shared_tmp),
            "--no-progress",
        ]
    )
    assert code == 2
    message = _error(capsys)
    if comm.rank == 0:
        assert "imperfections.tp.file_sha256: " in message and "mesh." not in message, message
    code = demo_main("install")(
        ["--quick", "--set", imperfect, "--resume", "--output", str(shared_tmp), "--no-progress"]
    )
    assert code == 2
    message = _error(capsys)
    if comm.rank == 0:  # install_quick against tiny: among others the time step
        assert (
            "time.steps_per_period: 4 -> 8" in message and "vibration.n_modes: 4 -> 6" in message
        ), message


def test_output_only_changes_resume(tiny_case, demo_main, shared_tmp):
    """A run killed after its first checkpoint resumes with other ParaView/picture settings and
    another dismount plan."""
    comm = MPI.COMM_WORLD
    killed = Installation(comm, tiny_case(*SHORT), shared_tmp, progress=False)
    assert killed.run(stop_after_checkpoints=1) == {}
    options = [f"--set={item}" for item in SHORT] + [
        "--set",
        "output.paraview=false",
        "--set",
        "output.plots=true",
        "--set",
        "dismount.pull_N=7000.0",
    ]
    code = demo_main("install")(
        ["--case", "tiny", *options, "--resume", "--output", str(shared_tmp), "--no-progress"]
    )
    assert code == 0
    if comm.rank == 0:
        assert "total settlement" in (shared_tmp / "summary.txt").read_text()
        assert (shared_tmp / "settlement.png").is_file()  # plots on in the resumed run
        written = json.loads((shared_tmp / "case.json").read_text())  # the resolved case
        assert written["source"].endswith("tiny.toml") and written["output"]["plots"] is True
        assert (
            written["mesh"]["n_circumferential"] == 12
            and written["contact"]["gamma0"] == read_case("tiny")["contact"]["gamma0"]
        )
        assert written["geometry"]["tp"]["half_angle_deg"] == 1.0
        assert written["schedule"] == [
            {
                "duration_s": 0.002,
                "frequency_hz": 100.0,
                "amplitude_N": "eccentric",
                "frequency_end_hz": None,
                "amplitude_end_N": None,
                "direction": "axial",
                "lateral_fraction": 0.05,
                "lateral_angle_deg": 0.0,
            }
        ]
