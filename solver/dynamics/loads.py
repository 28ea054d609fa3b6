"""Loads on the TP and their time histories (docs/physics.md §3). SI units: N, s, Hz, m.

Conventions: z is the axis, up; an axial force is along +z (negative pushes the TP
down onto the MP, positive pulls it off); "lateral" is the horizontal direction at
``lateral_angle_deg`` from the x axis.

* ``RampedAxialForce``: static axial force ramped linearly from 0 over ``ramp_time_s``,
  then held (self-weight emulation: -10 kN over 2 s).
* ``PiecewiseLinearForce``: static axial force through the points (t_k, F_k), linear
  between them, held outside (any static history, e.g. self-weight then a dismount pull).
* ``Stage``/``Schedule``: harmonic excitation F(t) = A(t) sin(phi(t)) d, stage by stage,
  with linear ramps of frequency and amplitude inside a stage. The phase is the
  integral phi(t) = 2 pi int_0^t f dt, so it is continuous across frequency ramps and
  jumps. The amplitude is a force [N] or "eccentric": the eccentric-motor law
  A = 0.3632 f^2 N (f in Hz) at the instantaneous frequency. A stage frequency may be
  "mode k", the k-th natural frequency of the current state (1-based), or "ranked k",
  the k-th best-ranked natural frequency chosen for excitation (1-based), filled in by
  ``Schedule.with_natural_frequencies`` before the stage is run. A stage with frequency
  0 Hz or amplitude 0 N is a stage without vibration (only the static force acts).
* ``TopFaceLoad``: a total force vector spread as a uniform traction over a tagged
  face (the TP top, ``geometry.tags.TP_TOP``); ``PointLoad``: a force at one point
  (shaker rod).
"""

import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import numpy.typing as npt
import ufl
from petsc4py import PETSc

from dolfinx import fem, la
from dolfinx.fem import petsc as fem_petsc

from common.case import construct
from solver.probes import PointLocator

ECCENTRIC_COEFFICIENT = (
    0.3632  #: eccentric-motor force amplitude per f^2 [N/Hz^2] (docs/physics.md §3)
)
DIRECTIONS = ("axial", "lateral", "both")
_MODE = re.compile(r"^\s*(mode|ranked)\s+(\d+)\s*$")


def eccentric_amplitude(frequency_hz: float | np.ndarray) -> float | np.ndarray:
    """Force amplitude [N] of the two counter-rotating eccentric motors at f [Hz]: 0.3632 f^2."""
    return ECCENTRIC_COEFFICIENT * np.asarray(frequency_hz) ** 2


@dataclass(frozen=True)
class RampedAxialForce:
    """Axial force [N] along +z: 0 at ``start_s``, linear to ``force_N`` at start_s + ramp_time_s, then held."""

    force_N: float = -10e3
    ramp_time_s: float = 2.0
    start_s: float = 0.0

    def __post_init__(self) -> None:
        if self.ramp_time_s < 0:
            raise ValueError(f"ramp_time_s must be >= 0, got {self.ramp_time_s} s")

    def __call__(self, t: float) -> float:
        if t <= self.start_s:
            return 0.0
        if self.ramp_time_s == 0 or t >= self.start_s + self.ramp_time_s:
            return self.force_N
        return self.force_N * (t - self.start_s) / self.ramp_time_s


@dataclass(frozen=True)
class PiecewiseLinearForce:
    """Axial force [N] along +z through the points (``times_s[k]``, ``forces_N[k]``).

    Linear between the points (times strictly increasing), ``forces_N[0]`` before the first
    and ``forces_N[-1]`` after the last point. ``RampedAxialForce(F, T)`` is the special case
    ((0, 0), (T, F)).
    """

    times_s: tuple[float, ...]
    forces_N: tuple[float, ...]

    def __post_init__(self) -> None:
        t = np.asarray(self.times_s, dtype=float)
        f = np.asarray(self.forces_N, dtype=float)
        if t.ndim != 1 or t.size == 0 or t.shape != f.shape:
            raise ValueError(
                f"need as many forces as times (at least one), got {t.size} times "
                f"and {f.size} forces"
            )
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(f))):
            raise ValueError("times_s and forces_N must be finite")
        if np.any(np.diff(t) <= 0):
            raise ValueError(f"times_s must be strictly increasing, got {list(t)}")
        object.__setattr__(self, "times_s", tuple(float(x) for x in t))
        object.__setattr__(self, "forces_N", tuple(float(x) for x in f))

    def __call__(self, t: float) -> float:
        return float(np.interp(t, self.times_s, self.forces_N))


