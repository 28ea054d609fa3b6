"""Measured radial imperfections of a part's wall (docs/physics.md §6).

A :class:`DeviationMap` gives the radial deviation dr [m] of a part's wall from
its nominal radius as a function of the angle theta and the part-local height z
(measured from the part's lower end, z up). Angles are counterclockwise about +z
from the +x axis. The map is periodic in angle (linear interpolation) and linear
in z between stations, held constant beyond the first and last station. Applied
to a mesh, every node of the part moves radially by dr (the whole wall moves, the
thickness is kept); see :func:`geometry.mesh.add_joint_to_gmsh`.

Two file formats (CSV with a header line; ``#`` starts a comment line):

(a) processed map: columns ``z_m, angle_deg, radial_deviation_m``; rows grouped
    by station (equal ``z_m``), stations in increasing ``z_m``.
(b) raw laser ring scans: columns ``z_m, loop, angle_deg, distance_m``; ``loop``
    is ``forward`` or ``backward``; ``distance_m`` is the measured radius of the
    part's inner surface (distance from the arm's rotation axis, on the part's
    axis, to the wall). At each station the arm
    turns 370 deg forward and back. Processing (docs/physics.md §6): (1) shift the backward
    loop onto the forward loop (best circular match; its readings at 360-370 deg,
    where the sensor dwells at the turn-around, are dropped); (2) average the two
    loops; (3) rotate each station onto the previous one (best circular match) so
    that 0 deg lines up along the axis -- the first station defines 0 deg;
    (4) interpolate between stations (the map). The deviation is the averaged
    radius minus the part's nominal radius at the station.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from geometry.parameters import ConePart

#: radial deviation [m] of a part's wall as a function of (angle [rad], part-local z [m])
RadialDeviation = Callable[
    [npt.NDArray[np.float64], npt.NDArray[np.float64]], npt.NDArray[np.float64]
]

MAP_COLUMNS = ("z_m", "angle_deg", "radial_deviation_m")
SCAN_COLUMNS = ("z_m", "loop", "angle_deg", "distance_m")


@dataclass(frozen=True)
class DeviationMap:
    """Radial deviation [m] on stations ``z`` [m] x uniform angles ``360 k / n`` deg."""

    z: npt.NDArray[np.float64]  #: part-local station heights [m], increasing, shape (n_z,)
    deviation: npt.NDArray[np.float64]  #: radial deviation [m], shape (n_z, n_angles)

    def __post_init__(self) -> None:
        z, dev = np.asarray(self.z, dtype=np.float64), np.asarray(self.deviation, dtype=np.float64)
        if z.ndim != 1 or dev.ndim != 2 or dev.shape[0] != z.size or dev.shape[1] < 3:
            raise ValueError(f"deviation must have shape (len(z), n_angles >= 3), got {dev.shape}")
        if np.any(np.diff(z) <= 0):
            raise ValueError("station heights z must be strictly increasing")
        if not (np.all(np.isfinite(z)) and np.all(np.isfinite(dev))):
            raise ValueError("station heights and deviations must be finite")
        object.__setattr__(self, "z", z)
        object.__setattr__(self, "deviation", dev)

    @property
    def angles_deg(self) -> npt.NDArray[np.float64]:
        """The uniform angle grid [deg]."""
        return np.arange(self.deviation.shape[1]) * 360.0 / self.deviation.shape[1]

    def __call__(self, theta: npt.ArrayLike, z: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Radial deviation [m] at angles ``theta`` [rad] and part-local heights ``z`` [m]."""
        theta, z = np.broadcast_arrays(
            np.asarray(theta, dtype=np.float64), np.asarray(z, dtype=np.float64)
        )
        n = self.deviation.shape[1]
        a = np.mod(np.degrees(theta) * n / 360.0, n)
        i0 = np.floor(a).astype(int) % n
        wa = a - np.floor(a)
        i1 = (i0 + 1) % n
        if self.z.size == 1:
            k0 = k1 = np.zeros(z.shape, dtype=int)
            wz = np.zeros(z.shape)
        else:
            zc = np.clip(z, self.z[0], self.z[-1])
            k0 = np.clip(np.searchsorted(self.z, zc, side="right") - 1, 0, self.z.size - 2)
            k1 = k0 + 1
            wz = (zc - self.z[k0]) / (self.z[k1] - self.z[k0])
        d = self.deviation
        lower = (1 - wa) * d[k0, i0] + wa * d[k0, i1]
        upper = (1 - wa) * d[k1, i0] + wa * d[k1, i1]
        return (1 - wz) * lower + wz * upper


