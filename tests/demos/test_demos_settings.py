"""Settings behind the sweep, dismount and imperfection demos, checked without a time loop:
the static axial force history, the sweep schedules, 'ranked k' stages and the imperfection
tables of an installation case."""

import math

import numpy as np
import pytest
from mpi4py import MPI

from common.case import read_case
from geometry.contact_map import tp_placement
from geometry.imperfections import ovality
from solver.contact import FrictionLaw
from solver.installation.case import InstallationCase
from solver.installation.frequencies import Excitation, schedule_excitations
from solver.dynamics.loads import (
    PiecewiseLinearForce,
    RampedAxialForce,
    Schedule,
    eccentric_amplitude,
    frequency_ramp,
    frequency_steps,
)

pytestmark = pytest.mark.mpi


def _case(*overrides: str) -> InstallationCase:
    return InstallationCase.from_dict(read_case("scaled", list(overrides)))


def test_piecewise_linear_force_interpolates_and_holds():
    force = PiecewiseLinearForce((0.0, 2.0, 2.1, 2.3), (0.0, -10e3, 20e3, 20e3))
    times = [-1.0, 0.0, 0.5, 2.0, 2.05, 2.2, 5.0]
    # by hand: -2.5 kN at a quarter of the ramp; halfway from -10 to +20 kN is +5 kN
    assert [force(t) for t in times] == pytest.approx([0, 0, -2.5e3, -10e3, 5e3, 20e3, 20e3])
    ramp = RampedAxialForce(-10e3, 2.0)
    two_points = PiecewiseLinearForce((0.0, 2.0), (0.0, -10e3))
    for t in np.linspace(-0.5, 3.0, 15):
        assert two_points(t) == pytest.approx(ramp(t), abs=1e-9)
    with pytest.raises(ValueError, match="strictly increasing"):
        PiecewiseLinearForce((0.0, 1.0, 1.0), (0.0, 1.0, 2.0))
    with pytest.raises(ValueError, match="as many forces as times"):
        PiecewiseLinearForce((0.0, 1.0), (0.0,))


def test_static_force_history_continues_the_self_weight():
    case = _case(
        "self_weight.ramp_time_s=2.0",
        "self_weight.hold_s=0.1",
        "static_force.times_s=[0.05, 0.15]",
        "static_force.forces_N=[20e3, 20e3]",
    )
    history = case.static_force.history(case.self_weight)
    assert history(1.0) == pytest.approx(-5e3)  # on the self-weight ramp
    assert history(2.1) == pytest.approx(-10e3)  # held until the end of the self-weight stage
    assert history(2.1 + 0.025) == pytest.approx(5e3)  # halfway up to the pull
    assert history(2.1 + 0.05) == pytest.approx(20e3)
    assert history(10.0) == pytest.approx(20e3)
    # without [static_force] the self-weight force is held (the installation default)
    plain = _case().static_force.history(_case().self_weight)
    assert isinstance(plain, RampedAxialForce) and plain(50.0) == -10e3


@pytest.mark.parametrize(
    "overrides, words",
    [
        (
            ["static_force.times_s=[0.1, 0.05]", "static_force.forces_N=[1e3, 2e3]"],
            ["[static_force]", "strictly increasing"],
        ),
        (
            ["static_force.times_s=[0.1]", "static_force.forces_N=[1e3, 2e3]"],
            ["[static_force]", "same length"],
        ),
        (["static_force.times_s=[0.0]", "static_force.forces_N=[1e3]"], ["positive"]),
        (
            ["imperfections.tp.amplitude_m=1e-3", "imperfections.tp.file='x.csv'"],
            ["[imperfections.tp]", "not both"],
        ),
        (["imperfections.tp.file='no_such_scan.csv'"], ["[imperfections.tp]", "no such file"]),
        (["imperfections.hub.amplitude_m=1e-3"], ["[imperfections]"]),
        (["imperfections.tp.amplitude_m=1e-3", "imperfections.tp.waves=0"], ["waves"]),
        (["vibration.modal_stage=false"], ["modal_stage", "[[schedule]]"]),
        (
            ["schedule=[{duration_s = 0.1, frequency_hz = 'ranked 5'}]"],
            ["ranked 5", "n_frequencies"],
        ),
        (["schedule=[{duration_s = 0.1, frequency_hz = 'ranked 0'}]"], ["ranked k"]),
    ],
)
def test_bad_demo_settings_name_the_problem(overrides, words):
    with pytest.raises(ValueError) as err:
        _case(*overrides)
    for w in words:
        assert w in str(err.value), str(err.value)


