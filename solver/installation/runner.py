"""Vibration-assisted installation of the slip-joint: model set-up and the staged run (SPEC 3, 5).

Stages of :class:`Installation`:

1. ``self-weight``: axial force on the TP top ramped 0 -> ``force_N`` over ``ramp_time_s``,
   then held for ``hold_s`` (dynamic by default); the TP settles in stick-slip steps.
2. ``modal``: natural frequencies of the settled joint, with the contact tangent at the
   settled status (``solver.modal.interface.ContactInterface``), ranked by
   ``solver.modal.ranking.describe_modes``; the excitation frequencies are chosen from the
   ranking (see :func:`choose_frequencies`), each with its reason.
3. ``vibration``: the harmonic schedule (lead-in stages, the chosen natural frequencies and
   a non-modal control frequency, or an explicit ``[[schedule]]``) on top of the held force.
4. the report (``solver.post.report``): settlement per stage, stick-slip events, contact status.

Settlement is ``solver.dynamics.elastodynamics.Settlement``: the axial slide [mm] of the TP's lower edge
relative to the MP wall beside it, positive down. After the self-weight stage the static axial
force may follow a piecewise-linear history (``[static_force]``, e.g. a dismount pull), and the
cones may carry radial imperfections (``[imperfections.mp]``, ``[imperfections.tp]``: ovality or
a measured map/scan file, ``geometry.imperfections``). All settings come from a case file
(tables below the geometry ones), checked as a whole by :meth:`InstallationCase.from_dict`
before anything is computed. SI units; frequencies in Hz, forces in N.
"""

from __future__ import annotations

import json
import sys
import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from common import backend  # noqa: F401  (before dolfinx/petsc4py)

import numpy as np
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from geometry import tags
from geometry.contact_map import tp_placement
from geometry.imperfections import RadialDeviation, ovality, read_imperfection
from geometry.mesh import create_joint_mesh
from geometry.parameters import JointGeometry, MeshOptions, geometry_from_case
from solver.installation import checkpoint
from solver.post import report
from common.case import construct
from solver.contact import FrictionLaw, NitscheContact, Status
from solver.dynamics.damping import ModalDamping, RayleighDamping
from solver.dynamics.elastodynamics import ContactZoneGuard, Elastodynamics, Settlement, StepResult, assemble_structure, run
from common.material import Material
from solver.dynamics.loads import (
    PiecewiseLinearForce,
    PointLoad,
    RampedAxialForce,
    Schedule,
    Stage,
    TopFaceLoad,
    TPLoading,
    shaker_point,
)
from solver.modal.eigen import EigenOptions, ModalResult, clamp, modal_analysis
from solver.modal.interface import ContactInterface, bonded_band
from solver.modal.ranking import JointParts, ModeRecord, describe_modes, write_csv, write_outputs
from solver.dynamics.schemes import scheme_from_name

SURFACES = ("TP_CONTACT", "MP_CONTACT")
FORCINGS = ("eccentric", "face", "shaker")


def _check_choice(name: str, value: Any, choices) -> None:
    if value not in choices:
        raise ValueError(f"{name} must be one of {tuple(choices)}, got {value!r}")


@dataclass(frozen=True)
class ContactSettings:
    """``[contact]``: Nitsche contact of the TP (slave) on the MP (master)."""

    slave: str = "TP_CONTACT"
    master: str = "MP_CONTACT"
    gamma0: float = 10.0  #: Nitsche parameter [-]
    theta: int = 1  #: 1 symmetric, 0 non-symmetric, -1 skew (the modal stage always uses 1)
    lagged_friction: bool = False
    degree: int = 2  #: Lagrange degree of the displacement
    max_iterations: int = 30  #: Newton iterations per step before the step is cut
    max_backtracks: int = 6  #: Newton line-search halvings (solver.dynamics.newton.ContactNewtonSolver)
    max_gap_change: float = 0.0  #: gap-limited Newton steps [m] (ContactNewtonSolver); 0: off
    #: sparse LU of the Newton corrections: "mumps" (faster), "superlu_dist" (bitwise repeatable on
    #: several ranks, where MUMPS's factors vary at round-off from run to run, which stick-slip
    #: amplifies), or "auto": MUMPS on one rank, SuperLU_DIST on several
    lu_solver: str = "auto"
    #: Newton on the contact zone with the linear bulk condensed exactly (solver.dynamics.condensation):
    #: cheaper steps, plus |interface| bulk solves whenever the step size changes
    condense_bulk: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.condense_bulk, bool):
            raise ValueError(f"condense_bulk must be true or false, got {self.condense_bulk!r}")
        if not (isinstance(self.max_iterations, int) and self.max_iterations >= 1):
            raise ValueError(f"max_iterations must be an integer >= 1, got {self.max_iterations!r}")
        if not (isinstance(self.max_backtracks, int) and self.max_backtracks >= 0):
            raise ValueError(f"max_backtracks must be an integer >= 0, got {self.max_backtracks!r}")
        _check_choice("slave", self.slave, SURFACES)
        _check_choice("master", self.master, SURFACES)
        if self.slave == self.master:
            raise ValueError(f"slave and master must differ, got {self.slave} for both")
        if not self.gamma0 > 0:
            raise ValueError(f"gamma0 must be positive, got {self.gamma0}")
        _check_choice("theta", self.theta, (1, 0, -1))
        if not self.max_gap_change >= 0:
            raise ValueError(f"max_gap_change must be >= 0 m, got {self.max_gap_change}")
        _check_choice("degree", self.degree, (1, 2, 3))
        _check_choice("lu_solver", self.lu_solver, ("auto", "mumps", "superlu_dist"))
        if self.lu_solver != "auto" and not PETSc.Sys.hasExternalPackage(self.lu_solver):
            raise ValueError(f"lu_solver {self.lu_solver!r}: this PETSc was built without it")


