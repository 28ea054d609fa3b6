"""Case files and command-line overrides: values land where they should, bad input is named."""

import pytest

from common.case import apply_override, construct, read_case
from solver.contact import FrictionLaw


def test_presets_resolve_and_overrides_apply():
    case = read_case("scaled", ["mesh.n_circumferential=24", "friction.mu_s=0.3", "run.name=abc"])
    assert case["mesh"]["n_circumferential"] == 24
    assert case["friction"]["mu_s"] == 0.3
    assert case["run"]["name"] == "abc"
    assert case["_source"].endswith("scaled.toml")


def test_bad_override_and_missing_case():
    with pytest.raises(ValueError, match="section.key=value"):
        apply_override({}, "mesh.n_circumferential")
    with pytest.raises(ValueError, match="not found"):
        read_case("no_such_case")


def test_construct_names_table_and_key():
    with pytest.raises(ValueError, match=r"\[friction\] has unknown key\(s\) \['mu_x'\]"):
        construct(FrictionLaw, {"mu_x": 0.1}, "friction")
    with pytest.raises(ValueError, match=r"\[friction\] mu_d"):
        construct(FrictionLaw, {"mu_s": 0.1, "mu_d": 0.2}, "friction")
    assert construct(FrictionLaw, {"mu_s": 0.6}, "friction").mu_s == 0.6
