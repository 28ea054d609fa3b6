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


def _write(folder, name: str, text: str):
    path = folder / f"{name}.toml"
    path.write_text(text)
    return path


def test_extends_merges_tables_and_the_child_wins(tmp_path):
    _write(
        tmp_path,
        "parent",
        'extends = "scaled"\n[mesh]\nn_circumferential = 16\n'
        "[vibration]\nlead_in_hz = [1.0, 2.0]\n[[schedule]]\nduration_s = 1.0\nfrequency_hz = 5.0\n",
    )
    child = _write(
        tmp_path,
        "child",
        'extends = "parent"\n[mesh]\naxial_size = 0.5\n[vibration]\nlead_in_hz = [3.0]\n',
    )
    case = read_case(child, ["mesh.n_layers=2"])
    scaled = read_case("scaled")
    assert "extends" not in case and case["_source"] == str(child)
    assert case["mesh"] == {
        **scaled["mesh"],
        "n_circumferential": 16,
        "axial_size": 0.5,
        "n_layers": 2,
    }
    assert case["vibration"]["lead_in_hz"] == [3.0]  # arrays are replaced whole
    assert case["vibration"]["n_modes"] == scaled["vibration"]["n_modes"]
    assert case["schedule"] == [{"duration_s": 1.0, "frequency_hz": 5.0}]
    assert case["geometry"] == scaled["geometry"] and case["friction"] == scaled["friction"]


def test_presets_extend_presets():
    scaled, coarse = read_case("scaled"), read_case("coarse")
    assert coarse["mesh"]["n_circumferential"] == 8 and coarse["contact"]["theta"] == -1
    assert coarse["contact"]["solver"] == "zone" and scaled["contact"]["solver"] == "points"
    assert coarse["friction"] == scaled["friction"] and coarse["time"] == scaled["time"]
    quick = read_case("install_quick")
    assert quick["friction"]["mu_s"] == 0.0 and quick["contact"] == scaled["contact"]
    assert read_case("scaled_full")["vibration"]["n_frequencies"] == 10


def test_extends_errors(tmp_path):
    unknown = _write(tmp_path, "orphan", 'extends = "no_such_parent"\n')
    with pytest.raises(ValueError, match="orphan.toml: extends 'no_such_parent'.*presets"):
        read_case(unknown)
    _write(tmp_path, "a", 'extends = "b"\n')
    b = _write(tmp_path, "b", 'extends = "a.toml"\n')
    with pytest.raises(ValueError, match="cycle"):
        read_case(b)
    itself = _write(tmp_path, "self", 'extends = "self"\n')
    with pytest.raises(ValueError, match="cycle"):
        read_case(itself)
    wrong = _write(tmp_path, "wrong", "extends = 3\n")
    with pytest.raises(ValueError, match="extends must name a case"):
        read_case(wrong)
