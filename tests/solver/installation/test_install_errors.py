"""Bad case files and options of the installation run give clear errors before any computation."""

from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from common.case import presets, read_case
from solver.installation.case import InstallationCase

pytestmark = pytest.mark.mpi


def _case(*overrides: str) -> InstallationCase:
    return InstallationCase.from_dict(read_case("scaled", list(overrides)))


def test_presets_are_valid_installation_cases():
    case = _case()
    assert case.damping.model == "rayleigh" and case.self_weight.force_N == -10e3
    assert InstallationCase.from_dict(read_case("full_scale")).self_weight.force_N < 0
    for name in presets():  # the imperfection demo's lead-in schedule is its own
        schedule = (
            ["schedule=[{duration_s = 0.01, frequency_hz = 68.0}]"]
            if "imperfections" in name
            else []
        )
        assert InstallationCase.from_dict(read_case(name, schedule)).self_weight.force_N < 0, name


@pytest.mark.parametrize(
    "override, words",
    [
        ("friction.mu_s=0.3", ["mu_d", "must not exceed mu_s"]),
        ("friction.mu=0.3", ["[friction]", "unknown key", "mu"]),
        ("damping.model=viscous", ["model", "rayleigh", "modal"]),
        ("vibration.forcing=motor", ["forcing", "eccentric"]),
        (
            "vibration.forcing=shaker vibration.shaker_height_m=5.0",
            ["shaker_height_m", "outside the TP"],
        ),
        ("vibration.forcing=shaker", None),  # valid: default height lies on the TP
        ("self_weight.force_N=10e3", ["force_N", "negative"]),
        ("self_weight.event_dt_s=0.003", ["event_dt_s", "must divide the step dt = 0.01 s"]),
        ("self_weight.event_dt_s=0.02", ["event_dt_s", "must divide the step dt = 0.01 s"]),
        ("self_weight.event_dt_s=-0.001", ["event_dt_s", "0 (none) or positive"]),
        ("self_weight.event_dt_s=0.001", None),
        ("self_weight.event_dt_s=0.0001", ["event_dt_s", "smallest cut step"]),
        ("self_weight.event_rate_mm_s=0", ["event_rate_mm_s", "positive"]),
        ("self_weight.event_calm_steps=0.5", ["event_calm_steps", "integer"]),
        ("self_weight.event_calm_steps=true", ["event_calm_steps", "integer"]),
        ("time.scheme=euler", ["scheme", "generalised-alpha"]),
        ("time.steps_per_period=2", ["steps_per_period"]),
        ("contact.slave=MP_CONTACT", ["slave and master must differ"]),
        ("contact.lu_solver=umfpack", ["lu_solver", "superlu_dist"]),
        ("contact.lu_solver=superlu_dist", ["superlu_dist", "event_dt_s = 0.001 s", "mumps"]),
        ("contact.lu_solver=superlu_dist self_weight.event_dt_s=0", None),
        ("contact.condense_bulk=yes", ["condense_bulk", "true or false"]),
        ("contact.newton_rtol=0", ["newton_rtol", "(0, 1)"]),
        ("contact.newton_rtol=1.5", ["newton_rtol", "(0, 1)"]),
        ('contact.solver="newton"', ["solver", "zone", "points"]),
        ("contact.candidate_gap=-1e-6", ["candidate_gap"]),
        ("contact.quadrature_degree=-1", ["quadrature_degree"]),
        ("output.checkpoint_every=0", ["checkpoint_every"]),
        ("output.stage_states=1", ["stage_states", "true or false"]),
        ("mesh.n_circumferential=10", ["n_circumferential", "multiple of 4"]),
        ("loading.force=1", ["unknown table", "loading"]),
    ],
)
def test_bad_entries_name_the_problem(override, words):
    if words is None:
        _case(*override.split())
        return
    with pytest.raises(ValueError) as err:
        _case(*override.split())
    message = str(err.value)
    assert message.count("scaled.toml") == 1, message  # the case file named once
    for w in words:
        assert w in message, message