def test_step_sweep_schedule():
    """docs/physics.md §3: 10 -> 130 Hz in 10 Hz steps of 0.5 s at the eccentric amplitude 0.3632 f^2."""
    schedule = Schedule(frequency_steps(10.0, 130.0, 10.0, 0.5), start_s=2.1)
    assert len(schedule.stages) == 13
    assert schedule.end_s == pytest.approx(2.1 + 13 * 0.5)
    for k in range(13):
        t = 2.1 + 0.5 * k + 0.25
        f = 10.0 * (k + 1)
        assert schedule.frequency(t) == pytest.approx(f)
        assert schedule.amplitude(t) == pytest.approx(0.3632 * f**2)
    assert schedule.amplitude(2.1 + 0.5 * 9 + 0.1) == pytest.approx(3632.0)  # 100 Hz: 3.6 kN
    with pytest.raises(ValueError, match="f_step"):
        frequency_steps(10.0, 130.0, 0.0, 0.5)


def test_ramp_sweep_schedule():
    """0 -> 125 Hz over 13 s: f(t) linear, phase the integral of f: pi f1 t^2 / T."""
    schedule = Schedule(frequency_ramp(0.0, 125.0, 13.0), start_s=1.0)
    for tau in (0.0, 3.0, 6.5, 13.0):
        assert schedule.frequency(1.0 + tau) == pytest.approx(125.0 * tau / 13.0)
        assert schedule.phase(1.0 + tau) == pytest.approx(math.pi * 125.0 * tau**2 / 13.0)
        f = 125.0 * tau / 13.0
        assert schedule.amplitude(1.0 + tau) == pytest.approx(eccentric_amplitude(f))


def test_sweep_plan_is_the_case_table():
    """[sweep] holds the sweep demo's stages (SweepPlan's defaults where absent: physics.md §3's
    10 -> 130 Hz in 10 Hz steps, of 30 ms); they replace the [[schedule]], with the case's
    [vibration] direction; the quick case's table; a ramp; bad entries named."""
    from solver.installation.sweep import SweepPlan, read_sweep, sweep_case

    assert _case().sweep == SweepPlan() == read_sweep(read_case("sweep"))
    data = read_case("sweep", ["vibration.direction='lateral'", "vibration.lateral_fraction=0.2"])
    data["schedule"] = [{"duration_s": 0.1, "frequency_hz": 50.0}]
    sweep_case(data, read_sweep(data))
    schedule = InstallationCase.from_dict(data).schedule
    assert schedule is not None and len(schedule.stages) == 13
    assert [s.frequency_hz for s in schedule.stages] == pytest.approx(np.arange(10.0, 131.0, 10.0))
    assert all(s.duration_s == 0.03 and s.amplitude_N == "eccentric" for s in schedule.stages)
    assert all(s.direction == "lateral" and s.lateral_fraction == 0.2 for s in schedule.stages)
    quick = read_sweep(read_case("sweep_quick"))
    assert [s.frequency_hz for s in quick.stages()] == [40.0, 80.0, 120.0]
    ramp = read_sweep(read_case("sweep", ["sweep.kind='ramp'", "sweep.amplitude_N=2e3"]))
    (stage,) = ramp.stages()
    assert (stage.frequency_hz, stage.frequency_end_hz, stage.duration_s) == (10.0, 130.0, 1.0)
    assert stage.amplitude_N == 2e3
    with pytest.raises(ValueError, match=r"\[sweep\] amplitude_N"):
        _case("sweep.amplitude_N='loud'")
    with pytest.raises(ValueError, match=r"\[sweep\] has unknown key"):
        _case("sweep.f_begin_hz=5.0")


