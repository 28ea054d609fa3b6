"""The case of an installation run: every table of a case file, checked as a whole before
anything is computed (:meth:`InstallationCase.from_dict`)."""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from common.case import construct
from common.material import Material
from geometry.contact_map import tp_placement
from geometry.imperfections import RadialDeviation
from geometry.parameters import JointGeometry, MeshOptions, geometry_from_tables
from solver.contact import FrictionLaw
from solver.dynamics.loads import Schedule
from solver.dynamics.schemes import Scheme, scheme_from_name
from solver.dynamics.time_loop import check_event_step
from solver.installation.dismount import DismountPlan
from solver.installation.planning import check_time_scheme
from solver.installation.sweep import SweepPlan
from solver.installation.settings import (
    ContactSettings,
    DampingSettings,
    ImperfectionSettings,
    OutputSettings,
    SelfWeightSettings,
    StaticForceSettings,
    TimeSettings,
    VibrationSettings,
)


SECTIONS = {
    "contact": ContactSettings,
    "dismount": DismountPlan,
    "damping": DampingSettings,
    "time": TimeSettings,
    "self_weight": SelfWeightSettings,
    "vibration": VibrationSettings,
    "output": OutputSettings,
    "static_force": StaticForceSettings,
    "sweep": SweepPlan,
}
KNOWN_TABLES = {
    "imperfections",
    "geometry",
    "material",
    "mesh",
    "friction",
    "schedule",
    "modal",
    "lumped",
    "_source",
    *SECTIONS,
}


@dataclass(frozen=True)
class InstallationCase:
    """Everything an installation run reads from a case (validated on construction)."""

    joint: JointGeometry
    material: Material
    mesh: MeshOptions
    friction: FrictionLaw
    contact: ContactSettings
    damping: DampingSettings
    time: TimeSettings
    self_weight: SelfWeightSettings
    vibration: VibrationSettings
    output: OutputSettings
    static_force: StaticForceSettings
    dismount: DismountPlan  #: the sequence demos/dismount.py writes into the case
    sweep: SweepPlan  #: the sweep demos/sweep.py writes into the case
    schedule: Schedule | None  #: explicit [[schedule]] (start time 0: shifted after self-weight)
    source: str = "case"
    imperfections: dict[str, ImperfectionSettings] = field(default_factory=dict)

    @classmethod
    def from_dict(cls, case: dict[str, Any]) -> InstallationCase:
        """Check every table of ``case`` (``read_case``); a ValueError names the problem."""
        source = case.get("_source", "case")
        try:
            unknown = set(case) - KNOWN_TABLES
            if unknown:
                raise ValueError(
                    f"unknown table(s) {sorted(unknown)}; "
                    f"expected some of {sorted(KNOWN_TABLES - {'_source'})}"
                )
            joint, material, mesh = geometry_from_tables(case)
            settings = {}
            for name, kind in SECTIONS.items():
                data = dict(case.get(name, {}))
                if not isinstance(case.get(name, {}), dict):
                    raise ValueError(f"[{name}] must be a table")
                if "lead_in_hz" in data:
                    data["lead_in_hz"] = tuple(data["lead_in_hz"])
                settings[name] = construct(kind, data, name)
            friction = construct(FrictionLaw, dict(case.get("friction", {})), "friction")
            schedule = Schedule.from_dicts(case["schedule"]) if "schedule" in case else None
            vib = settings["vibration"]
            if schedule is not None:
                for i, s in enumerate(schedule.stages):
                    if s.mode_number is not None and s.mode_number > vib.n_modes:
                        raise ValueError(
                            f"schedule stage {i + 1} asks for mode {s.mode_number} but the modal "
                            f"stage computes {vib.n_modes} (vibration.n_modes)"
                        )
                    if s.ranked_number is not None and s.ranked_number > vib.n_frequencies:
                        raise ValueError(
                            f"schedule stage {i + 1} asks for ranked {s.ranked_number} but "
                            f"{vib.n_frequencies} ranked frequencies are chosen "
                            "(vibration.n_frequencies)"
                        )
            if not vib.modal_stage and (schedule is None or schedule.needs_modes):
                raise ValueError(
                    "vibration.modal_stage = false needs a [[schedule]] without 'mode k' or "
                    "'ranked k' stages (the automatic schedule comes from the modal stage)"
                )
            check_time_scheme(settings["time"], settings["damping"])
            sw, smallest = settings["self_weight"], settings["time"].dt_min_fraction
            if sw.event_dt_s and settings["contact"].lu_solver == "superlu_dist":
                raise ValueError(
                    '[contact] lu_solver = "superlu_dist" with event steps ([self_weight] '
                    f"event_dt_s = {sw.event_dt_s} s): SuperLU_DIST crashes in the first "
                    "vibration stage after the event steps' operator is freed (docs/install.md, "
                    'design decisions). Use lu_solver = "mumps" or "auto", or event_dt_s = 0'
                )
            if sw.event_dt_s:
                try:
                    check_event_step(sw.dt_s, sw.event_dt_s, smallest * sw.dt_s)
                except ValueError as error:
                    raise ValueError(
                        f"[self_weight] event_dt_s = {sw.event_dt_s} s: {error} "
                        "([self_weight] dt_s, dt_s * time.dt_min_fraction)"
                    ) from None
            imperfections = _imperfections(case, joint)
            if vib.forcing == "shaker" and not 0 <= vib.shaker_height_m <= joint.tp.total_length:
                raise ValueError(
                    f"[vibration] shaker_height_m = {vib.shaker_height_m} m lies outside the TP "
                    f"(0 .. {joint.tp.total_length} m)"
                )
        except ValueError as e:
            raise ValueError(f"{source}: {e}") from None
        return cls(
            joint,
            material,
            mesh,
            friction,
            schedule=schedule,
            source=source,
            imperfections=imperfections,
            **settings,
        )

    def vibration_scheme(self) -> Scheme:
        """The time scheme of the vibration stages ([time])."""
        return scheme_from_name(self.time.scheme, self.time.rho_inf)

    def self_weight_scheme(self) -> Scheme:
        """The time scheme of the self-weight stage ([self_weight] scheme, else [time]'s)."""
        sw = self.self_weight
        return scheme_from_name(sw.scheme, sw.rho_inf) if sw.scheme else self.vibration_scheme()

    def deviations(self) -> dict[str, RadialDeviation]:
        """The radial deviations of the imperfect parts (``geometry.imperfections``)."""
        case_dir = Path(self.source).parent
        return {
            name: setting.deviation(getattr(self.joint, name), case_dir)
            for name, setting in self.imperfections.items()
        }

    def describe(self) -> dict[str, Any]:
        """The resolved case as plain data: every table with its defaults filled in, the
        [[schedule]] stages and the case file (written to the output folder as case.json)."""
        out = {
            "source": self.source,
            "geometry": asdict(self.joint),
            "material": asdict(self.material),
            "mesh": asdict(self.mesh),
            "friction": asdict(self.friction),
            **{name: asdict(getattr(self, name)) for name in SECTIONS},
            "schedule": None
            if self.schedule is None
            else [asdict(s) for s in self.schedule.stages],
            "imperfections": {k: asdict(v) for k, v in self.imperfections.items()},
        }
        return json.loads(json.dumps(out))

    def fingerprint(self) -> dict[str, Any]:
        """Dotted key -> value of everything that decides the computed result: the resolved case
        without the case file's name, the demos' plans (``DEMO_PLANS``), the output-only keys
        (``OUTPUT_ONLY``) and the imperfection files' names, whose content counts instead
        (``imperfections.<part>.file_sha256``)."""
        skipped = ("source", *DEMO_PLANS)
        flat = flatten({k: v for k, v in self.describe().items() if k not in skipped})
        for key in OUTPUT_ONLY:
            flat.pop(key)
        case_dir = Path(self.source).parent
        for name, setting in self.imperfections.items():
            path = setting.path(case_dir)
            if path is not None:
                flat.pop(f"imperfections.{name}.file")
                flat[f"imperfections.{name}.file_sha256"] = hashlib.sha256(
                    path.read_bytes()
                ).hexdigest()
        return flat