def check_imperfections(
    imperfections: Mapping[str, RadialDeviation] | None,
) -> dict[str, RadialDeviation]:
    """The joint's imperfections as a dict with keys among ``"mp"``, ``"tp"``."""
    imperfections = dict(imperfections or {})
    unknown = set(imperfections) - {"mp", "tp"}
    if unknown:
        raise ValueError(f"imperfections keys must be 'mp' and/or 'tp', got {sorted(unknown)}")
    return imperfections


def ovality(amplitude: float, m: int = 2, phase_deg: float = 0.0) -> RadialDeviation:
    """Synthetic radial deviation ``amplitude cos(m (theta - phase))`` [m], uniform in z."""
    phase = math.radians(phase_deg)

    def deviation(theta: npt.ArrayLike, z: npt.ArrayLike) -> npt.NDArray[np.float64]:
        theta, z = np.broadcast_arrays(np.asarray(theta, dtype=np.float64), np.asarray(z))
        return amplitude * np.cos(m * (theta - phase))

    return deviation


# --- reading ----------------------------------------------------------------------------


@dataclass(frozen=True)
class _Station:
    z: float
    lines: tuple[int, int]  #: first and last line of the station in the file
    rows: list[tuple[int, dict[str, float | str]]]


def _data_lines(path: Path) -> list[tuple[int, str]]:
    """(line number, text) of the non-blank, non-comment lines; the first is the header."""
    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    with path.open(newline="") as f:
        lines = [
            (i, line)
            for i, line in enumerate(f, start=1)
            if line.strip() and not line.lstrip().startswith("#")
        ]
    if not lines:
        raise ValueError(f"{path}: empty file (expected a header line)")
    return lines


def _split(line: str) -> list[str]:
    return [c.strip() for c in next(csv.reader([line]))]


def _read_rows(
    path: Path, columns: tuple[str, ...], text_columns: tuple[str, ...] = ()
) -> list[tuple[int, dict[str, float | str]]]:
    """Rows of a CSV file as (line number, {column: value}); numeric columns checked."""
    lines = _data_lines(path)
    header_line, header = lines[0]
    names = _split(header)
    missing = [c for c in columns if c not in names]
    if missing:
        raise ValueError(
            f"{path}, line {header_line}: missing column(s) {missing}; "
            f"expected {list(columns)}, found {names}"
        )
    index = {c: names.index(c) for c in columns}
    rows = []
    for lineno, line in lines[1:]:
        fields = _split(line)
        if len(fields) < len(names):
            raise ValueError(f"{path}, line {lineno}: {len(fields)} fields, expected {len(names)}")
        row: dict[str, float | str] = {}
        for c in columns:
            text = fields[index[c]]
            if c in text_columns:
                row[c] = text
                continue
            try:
                value = float(text)
            except ValueError:
                raise ValueError(f"{path}, line {lineno}: {c} = {text!r} is not a number") from None
            if not math.isfinite(value):
                raise ValueError(f"{path}, line {lineno}: {c} is {text} (NaN or infinite)")
            row[c] = value
        rows.append((lineno, row))
    if not rows:
        raise ValueError(f"{path}: no data rows")
    return rows


