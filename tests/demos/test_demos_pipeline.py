"""The installation pipeline with the demos' settings on the tiny joint (cases/tiny.toml: 12
around, 0.2 m, degree 2, frictionless, as in tests/solver/installation/test_install_pipeline.py; here 8 steps a
period, checkpoints every 50 steps, no ParaView files):

* an ovality of the TP set in ``[imperfections.tp]`` reaches the mesh: the TP's inner-surface
  nodes deviate from the nominal cone by A cos(2 (theta - phase)), and the TP is placed higher
  by A / tan(alpha) (it touches first where it is narrowest; closed form);
* a dismount pull through ``[static_force]``: the history's axial force is the piecewise-linear
  static force at every step, and without friction the pull lifts the TP off the MP (settlement
  decreases, the contact normal force drops to zero), which ``solver.installation.dismount`` reports.
"""

import math

import numpy as np
import pytest
from mpi4py import MPI

from common.case import read_case
from geometry import tags
from solver.installation.case import InstallationCase
from solver.installation.dismount import DismountPlan, dismount_case, dismount_table
from solver.installation.model import set_up_joint_model
from solver.installation.runner import Installation

pytestmark = pytest.mark.mpi

#: on the tiny joint: 8 steps a period, checkpoints every 50 steps, no ParaView files
PIPELINE = ["time.steps_per_period=8", "output.checkpoint_every=50", "output.paraview=false"]


def test_imperfection_reaches_the_mesh(tiny_case):
    amplitude, phase = 0.4e-3, 30.0
    case = tiny_case(
        *PIPELINE,
        f"imperfections.tp.amplitude_m={amplitude}",
        f"imperfections.tp.phase_deg={phase}",
    )
    model = set_up_joint_model(MPI.COMM_WORLD, case)
    joint, tp_z = case.joint, model.placed.tp_offset
    shift = tp_z - joint.tp_offset
    assert shift == pytest.approx(amplitude / math.tan(joint.mp.half_angle), rel=2e-3)
    mesh = model.mesh_data.mesh
    facets = model.mesh_data.facet_tags.find(tags.TP_CONTACT)
    mesh.topology.create_connectivity(2, 0)
    from dolfinx.mesh import entities_to_geometry

    nodes = np.unique(entities_to_geometry(mesh, 2, facets).ravel())
    x = mesh.geometry.x[nodes]
    theta = np.arctan2(x[:, 1], x[:, 0])
    deviation = np.hypot(x[:, 0], x[:, 1]) - joint.tp.inner_radius(x[:, 2] - tp_z)
    expected = amplitude * np.cos(2 * (theta - math.radians(phase)))
    local = float(np.max(np.abs(deviation - expected), initial=0.0))
    worst = MPI.COMM_WORLD.allreduce(local, op=MPI.MAX)
    print(f"\nTP placed {shift * 1e3:.4f} mm higher; node deviation error {worst * 1e9:.3g} nm")
    assert worst < 1e-9  # nodes moved exactly (to round-off) by the ovality
    assert model.settlement()["settlement_mm"] == pytest.approx(0.0, abs=1e-12)  # probes inside


def test_dismount_pull_lifts_the_frictionless_tp(shared_tmp):
    comm = MPI.COMM_WORLD
    out = shared_tmp
    plan = DismountPlan(pull_N=20e3, ramp_s=0.004, hold_s=0.016, n_frequencies=0)
    data = read_case("tiny", PIPELINE + ["vibration.modal_stage=false"])
    dismount_case(data, plan)
    case = InstallationCase.from_dict(data)
    runner = Installation(comm, case, out, progress=False)
    runner.run()
    static = runner.model.static
    for row in runner.history:  # no vibration: the axial force is the static history
        assert row["axial_force_N"] == pytest.approx(static(row["time_s"]), abs=1e-9)
    assert static(runner.history[-1]["time_s"]) == pytest.approx(20e3)
    table = dismount_table(runner.history, runner.stages, plan.roles(), static)
    s = [r["settlement_mm"] for r in runner.history]
    print(
        "\n"
        + "\n".join(
            f"{r['role']}: motion {r['axial_motion_mm']:+.4f} mm, normal force "
            f"{r['normal_force_end_N']:.1f} N, separated {r['separated']}"
            for r in table
        )
        + f"\nself-weight settlement {runner.stages[0]['settlement_end_mm']:.4f} mm, "
        f"final {s[-1]:.4f} mm"
    )
    assert runner.stages[0]["settlement_end_mm"] > 0  # installed first
    assert [r["role"] for r in table] == ["pull ramp", "pull alone"]
    hold = table[-1]
    assert hold["axial_motion_mm"] > 0  # the TP moved up while the pull acted alone
    assert s[-1] < runner.stages[0]["settlement_end_mm"]  # above where the self-weight put it
    assert hold["normal_force_end_N"] == 0.0 and hold["open_fraction_end"] == 1.0
    assert hold["separated"]
