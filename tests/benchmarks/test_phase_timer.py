"""The phase timer's tally of the inner problem's linear algebra (``benchmarks/phase_timer.py``,
from ``common.timing.count``) against the traction Jacobian's own counters."""

import numpy as np

from benchmarks.phase_timer import PhaseTimer
from common.timing import recording
from solver.dynamics.traction_jacobian import TractionJacobian


def test_inner_tally_matches_the_jacobian_counters():
    rng = np.random.default_rng(5)
    n = 30
    G = rng.uniform(0.0, 1.0, (3 * n, 3 * n))
    G = 30.0 * G @ G.T / n
    jacobian = TractionJacobian()
    jacobian.set_compliance(G)
    timer = PhaseTimer()
    with recording(timer):
        for size in (20, 20, 19, 12):  # a factorisation, a reuse, an update, a renewal
            active = np.arange(size)
            D = np.tile(np.eye(3), (size, 1, 1)) * (1.0 + 0.01 * rng.normal(size=(size, 1, 1)))
            jacobian.solve(active, D, rng.normal(size=3 * size))
    assert jacobian.factorizations == 2 and jacobian.updates == 1
    assert dict(timer.inner) == {
        "factorisations": jacobian.factorizations,
        "factor rows": 3 * 20 + 3 * 12,  # D invertible: no kernel
        "updates": jacobian.updates,
        "krylov": jacobian.krylov_iterations,
    }
