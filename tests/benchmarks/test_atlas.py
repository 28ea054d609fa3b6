"""The scenario atlas (benchmarks/scenarios.py) on the tiny joint: it runs a list of scenarios,
makes the runs they share once, and rebuilds its page from every outcome in its output folder
and those kept beside the page; S2 and S4 read the stages of an installation run (S4 also its
modal table), S3, S4, S5 and S8 also start from its last checkpoint (S8 also from the states it
kept, as left and brought to rest); bad requests are refused before anything runs. (The tiny
joint's verdicts say nothing about the physics; docs/scenarios.md has the converged joint's.)"""

import csv
import json
import shutil

import numpy as np
import pytest
from mpi4py import MPI

from benchmarks.atlas.catalogue import SCENARIOS
from benchmarks.atlas.criteria.s5_dismount import motors_rows, release_word
from benchmarks.atlas.dismount import dismount_runs, lift_rate, released
from benchmarks.atlas.outcome import Outcome, Row
from benchmarks.atlas.page import write_page
from benchmarks.atlas.selectivity import selectivity_ratio
from benchmarks.atlas.settled import settle
from benchmarks.atlas.stepping import joint_state
from benchmarks.scenarios import main
from solver.dynamics.loads import eccentric_amplitude
from solver.installation.planning import stage_step
from solver.installation.runner import Installation

pytestmark = pytest.mark.mpi


@pytest.fixture(scope="module")
def atlas_output(shared_dir):
    """The atlas's output folder of this module: its runs are kept and reused."""
    return shared_dir("atlas")


def test_atlas_runs_scenarios_and_rebuilds_its_page(atlas_output):
    out = atlas_output
    page = out / "page.md"
    common = ["--case", "tiny", "--output", str(out / "runs_of"), "--docs", str(page)]
    assert main(["S1", *common]) == 0
    reference = out / "runs_of" / "runs" / "reference" / "run.json"
    made = reference.stat().st_mtime_ns
    assert main(["S8", *common]) == 0
    assert reference.stat().st_mtime_ns == made  # S8 reads S1's reference run
    assert main(["S5", *common]) == 0
    # the sweeps on the tiny joint with friction: frictionless, its TP keeps sliding under the
    # self-weight force and Newton fails in the ramps' lead-in on 2 ranks
    assert main(["S7", *common, "--set", "friction.mu_s=0.3", "--set", "friction.mu_d=0.3"]) == 0
    MPI.COMM_WORLD.Barrier()
    text = page.read_text()
    run = json.loads(reference.read_text())
    assert f"settlement {run['settlement_mm'][-1]:.4f} mm" in text  # S1's row, from its run
    assert "| S8: stiffening |" in text
    dismount = json.loads((out / "runs_of" / "runs" / "dismount" / "run.json").read_text())
    branches = dismount["branches"]
    vibrated = not branches["pull 1 x"]["released"]  # the tiny joint is frictionless: released
    assert set(branches) == {"pull 1 x", "pull 1.25 x"} | (
        {"modal", "control"} if vibrated else set()
    )
    assert "| S5: dismount |" in text
    assert (out / "figures" / "scenarios" / "S5_dismount.png").exists()
    assert "(figures/scenarios/S1_settlement.png)" in text
    assert (out / "figures" / "scenarios" / "S8_frequencies.png").exists()
    not_run = text.split("## Not run yet")[1]
    assert all(f"| {k}:" in not_run for k in SCENARIOS if k not in ("S1", "S5", "S7", "S8"))
    sweeps = json.loads((out / "runs_of" / "runs" / "sweeps" / "run.json").read_text())
    assert set(sweeps["runs"]) == {"steps", "lead-in", "slow", "fast"}
    assert len(sweeps["runs"]["steps"]["starts_s"]) == 13  # 10 to 130 Hz in 10 Hz steps
    unexcited = json.loads((out / "runs_of" / "runs" / "sweeps_unexcited" / "run.json").read_text())
    steps = sweeps["runs"]["steps"]["rows"]
    assert unexcited["rows"][0][:2] == steps[0][:2]  # from the same settled state, as long
    assert unexcited["rows"][-1][0] == pytest.approx(steps[-1][0])
    assert "| S7: sweeps |" in text
    assert (out / "figures" / "scenarios" / "S7_ramps.png").exists()
    if MPI.COMM_WORLD.rank == 0:  # the outcomes kept beside the page rebuild it alone
        assert sorted(p.name for p in (out / "page").iterdir()) == [
            f"{k}.json" for k in ("S1", "S5", "S7", "S8")
        ]
        write_page(out / "no_runs", page)
        assert page.read_text() == text


