"""Coulomb block: a block pressed on a base and dragged sideways (displacement control).

The horizontal reaction T of the dragged face (from the bulk stress, independent of the
contact module's own tractions) grows while the block sticks and levels off at mu N once
the whole interface slides. With the velocity law the plateau follows mu(v) at the
imposed sliding speed v = slide per step / dt.
"""

from mpi4py import MPI

import numpy as np
import pytest

from contact_cases import sliding_block
from solver.contact import FrictionLaw

pytestmark = pytest.mark.mpi


def test_stick_then_slide_at_mu_s():
    friction = FrictionLaw(mu_s=0.3, mu_d=0.3, d_c=0.0)
    history, _, results, _ = sliding_block(
        MPI.COMM_WORLD, friction, steps=8, slide_per_step=2e-4, dt=None
    )
    assert all(r.converged for r in results), [r.message for r in results]
    ratio, stick, slip = history.T
    # first step: well below the threshold, the interface mostly sticks (slip only at the edges)
    assert ratio[0] < 0.6 * friction.mu_s and stick[0] > 0.3
    # the load never exceeds the static threshold; once everything slides it equals mu_s N
    assert ratio.max() <= friction.mu_s * 1.01
    assert slip[-1] == pytest.approx(1.0)
    assert ratio[-1] == pytest.approx(friction.mu_s, rel=1e-2)


@pytest.mark.parametrize("dt, lagged", [(1.0, False), (0.5, True)])
def test_sliding_force_follows_velocity_law(dt, lagged):
    """Implicit mu(|v|) with its consistent derivative, and mu lagged by one step."""
    friction = FrictionLaw(mu_s=0.5, mu_d=0.4, d_c=5000.0)
    slide = 2e-4
    history, contact, results, _ = sliding_block(
        MPI.COMM_WORLD, friction, steps=10, slide_per_step=slide, dt=dt, lagged=lagged
    )
    assert all(r.converged for r in results), [r.message for r in results]
    mu_v = friction.coefficient(slide / dt)
    assert friction.mu_d < mu_v < friction.mu_s
    assert history[-1, 0] == pytest.approx(mu_v, rel=1e-2)
    assert history[-2, 0] == pytest.approx(mu_v, rel=1e-2)


def test_distributed_equals_serial():
    """The whole sliding history is the same on all ranks' mesh and on an undistributed copy."""
    friction = FrictionLaw(mu_s=0.5, mu_d=0.4, d_c=5000.0)
    distributed, *_ = sliding_block(MPI.COMM_WORLD, friction, steps=4, slide_per_step=2e-4, dt=1.0)
    serial, *_ = sliding_block(MPI.COMM_SELF, friction, steps=4, slide_per_step=2e-4, dt=1.0)
    assert np.allclose(distributed, serial, rtol=1e-8, atol=1e-10)


def test_contact_at_the_top_of_the_slave_surface_is_detected():
    """touches_top: the pressed block touches within the margin of the slave surface's highest
    point (along x here), and ContactZoneGuard then stops a run; lifted off (all open) neither."""
    from types import SimpleNamespace

    import dolfinx

    from solver.installation.observers import ContactZoneGuard, touches_top

    _, contact, results, u = sliding_block(
        MPI.COMM_WORLD,
        FrictionLaw(mu_s=0.3, mu_d=0.3, d_c=0.0),
        steps=1,
        slide_per_step=0.0,
        dt=None,
    )
    assert results[0].converged
    guard = ContactZoneGuard(contact, margin=0.05, zone_above=0.15)
    assert touches_top(contact, 0.05, axis=0)
    with pytest.raises(RuntimeError, match="contact_zone_above"):
        guard(SimpleNamespace(t=1.0))
    lifted = dolfinx.fem.Function(u.function_space)
    lifted.x.array[:] = -u.x.array  # the block lifted off the base as far as it was pressed in
    contact.update(lifted)
    assert not touches_top(contact, 0.05, axis=0)
    assert guard(SimpleNamespace(t=1.0)) == {}
