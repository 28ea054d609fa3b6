"""The pointwise contact law (solver/contact/law.py): the multipliers against their definition
(open, stick, slip) and the generalized derivative against finite differences."""

import numpy as np
import pytest

from solver.contact.law import derivative, multipliers


def _points(rng: np.random.Generator, n: int):
    """Random unit normals, trial tractions split into P_n and a tangential P_t, and mu."""
    normal = rng.normal(size=(n, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    P = rng.normal(size=(n, 3))
    P_n = np.einsum("pi,pi->p", P, normal)
    return normal, P_n, P - P_n[:, None] * normal, rng.uniform(0.1, 0.6, n)


def test_multipliers_open_stick_slip():
    normal = np.array([[0.0, 0.0, 1.0]] * 3)
    P_n = np.array([2.0, -2.0, -2.0])  # [Pa] open, then in contact
    P_t = np.array([[1.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.0, 3.0, 0.0]])
    mu = np.array([0.5, 0.5, 0.5])  # friction disk radius 1 Pa where in contact
    lam = multipliers(P_n, P_t, mu)
    assert list(lam.active) == [False, True, True]
    assert list(lam.stick) == [False, True, False]
    assert list(lam.slip) == [False, False, True]
    assert lam.normal == pytest.approx([0.0, -2.0, -2.0])
    assert lam.tangential == pytest.approx(np.array([[0, 0, 0], [0.5, 0, 0], [0, 1.0, 0]]))
    assert lam.vector(normal)[2] == pytest.approx([0.0, 1.0, -2.0])


def test_derivative_matches_finite_differences():
    rng = np.random.default_rng(3)
    normal, P_n, P_t, mu = _points(rng, 200)
    lam = multipliers(P_n, P_t, mu)
    D = derivative(normal, P_t, mu, -lam.normal, lam.stick, lam.slip)
    D[~lam.active] = 0.0
    h = 1e-7
    for k in range(3):
        step = np.zeros(3)
        step[k] = h
        values = []
        for sign in (1, -1):
            P = P_n[:, None] * normal + P_t + sign * step
            Pn = np.einsum("pi,pi->p", P, normal)
            shifted = multipliers(Pn, P - Pn[:, None] * normal, mu)
            values.append(shifted.vector(normal))
        fd = (values[0] - values[1]) / (2 * h)
        # away from the kinks (P_n = 0, |P_t| = mu p) the law is smooth
        far = (np.abs(P_n) > 1e-3) & (np.abs(np.linalg.norm(P_t, axis=1) + mu * P_n) > 1e-3)
        assert np.allclose(D[far, :, k], fd[far], atol=1e-6)
    assert lam.stick.any() and lam.slip.any() and (~lam.active).any()


def test_slip_derivative_has_the_slip_direction_as_null_vector():
    rng = np.random.default_rng(4)
    normal, P_n, P_t, mu = _points(rng, 50)
    P_n = -np.abs(P_n) - 0.1
    P_t *= 100.0  # far outside the friction disk: every point slips
    lam = multipliers(P_n, P_t, mu)
    assert lam.slip.all()
    D = derivative(normal, P_t, mu, -lam.normal, lam.stick, lam.slip)
    q = P_t / np.linalg.norm(P_t, axis=1)[:, None]
    assert np.abs(np.einsum("pij,pj->pi", D, q)).max() < 1e-12