@dataclass(frozen=True)
class DampingSettings:
    """``[damping]``: "rayleigh" (zeta at ``frequency_hz``, the default) or "modal" (zeta for
    the first ``n_modes`` modes of the joint with a bonded band ``band_height`` at the TP's
    lower edge, computed before the run)."""

    model: str = "rayleigh"
    zeta: float = 0.01  #: damping ratio [-]
    frequency_hz: float = 120.0  #: Rayleigh: frequency of the minimum (the m = 2, n = 1 mode) [Hz]
    n_modes: int = 10  #: modal: number of damped modes
    band_height: float = 0.05  #: modal: bonded band of the damping modes [m]

    def __post_init__(self) -> None:
        _check_choice("model", self.model, ("rayleigh", "modal"))
        if not 0 <= self.zeta < 1:
            raise ValueError(f"zeta must lie in [0, 1), got {self.zeta}")
        if not self.frequency_hz > 0:
            raise ValueError(f"frequency_hz must be positive, got {self.frequency_hz}")
        if not (isinstance(self.n_modes, int) and self.n_modes >= 1):
            raise ValueError(f"n_modes must be an integer >= 1, got {self.n_modes!r}")
        if not self.band_height > 0:
            raise ValueError(f"band_height must be positive, got {self.band_height} m")


@dataclass(frozen=True)
class TimeSettings:
    """``[time]``: scheme and step sizes of the dynamic stages."""

    scheme: str = "generalised-alpha"  #: newmark | generalised-alpha | quasi-static
    rho_inf: float = 0.8  #: generalised-alpha spectral radius [-]
    steps_per_period: int = 24  #: vibration stages: steps per period of the stage frequency
    dt_min_fraction: float = 1 / 64  #: smallest cut step as a fraction of the nominal step

    def __post_init__(self) -> None:
        _check_choice("scheme", self.scheme, ("newmark", "generalised-alpha", "quasi-static"))
        if not 0 <= self.rho_inf <= 1:
            raise ValueError(f"rho_inf must lie in [0, 1], got {self.rho_inf}")
        if not (isinstance(self.steps_per_period, int) and self.steps_per_period >= 4):
            raise ValueError(
                f"steps_per_period must be an integer >= 4, got {self.steps_per_period!r}"
            )
        if not 0 < self.dt_min_fraction <= 1:
            raise ValueError(f"dt_min_fraction must lie in (0, 1], got {self.dt_min_fraction}")


@dataclass(frozen=True)
class SelfWeightSettings:
    """``[self_weight]``: SPEC 3 self-weight emulation on the TP top face."""

    force_N: float = -10e3  #: axial force, negative = down [N]
    ramp_time_s: float = 2.0
    hold_s: float = 0.1  #: held after the ramp [s]
    dt_s: float = 0.01  #: time step [s]
    scheme: str = ""  #: "" = the [time] scheme; or quasi-static / newmark / generalised-alpha

    def __post_init__(self) -> None:
        if not self.force_N < 0:
            raise ValueError(
                f"force_N must be negative (pushing the TP down), got {self.force_N} N"
            )
        if not (self.ramp_time_s >= 0 and self.hold_s >= 0 and self.ramp_time_s + self.hold_s > 0):
            raise ValueError(
                f"need ramp_time_s, hold_s >= 0 with a positive sum, "
                f"got {self.ramp_time_s}, {self.hold_s}"
            )
        if not 0 < self.dt_s <= self.ramp_time_s + self.hold_s:
            raise ValueError(f"dt_s must lie in (0, ramp_time_s + hold_s], got {self.dt_s} s")
        if self.scheme:
            _check_choice("scheme", self.scheme, ("newmark", "generalised-alpha", "quasi-static"))

    @property
    def duration_s(self) -> float:
        return self.ramp_time_s + self.hold_s


@dataclass(frozen=True)
class VibrationSettings:
    """``[vibration]``: forcing and the automatic schedule after the modal stage.

    ``forcing``: "eccentric" (motors fixed to the TP top edge at ``angle_deg``: a point
    force there), "face" (spread uniformly over the TP top face: on a perfect joint it
    excites only m = 0 and m = 1 modes), "shaker" (a point force at ``shaker_height_m``
    above the TP's lower end, ``angle_deg``). Automatic schedule: the ``lead_in_hz``
    stages at the eccentric-motor amplitude 0.3632 f^2 (SPEC 3: 68 and 100 Hz), then each
    chosen natural frequency and the control frequency at ``amplitude_N``, each
    ``stage_duration_s`` long, in increasing frequency.
    """

    forcing: str = "eccentric"
    amplitude_N: float = 3600.0  #: force amplitude of the modal and control stages [N]
    direction: str = "axial"  #: axial | lateral | both (axial + lateral_fraction laterally)
    lateral_fraction: float = 0.05
    angle_deg: float = 0.0  #: circumferential position of the point force / lateral direction [deg]
    shaker_height_m: float = 1.2  #: shaker: height above the TP's lower end [m]
    stage_duration_s: float = 0.1
    lead_in_hz: tuple[float, ...] = (68.0, 100.0)
    n_frequencies: int = (
        3  #: number of ranked natural frequencies excited (the m = 2, n = 1 mode is added)
    )
    n_modes: int = 12  #: modes computed in the modal stage
    max_frequency_hz: float = 300.0  #: ranked modes above this are not excited [Hz]
    m2n1_mode: bool = True  #: add the lowest (m = 2, n = 1) mode, also above max_frequency_hz
    control: bool = True  #: insert a non-modal control frequency
    modal_stage: bool = True  #: false: no modal stage (needs a [[schedule]] without mode/ranked)

    def __post_init__(self) -> None:
        _check_choice("forcing", self.forcing, FORCINGS)
        _check_choice("direction", self.direction, ("axial", "lateral", "both"))
        if not self.amplitude_N > 0:
            raise ValueError(f"amplitude_N must be positive, got {self.amplitude_N} N")
        if not 0 <= self.lateral_fraction <= 1:
            raise ValueError(f"lateral_fraction must lie in [0, 1], got {self.lateral_fraction}")
        if not self.stage_duration_s > 0:
            raise ValueError(f"stage_duration_s must be positive, got {self.stage_duration_s} s")
        if not all(isinstance(f, (int, float)) and f > 0 for f in self.lead_in_hz):
            raise ValueError(
                f"lead_in_hz must be a list of positive frequencies, got {self.lead_in_hz!r}"
            )
        if not (isinstance(self.n_frequencies, int) and self.n_frequencies >= 0):
            raise ValueError(f"n_frequencies must be an integer >= 0, got {self.n_frequencies!r}")
        if not (isinstance(self.n_modes, int) and self.n_modes >= 2):
            raise ValueError(f"n_modes must be an integer >= 2, got {self.n_modes!r}")
        if not self.max_frequency_hz > 0:
            raise ValueError(f"max_frequency_hz must be positive, got {self.max_frequency_hz}")
        for name in ("m2n1_mode", "control", "modal_stage"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name} must be true or false, got {getattr(self, name)!r}")

    def stage(self, duration_s: float, frequency_hz: float, amplitude: float | str) -> Stage:
        return Stage(
            duration_s,
            frequency_hz,
            amplitude,
            direction=self.direction,
            lateral_fraction=self.lateral_fraction,
            lateral_angle_deg=self.angle_deg,
        )