def test_the_settled_joint_is_the_installation_runs_self_weight_stage(
    installed, tiny_case, shared_dir
):
    """The state S5, S6 and S7 branch from is the installation run's after its self-weight
    stage, event steps included; with them it differs from the uniform steps' state."""
    events = ["self_weight.event_dt_s=0.001"]  # the sliding TP: every step an event step
    out = shared_dir("events")
    Installation(MPI.COMM_WORLD, tiny_case(*events), out, progress=False).run()
    stage = json.loads((out / "checkpoint" / "manifest.json").read_text())["stages"][0]
    manifest = json.loads((installed / "checkpoint" / "manifest.json").read_text())
    uniform = manifest["stages"][0]
    t, settlement_mm, _ = joint_state(settle(MPI.COMM_WORLD, events, "tiny").model)
    assert t == pytest.approx(stage["end_s"], rel=1e-12)
    assert settlement_mm == pytest.approx(stage["settlement_end_mm"], rel=1e-9)
    assert abs(settlement_mm / uniform["settlement_end_mm"] - 1) > 1e-6


def test_s2_s4_s5_s8_from_the_installed_state(installed, atlas_output, tiny_case):
    out = atlas_output / "runs_of"  # the settled-state runs of the test above are reused
    page = atlas_output / "page_installed.md"
    argv = ["S2", "S4", "S5", "S8", "--case", "tiny", "--output", str(out), "--docs", str(page)]
    assert main([*argv, "--installed", str(installed)]) == 0
    MPI.COMM_WORLD.Barrier()
    manifest = json.loads((installed / "checkpoint" / "manifest.json").read_text())
    r = json.loads((out / "runs" / "dismount_installed" / "run.json").read_text())
    assert r["request"]["installed"] == str(installed)
    assert r["settled"]["time_s"] == pytest.approx(manifest["time_s"])
    assert r["natural_Hz"] == manifest["natural_frequencies_Hz"]
    t0 = r["branches"]["pull 1 x"]["rows"][0][0]
    assert t0 == pytest.approx(manifest["time_s"])  # the pull starts from the installed state
    text = page.read_text()
    assert f"installed (t = {manifest['time_s']:.2f} s): pull alone" in text
    assert "settled by self-weight: pull alone" in text
    assert (atlas_output / "figures" / "scenarios" / "S5_dismount_installed.png").exists()
    modes = json.loads((out / "runs" / "modes_installed" / "run.json").read_text())
    assert modes["time_s"] == pytest.approx(manifest["time_s"])
    assert len(modes["frequencies_Hz"]) == len(modes["bonded_Hz"]) == 10
    assert f"(t = {manifest['time_s']:.2f} s) against the end of self-weight" in text
    # S8 after each vibration stage: the last stage's kept state is the installed state
    last = json.loads((out / "runs" / "modes_stage_2" / "run.json").read_text())
    assert last["time_s"] == pytest.approx(manifest["time_s"])
    assert last["frequencies_Hz"] == pytest.approx(modes["frequencies_Hz"], rel=1e-6)
    first = json.loads((out / "runs" / "modes_stage_1" / "run.json").read_text())
    assert first["time_s"] == pytest.approx(manifest["stages"][1]["end_s"])
    s8 = text.split("| S8: stiffening")[1]
    for m in (first, last):
        assert f"({m['settlement_mm']:.3f} mm): " in s8.split("against those before it")[1]
    # the probe: each stage's state brought to rest, the static load held as in the self-weight
    rest = json.loads((out / "runs" / "modes_stage_1_at_rest" / "run.json").read_text())
    assert rest["time_s"] == pytest.approx(first["time_s"] + tiny_case().self_weight.hold_s)
    assert f"stage 1 ({rest['settlement_mm']:.3f} mm, contact " in s8.split("brought to rest")[1]
    assert (atlas_output / "figures" / "scenarios" / "S8_stiffening.png").exists()
    s2 = text.split("| S2: reference sequence")[1].split("| S4:")[0]
    vibration = [s for s in manifest["stages"] if s["stage"] >= 1]
    assert len(vibration) == 2  # the tiny case's sequence: one mode and the control
    for s in vibration:  # S2's rows are the run's stages
        assert f"{s['name']} at " in s2
        assert f"gained {1e3 * s['gained_mm']:.1f} um" in s2
    assert "2 of 2 vibration stages" in s2
    continued = json.loads((out / "runs" / "continued" / "run.json").read_text())
    stage = manifest["stages"][continued["request"]["stage"]]  # the modal stage, continued
    assert manifest["excitations"][stage["stage"] - 1]["role"] == "modal"
    assert continued["plan"] == manifest["plans"][stage["stage"]]  # its forcing and step
    first_row, last_row = continued["rows"][0], continued["rows"][-1]
    assert first_row[:2] == pytest.approx([stage["end_s"], stage["settlement_end_mm"]])
    assert last_row[0] == pytest.approx(2 * stage["end_s"] - stage["start_s"])
    assert f"gained {1e3 * (last_row[1] - first_row[1]):.1f} um more" in s2
    assert f"{continued['step_cuts']} step cut(s)" in s2
    assert (atlas_output / "figures" / "scenarios" / "S2_sequence.png").exists()
    direction = json.loads((out / "runs" / "direction_installed" / "run.json").read_text())
    s4 = text.split("| S4: which modes work")[1].split("| S5:")[0]
    stage, modal = next(
        (s, e)
        for s in vibration
        if (e := manifest["excitations"][s["stage"] - 1])["role"] == "modal"
    )
    rate = 2 * stage["gained_second_half_mm"] / (stage["end_s"] - stage["start_s"])
    assert f"rank {modal['rank']}, ({modal['m']}, {modal['n']}), " in s4  # S2's modal stage
    assert f"{modal['frequency_Hz']:.2f} Hz: {rate:.3f} mm/s" in s4
    with (installed / "modes.csv").open() as f:  # the probe: the modal stage's indicator
        row = next(r for r in csv.DictReader(f) if int(r["mode"]) == modal["mode"])
    slip, motors = float(row["resonant_slip_axial_um"]), eccentric_amplitude(modal["frequency_Hz"])
    at_stage = slip * tiny_case().vibration.amplitude_N / motors  # it scales with the force
    assert f"{at_stage:.1f} um ({slip:.1f} um at {motors / 1e3:.2f} kN)" in s4
    with (installed / "modes.csv").open() as f:  # the lowest m = 1 mode of the modal stage
        lowest = min(
            (r for r in csv.DictReader(f) if r["m"] == "1"), key=lambda r: float(r["frequency_Hz"])
        )
    mode = direction["mode"]
    assert mode["mode"] == int(lowest["mode"])
    assert mode["frequency_Hz"] == pytest.approx(float(lowest["frequency_Hz"]))
    assert set(direction["branches"]) == {"axial", "both", "both reversed"}
    stage_s = tiny_case().vibration.stage_duration_s
    for branch in direction["branches"].values():  # both from the installed state
        assert branch[0][0] == pytest.approx(manifest["time_s"])
        assert branch[-1][0] == pytest.approx(manifest["time_s"] + stage_s)
    gain = {d: b[-1][1] - b[0][1] for d, b in direction["branches"].items()}
    assert f"{1e3 * gain['both']:.1f} um against {1e3 * gain['axial']:.1f} um" in s4
    assert f"{1e3 * gain['both reversed']:.1f} um against {1e3 * gain['axial']:.1f} um" in s4
    assert (atlas_output / "figures" / "scenarios" / "S4_direction.png").exists()