def test_lumped_study_is_the_case_table():
    """[lumped] holds the lumped demo's study (docs/physics.md §7: LumpedStudy's defaults, the
    values of cases/lumped.toml); its quick case the short map; bad entries named."""
    from solver.reduced.study import LumpedStudy, read_study

    assert read_study(read_case("lumped")) == LumpedStudy() == read_study({})
    quick = read_study(read_case("lumped_quick"))
    assert (quick.duration_s, quick.n_frequencies, quick.n_amplitudes) == (2.0, 5, 3)
    assert quick.friction(0.2) == FrictionLaw(0.5, 0.2, math.inf)
    with pytest.raises(ValueError, match=r"\[lumped\] mu_d"):
        read_study({"lumped": {"mu_d": 0.9}})
    with pytest.raises(ValueError, match="n_amplitudes"):
        read_study({"lumped": {"n_amplitudes": 1}})
    InstallationCase.from_dict(read_case("lumped"))  # an installation run ignores the table


def test_ranked_stages_take_the_chosen_frequencies():
    schedule = Schedule.from_dicts(
        [
            dict(duration_s=0.1, frequency_hz=0.0, amplitude_N=0.0),
            dict(duration_s=0.1, frequency_hz="ranked 2", amplitude_N=3600.0),
            dict(duration_s=0.1, frequency_hz="mode 1", amplitude_N=100.0),
        ]
    )
    assert schedule.needs_modes and schedule.stages[1].ranked_number == 2
    chosen = [
        Excitation(68.0, "eccentric", "lead-in", 0, -1, -1, 0, "lead"),
        Excitation(90.0, 3600.0, "modal", 5, 3, 0, 2, "second"),
        Excitation(120.0, 3600.0, "modal", 7, 2, 1, 1, "first"),
        Excitation(105.0, 3600.0, "control", 0, -1, -1, 0, "control"),
    ]
    out = schedule_excitations(schedule, [11.0, 12.0], chosen)
    assert [e.frequency_Hz for e in out] == [0.0, 90.0, 11.0]  # rank 2 is the 90 Hz mode
    assert out[0].reason == "no vibration" and "second" in out[1].reason
    assert (out[1].m, out[1].n, out[1].amplitude_N) == (3, 0, 3600.0)


def test_imperfection_setting_gives_the_deviation_and_placement(shared_tmp):
    case = _case("imperfections.tp.amplitude_m=0.5e-3", "imperfections.tp.phase_deg=10.0")
    deviation = case.deviations()["tp"]
    theta = np.linspace(0, 2 * np.pi, 7)
    assert deviation(theta, 0.3 * np.ones(7)) == pytest.approx(
        0.5e-3 * np.cos(2 * (theta - math.radians(10.0)))
    )
    # a processed map file beside the case: read through geometry.imperfections
    comm = MPI.COMM_WORLD
    folder = shared_tmp
    path = f"{folder}/map.csv"
    if comm.rank == 0:
        rows = ["z_m,angle_deg,radial_deviation_m"]
        for z in (0.0, 1.4):
            rows += [
                f"{z},{a},{0.3e-3 * math.cos(math.radians(2 * a)):.9e}" for a in range(0, 360, 5)
            ]
        with open(path, "w") as f:
            f.write("\n".join(rows) + "\n")
    comm.barrier()
    from_file = _case(f"imperfections.tp.file='{path}'")
    dev = from_file.deviations()["tp"]
    assert dev(np.radians([0.0, 45.0, 90.0]), np.full(3, 0.7)) == pytest.approx(
        [0.3e-3, 0.0, -0.3e-3], abs=1e-9
    )
    # the TP is placed at first contact: 0.3 mm narrower at 90 deg -> higher by 0.3 mm / tan(alpha)
    joint = from_file.joint
    shift = tp_placement(joint, {"tp": ovality(0.3e-3)}) - joint.tp_offset
    assert shift == pytest.approx(0.3e-3 / math.tan(joint.mp.half_angle), rel=1e-3)