@dataclass(frozen=True)
class Stage:
    """One stage of harmonic excitation.

    ``frequency_hz`` [Hz] (or "mode k") at the stage start, ramped linearly to
    ``frequency_end_hz`` (default: held); ``amplitude_N`` [N] or "eccentric", ramped
    linearly to ``amplitude_end_N`` (default: held; not with "eccentric");
    ``direction`` "axial", "lateral" or "both" (axial plus ``lateral_fraction`` times
    the amplitude laterally).
    """

    duration_s: float
    frequency_hz: float | str
    amplitude_N: float | str = "eccentric"
    frequency_end_hz: float | None = None
    amplitude_end_N: float | None = None
    direction: str = "axial"
    lateral_fraction: float = 0.05
    lateral_angle_deg: float = 0.0

    def __post_init__(self) -> None:
        if not (isinstance(self.duration_s, (int, float)) and self.duration_s > 0):
            raise ValueError(
                f"stage duration_s must be a positive number of seconds, got {self.duration_s!r}"
            )
        if isinstance(self.frequency_hz, str):
            m = _MODE.match(self.frequency_hz)
            if not m or int(m.group(2)) < 1:
                raise ValueError(
                    f"stage frequency_hz must be a number [Hz], 'mode k' or 'ranked k' "
                    f"(k >= 1), got {self.frequency_hz!r}"
                )
            if self.frequency_end_hz is not None:
                raise ValueError(
                    f"a stage at {self.frequency_hz!r} cannot ramp its frequency (frequency_end_hz)"
                )
        elif not self.frequency_hz >= 0:
            raise ValueError(f"stage frequency_hz must be >= 0 Hz, got {self.frequency_hz}")
        if self.frequency_end_hz is not None and not self.frequency_end_hz >= 0:
            raise ValueError(f"stage frequency_end_hz must be >= 0 Hz, got {self.frequency_end_hz}")
        if isinstance(self.amplitude_N, str):
            if self.amplitude_N != "eccentric":
                raise ValueError(
                    f"stage amplitude_N must be a force [N] or 'eccentric', got {self.amplitude_N!r}"
                )
            if self.amplitude_end_N is not None:
                raise ValueError(
                    "amplitude_end_N cannot be combined with the 'eccentric' amplitude law"
                )
        elif not self.amplitude_N >= 0:
            raise ValueError(f"stage amplitude_N must be >= 0 N, got {self.amplitude_N}")
        if self.amplitude_end_N is not None and not self.amplitude_end_N >= 0:
            raise ValueError(f"stage amplitude_end_N must be >= 0 N, got {self.amplitude_end_N}")
        if self.direction not in DIRECTIONS:
            raise ValueError(f"stage direction must be one of {DIRECTIONS}, got {self.direction!r}")
        if not 0 <= self.lateral_fraction <= 1:
            raise ValueError(
                f"stage lateral_fraction must lie in [0, 1], got {self.lateral_fraction}"
            )

    @property
    def mode_number(self) -> int | None:
        """k of a 'mode k' stage, else None."""
        return self._natural("mode")

    @property
    def ranked_number(self) -> int | None:
        """k of a 'ranked k' stage, else None."""
        return self._natural("ranked")

    def _natural(self, kind: str) -> int | None:
        m = _MODE.match(self.frequency_hz) if isinstance(self.frequency_hz, str) else None
        return int(m.group(2)) if m and m.group(1) == kind else None

    def frequency(self, tau: float) -> float:
        """Frequency [Hz] at time tau [s] into the stage."""
        f0 = self._f0()
        f1 = f0 if self.frequency_end_hz is None else self.frequency_end_hz
        return f0 + (f1 - f0) * tau / self.duration_s

    def phase_increment(self, tau: float) -> float:
        """2 pi int_0^tau f dt [rad] (exact for the linear ramp)."""
        f0 = self._f0()
        f1 = f0 if self.frequency_end_hz is None else self.frequency_end_hz
        return 2 * math.pi * (f0 * tau + 0.5 * (f1 - f0) * tau**2 / self.duration_s)

    def amplitude(self, tau: float) -> float:
        """Force amplitude [N] at time tau [s] into the stage."""
        if self.amplitude_N == "eccentric":
            return float(eccentric_amplitude(self.frequency(tau)))
        a1 = self.amplitude_N if self.amplitude_end_N is None else self.amplitude_end_N
        return self.amplitude_N + (a1 - self.amplitude_N) * tau / self.duration_s

    def direction_vector(self) -> np.ndarray:
        """Unit-amplitude force direction (x, y, z) [-]; 'both' = e_z + lateral_fraction e_lat."""
        angle = math.radians(self.lateral_angle_deg)
        lateral = np.array([math.cos(angle), math.sin(angle), 0.0])
        axial = np.array([0.0, 0.0, 1.0])
        return {
            "axial": axial,
            "lateral": lateral,
            "both": axial + self.lateral_fraction * lateral,
        }[self.direction]

    def _f0(self) -> float:
        if isinstance(self.frequency_hz, str):
            raise ValueError(
                f"stage at {self.frequency_hz!r}: natural frequencies not filled in yet "
                "(Schedule.with_natural_frequencies)"
            )
        return self.frequency_hz