def test_dismount_at_the_motors_force(tiny_case, shared_dir):
    """S5's probe: with no amplitude given, the vibration branches under the pull have the
    eccentric motors' force at the best mode, the control the same; its rows state it."""
    friction = ["friction.mu_s=0.3", "friction.mu_d=0.3"]  # the tiny joint is frictionless
    stage_s = tiny_case().vibration.stage_duration_s
    folder = shared_dir("dismount_motors")
    # half the self-weight force: the pull alone holds the joint settled by the whole of it
    r = dismount_runs(MPI.COMM_WORLD, "tiny", friction, folder, (0.5,), None, stage_s)
    b = r["branches"]
    assert not b["pull 0.5 x"]["released"]
    motors = eccentric_amplitude(b["modal"]["frequency_Hz"])
    assert b["modal"]["amplitude_N"] == pytest.approx(motors)
    assert b["control"]["amplitude_N"] == b["modal"]["amplitude_N"]
    assert b["control"]["frequency_Hz"] != b["modal"]["frequency_Hz"]
    steps = tiny_case().time.steps_per_period
    for branch in (b["modal"], b["control"]):  # from the pulled state
        t = np.array(branch["rows"])[:, 0]
        assert t[0] == pytest.approx(r["settled"]["time_s"] + 2 * stage_s)
        # every step the one its drive was compensated for (no partial step at a chunk's end)
        dt = stage_step(stage_s, branch["forcing_Hz"], steps)
        assert np.allclose(np.diff(t), dt, rtol=1e-9, atol=0.0)
    row = motors_rows(r, r, "settled", tiny_case().output.slip_rate_mm_s)[1]
    assert f"0.3632 f^2 = {motors / 1e3:.2f} kN" in row.criterion
    lift = b["modal"]["rows"][0][1] - b["modal"]["rows"][-1][1]
    assert f"the TP {lift:+.3f} mm up" in row.measured