#: keys that change only what a run writes, not what it computes: a resumed run may differ in them
OUTPUT_ONLY = ("output.paraview", "output.plots")
#: tables that the installation run does not read (the demos' plans, which they write into the
#: [static_force] and [[schedule]] tables it reads): not in the fingerprint, so that an installed
#: state serves any dismount plan
DEMO_PLANS = ("dismount", "sweep")


def flatten(data: Any, prefix: str = "") -> dict[str, Any]:
    """Nested tables and lists of tables -> {dotted key: value} (list items as ``key[k]``, k from 1)."""
    if isinstance(data, dict):
        out = {}
        for key, value in data.items():
            out.update(flatten(value, f"{prefix}.{key}" if prefix else str(key)))
        return out
    if isinstance(data, list) and data and all(isinstance(item, dict) for item in data):
        out = {}
        for k, item in enumerate(data, start=1):
            out.update(flatten(item, f"{prefix}[{k}]"))
        return out
    return {prefix: data}


def case_differences(old: dict[str, Any], new: dict[str, Any]) -> list[str]:
    """``key: old -> new`` for every dotted key whose value differs between two fingerprints
    (``-`` where one of them lacks the key)."""
    lines = []
    for key in sorted(set(old) | set(new)):
        a, b = old.get(key, "-"), new.get(key, "-")
        if a != b:
            lines.append(f"{key}: {a} -> {b}")
    return lines


def _imperfections(case: dict[str, Any], joint: JointGeometry) -> dict[str, ImperfectionSettings]:
    """The ``[imperfections]`` tables, checked (files read) and placed (first contact found)."""
    table = case.get("imperfections", {})
    if not isinstance(table, dict) or set(table) - {"mp", "tp"}:
        raise ValueError(
            "[imperfections] must hold the tables [imperfections.mp] and/or [imperfections.tp]"
        )
    settings = {
        name: construct(ImperfectionSettings, dict(data), f"imperfections.{name}")
        for name, data in table.items()
    }
    case_dir = Path(case.get("_source", ".")).parent
    deviations = {}
    for name, setting in settings.items():
        try:
            deviations[name] = setting.deviation(getattr(joint, name), case_dir)
        except ValueError as e:
            raise ValueError(f"[imperfections.{name}] {e}") from None
    if deviations:
        try:
            tp_placement(joint, deviations)
        except ValueError as e:
            raise ValueError(f"[imperfections] {e}") from None
    return settings