@dataclass(frozen=True)
class OutputSettings:
    """``[output]``: checkpoints, ParaView files, plots, stick-slip detection."""

    checkpoint_every: int = 100  #: steps between checkpoints (and at every stage end)
    paraview: bool = True
    plots: bool = True
    slip_rate_mm_s: float = (
        1.0  #: the TP slips as a whole while d(settlement)/dt exceeds this [mm/s]
    )

    def __post_init__(self) -> None:
        if not (isinstance(self.checkpoint_every, int) and self.checkpoint_every >= 1):
            raise ValueError(
                f"checkpoint_every must be an integer >= 1, got {self.checkpoint_every!r}"
            )
        if not self.slip_rate_mm_s > 0:
            raise ValueError(f"slip_rate_mm_s must be positive, got {self.slip_rate_mm_s}")


@dataclass(frozen=True)
class StaticForceSettings:
    """``[static_force]``: the static axial force after the self-weight stage [N, +z up].

    From the held self-weight force at the end of the self-weight stage (time 0 of this
    history) the force goes linearly through the points (``times_s[k]``, ``forces_N[k]``),
    times counted from the end of the self-weight stage, and is held at the last value.
    Empty (the default): the self-weight force is held to the end. Dismount: ramp to a
    positive pull, e.g. ``times_s = [0.05]``, ``forces_N = [20e3]``.
    """

    times_s: tuple[float, ...] = ()
    forces_N: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "times_s", tuple(self.times_s))
        object.__setattr__(self, "forces_N", tuple(self.forces_N))
        if len(self.times_s) != len(self.forces_N):
            raise ValueError(
                f"times_s and forces_N need the same length, got {len(self.times_s)} and "
                f"{len(self.forces_N)}"
            )
        if not all(isinstance(x, (int, float)) for x in self.times_s + self.forces_N):
            raise ValueError("times_s and forces_N must be lists of numbers [s], [N]")
        if self.times_s and not (
            self.times_s[0] > 0 and all(b > a for a, b in zip(self.times_s, self.times_s[1:]))
        ):
            raise ValueError(
                f"times_s must be positive and strictly increasing (s after the self-weight "
                f"stage), got {list(self.times_s)}"
            )

    def history(self, self_weight: SelfWeightSettings) -> Callable[[float], float]:
        """The whole static axial force [N] against the run's time [s]."""
        sw = self_weight
        if not self.times_s:
            return RampedAxialForce(sw.force_N, sw.ramp_time_s)
        start = [(0.0, 0.0)] if sw.ramp_time_s > 0 else []
        start += [(sw.ramp_time_s, sw.force_N)]
        if sw.hold_s > 0:
            start += [(sw.duration_s, sw.force_N)]
        after = [(sw.duration_s + t, f) for t, f in zip(self.times_s, self.forces_N)]
        times, forces = zip(*(start + after))
        return PiecewiseLinearForce(times, forces)


@dataclass(frozen=True)
class ImperfectionSettings:
    """``[imperfections.mp]`` / ``[imperfections.tp]``: radial imperfection of a part's wall.

    Either ``file`` (a processed map or raw laser ring scans, ``geometry.imperfections``; a
    relative path is looked up from the working directory, then beside the case file) or an
    ovality ``amplitude_m`` cos(``waves`` (theta - ``phase_deg``)) [m], uniform along the axis.
    """

    file: str = ""
    amplitude_m: float = 0.0  #: ovality amplitude [m]
    waves: int = 2  #: circumferential wave number of the ovality
    phase_deg: float = 0.0

    def __post_init__(self) -> None:
        if self.file and self.amplitude_m:
            raise ValueError("give either file or amplitude_m (ovality), not both")
        if not self.file and not self.amplitude_m:
            raise ValueError("needs a file or a non-zero ovality amplitude_m")
        if not (isinstance(self.waves, int) and self.waves >= 1):
            raise ValueError(f"waves must be an integer >= 1, got {self.waves!r}")

    def deviation(self, part, case_dir: Path) -> RadialDeviation:
        """The radial deviation function of ``part`` (reads and checks the file)."""
        if not self.file:
            return ovality(self.amplitude_m, self.waves, self.phase_deg)
        path = Path(self.file)
        if not path.is_file() and not path.is_absolute() and (case_dir / path).is_file():
            path = case_dir / path
        return read_imperfection(path, part)