def test_release_of_a_dismount_branch():
    """A branch ends released above its first-contact position (settlement < 0) when the contact
    normal force is below 1 % of the settled one, or, though a shaken TP still strikes the MP
    there, when it lifts faster than the event threshold over the second half."""
    settled_N, threshold = 1e4, 1.0  # N, mm/s

    def rows(settlement_mm: list[float], normal_N: float = 1e3) -> list:
        return [(0.01 * k, s, normal_N) for k, s in enumerate(settlement_mm)]

    lifting_above = rows([0.2, 0.1, -0.05, -0.2, -0.4])
    assert lift_rate(lifting_above) == pytest.approx(17.5)  # (0.35 mm) / (0.02 s)
    assert released(lifting_above, settled_N, threshold)
    assert release_word({"rows": lifting_above}, settled_N, threshold).startswith("released")
    lifting_below = rows([0.9, 0.8, 0.6, 0.4, 0.2])
    assert not released(lifting_below, settled_N, threshold)
    word = release_word({"rows": lifting_below}, settled_N, threshold)
    assert word == "holds, lifting, 0.200 mm below its first-contact position at the end"
    resting_above = rows([-0.1] * 5)
    assert not released(resting_above, settled_N, threshold)
    word = release_word({"rows": resting_above}, settled_N, threshold)
    assert word == "holds, 0.100 mm above its first-contact position at the end"
    apart = rows([-0.1] * 5, normal_N=0.0)
    assert released(apart, settled_N, threshold)
    assert release_word({"rows": apart}, settled_N, threshold) == "separated"
    assert not released(rows([0.1] * 5, normal_N=0.0), settled_N, threshold)


def test_page_names_the_joint_of_each_scenario(shared_tmp):
    """Outcomes on two joints: the page says which scenarios ran on which."""
    if MPI.COMM_WORLD.rank != 0:  # the page is written on one rank
        return
    for key, joint in (("S1", "`a`"), ("S2", "`b`"), ("S3", "`a`")):
        outcome = Outcome(
            key, SCENARIOS[key].title, joint, [Row("c", "m", "measured")], {key: 60.0}, 2
        )
        outcome.save(shared_tmp / "page" / f"{key}.json")
    write_page(shared_tmp / "no_runs", shared_tmp / "page.md")
    text = (shared_tmp / "page.md").read_text()
    assert "Joint of S1, S3: `a`." in text and "Joint of S2: `b`." in text
    assert "Wall time of the scenarios below: 3.0 min (3 runs" in text


@pytest.mark.slow  # about 3 min serially: three settled joints (friction, damping) and their branches
def test_s6_selectivity_of_friction_decay_and_damping(atlas_output, tiny_case):
    out = atlas_output / "runs_of"
    page = atlas_output / "page_s6.md"
    assert main(["S6", "--case", "tiny", "--output", str(out), "--docs", str(page)]) == 0
    MPI.COMM_WORLD.Barrier()
    stage_s = tiny_case().vibration.stage_duration_s
    text = page.read_text()
    for folder in ("selectivity", "selectivity_slow_decay", "selectivity_modal_damping"):
        r = json.loads((out / "runs" / folder / "run.json").read_text())
        lead, control, modal = (r["branches"][b]["rows"] for b in ("lead-in", "control", "modal"))
        assert lead[0][0] == pytest.approx(r["settled"]["time_s"])
        # the modal branch restarts from the lead-in's end (the control goes on from there)
        assert modal[0][:2] == lead[-1][:2]
        assert modal[0][2] == pytest.approx(lead[-1][2], rel=1e-8)
        natural = r["branches"]["modal"]["frequency_Hz"]
        for rows, f in ((lead, r["branches"]["control"]["frequency_Hz"]), (modal, natural)):
            periods = (rows[-1][0] - rows[0][0]) * f  # the whole periods nearest half a stage
            assert periods == pytest.approx(max(1, round(0.5 * stage_s * f)), abs=1e-6)
        assert control[-1][0] - control[0][0] == pytest.approx(lead[-1][0] - lead[0][0])
        assert f"{selectivity_ratio(modal, control):.1f} x" in text
    assert (atlas_output / "figures" / "scenarios" / "S6_selectivity.png").exists()