def _stations(path: Path, rows: list[tuple[int, dict]]) -> list[_Station]:
    """Group consecutive rows of equal z_m into stations; stations must increase in z."""
    stations: list[_Station] = []
    current: list[tuple[int, dict]] = []
    for lineno, row in rows:
        if current and row["z_m"] != current[0][1]["z_m"]:
            stations.append(
                _Station(current[0][1]["z_m"], (current[0][0], current[-1][0]), current)
            )
            current = []
            if row["z_m"] < stations[-1].z:
                raise ValueError(
                    f"{path}, line {lineno}: station z_m = {row['z_m']} m comes after station "
                    f"z_m = {stations[-1].z} m; stations must be in increasing z_m "
                    "(non-monotonic stations)"
                )
        current.append((lineno, row))
    stations.append(_Station(current[0][1]["z_m"], (current[0][0], current[-1][0]), current))
    return stations


def _check_full_turn(
    path: Path, lines: tuple[int, int], what: str, angles_deg: np.ndarray, max_gap_deg: float
) -> None:
    """The angles (mod 360) must cover a full turn with no gap wider than ``max_gap_deg``."""
    a = np.unique(np.mod(angles_deg, 360.0))
    gaps = np.diff(np.append(a, a[0] + 360.0))
    k = int(np.argmax(gaps))
    if a.size < 3 or gaps[k] > max_gap_deg:
        raise ValueError(
            f"{path}, lines {lines[0]}-{lines[1]}: {what} angles do not cover a full turn: "
            f"gap of {gaps[k]:.4g} deg after {a[k]:.4g} deg (at most {max_gap_deg} deg allowed)"
        )


