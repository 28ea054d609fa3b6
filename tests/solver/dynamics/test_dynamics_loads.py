"""Loads and schedules: eccentric law, continuous phase, ramps, total force on a tube, bad input."""

import math

import numpy as np
import pytest
from mpi4py import MPI
from scipy.integrate import quad

from dolfinx import fem

from geometry import tags
from geometry.mesh import create_tube_mesh
from geometry.parameters import ConePart, MeshOptions
from solver.dynamics.loads import (
    PointLoad,
    RampedAxialForce,
    Schedule,
    Stage,
    TopFaceLoad,
    TPLoading,
    eccentric_amplitude,
    shaker_point,
)

pytestmark = pytest.mark.mpi

TP = ConePart(
    half_angle_deg=1.0,
    bottom_outer_diameter=0.61,
    cone_length=1.0,
    straight_length=0.4,
    thickness=0.006,
    straight_part="above",
)


def test_eccentric_law():
    # docs/physics.md §3: F = 2 m_e r (2 pi f)^2 = 0.3632 f^2 N; 3.6 kN at 100 Hz
    assert eccentric_amplitude(100.0) == pytest.approx(3632.0)
    assert eccentric_amplitude(68.0) == pytest.approx(0.3632 * 68.0**2)
    stage = Stage(duration_s=0.1, frequency_hz=50.0, frequency_end_hz=150.0)
    assert stage.amplitude(0.05) == pytest.approx(
        0.3632 * 100.0**2
    )  # at the instantaneous frequency


def test_self_weight_ramp():
    ramp = RampedAxialForce(force_N=-10e3, ramp_time_s=2.0)
    assert [ramp(t) for t in (-1.0, 0.0, 0.5, 2.0, 5.0)] == pytest.approx(
        [0, 0, -2.5e3, -10e3, -10e3]
    )


def reference_schedule() -> Schedule:
    stages = [
        dict(duration_s=0.1, frequency_hz=68.0),
        dict(duration_s=0.1, frequency_hz=100.0),
        dict(duration_s=0.37, frequency_hz=10.0, frequency_end_hz=125.0, amplitude_N=3600.0),
        dict(
            duration_s=0.2,
            frequency_hz=120.0,
            amplitude_N=1000.0,
            amplitude_end_N=3000.0,
            direction="both",
            lateral_fraction=0.05,
        ),
    ]
    return Schedule.from_dicts(stages, start_s=2.0)


def test_phase_is_the_integral_of_the_frequency_and_continuous():
    schedule = reference_schedule()
    for t in np.linspace(2.0, schedule.end_s, 23):
        expected, _ = quad(
            lambda s: 2 * math.pi * schedule.frequency(s),
            2.0,
            t,
            points=schedule.stage_starts,
            limit=200,
            epsabs=1e-11,
        )
        assert schedule.phase(t) == pytest.approx(expected, abs=1e-8)
    for t_k in schedule.stage_starts[1:]:  # no jump at stage boundaries, even where f jumps
        assert abs(schedule.phase(t_k + 1e-12) - schedule.phase(t_k - 1e-12)) < 1e-8
    # the force oscillates at the instantaneous frequency: zero crossings of the 100 Hz stage
    t100 = schedule.stage_starts[1]
    assert math.sin(schedule.phase(t100)) == pytest.approx(
        math.sin(2 * math.pi * 68.0 * 0.1), abs=1e-12
    )


def test_schedule_force_directions_and_ramps():
    schedule = reference_schedule()
    assert np.all(schedule.force(1.0) == 0) and np.all(schedule.force(schedule.end_s + 0.1) == 0)
    t = schedule.stage_starts[3] + 0.1  # mid-ramp of the last stage
    force = schedule.force(t)
    assert schedule.amplitude(t) == pytest.approx(2000.0)
    assert force[2] == pytest.approx(2000.0 * math.sin(schedule.phase(t)))
    assert force[0] == pytest.approx(0.05 * force[2]) and force[1] == 0.0


def test_mode_frequencies_are_filled_in():
    schedule = Schedule.from_dicts(
        [dict(duration_s=0.1, frequency_hz="mode 2", amplitude_N=3600.0)]
    )
    with pytest.raises(ValueError, match="natural frequencies"):
        schedule.force(0.05)
    filled = schedule.with_natural_frequencies([80.0, 120.0])
    assert filled.frequency(0.05) == 120.0
    with pytest.raises(ValueError, match="mode 2"):
        schedule.with_natural_frequencies([80.0])