def test_bad_schedule_stage(shared_tmp):
    comm = MPI.COMM_WORLD
    path = shared_tmp / "bad_schedule.toml"
    if comm.rank == 0:
        text = (
            read_case_text() + "\n[[schedule]]\nduration_s = 0.1\nfrequency_hz = 100.0\n"
            "[[schedule]]\nduration_s = -1.0\nfrequency_hz = 50.0\n"
        )
        path.write_text(text)
    comm.barrier()
    with pytest.raises(ValueError, match=r"schedule stage 2.*duration_s"):
        InstallationCase.from_dict(read_case(path))
    with pytest.raises(ValueError, match=r"mode 40.*n_modes"):
        InstallationCase.from_dict(
            read_case(path, ["schedule=[{duration_s = 0.1, frequency_hz = 'mode 40'}]"])
        )


def read_case_text() -> str:
    from common.case import resolve_case_path

    return resolve_case_path("scaled").read_text()


def test_demo_rejects_bad_options_before_computing(demo_main, shared_tmp, capsys):
    comm = MPI.COMM_WORLD
    out = str(shared_tmp / "run")
    assert demo_main("install")(["--mu-s", "-1", "--output", out]) == 2
    assert demo_main("install")(["--case", "no_such_case", "--output", out]) == 2
    assert demo_main("install")(["--set", "friction.d_c", "--output", out]) == 2
    assert (
        demo_main("install")(
            [
                "--resume",
                "--output",
                out,
                "--set",
                "mesh.n_circumferential=8",
                "--set",
                "mesh.axial_size=0.7",
                "--set",
                "contact.degree=1",
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    if comm.rank == 0:
        assert "friction coefficients must be >= 0" in err
        assert "no_such_case" in err
        assert "not of the form section.key=value" in err
        assert "no checkpoint" in err
    assert not (Path(out) / "history.csv").exists()  # nothing computed


def test_resume_needs_the_same_rank_count(shared_tmp):
    import json

    from solver.installation import checkpoint

    comm = MPI.COMM_WORLD
    folder = shared_tmp
    if comm.rank == 0:
        manifest = {"ranks": comm.size + 1, "time_s": 0.1}
        (Path(folder) / checkpoint.MANIFEST).write_text(json.dumps(manifest))
    comm.barrier()
    with pytest.raises(ValueError, match=rf"written by {comm.size + 1} rank\(s\).*not {comm.size}"):
        checkpoint.read_manifest(folder, comm)


def test_resume_needs_a_complete_checkpoint(shared_tmp):
    """A checkpoint without the contact memory (e.g. from before the pairing coordinates were
    saved) is refused with a clear error, not a KeyError."""
    import json
    from types import SimpleNamespace

    from solver.installation import checkpoint

    comm = MPI.COMM_WORLD
    folder = shared_tmp
    if comm.rank == 0:
        (folder / checkpoint.MANIFEST).write_text(json.dumps({"ranks": comm.size, "time_s": 0.1}))
    comm.barrier()
    state = np.zeros(6)
    np.savez(
        folder / f"rank{comm.rank}.npz",
        u=state,
        v=state,
        a=state,
        r_contact_old=state,
        slip_velocity=np.zeros((2, 3)),
        paired_facet=np.zeros(2, dtype=int),
    )
    comm.barrier()
    expected = {
        "u": state,
        "v": state,
        "a": state,
        "r_contact_old": state,
        "slip_velocity": np.zeros((2, 3)),
        "paired_facet": np.zeros(2, dtype=int),
        "paired_coordinates": np.zeros((2, 2)),
    }
    problem = SimpleNamespace(
        V=SimpleNamespace(mesh=SimpleNamespace(comm=comm)), state_arrays=lambda: expected
    )
    with pytest.raises(ValueError, match="lacks paired_coordinates.*without --resume"):
        checkpoint.restore(folder, problem)
