"""The package layout as a map of the design: lower layers never import higher ones.

Layers, lowest first: ``common``; ``geometry``; ``solver``'s own modules (elasticity,
probes); ``solver.contact``; ``solver.dynamics``; ``solver.post``; ``solver.modal`` and
``solver.reduced`` (side by side, neither imports the other); ``solver.installation``.
A module may import its own layer's package and lower layers (checked on every import
statement, also those inside functions)."""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LAYERS = {
    "common": 0,
    "geometry": 1,
    "solver": 2,
    "solver.contact": 3,
    "solver.dynamics": 4,
    "solver.post": 5,
    "solver.modal": 6,
    "solver.reduced": 6,
    "solver.installation": 7,
}


def package_of(module: str) -> str | None:
    """The layered package a dotted module name belongs to (the longest prefix in LAYERS)."""
    parts = module.split(".")
    for n in range(len(parts), 0, -1):
        name = ".".join(parts[:n])
        if name in LAYERS:
            return name
    return None


def imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def modules() -> list[Path]:
    return sorted(p for d in ("common", "geometry", "solver") for p in (ROOT / d).rglob("*.py"))


@pytest.mark.parametrize("path", modules(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_module_imports_a_higher_layer(path):
    own = package_of(".".join(path.relative_to(ROOT).with_suffix("").parts))
    wrong = sorted(
        name
        for name in imports(path)
        if (other := package_of(name)) is not None and other != own and LAYERS[other] >= LAYERS[own]
    )
    assert not wrong, f"{path.relative_to(ROOT)} ({own}) imports higher or sibling layers: {wrong}"


def test_no_module_is_longer_than_about_500_lines():
    long = {
        str(p.relative_to(ROOT)): n
        for p in modules()
        if (n := len(p.read_text().splitlines())) > 520
    }
    assert not long, f"modules over 500 lines: {long}"