class Schedule:
    """Stages run back to back from ``start_s``; zero force before and after."""

    def __init__(self, stages: Sequence[Stage], start_s: float = 0.0):
        if len(stages) == 0:
            raise ValueError("a schedule needs at least one stage")
        self.stages = tuple(stages)
        self.start_s = float(start_s)
        durations = np.array([s.duration_s for s in self.stages])
        self.stage_starts = self.start_s + np.concatenate([[0.0], np.cumsum(durations)[:-1]])
        self.end_s = self.start_s + float(durations.sum())
        self._phase_starts = None

    @classmethod
    def from_dicts(cls, stages: Sequence[dict[str, Any]], start_s: float = 0.0) -> "Schedule":
        """Schedule from a list of tables (the ``[[schedule]]`` array of a TOML case)."""
        if not isinstance(stages, (list, tuple)):
            raise ValueError(
                f"[[schedule]] must be a list of stage tables, got {type(stages).__name__}"
            )
        return cls(
            [construct(Stage, dict(s), f"schedule stage {i + 1}") for i, s in enumerate(stages)],
            start_s,
        )

    def with_natural_frequencies(
        self, frequencies_hz: Sequence[float], ranked_hz: Sequence[float] = ()
    ) -> "Schedule":
        """Copy with every 'mode k' stage set to frequencies_hz[k - 1] and every 'ranked k'
        stage to ranked_hz[k - 1] [Hz]."""
        stages = []
        for s in self.stages:
            for k, known, what in (
                (s.mode_number, frequencies_hz, "mode"),
                (s.ranked_number, ranked_hz, "ranked"),
            ):
                if k is not None:
                    if not 1 <= k <= len(known):
                        raise ValueError(
                            f"stage asks for {what} {k}, but {len(known)} {what} frequencies are known"
                        )
                    s = replace(s, frequency_hz=float(known[k - 1]))
            stages.append(s)
        return Schedule(stages, self.start_s)

    @property
    def needs_modes(self) -> bool:
        """Whether some stage is at 'mode k' or 'ranked k' (needs the modal stage)."""
        return any(s.mode_number is not None or s.ranked_number is not None for s in self.stages)

    def _stage_at(self, t: float) -> tuple[int, float] | None:
        if t < self.start_s or t > self.end_s:
            return None
        k = int(np.searchsorted(self.stage_starts, t, side="right") - 1)
        return k, t - self.stage_starts[k]

    def phase(self, t: float) -> float:
        """phi(t) = 2 pi int_start^t f dt [rad], continuous across stages."""
        if self._phase_starts is None:
            inc = [s.phase_increment(s.duration_s) for s in self.stages]
            self._phase_starts = np.concatenate([[0.0], np.cumsum(inc)])
        where = self._stage_at(min(max(t, self.start_s), self.end_s))
        k, tau = where
        return float(self._phase_starts[k] + self.stages[k].phase_increment(tau))

    def frequency(self, t: float) -> float:
        """Excitation frequency [Hz] at t (0 outside the schedule)."""
        where = self._stage_at(t)
        return 0.0 if where is None else self.stages[where[0]].frequency(where[1])

    def amplitude(self, t: float) -> float:
        """Force amplitude [N] at t (0 outside the schedule)."""
        where = self._stage_at(t)
        return 0.0 if where is None else self.stages[where[0]].amplitude(where[1])

    def force(self, t: float) -> np.ndarray:
        """Force vector (Fx, Fy, Fz) [N] at t: A(t) sin(phi(t)) d."""
        where = self._stage_at(t)
        if where is None:
            return np.zeros(3)
        stage = self.stages[where[0]]
        return stage.amplitude(where[1]) * math.sin(self.phase(t)) * stage.direction_vector()


class _UnitForces:
    """Load vectors of a unit total force along x, y and z; f = sum_i F_i g_i."""

    def __init__(self, vectors: list[PETSc.Vec]):
        self.vectors = vectors

    def add(self, force: npt.ArrayLike, out: PETSc.Vec) -> None:
        """out += load vector of the total force (Fx, Fy, Fz) [N]."""
        for F_i, g_i in zip(np.asarray(force, dtype=float), self.vectors):
            if F_i:
                out.axpy(F_i, g_i)