def test_dismount_case_sequence():
    from solver.installation.dismount import DismountPlan, dismount_case

    plan = DismountPlan(
        pull_N=30e3,
        ramp_s=0.05,
        hold_s=0.1,
        n_install=2,
        n_frequencies=3,
        stage_duration_s=0.1,
        amplitude_N=3600.0,
    )
    data = read_case("scaled", ["self_weight.ramp_time_s=2.0", "self_weight.hold_s=0.1"])
    dismount_case(data, plan)
    case = InstallationCase.from_dict(data)
    frequencies = [s.frequency_hz for s in case.schedule.stages]
    assert frequencies == ["ranked 1", "ranked 2", 0.0, 0.0, "ranked 1", "ranked 2", "ranked 3"]
    assert plan.roles() == ["install"] * 2 + ["pull ramp", "pull alone"] + ["pull + vibration"] * 3
    assert case.vibration.n_frequencies == max(
        3, read_case("scaled")["vibration"]["n_frequencies"]
    )  # raised, never lowered
    force = case.static_force.history(case.self_weight)
    t_sw = 2.1
    # self-weight held through the two installation stages, then ramped to the pull over 0.05 s
    assert force(t_sw + 0.2) == pytest.approx(-10e3)
    assert force(t_sw + 0.225) == pytest.approx(10e3)  # halfway from -10 to +30 kN
    assert force(t_sw + 0.25) == pytest.approx(30e3) and force(t_sw + 0.7) == pytest.approx(30e3)
    with pytest.raises(ValueError, match="positive"):
        DismountPlan(pull_N=-5e3)
    with pytest.raises(ValueError, match="n_install"):
        DismountPlan(n_install=-1)


def test_dismount_plan_is_the_case_table():
    """[dismount] holds the demo's sequence: DismountPlan's defaults where absent, checked with
    the case before any computation."""
    from solver.installation.dismount import DismountPlan, read_plan

    assert _case().dismount == DismountPlan() == read_plan(read_case("dismount"))
    quick = read_case("dismount_quick", ["dismount.pull_N=2e4"])
    plan = read_plan(quick)
    assert (plan.pull_N, plan.ramp_s, plan.stage_duration_s, plan.n_frequencies) == (
        2e4,
        0.004,
        0.004,
        1,
    )
    assert InstallationCase.from_dict(quick).dismount == plan
    with pytest.raises(ValueError, match=r"\[dismount\] has unknown key"):
        _case("dismount.pull=1e4")


def test_dismount_table_motion_and_separation():
    """Synthetic history: the TP goes up 0.5 mm in the pull stage but keeps contact, then
    rises 3 mm with zero normal force."""
    from solver.installation.dismount import dismount_table

    def row(stage, t, s, normal, contact):
        return {
            "stage": stage,
            "time_s": t,
            "settlement_mm": s,
            "normal_force_N": normal,
            "amplitude_N": 0.0,
            "axial_force_N": 0.0,
            "stick_fraction": contact,
            "slip_fraction": 0.0,
        }

    history = [row(0, 1.0, 5.0, 4e4, 0.2), row(1, 1.1, 4.5, 3e4, 0.1), row(2, 1.2, 1.5, 0.0, 0.0)]

    def stage(k, s0, s1, t0, t1):
        return {
            "stage": k,
            "start_s": t0,
            "end_s": t1,
            "frequency_Hz": 0.0,
            "settlement_start_mm": s0,
            "settlement_end_mm": s1,
        }

    stages = [
        stage(0, 0.0, 5.0, 0.0, 1.0),
        stage(1, 5.0, 4.5, 1.0, 1.1),
        stage(2, 4.5, 1.5, 1.1, 1.2),
    ]
    table = dismount_table(history, stages, ["pull ramp", "pull alone"], lambda t: 2e4)
    assert [r["axial_motion_mm"] for r in table] == pytest.approx([0.5, 3.0])
    assert [r["separated"] for r in table] == [False, True]
    assert table[0]["static_force_end_N"] == 2e4 and table[1]["open_fraction_end"] == 1.0