def _resample(angles_deg: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """Periodic linear interpolation onto the uniform grid 360 k / n deg."""
    return np.interp(np.arange(n) * 360.0 / n, np.mod(angles_deg, 360.0), values, period=360.0)


def _n_angles(angles_deg: np.ndarray) -> int:
    """Grid size matching the median angular spacing of a station."""
    a = np.unique(np.mod(angles_deg, 360.0))
    return max(3, int(round(360.0 / float(np.median(np.diff(a))))))


def _check_size(
    path: Path, where: str, deviation: np.ndarray, part: ConePart, max_thickness_fraction: float
) -> None:
    limit = max_thickness_fraction * part.thickness
    worst = float(np.max(np.abs(deviation)))
    if worst > limit:
        raise ValueError(
            f"{path}, {where}: radial deviation of {worst * 1e3:.4g} mm exceeds "
            f"{max_thickness_fraction} x thickness = {limit * 1e3:.4g} mm"
        )


def read_deviation_map(
    path: str | Path,
    part: ConePart,
    max_thickness_fraction: float = 0.5,
    max_angle_gap_deg: float = 10.0,
) -> DeviationMap:
    """Read a processed deviation map CSV (``z_m, angle_deg, radial_deviation_m``).

    Deviations larger than ``max_thickness_fraction * part.thickness`` and stations
    whose angles leave a gap wider than ``max_angle_gap_deg`` are rejected.
    """
    path = Path(path)
    rows = _read_rows(path, MAP_COLUMNS)
    for lineno, row in rows:
        _check_size(
            path,
            f"line {lineno}",
            np.array([row["radial_deviation_m"]]),
            part,
            max_thickness_fraction,
        )
    stations = _stations(path, rows)
    angles = [np.array([r["angle_deg"] for _, r in s.rows]) for s in stations]
    for s, a in zip(stations, angles):
        _check_full_turn(path, s.lines, f"station z_m = {s.z} m:", a, max_angle_gap_deg)
    n = max(_n_angles(a) for a in angles)
    dev = np.array(
        [
            _resample(a, np.array([r["radial_deviation_m"] for _, r in s.rows]), n)
            for s, a in zip(stations, angles)
        ]
    )
    return DeviationMap(np.array([s.z for s in stations]), dev)


def circular_shift(
    reference: np.ndarray, signal: np.ndarray, max_shift_deg: float = 180.0
) -> float:
    """Shift s [deg] minimising sum (reference(phi) - signal(phi + s))^2 over a uniform turn.

    Circular cross-correlation (FFT) at whole grid steps within ``|s| <= max_shift_deg``,
    refined by a parabola through the best step and its neighbours.
    """
    n = reference.size
    step = 360.0 / n
    corr = np.fft.irfft(np.conj(np.fft.rfft(reference)) * np.fft.rfft(signal), n)
    shifts = np.arange(n)
    shifts[shifts > n // 2] -= n
    corr[np.abs(shifts) * step > max_shift_deg] = -np.inf
    j = int(np.argmax(corr))
    c_minus, c0, c_plus = corr[(j - 1) % n], corr[j], corr[(j + 1) % n]
    denom = c_minus - 2 * c0 + c_plus
    frac = 0.5 * (c_minus - c_plus) / denom if np.isfinite(denom) and denom < 0 else 0.0
    return (shifts[j] + frac) * step


def _shifted(values: np.ndarray, shift_deg: float) -> np.ndarray:
    """values(phi + shift) on the same uniform grid (periodic linear interpolation)."""
    n = values.size
    grid = np.arange(n) * 360.0 / n
    return np.interp(grid + shift_deg, grid, values, period=360.0)


def process_ring_scans(
    path: str | Path,
    part: ConePart,
    max_thickness_fraction: float = 0.5,
    max_angle_gap_deg: float = 10.0,
    max_loop_shift_deg: float = 20.0,
) -> DeviationMap:
    """Process raw laser ring scans (``z_m, loop, angle_deg, distance_m``) into a map.

    The four steps of docs/physics.md §6 (module docstring). ``max_loop_shift_deg`` bounds the
    backward-loop shift searched in step 1.
    """
    path = Path(path)
    rows = _read_rows(path, SCAN_COLUMNS, text_columns=("loop",))
    for lineno, row in rows:
        if row["loop"] not in ("forward", "backward"):
            raise ValueError(
                f"{path}, line {lineno}: loop = {row['loop']!r}, expected 'forward' or 'backward'"
            )
    stations = _stations(path, rows)
    profiles = []
    for s in stations:
        loops = {}
        for name in ("forward", "backward"):
            data = np.array(
                [(r["angle_deg"], r["distance_m"]) for _, r in s.rows if r["loop"] == name]
            )
            if data.size == 0:
                raise ValueError(
                    f"{path}, lines {s.lines[0]}-{s.lines[1]}: station z_m = {s.z} m "
                    f"has no {name} loop"
                )
            data = data[(data[:, 0] >= 0.0) & (data[:, 0] < 360.0)]  # drop the turn-around
            _check_full_turn(
                path, s.lines, f"station z_m = {s.z} m, {name} loop", data[:, 0], max_angle_gap_deg
            )
            loops[name] = data
        n = _n_angles(loops["forward"][:, 0])
        forward, backward = (_resample(d[:, 0], d[:, 1], n) for d in loops.values())
        lag = circular_shift(forward, backward, max_loop_shift_deg)  # (1)
        profiles.append(0.5 * (forward + _shifted(backward, lag)))  # (2)
    n = max(p.size for p in profiles)
    profiles = [
        p if p.size == n else _resample(np.arange(p.size) * 360.0 / p.size, p, n) for p in profiles
    ]
    aligned = [profiles[0]]
    for p in profiles[1:]:  # (3) rotate onto the previous station
        ref = aligned[-1] - aligned[-1].mean()
        aligned.append(_shifted(p, circular_shift(ref, p - p.mean())))
    z = np.array([s.z for s in stations])
    deviation = np.array(aligned) - part.inner_radius(z)[:, None]
    for s, d in zip(stations, deviation):
        _check_size(
            path,
            f"lines {s.lines[0]}-{s.lines[1]} (station z_m = {s.z} m)",
            d,
            part,
            max_thickness_fraction,
        )
    return DeviationMap(z, deviation)  # (4) interpolation: DeviationMap.__call__


def read_imperfection(path: str | Path, part: ConePart, **limits: float) -> DeviationMap:
    """A deviation map from either file format, told apart by the header (``loop`` column:
    raw scans); ``limits`` are passed on (``max_thickness_fraction``, ``max_angle_gap_deg``)."""
    path = Path(path)
    if "loop" in _split(_data_lines(path)[0][1]):
        return process_ring_scans(path, part, **limits)
    return read_deviation_map(path, part, **limits)