@pytest.mark.slow  # about 6 min on 2 ranks: the tiny joint slides at every amplitude (5 branches)
def test_s3_from_the_installed_state(installed, atlas_output):
    out = atlas_output / "runs_of"
    page = atlas_output / "page_s3.md"
    argv = ["S3", "--case", "tiny", "--output", str(out), "--docs", str(page)]
    assert main([*argv, "--installed", str(installed)]) == 0
    MPI.COMM_WORLD.Barrier()
    manifest = json.loads((installed / "checkpoint" / "manifest.json").read_text())
    text = page.read_text()
    amplitude = json.loads((out / "runs" / "amplitude_installed" / "run.json").read_text())
    control = next(e for e in manifest["excitations"] if e["role"] == "control")
    drive = control["forcing_Hz"] or control["frequency_Hz"]
    assert list(amplitude["frequencies"]) == [f"{drive:.6g}"]  # the tiny run has no lead-in
    branches = amplitude["frequencies"][f"{drive:.6g}"]
    assert {"0", "1"} <= set(branches)  # the baseline, then the modal amplitude
    for rows in branches.values():  # each from the installed state, 5 periods
        assert rows[0][0] == pytest.approx(manifest["time_s"])
        assert rows[-1][0] == pytest.approx(manifest["time_s"] + 5 / drive)
    s3 = text.split("| S3: amplitude-driven settlement")[1].split("| S4:")[0]
    assert f"at {drive:.2f} Hz (not at a natural frequency)" in s3
    assert "threshold between" in s3 or "not bracketed" in s3
    assert (atlas_output / "figures" / "scenarios" / f"S3_amplitude_{drive:.0f}Hz.png").exists()


def test_s8_says_when_the_run_kept_no_stage_states(installed, shared_dir):
    """S8 from a run without stage states: its installed state only, and a "not run" row."""
    bare = shared_dir("installed_bare")
    if MPI.COMM_WORLD.rank == 0:
        shutil.copytree(
            installed, bare, ignore=shutil.ignore_patterns("states"), dirs_exist_ok=True
        )
    MPI.COMM_WORLD.Barrier()
    out = shared_dir("atlas_bare")
    argv = ["S8", "--case", "tiny", "--output", str(out), "--docs", str(out / "page.md")]
    assert main([*argv, "--installed", str(bare)]) == 0
    MPI.COMM_WORLD.Barrier()
    s8 = (out / "page.md").read_text().split("| S8: stiffening")[1]
    assert "kept no stage states (`--set output.stage_states=true`) | not run |" in s8
    assert "against the end of self-weight" in s8  # the installed state's rows
    assert not (out / "runs" / "modes_stage_1").exists()


def test_installed_state_of_another_case_is_refused(installed, shared_dir, capsys):
    refused = shared_dir("atlas_installed_refused")
    argv = ["S5", "--case", "tiny", "--output", str(refused), "--docs", str(refused / "page.md")]
    assert main([*argv, "--set", "friction.mu_s=0.1", "--installed", str(installed)]) == 2
    if MPI.COMM_WORLD.rank == 0:
        assert (
            "is of another case (run -> now): friction.mu_s: 0.0 -> 0.1" in capsys.readouterr().err
        )
    assert not (refused / "page.md").exists()


@pytest.mark.parametrize(
    "argv, message",
    [
        (["S9"], "unknown scenario(s) S9"),
        ([], "no scenario given"),
        (["S3", "--case", "tiny"], "S3 read(s) an installation run of the case: --installed"),
        (["S2", "--case", "tiny"], "S2 read(s) an installation run of the case: --installed"),
        (["S4", "--case", "tiny"], "S4 read(s) an installation run of the case: --installed"),
        (["S1", "--case", "no_such_case"], "error:"),
        (["S5", "--case", "tiny", "--installed", "no_such_run"], "error: no checkpoint in"),
    ],
)
def test_atlas_refuses_bad_requests(argv, message, capsys, shared_dir):
    out = shared_dir("atlas_refused")
    assert main([*argv, "--output", str(out), "--docs", str(out / "page.md")]) == 2
    if MPI.COMM_WORLD.rank == 0:
        assert message in capsys.readouterr().err
    assert not (out / "page.md").exists()