class TopFaceLoad(_UnitForces):
    """A total force [N] spread as a uniform traction F / area over the facets tagged ``tag``."""

    def __init__(self, V: fem.FunctionSpace, facet_tags, tag: int):
        mesh = V.mesh
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags, subdomain_id=tag)
        area = mesh.comm.allreduce(fem.assemble_scalar(fem.form(1.0 * ds)))
        if not area > 0:
            raise ValueError(f"TopFaceLoad: no facets with tag {tag} (area 0)")
        self.area = area  #: [m^2]
        w = ufl.TestFunction(V)
        vectors = []
        for i in range(mesh.geometry.dim):
            e_i = ufl.as_vector([1.0 / area if j == i else 0.0 for j in range(mesh.geometry.dim)])
            g = fem_petsc.assemble_vector(fem.form(ufl.inner(e_i, w) * ds))
            g.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            vectors.append(g)
        super().__init__(vectors)


class PointLoad(_UnitForces):
    """A force [N] at one point x_p (m) of the body: f_i = F phi_i(x_p) (V Lagrange)."""

    def __init__(self, V: fem.FunctionSpace, point: npt.ArrayLike):
        locator = PointLocator(V.mesh, point)
        phi = locator.basis_values(V)
        bs = V.dofmap.index_map_bs
        vectors = []
        for i in range(bs):
            g = la.vector(V.dofmap.index_map, bs)
            for cell, values in zip(locator.cells, phi):
                np.add.at(g.array, V.dofmap.cell_dofs(cell) * bs + i, values)
            g.scatter_reverse(la.InsertMode.add)
            vec = fem_petsc.create_vector(V)
            vec.array_w[:] = g.array[: vec.getLocalSize()]
            vectors.append(vec)
        super().__init__(vectors)


def shaker_point(part, z_offset: float, height: float, angle_deg: float) -> np.ndarray:
    """Mid-wall point [m] of a cone part at part-local ``height`` [m] and ``angle_deg`` about z.

    ``part`` is a ``geometry.parameters.ConePart`` whose lower end sits at global z_offset [m].
    """
    if not 0 <= height <= part.total_length:
        raise ValueError(f"shaker height {height} m outside the part (0 .. {part.total_length} m)")
    r = 0.5 * (float(part.outer_radius(height)) + float(part.inner_radius(height)))
    a = math.radians(angle_deg)
    return np.array([r * math.cos(a), r * math.sin(a), z_offset + height])


@dataclass
class TPLoading:
    """Total load on the TP at time t: static axial force + scheduled harmonic force.

    The static force and the ``schedule`` act through the top face; a ``shaker``
    (PointLoad, Schedule) pair adds a point force. Call as ``load(t, out)`` (out += f(t)).
    """

    top: TopFaceLoad
    static_axial: Callable[[float], float] | None = None
    schedule: Schedule | None = None
    shaker: tuple[PointLoad, Schedule] | None = None

    def force_on_top(self, t: float) -> np.ndarray:
        """Total force (Fx, Fy, Fz) [N] on the top face at t."""
        force = np.zeros(3)
        if self.static_axial is not None:
            force[2] += self.static_axial(t)
        if self.schedule is not None:
            force += self.schedule.force(t)
        return force

    def __call__(self, t: float, out: PETSc.Vec) -> None:
        self.top.add(self.force_on_top(t), out)
        if self.shaker is not None:
            point, schedule = self.shaker
            point.add(schedule.force(t), out)


def frequency_steps(
    f_start_hz: float,
    f_stop_hz: float,
    f_step_hz: float,
    dwell_s: float,
    amplitude_N: float | str = "eccentric",
    **stage_options: Any,
) -> list[Stage]:
    """Step-wise frequency increase: f_start, f_start + f_step, ... up to f_stop [Hz] (included
    when it is on the grid), each held ``dwell_s`` [s] (docs/physics.md §3: 10 -> 130 Hz in 10 Hz steps of
    0.5 s with the eccentric amplitude). ``stage_options``: direction, lateral_fraction, ..."""
    if not (f_start_hz > 0 and f_step_hz > 0 and f_stop_hz >= f_start_hz):
        raise ValueError(
            f"need 0 < f_start <= f_stop and f_step > 0, got f_start = {f_start_hz} Hz, "
            f"f_stop = {f_stop_hz} Hz, f_step = {f_step_hz} Hz"
        )
    n = int(math.floor((f_stop_hz - f_start_hz) / f_step_hz + 1e-9)) + 1
    return [
        Stage(dwell_s, f_start_hz + k * f_step_hz, amplitude_N, **stage_options) for k in range(n)
    ]


def frequency_ramp(
    f_start_hz: float,
    f_stop_hz: float,
    duration_s: float,
    amplitude_N: float | str = "eccentric",
    **stage_options: Any,
) -> list[Stage]:
    """A slow linear frequency ramp f_start -> f_stop [Hz] over ``duration_s`` [s] (docs/physics.md §3:
    0 -> 125 Hz over 13 to 200 s), as one stage (the phase stays continuous)."""
    return [Stage(duration_s, f_start_hz, amplitude_N, frequency_end_hz=f_stop_hz, **stage_options)]
