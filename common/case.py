"""Case files: a TOML file plus command-line overrides, checked before any computation.

A case is a nested dict of TOML tables: [geometry.mp], [geometry.tp], [material], [mesh],
[contact], [friction], [damping], [time], [self_weight], [vibration], [static_force], [dismount],
[output], [modal], [imperfections.mp], [imperfections.tp] and [[schedule]] (the tables an
installation case accepts, ``solver.installation.case.KNOWN_TABLES``; a modal case reads
the geometry, [material], [mesh] and [modal]). A case file may start from
another one: ``extends = "coarse"`` (a preset name in ``cases/``, or a path, looked up
beside the file first) takes that case and lays the file's own tables over it (a deep
merge of tables: the file wins key by key; arrays, also arrays of tables, are replaced
whole). Parents may extend further; an unknown parent or a cycle is an error.

Overrides use dotted keys, ``--set friction.mu_s=0.6 --set mesh.n_circumferential=24``;
the value is read as TOML (numbers, booleans, strings, arrays), and a bare word as a
string. Each table is turned into a typed object by its owner's ``from_dict`` through
:func:`construct`, which names the table and key of any problem.
"""

from __future__ import annotations

import copy
import tomllib
from dataclasses import fields
from pathlib import Path
from typing import Any

CASES_DIR = Path(__file__).resolve().parent.parent / "cases"
DEFAULT_CASE = CASES_DIR / "scaled.toml"


def presets() -> list[str]:
    """The names of the case files in ``cases/``."""
    return sorted(p.stem for p in CASES_DIR.glob("*.toml"))


def resolve_case_path(name: str | Path) -> Path:
    """A case file path, or the name of a file in ``cases/`` (``scaled``, ``coarse``, ...)."""
    path = Path(name)
    if path.is_file():
        return path
    preset = CASES_DIR / f"{path.stem}.toml"
    if preset.is_file():
        return preset
    raise ValueError(
        f"case file {str(name)!r} not found (and no preset of that name; presets: {presets()})"
    )


def _parent_path(child: Path, parent: Any) -> Path:
    """The file that ``extends = parent`` in ``child`` names: beside the child, else a preset."""
    if not isinstance(parent, str) or not parent:
        raise ValueError(f"{child}: extends must name a case (a preset or a file), got {parent!r}")
    for candidate in (child.parent / parent, child.parent / f"{parent}.toml"):
        if candidate.is_file():
            return candidate
    try:
        return resolve_case_path(parent)
    except ValueError:
        raise ValueError(
            f"{child}: extends {parent!r}, which is neither a file beside it nor a preset "
            f"(presets: {presets()})"
        ) from None


def merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    """``over`` laid over ``base`` (new dicts): tables merged key by key, anything else replaced."""
    out = copy.deepcopy(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def _load(path: Path, chain: tuple[Path, ...] = ()) -> dict[str, Any]:
    """The case of ``path`` with its ``extends`` chain resolved; ``chain``: the children."""
    resolved = path.resolve()
    if resolved in chain:
        cycle = " -> ".join(str(p) for p in (*chain, resolved))
        raise ValueError(f"{path}: extends forms a cycle: {cycle}")
    try:
        with path.open("rb") as f:
            data = tomllib.load(f)
    except tomllib.TOMLDecodeError as e:
        raise ValueError(f"{path}: invalid TOML: {e}") from None
    if "extends" not in data:
        return data
    parent = _parent_path(path, data.pop("extends"))
    return merge(_load(parent, (*chain, resolved)), data)


def read_case(
    name: str | Path = DEFAULT_CASE, overrides: list[str] | None = None
) -> dict[str, Any]:
    """Read a TOML case file (resolving ``extends``) and apply ``key.path=value`` overrides."""
    path = resolve_case_path(name)
    case = _load(path)
    for item in overrides or []:
        apply_override(case, item)
    case["_source"] = str(path)
    return case


def apply_override(case: dict[str, Any], item: str) -> None:
    """Set ``a.b.c=value`` in the nested dict ``case`` (in place)."""
    key, sep, text = item.partition("=")
    keys = key.strip().split(".")
    if not sep or not all(keys):
        raise ValueError(f"override {item!r} is not of the form section.key=value")
    try:
        value = tomllib.loads(f"v = {text.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = text.strip()
    table = case
    for k in keys[:-1]:
        table = table.setdefault(k, {})
        if not isinstance(table, dict):
            raise ValueError(f"override {item!r}: {k!r} is not a table")
    table[keys[-1]] = value


def construct(cls: type, data: dict[str, Any], name: str) -> Any:
    """``cls(**data)`` for a dataclass, with errors that name the table and the offending keys."""
    known = {f.name for f in fields(cls)}
    unknown = set(data) - known
    if unknown:
        raise ValueError(
            f"[{name}] has unknown key(s) {sorted(unknown)}; expected some of {sorted(known)}"
        )
    try:
        return cls(**copy.deepcopy(data))
    except TypeError as e:  # missing required keys or wrong types
        raise ValueError(f"[{name}] {e}") from None
    except ValueError as e:
        raise ValueError(f"[{name}] {e}") from None
