"""The friction law mu(v) against its closed form and its derivative."""

import numpy as np
import pytest

from solver.contact import FrictionLaw


def test_limits_and_decay():
    law = FrictionLaw(mu_s=0.5, mu_d=0.4, d_c=100.0)
    assert law.coefficient(0.0) == pytest.approx(0.5)
    assert law.coefficient(1.0) == pytest.approx(0.4 + 0.1 * np.exp(-100.0))
    assert law.coefficient(-0.01) == pytest.approx(0.4 + 0.1 * np.exp(-1.0))


def test_derivative_matches_finite_difference():
    law = FrictionLaw(mu_s=0.5, mu_d=0.4, d_c=100.0)
    v, h = 0.003, 1e-7
    fd = (law.coefficient(v + h) - law.coefficient(v - h)) / (2 * h)
    assert law.derivative(v) == pytest.approx(fd, rel=1e-6)


@pytest.mark.parametrize(
    "kwargs", [dict(mu_s=0.3, mu_d=0.4), dict(d_c=-1.0), dict(mu_s=-0.1, mu_d=-0.2)]
)
def test_bad_parameters_raise(kwargs):
    with pytest.raises(ValueError):
        FrictionLaw(**kwargs)