def test_parameter_study_summary_carries_the_sustained_rate():
    """A variant's summary row per stage: its whole gain and its rate over the second half
    (0.05 mm over 0.015 s = 3.333 mm/s), with the role of the stage's excitation."""
    from types import SimpleNamespace

    from solver.installation.parameter_study import SUMMARY_COLUMNS, summary_rows, variants

    stages = [
        {
            "stage": k,
            "name": name,
            "frequency_Hz": f,
            "amplitude_N": 3600.0,
            "start_s": t0,
            "end_s": t1,
            "settlement_start_mm": 0.0,
            "settlement_end_mm": gain,
            "gained_mm": gain,
            "gained_second_half_mm": half,
            "stick_slip_events": 1,
            "steps": 10,
            "wall_s": 1.0,
        }
        for k, name, f, t0, t1, gain, half in [
            (0, "self-weight", 0.0, 0.0, 2.1, 2.5, 0.9),
            (1, "vibration 1", 99.65, 2.1, 2.13, 0.6, 0.05),
        ]
    ]
    rows = summary_rows(variants(_case())[0], stages, [SimpleNamespace(role="control")], "done")
    assert all(list(r) == SUMMARY_COLUMNS for r in rows)
    assert [r["role"] for r in rows] == ["self-weight", "control"]
    assert rows[1]["gained_mm"] == 0.6
    assert rows[1]["sustained_rate_mm_s"] == pytest.approx(0.05 / 0.015)


def test_parameter_study_varies_one_thing_at_a_time():
    from solver.installation.parameter_study import select, variants

    base = _case()
    study = variants(base)
    assert study[0].value == "mu 0.5/0.4, d_c 100 s/m, rayleigh, 80 mm"
    assert variants(_case("friction.mu_s=0.6", "damping.model='modal'"))[0].value.startswith(
        "mu 0.6/0.4, d_c 100 s/m, modal"
    )
    assert [v.name for v in study][0] == "base" and study[0].overrides == ()
    changed = {}
    for v in study[1:]:
        case = _case(*v.overrides)
        diff = {
            name
            for name in ("friction", "damping", "mesh", "contact", "time", "vibration")
            if getattr(case, name) != getattr(base, name)
        }
        changed[v.parameter] = diff
    assert changed == {
        "friction": {"friction"},
        "d_c": {"friction"},
        "damping": {"damping"},
        "mesh size": {"mesh"},
    }
    low = _case(*study[1].overrides).friction
    assert (low.mu_s, low.mu_d) == (0.0625, 0.05)
    assert _case(*study[2].overrides).friction.d_c == 1.0
    assert _case(*study[4].overrides).mesh.axial_size == 0.5 * base.mesh.axial_size
    assert [v.name for v in select(study, ["slow_decay"])] == ["base", "slow_decay"]
    with pytest.raises(ValueError, match="unknown variant"):
        select(study, ["wet_friction"])


def test_quick_preset_is_the_tiny_mesh_with_the_coarse_contact(quick_case, coarse_case):
    """cases/quick.toml extends cases/coarse.toml: the landing contact settings on 12 x 0.2 m."""
    quick, coarse = quick_case(), coarse_case()
    assert quick.contact == coarse.contact and quick.friction == coarse.friction
    assert (quick.mesh.n_circumferential, quick.mesh.axial_size, quick.mesh.contact_axial_size) == (
        12,
        0.2,
        0.0,
    )
    assert quick.self_weight.ramp_time_s == 0.012 and not quick.output.paraview