@pytest.mark.parametrize(
    "stage, match",
    [
        (dict(duration_s=-0.1, frequency_hz=10.0), "duration_s"),
        (dict(duration_s=0.1, frequency_hz=-10.0), "frequency_hz"),
        (dict(duration_s=0.1, frequency_hz="fast"), "frequency_hz"),
        (dict(duration_s=0.1, frequency_hz=10.0, amplitude_N="big"), "amplitude_N"),
        (dict(duration_s=0.1, frequency_hz=10.0, amplitude_end_N=5.0), "eccentric"),
        (dict(duration_s=0.1, frequency_hz=10.0, direction="sideways"), "direction"),
        (dict(duration_s=0.1, frequency_hz=10.0, lateral_fraction=2.0), "lateral_fraction"),
        (dict(duration_s=0.1, frequency_hz=10.0, frequncy_end_hz=20.0), "unknown key"),
        (dict(frequency_hz=10.0), "duration_s"),
    ],
)
def test_bad_schedules_raise(stage, match):
    with pytest.raises(ValueError, match=match):
        Schedule.from_dicts([stage])


def test_empty_schedule_raises():
    with pytest.raises(ValueError, match="at least one stage"):
        Schedule.from_dicts([])


@pytest.fixture(scope="module")
def tube():
    data = create_tube_mesh(MPI.COMM_WORLD, TP, MeshOptions(n_circumferential=8, axial_size=0.5))
    V = fem.functionspace(data.mesh, ("Lagrange", 2, (3,)))
    x = fem.Function(V)
    x.interpolate(lambda p: p)  # nodal coordinates, to take moments
    return V, data.facet_tags, x


def resultant(V, x, vec):
    """Total force and moment about the origin of a nodal load vector (owned entries)."""
    n = V.dofmap.index_map.size_local * 3
    f = vec.array_r[:n].reshape(-1, 3)
    r = x.x.array[:n].reshape(-1, 3)
    comm = V.mesh.comm
    return comm.allreduce(f.sum(axis=0)), comm.allreduce(np.cross(r, f).sum(axis=0))


def test_top_face_load_integrates_to_the_requested_force(tube):
    V, facet_tags, x = tube
    top = TopFaceLoad(V, facet_tags, tags.TOP)
    r_o, r_i = TP.outer_radius(TP.total_length), TP.inner_radius(TP.total_length)
    assert top.area == pytest.approx(math.pi * (r_o**2 - r_i**2), rel=2e-3)  # curved hex27 annulus
    loading = TPLoading(
        top,
        static_axial=RampedAxialForce(-10e3, 2.0),
        schedule=Schedule([Stage(0.1, 100.0, direction="lateral")], start_s=2.0),
    )
    vec = fem.petsc.create_vector(V)
    for t in (1.0, 2.0 + 0.3 / 400):  # during the ramp; during the shaking
        vec.set(0.0)
        loading(t, vec)
        force, moment = resultant(V, x, vec)
        assert force == pytest.approx(loading.force_on_top(t), abs=1e-9 * 1e4)
        # uniform traction on an axisymmetric annulus at height H acts through the axis
        H = TP.total_length
        expected = np.cross([0.0, 0.0, H], loading.force_on_top(t))
        assert moment == pytest.approx(expected, abs=1e-6 * 1e4)


def test_point_load_acts_at_the_point(tube):
    V, facet_tags, x = tube
    p = shaker_point(TP, 0.0, 1.2, 30.0)
    point = PointLoad(V, p)
    F = np.array([120.0, -40.0, 15.0])
    vec = fem.petsc.create_vector(V)
    vec.set(0.0)
    point.add(F, vec)
    force, moment = resultant(V, x, vec)
    assert force == pytest.approx(F, rel=1e-12)
    assert moment == pytest.approx(np.cross(p, F), rel=1e-9)


def test_point_outside_the_body_raises(tube):
    V, facet_tags, x = tube
    with pytest.raises(ValueError, match="outside"):
        PointLoad(V, [0.0, 0.0, 0.5])  # on the axis: inside the tube's hole
    with pytest.raises(ValueError, match="outside the part"):
        shaker_point(TP, 0.0, 2.0, 0.0)
