"""Settings of an installation run: the case-file tables below the geometry ones.

``[contact]``, ``[damping]``, ``[time]``, ``[self_weight]``, ``[vibration]``, ``[output]``,
``[static_force]`` and ``[imperfections.mp]`` / ``[imperfections.tp]``, each a frozen
dataclass checked on construction (a ValueError names the key); ``InstallationCase``
(``solver.installation.case``) reads them from a case as a whole. SI units; frequencies
in Hz, forces in N.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from petsc4py import PETSc

from geometry.imperfections import RadialDeviation, ovality, read_imperfection
from solver.dynamics.loads import PiecewiseLinearForce, RampedAxialForce, Stage

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
    #: degree of the Gauss rule on the slave facets (0: 2 degree + 1); its points are the contact
    #: points (docs/contact.md)
    quadrature_degree: int = 0
    max_iterations: int = 30  #: Newton iterations per step before the step is cut
    #: a step has converged when ||R|| <= newton_rtol max(||R_0||, ||b||) [N] (R: the residual
    #: forces, b: the step's load with its inertia terms; docs/dynamics.md, time loop)
    newton_rtol: float = 1e-7
    max_backtracks: int = (
        6  #: Newton line-search halvings (solver.dynamics.newton.ContactNewtonSolver)
    )
    max_gap_change: float = 0.0  #: gap-limited Newton steps [m] (ContactNewtonSolver); 0: off
    #: sparse LU of the Newton corrections: "mumps" (faster), "superlu_dist" (bitwise repeatable on
    #: several ranks, where MUMPS's factors vary at round-off from run to run, which stick-slip
    #: amplifies; not with event steps in the self-weight stage), or "auto": MUMPS on one rank,
    #: SuperLU_DIST on several where it may run
    lu_solver: str = "auto"
    #: Newton on the contact zone with the linear bulk condensed exactly (solver.dynamics.condensation):
    #: cheaper steps, plus |interface| bulk solves whenever the step size changes
    condense_bulk: bool = False
    #: nonlinear solver of a step: "zone" (generalized Newton on the contact zone,
    #: solver.dynamics.newton) or "points" (Newton on the contact points' tractions,
    #: solver.dynamics.point_newton; without lagged_friction, mu follows the outer iterate's slip
    #: speed: a fixed point)
    solver: str = "zone"
    #: "points": slave points within this gap of the master [m] are candidates from the start
    candidate_gap: float = 2e-6

    def __post_init__(self) -> None:
        if not isinstance(self.condense_bulk, bool):
            raise ValueError(f"condense_bulk must be true or false, got {self.condense_bulk!r}")
        if not (isinstance(self.max_iterations, int) and self.max_iterations >= 1):
            raise ValueError(f"max_iterations must be an integer >= 1, got {self.max_iterations!r}")
        if not 0 < self.newton_rtol < 1:
            raise ValueError(f"newton_rtol must lie in (0, 1), got {self.newton_rtol!r}")
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
        if not (isinstance(self.quadrature_degree, int) and self.quadrature_degree >= 0):
            raise ValueError(
                f"quadrature_degree must be an integer >= 0, got {self.quadrature_degree!r}"
            )
        _check_choice("lu_solver", self.lu_solver, ("auto", "mumps", "superlu_dist"))
        _check_choice("solver", self.solver, ("zone", "points"))
        if not self.candidate_gap >= 0:
            raise ValueError(f"candidate_gap must be >= 0 m, got {self.candidate_gap}")
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

    #: newmark | generalised-alpha (a case with quasi-static is refused when it is checked:
    #: the vibration stages need inertia, ``planning.check_time_scheme``)
    scheme: str = "generalised-alpha"
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
    """``[self_weight]``: docs/physics.md §3 self-weight emulation on the TP top face."""

    force_N: float = -10e3  #: axial force, negative = down [N]
    ramp_time_s: float = 2.0
    hold_s: float = 0.1  #: held after the ramp [s]
    dt_s: float = 0.01  #: time step [s]
    #: step within settling events [s] (0: none): a step during which the settlement rate
    #: exceeds event_rate_mm_s is retaken in steps of event_dt_s (it divides dt_s)
    event_dt_s: float = 0.0
    #: settlement rate that starts an event [mm/s]: a tenth of the one that counts an episode
    #: ([output] slip_rate_mm_s), so the steps before an event's onset are retaken as well
    event_rate_mm_s: float = 0.1
    #: fine steps below event_rate_mm_s after which the step dt_s resumes (the ringing after an
    #: event resolved)
    event_calm_steps: int = 20
    #: "" = the [time] scheme and rho_inf; or quasi-static / newmark / generalised-alpha (with
    #: ``rho_inf``): the self-weight stage may damp numerically what the vibration stages must not
    scheme: str = ""
    rho_inf: float = 0.0  #: generalised-alpha spectral radius of the self-weight stage [-]

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
        if not self.event_dt_s >= 0:
            raise ValueError(f"event_dt_s must be 0 (none) or positive, got {self.event_dt_s} s")
        if not self.event_rate_mm_s > 0:
            raise ValueError(f"event_rate_mm_s must be positive, got {self.event_rate_mm_s}")
        if not (type(self.event_calm_steps) is int and self.event_calm_steps >= 1):
            raise ValueError(
                f"event_calm_steps must be an integer >= 1, got {self.event_calm_steps!r}"
            )
        if self.scheme:
            _check_choice("scheme", self.scheme, ("newmark", "generalised-alpha", "quasi-static"))
        if not 0 <= self.rho_inf <= 1:
            raise ValueError(f"rho_inf must lie in [0, 1], got {self.rho_inf}")

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
    stages at the eccentric-motor amplitude 0.3632 f^2 (docs/physics.md §3: 68 and 100 Hz), then each
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
    #: also keep the state at the end of every stage in states/<k> (k = 0: self-weight), e.g.
    #: for the natural frequencies after each stage (benchmarks/scenarios.py, S8)
    stage_states: bool = False
    paraview: bool = True
    plots: bool = True
    slip_rate_mm_s: float = (
        1.0  #: the TP slips as a whole while d(settlement)/dt exceeds this [mm/s]
    )

    def __post_init__(self) -> None:
        if not isinstance(self.stage_states, bool):
            raise ValueError(f"stage_states must be true or false, got {self.stage_states!r}")
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

    def path(self, case_dir: Path) -> Path | None:
        """The map or scan file (from the working directory, else beside the case file in
        ``case_dir``); None for an ovality."""
        if not self.file:
            return None
        path = Path(self.file)
        if not path.is_file() and not path.is_absolute() and (case_dir / path).is_file():
            path = case_dir / path
        return path

    def deviation(self, part, case_dir: Path) -> RadialDeviation:
        """The radial deviation function of ``part`` (reads and checks the file)."""
        if not self.file:
            return ovality(self.amplitude_m, self.waves, self.phase_deg)
        return read_imperfection(self.path(case_dir), part)