SECTIONS = {
    "contact": ContactSettings,
    "damping": DampingSettings,
    "time": TimeSettings,
    "self_weight": SelfWeightSettings,
    "vibration": VibrationSettings,
    "output": OutputSettings,
    "static_force": StaticForceSettings,
}
KNOWN_TABLES = {
    "imperfections",
    "geometry",
    "material",
    "mesh",
    "friction",
    "schedule",
    "modal",
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
            joint, material, mesh = geometry_from_case(case)
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

    def deviations(self) -> dict[str, RadialDeviation]:
        """The radial deviations of the imperfect parts (``geometry.imperfections``)."""
        case_dir = Path(self.source).parent
        return {
            name: setting.deviation(getattr(self.joint, name), case_dir)
            for name, setting in self.imperfections.items()
        }

    def describe(self) -> dict[str, Any]:
        """Plain-data summary of the settings (written to the output folder)."""
        out = {name: asdict(getattr(self, name)) for name in ("mesh", "friction", *SECTIONS)}
        out["material"] = asdict(self.material)
        out["imperfections"] = {k: asdict(v) for k, v in self.imperfections.items()}
        out["source"] = self.source
        return out


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


@dataclass(frozen=True)
class PlacedJoint:
    """The joint's parts with the TP's lower end at ``tp_offset`` [m] as meshed: at the first
    contact of the (imperfect) surfaces, ``geometry.contact_map.tp_placement``. Used where a
    position on the TP is needed (settlement probes, point forces, plots)."""

    mp: Any
    tp: Any
    tp_offset: float


class InstallationProblem(Elastodynamics):
    """Elastodynamics that remembers the last step's result (Newton iterations for the history)."""

    last_result: StepResult | None = None

    def step(self, dt: float) -> StepResult:
        self.last_result = super().step(dt)
        return self.last_result

    def refresh_load(self) -> None:
        """Re-evaluate the load at the current time (after the load callable was changed)."""
        self._evaluate_load(self.t, self._f_old)

    def rebuild_solver(self) -> None:
        """Drop the factorisation and Newton workspace: the next step starts afresh."""
        self._dt_of_A = None


@dataclass
class JointModel:
    """Mesh, space, clamp, matrices, contact, loads and the time-stepping problem of a case."""

    case: InstallationCase
    mesh_data: Any
    V: fem.FunctionSpace
    bcs: list
    contact: NitscheContact
    top: TopFaceLoad
    static: Callable[[float], float]  #: static axial force [N] against time [s]
    problem: InstallationProblem
    settlement: Settlement
    damping: RayleighDamping | ModalDamping
    placed: PlacedJoint
    timings_s: dict[str, float] = field(default_factory=dict)

    @property
    def comm(self) -> MPI.Comm:
        return self.V.mesh.comm

    @property
    def n_dofs(self) -> int:
        return self.V.dofmap.index_map.size_global * self.V.dofmap.index_map_bs


def _lu_package(choice: str, comm: MPI.Comm) -> str:
    """The PETSc LU package of ``[contact] lu_solver`` ("auto": MUMPS on one rank, SuperLU_DIST,
    which repeats its arithmetic, on several if PETSc has it)."""
    if choice != "auto":
        return choice
    several = comm.size > 1 and PETSc.Sys.hasExternalPackage("superlu_dist")
    return "superlu_dist" if several else "mumps"


def build_joint_model(comm: MPI.Comm, case: InstallationCase) -> JointModel:
    """Set up the joint of ``case`` at rest in its first-contact position (collective)."""
    t0 = time.perf_counter()
    deviations = case.deviations()
    placed = PlacedJoint(case.joint.mp, case.joint.tp, tp_placement(case.joint, deviations))
    mesh_data = create_joint_mesh(comm, case.joint, case.mesh, deviations)
    V = fem.functionspace(mesh_data.mesh, ("Lagrange", case.contact.degree, (3,)))
    bcs = [clamp(V, mesh_data.facet_tags, [tags.MP_CLAMPED])]
    M, K = assemble_structure(V, case.material, bcs)
    contact = NitscheContact(
        V,
        mesh_data.facet_tags,
        getattr(tags, case.contact.slave),
        getattr(tags, case.contact.master),
        case.material,
        case.friction,
        gamma0=case.contact.gamma0,
        theta=case.contact.theta,
        lagged_friction=case.contact.lagged_friction,
    )
    d = case.damping
    if d.model == "rayleigh":
        damping = RayleighDamping.at_frequency(d.zeta, d.frequency_hz)
    else:
        band = bonded_band(
            V, mesh_data.facet_tags, case.material, d.band_height, case.contact.gamma0
        )
        modes = modal_analysis(V, case.material, bcs, [band], EigenOptions(n_modes=d.n_modes))
        damping = ModalDamping(
            M, [u.x.petsc_vec for u in modes.modes], modes.frequencies_hz, d.zeta
        )
        damping.check_step(case.self_weight.dt_s)  # explicit in time: fail before the time loop
    sw = case.self_weight
    static = case.static_force.history(sw)
    top = TopFaceLoad(V, mesh_data.facet_tags, tags.TP_TOP)
    problem = InstallationProblem(
        V,
        M,
        K,
        bcs,
        load=TPLoading(top, static_axial=static),
        scheme=scheme_from_name(sw.scheme or case.time.scheme, case.time.rho_inf),
        damping=damping,
        contact=contact,
        newton_options={
            "max_iterations": case.contact.max_iterations,
            "max_backtracks": case.contact.max_backtracks,
            "max_gap_change": case.contact.max_gap_change or None,
            "lu_solver": _lu_package(case.contact.lu_solver, comm),
        },
        condense_bulk=case.contact.condense_bulk,
    )
    problem.initialise(0.0)
    settlement = Settlement(problem.u, placed, mesh_data.cell_tags)
    return JointModel(
        case,
        mesh_data,
        V,
        bcs,
        contact,
        top,
        static,
        problem,
        settlement,
        damping,
        placed,
        {"set-up": time.perf_counter() - t0},
    )


def settled_modes(model: JointModel, n_modes: int) -> tuple[ModalResult, ContactInterface]:
    """The ``n_modes`` lowest modes of the joint in its current contact state (collective).

    Small vibrations about the settled, resting joint: every slave point in contact is tied
    normally and tangentially (STICK), the others are free. (A point that slipped in the
    last step is at rest now; tying only its normal motion would let the TP slide and rock
    on the thin contact band: spurious modes near 0 Hz.) The interface tangent is the
    symmetric Nitsche one (theta = 1) at the same pairing, as the eigenproblem needs.
    """
    contact, c = model.contact, model.case.contact
    if contact.theta != 1:
        contact = NitscheContact(
            model.V,
            model.mesh_data.facet_tags,
            getattr(tags, c.slave),
            getattr(tags, c.master),
            model.case.material,
            model.case.friction,
            gamma0=c.gamma0,
            theta=1,
        )
        contact.update(model.problem.u)
    status = np.where(model.contact.state.status == Status.OPEN, Status.OPEN, Status.STICK)
    interface = ContactInterface(contact, status)
    result = modal_analysis(
        model.V, model.case.material, model.bcs, [interface], EigenOptions(n_modes=n_modes)
    )
    return result, interface


def attach_vibration(model: JointModel, schedule: Schedule) -> None:
    """Apply the harmonic ``schedule`` to the TP through the case's forcing ([vibration]):
    "face" spreads it over the TP top face, "eccentric" puts it at a point of the top edge,
    "shaker" at ``shaker_height_m`` above the TP's lower end (both at ``angle_deg``)."""
    vib = model.case.vibration
    loading: TPLoading = model.problem.load
    if vib.forcing == "face":
        loading.schedule = schedule
    else:
        j = model.placed
        if vib.forcing == "eccentric":
            point = shaker_point(j.tp, j.tp_offset, j.tp.total_length, vib.angle_deg)
            point[2] -= 1e-6 * j.tp.total_length  # just inside the top face
        else:
            point = shaker_point(j.tp, j.tp_offset, vib.shaker_height_m, vib.angle_deg)
        loading.shaker = (PointLoad(model.V, point), schedule)
    model.problem.refresh_load()


# -- frequency choice -----------------------------------------------------------------------
@dataclass(frozen=True)
class Excitation:
    """One vibration stage of the automatic schedule and why it was chosen."""

    frequency_Hz: float
    amplitude_N: float | str
    role: str  #: lead-in | modal | control
    mode: int  #: mode number (0: none)
    m: int
    n: int
    rank: int
    reason: str


PAIR_TOLERANCE = 0.02  #: relative frequency difference within which two modes are one pair
MIN_FREQUENCY_HZ = 1.0  #: modes below this are not excited [Hz]


def choose_frequencies(records: list[ModeRecord], settings: VibrationSettings) -> list[Excitation]:
    """Excitation stages from the ranking of the settled joint's modes.

    * the lead-in frequencies (SPEC 3 reference sequence) at the eccentric amplitude;
    * the ``n_frequencies`` best-ranked distinct frequencies up to ``max_frequency_hz``
      (one per degenerate pair: modes within ``PAIR_TOLERANCE`` of a chosen frequency are
      its partner);
    * the lowest (m = 2, n = 1) mode among all computed modes if not among them (SPEC 5.4: the
      most effective; also above ``max_frequency_hz``, unless ``m2n1_mode`` is false);
    * a non-modal control frequency: the point of [f_lo / 2, f_hi] farthest from every computed
      natural frequency in ratio (|ln(f / f_n)|: the dynamic amplification of a mode depends
      on f / f_n), f_lo and f_hi the lowest and highest chosen natural frequency (with a single
      chosen frequency f: f_hi = min(1.5 f, max_frequency_hz)). The octave below f_lo admits a
      control in the quasi-static band below the lowest modes, where a point between dense
      higher modes may lie within a few per cent of one (docs/install.md).
    Stages are returned in increasing frequency after the lead-in.
    """
    # below MIN_FREQUENCY_HZ: rigid-body motions of a part the contact does not hold, not modes
    modes = [r for r in records if r.frequency_Hz >= MIN_FREQUENCY_HZ]
    candidates = [r for r in modes if r.frequency_Hz <= settings.max_frequency_hz]
    chosen: list[Excitation] = []

    def same_pair(r: ModeRecord) -> bool:  # the partner of a degenerate pair (or a near-tie)
        return any(abs(r.frequency_Hz - c.frequency_Hz) <= PAIR_TOLERANCE * c.frequency_Hz
                   for c in chosen)

    for r in sorted(candidates, key=lambda r: (r.rank, r.mode)):
        if len(chosen) >= settings.n_frequencies:
            break
        if same_pair(r):
            continue
        chosen.append(
            Excitation(
                r.frequency_Hz,
                settings.amplitude_N,
                "modal",
                r.mode,
                r.m,
                r.n,
                r.rank,
                f"rank {r.rank} of {len({x.rank for x in records})}: resonant interface slip "
                f"{max(r.resonant_slip_axial_um, r.resonant_slip_lateral_um):.3g} um",
            )
        )
    m2n1 = [r for r in modes if (r.m, r.n) == (2, 1)]
    if settings.m2n1_mode and m2n1 and all((c.m, c.n) != (2, 1) for c in chosen):
        r = min(m2n1, key=lambda r: r.frequency_Hz)
        if not same_pair(r):
            above = (f", above the ranked choice's {settings.max_frequency_hz:g} Hz"
                     if r.frequency_Hz > settings.max_frequency_hz else "")
            chosen.append(
                Excitation(
                    r.frequency_Hz,
                    settings.amplitude_N,
                    "modal",
                    r.mode,
                    r.m,
                    r.n,
                    r.rank,
                    f"lowest m = 2, n = 1 mode (SPEC 5.4: most effective in the experiments{above})",
                )
            )
    chosen.sort(key=lambda e: e.frequency_Hz)
    if settings.control and chosen:
        natural = np.array([r.frequency_Hz for r in modes])
        lo, hi = chosen[0].frequency_Hz, chosen[-1].frequency_Hz
        if hi - lo < 1e-6 * hi:
            hi = min(1.5 * hi, settings.max_frequency_hz)
        grid = np.geomspace(0.5 * lo, hi, 2001)
        ratio = np.min(np.abs(np.log(grid[:, None] / natural[None, :])), axis=1)
        f_c = float(grid[np.argmax(ratio)])
        nearest = float(natural[np.argmin(np.abs(np.log(f_c / natural)))])
        chosen.append(
            Excitation(
                f_c,
                settings.amplitude_N,
                "control",
                0,
                -1,
                -1,
                0,
                f"non-modal control: a factor {np.exp(ratio.max()):.2f} from the nearest natural "
                f"frequency ({nearest:.1f} Hz)",
            )
        )
        chosen.sort(key=lambda e: e.frequency_Hz)
    lead = [
        Excitation(
            f,
            "eccentric",
            "lead-in",
            0,
            -1,
            -1,
            0,
            "SPEC 3 reference sequence, eccentric amplitude",
        )
        for f in settings.lead_in_hz
    ]
    return lead + chosen


def _schedule_excitations(
    schedule: Schedule, natural_hz: list[float], chosen: list[Excitation]
) -> list[Excitation]:
    """One Excitation per stage of an explicit schedule: 'mode k' at the k-th natural frequency,
    'ranked k' at the k-th best-ranked chosen natural frequency (with its reason)."""
    ranked = sorted((e for e in chosen if e.role == "modal"), key=lambda e: (e.rank, e.mode))
    resolved = schedule.with_natural_frequencies(natural_hz, [e.frequency_Hz for e in ranked])
    out = []
    for s, r in zip(schedule.stages, resolved.stages):
        f = float(r.frequency_hz)
        if s.ranked_number is not None:
            e = ranked[s.ranked_number - 1]
            out.append(
                replace(
                    e,
                    amplitude_N=s.amplitude_N,
                    role="schedule",
                    reason=f"[[schedule]] ranked {s.ranked_number}: {e.reason}",
                )
            )
        elif s.mode_number is not None:
            out.append(
                Excitation(
                    f, s.amplitude_N, "schedule", s.mode_number, -1, -1, 0, "[[schedule]] mode"
                )
            )
        else:
            what = "no vibration" if f == 0 or s.amplitude_N == 0 else "[[schedule]] of the case"
            out.append(Excitation(f, s.amplitude_N, "schedule", 0, -1, -1, 0, what))
    return out


# -- the run ----------------------------------------------------------------------------------
@dataclass
class StagePlan:
    """A stage of the time loop: name, interval [s], nominal step [s], frequency, amplitude."""

    name: str
    start_s: float
    end_s: float
    dt_s: float
    frequency_Hz: float
    amplitude_N: float
    reason: str = ""


def _plan_vibration(
    schedule: Schedule, steps_per_period: int, reasons: list[str]
) -> list[StagePlan]:
    plans = []
    for i, (stage, start) in enumerate(zip(schedule.stages, schedule.stage_starts)):
        f_max = max(stage.frequency(0.0), stage.frequency(stage.duration_s))
        periods = max(1, math.ceil(stage.duration_s * f_max)) if f_max > 0 else 1
        dt = stage.duration_s / (periods * steps_per_period)
        plans.append(
            StagePlan(
                f"vibration {i + 1}",
                float(start),
                float(start + stage.duration_s),
                dt,
                stage.frequency(0.0),
                stage.amplitude(0.0),
                reasons[i] if i < len(reasons) else "",
            )
        )
    return plans


class Installation:
    """The staged installation run of one case, writing its outputs to ``output`` as it goes.

    ``run(resume=False, stop_after_checkpoints=None)``: the whole pipeline; with ``resume``
    it continues from the checkpoint in ``output/checkpoint``; ``stop_after_checkpoints``
    ends the run early after that many checkpoints (used to test resuming).
    """

    def __init__(
        self,
        comm: MPI.Comm,
        case: InstallationCase,
        output: str | Path,
        log: Callable[[str], None] | None = None,
        progress: bool = True,
    ):
        self.comm, self.case = comm, case
        self.output = Path(output)
        self.log = log or (_write_line if comm.rank == 0 else (lambda s: None))
        self.progress = progress and comm.rank == 0
        self.model: JointModel | None = None
        self.history: list[dict[str, float]] = []
        self.stages: list[dict[str, Any]] = []
        self.plans: list[StagePlan] = []
        self.excitations: list[Excitation] = []
        self.modal: tuple[ModalResult, list[ModeRecord]] | None = None
        self.natural_frequencies: list[float] = []
        self._checkpoints = 0
        self._stop_after: int | None = None

    # paths
    @property
    def checkpoint_dir(self) -> Path:
        return self.output / "checkpoint"

    def _record(self, next_stage: int, chunk: int) -> dict[str, Any]:
        return {
            "next_stage": next_stage,
            "next_chunk": chunk,
            "history": self.history,
            "stages": self.stages,
            "plans": [asdict(p) for p in self.plans],
            "excitations": [asdict(e) for e in self.excitations],
            "natural_frequencies_Hz": self.natural_frequencies,
        }

    def _checkpoint(self, next_stage: int, chunk: int) -> None:
        # a resumed run starts with a fresh factorisation, so does the uninterrupted one
        self.model.problem.rebuild_solver()
        checkpoint.save(self.checkpoint_dir, self.model.problem, self._record(next_stage, chunk))
        self._checkpoints += 1
        if self._stop_after is not None and self._checkpoints >= self._stop_after:
            raise _Stopped()

    # stages
    def _observer(self, stage_index: int, plan: StagePlan, writer: report.HistoryWriter, bar):
        model = self.model
        loading: TPLoading = model.problem.load

        def observe(problem: InstallationProblem) -> dict[str, float]:
            t = problem.t
            prev_t = self.history[-1]["time_s"] if self.history else 0.0
            schedule = loading.schedule or (loading.shaker[1] if loading.shaker else None)
            state = model.contact.state
            counts = np.array(
                [np.count_nonzero(state.status == s) for s in (Status.STICK, Status.SLIP)]
            )
            counts = self.comm.allreduce(counts, op=MPI.SUM)
            n_points = self.comm.allreduce(len(state.status))
            normal, _ = model.contact.forces()
            row = {
                "time_s": t,
                "dt_s": t - prev_t,
                "stage": stage_index,
                "frequency_Hz": schedule.frequency(t) if schedule else 0.0,
                "amplitude_N": schedule.amplitude(t) if schedule else 0.0,
                "axial_force_N": float(
                    model.static(t) + (schedule.force(t)[2] if schedule else 0.0)
                ),
                **model.settlement(problem),
                "newton_iterations": problem.last_result.iterations if problem.last_result else 0,
                "stick_fraction": counts[0] / n_points,
                "slip_fraction": counts[1] / n_points,
                "normal_force_N": normal,
            }
            self.history.append(row)
            writer.write(row)
            if bar is not None:
                bar.update(min(row["dt_s"], bar.total - bar.n))  # sums of dt overshoot by round-off
                bar.set_postfix_str(
                    f"{plan.name}, dt {row['dt_s']:.3g} s, "
                    f"settlement {row['settlement_mm']:.4f} mm, Newton {row['newton_iterations']}",
                    refresh=False,
                )
            return {}

        return observe

    def _run_stage(self, index: int, first_chunk: int, writer, bar) -> None:
        plan, model = self.plans[index], self.model
        problem = model.problem
        steps = self.case.output.checkpoint_every
        n_chunks = max(1, math.ceil((plan.end_s - plan.start_s) / (steps * plan.dt_s) - 1e-9))
        observers = [self._observer(index, plan, writer, bar)]
        mesh = self.case.mesh
        if mesh.contact_axial_size > 0:
            observers.append(ContactZoneGuard(model.contact, mesh.contact_axial_size, mesh.contact_zone_above))
        wall0 = time.perf_counter()
        rows0 = len(self.history)
        for chunk in range(first_chunk, n_chunks):
            t_end = min(plan.start_s + (chunk + 1) * steps * plan.dt_s, plan.end_s)
            if chunk == n_chunks - 1:
                t_end = plan.end_s
            if t_end > problem.t + 1e-12 * max(t_end, 1.0):
                run(
                    problem,
                    t_end,
                    plan.dt_s,
                    dt_min=plan.dt_s * self.case.time.dt_min_fraction,
                    observers=observers,
                    progress=False,
                )
            if chunk < n_chunks - 1:
                self._checkpoint(index, chunk + 1)
        rows = [r for r in self.history if r["stage"] == index]
        summary = report.stage_summary(
            index, plan, rows, self.history, self.case.output.slip_rate_mm_s
        )
        summary["wall_s"] = (
            time.perf_counter() - wall0 if len(self.history) > rows0 else float("nan")
        )
        self.stages.append(summary)
        report.write_stage_table(self.stages, self.output / "stages.csv", self.comm)
        self._write_state(plan.name)
        self.log(report.format_stage(summary))

    def _write_state(self, name: str) -> None:
        if self.case.output.paraview:
            report.write_state(self.model, self.output, name, len(self.stages))
        if self.case.output.plots:
            report.plot_contact_status(
                self.model.contact,
                self.model.placed,
                self.output / f"contact_status_{len(self.stages)}.png",
                f"after {name}, t = {self.model.problem.t:.4g} s",
            )

    def _schedule(self, start_s: float) -> Schedule:
        """The vibration schedule from ``start_s``: the automatic one (from the chosen excitations)
        or the case's [[schedule]] with 'mode k' / 'ranked k' set to the settled joint's
        frequencies."""
        vib = self.case.vibration
        if self.case.schedule is None:
            stages = [
                vib.stage(vib.stage_duration_s, e.frequency_Hz, e.amplitude_N)
                for e in self.excitations
            ]
        else:  # 'mode k' / 'ranked k' stages at the frequencies found by the modal stage
            stages = [
                replace(s, frequency_hz=e.frequency_Hz) if isinstance(s.frequency_hz, str) else s
                for s, e in zip(self.case.schedule.stages, self.excitations)
            ]
        return Schedule(stages, start_s=start_s)

    def _modal_stage(self) -> None:
        """Modes of the settled joint (contact tangent at its current status); frequency choice.

        With ``vibration.modal_stage = false`` only the explicit [[schedule]] is planned."""
        model, vib = self.model, self.case.vibration
        t0 = time.perf_counter()
        records: list[ModeRecord] = []
        if vib.modal_stage:
            result, interface = settled_modes(model, vib.n_modes)
            parts = JointParts.for_joint(model.V, model.mesh_data, model.placed)
            nodes_around = self.case.mesh.n_circumferential * self.case.contact.degree
            records = describe_modes(
                result,
                self.case.material,
                parts,
                zeta=max(self.case.damping.zeta, 1e-4),
                m_max=min(12, (nodes_around - 1) // 2),
            )
            if self.case.output.plots:
                write_outputs(result, records, self.output)
            else:
                write_csv(records, self.output / "modes.csv", self.comm)
            self.modal = (result, records)
            self.natural_frequencies = [float(f) for f in result.frequencies_hz]
        chosen = choose_frequencies(records, vib)
        if self.case.schedule is None:
            self.excitations = chosen
        else:
            self.excitations = _schedule_excitations(
                self.case.schedule, self.natural_frequencies, chosen
            )
        if self.excitations:  # (none: the run ends after the modal stage)
            self.plans += _plan_vibration(
                self._schedule(model.problem.t),
                self.case.time.steps_per_period,
                [e.reason for e in self.excitations],
            )
        report.write_choice(self.excitations, self.output / "frequencies.csv", self.comm)
        if vib.modal_stage:
            self.log(
                f"modal stage: {len(records)} modes of the settled joint "
                f"({100 * interface.tied_fraction():.1f} % of the contact points tied) in "
                f"{time.perf_counter() - t0:.1f} s; excitation:"
            )
        else:
            self.log("no modal stage (vibration.modal_stage = false); excitation:")
        for e in self.excitations:
            amp = e.amplitude_N if isinstance(e.amplitude_N, str) else f"{e.amplitude_N:.0f} N"
            self.log(f"  {e.frequency_Hz:8.2f} Hz  {amp:>9}  {e.role:8} {e.reason}")

    def _install_schedule(self) -> None:
        """Attach the vibration schedule to the loads through the chosen forcing."""
        model, vib = self.model, self.case.vibration
        plans = self.plans[1:]
        if not plans:
            return
        attach_vibration(model, self._schedule(plans[0].start_s))

    def run(
        self, resume: bool = False, stop_after_checkpoints: int | None = None
    ) -> dict[str, Any]:
        """Run (or resume) the installation; returns the summary (collective)."""
        self._stop_after = stop_after_checkpoints
        case, comm = self.case, self.comm
        manifest = checkpoint.read_manifest(self.checkpoint_dir, comm) if resume else None
        if comm.rank == 0:
            self.output.mkdir(parents=True, exist_ok=True)
            (self.output / "case.json").write_text(
                json.dumps(case.describe(), indent=1, default=str)
            )
        self.model = build_joint_model(comm, case)
        model = self.model
        self.log(
            f"joint: {model.n_dofs} dofs (degree {case.contact.degree}, "
            f"{case.mesh.n_circumferential} around, {case.mesh.axial_size} m axially), "
            f"{comm.size} rank(s), damping {case.damping.model}; "
            f"set-up {model.timings_s['set-up']:.1f} s"
        )
        sw = case.self_weight
        self.plans = [
            StagePlan(
                "self-weight",
                0.0,
                sw.duration_s,
                sw.dt_s,
                0.0,
                0.0,
                f"{-sw.force_N:.0f} N down over {sw.ramp_time_s} s, held {sw.hold_s} s",
            )
        ]
        next_stage, next_chunk = 0, 0
        if manifest is not None:
            checkpoint.restore(self.checkpoint_dir, model.problem)
            self.history, self.stages = manifest["history"], manifest["stages"]
            self.plans = [StagePlan(**p) for p in manifest["plans"]]
            self.excitations = [Excitation(**e) for e in manifest["excitations"]]
            self.natural_frequencies = manifest["natural_frequencies_Hz"]
            next_stage, next_chunk = manifest["next_stage"], manifest["next_chunk"]
            self.log(
                f"resumed at t = {model.problem.t:.6g} s "
                f"(stage {next_stage + 1}, chunk {next_chunk})"
            )
        writer = report.HistoryWriter(self.output / "history.csv", comm, self.history)
        bar = None
        try:
            if next_stage == 0:
                bar = self._bar(sw.duration_s)
                self._run_stage(0, next_chunk, writer, bar)
                next_stage, next_chunk = 1, 0
                if bar is not None:
                    bar.close()
                    bar = None
                self._modal_stage()
                self._checkpoint(1, 0)
            self._install_schedule()
            if len(self.plans) > 1 and next_stage < len(self.plans):
                if (
                    sw.scheme or case.time.scheme
                ) != case.time.scheme:  # vibration stages: the [time] scheme
                    model.problem.scheme = scheme_from_name(case.time.scheme, case.time.rho_inf)
                    model.problem.rebuild_solver()
                bar = self._bar(self.plans[-1].end_s - model.problem.t)
                for index in range(next_stage, len(self.plans)):
                    self._run_stage(index, next_chunk if index == next_stage else 0, writer, bar)
                    if index + 1 < len(self.plans):
                        self._checkpoint(index + 1, 0)
        except _Stopped:
            return {}
        finally:
            writer.close()
            if bar is not None:
                bar.close()
        summary = report.summary(self.stages, model.contact, self.history)
        report.write_summary(
            summary, self.stages, self.excitations, self.output / "summary.txt", comm
        )
        if case.output.plots:
            report.plot_history(self.history, self.stages, self.output, comm)
        self.log(report.format_summary(summary, self.stages, self.excitations))
        return summary

    def _bar(self, total: float):
        if not self.progress or total <= 0:
            return None
        from tqdm import tqdm

        return tqdm(
            total=total,
            unit="s",
            bar_format="{l_bar}{bar}| {n:.4g}/{total:.4g} s simulated {postfix}",
        )


def _write_line(text: str) -> None:
    """Print a line of the run's log without breaking an active progress bar (rank 0)."""
    from tqdm import tqdm

    tqdm.write(text)
    sys.stdout.flush()


class _Stopped(Exception):
    """Raised after ``stop_after_checkpoints`` checkpoints (simulated kill)."""
