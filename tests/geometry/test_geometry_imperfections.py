"""Imperfection maps and raw laser ring scans (docs/physics.md §6): processing and bad-file errors."""

import math
from pathlib import Path

import numpy as np
import pytest

from geometry.imperfections import (
    DeviationMap,
    process_ring_scans,
    read_deviation_map,
    read_imperfection,
)
from geometry.parameters import ConePart, load_geometry

CASES = Path(__file__).resolve().parents[2] / "cases"


@pytest.fixture(scope="module")
def tp() -> ConePart:
    return load_geometry(CASES / "scaled.toml")[0].tp


def known_shape(phi_deg: np.ndarray, z: float) -> np.ndarray:
    """Radial deviation [m]: ovality growing with z, a 3-lobe term and a weld seam at 75 deg."""
    phi = np.radians(phi_deg)
    seam = (np.mod(phi_deg - 75.0 + 180.0, 360.0) - 180.0) / 6.0
    return (
        (0.8e-3 + 0.4e-3 * z) * np.cos(2 * (phi - math.radians(20.0)))
        + 0.2e-3 * np.cos(3 * phi + 0.4)
        + 0.4e-3 * np.exp(-0.5 * seam**2)
    )


def write_scans(
    path: Path, tp: ConePart, stations: np.ndarray, lag_deg: float, offsets_deg: np.ndarray
) -> None:
    """Raw scans of ``known_shape``: arm 0 deg at true angle ``offset``; the backward loop
    lags by ``lag_deg``; the sensor dwells at the turn-around (360-370 deg backward)."""
    forward = np.arange(0.0, 371.0)
    lines = ["z_m,loop,angle_deg,distance_m"]
    for z, offset in zip(stations, offsets_deg):

        def radius(a, z=z, offset=offset):
            return float(tp.inner_radius(z)) + known_shape(a + offset, z)

        for a, r in zip(forward, radius(forward)):
            lines.append(f"{z:.4f},forward,{a:.1f},{r:.9f}")
        backward = forward[::-1]
        r_back = radius(backward - lag_deg)
        r_back[backward >= 360.0] = radius(np.array([370.0]))[0] + 3e-3  # dwell: junk
        for a, r in zip(backward, r_back):
            lines.append(f"{z:.4f},backward,{a:.1f},{r:.9f}")
    path.write_text("\n".join(lines) + "\n")


def test_raw_scans_processed_back_to_known_shape(tp, tmp_path):
    """Lagged backward loop, corrupted turn-around and random station rotations are undone
    within 0.05 mm of the known shape (0 deg is the first station's)."""
    rng = np.random.default_rng(1)
    stations = np.arange(0.10, 0.901, 0.02)
    offsets = np.concatenate([[0.0], rng.uniform(0.0, 360.0, stations.size - 1)])
    path = tmp_path / "scans.csv"
    write_scans(path, tp, stations, lag_deg=2.7, offsets_deg=offsets)
    deviation_map = process_ring_scans(path, tp)
    assert np.allclose(deviation_map.z, stations)
    angles = deviation_map.angles_deg
    truth = np.array([known_shape(angles, z) for z in stations])
    error = np.max(np.abs(deviation_map.deviation - truth))
    assert error < 0.05e-3, f"max error {error * 1e3:.4f} mm"
    # without the backward-loop shift the average would be off by far more than the tolerance
    lagged = 0.5 * (known_shape(angles, 0.1) + known_shape(angles - 2.7, 0.1))
    assert np.max(np.abs(lagged - truth[0])) > 0.05e-3
    # between stations: linear in z; between angles: periodic
    z_mid = 0.5 * (stations[3] + stations[4])
    theta = np.radians(np.array([0.0, 359.5, 360.0]))
    expected = 0.5 * (deviation_map.deviation[3] + deviation_map.deviation[4])
    got = deviation_map(theta, z_mid)
    assert got[0] == pytest.approx(expected[0], abs=1e-12)
    assert got[2] == pytest.approx(expected[0], abs=1e-12)
    assert got[1] == pytest.approx(0.5 * (expected[-1] + expected[0]), abs=1e-12)


def test_deviation_map_reads_processed_csv(tp, tmp_path):
    """A processed map written from a known field is read back exactly at its samples."""
    z = np.array([0.0, 0.5, 1.0])
    angles = np.arange(0.0, 360.0, 5.0)
    rows = ["# processed map", "z_m,angle_deg,radial_deviation_m"]
    for zk in z:
        rows += [f"{zk},{a},{known_shape(np.array([a]), zk)[0]:.12f}" for a in angles]
    path = tmp_path / "map.csv"
    path.write_text("\n".join(rows) + "\n")
    m = read_deviation_map(path, tp)
    assert m.deviation.shape == (3, 72)
    th, zz = np.meshgrid(np.radians(angles), z)
    assert np.allclose(m(th, zz), [known_shape(angles, zk) for zk in z], atol=1e-12)
    # held constant beyond the last station
    assert np.allclose(m(th[0], 2.0), m(th[0], 1.0))


def good_map_rows() -> list[str]:
    rows = ["z_m,angle_deg,radial_deviation_m"]
    for z in (0.1, 0.2, 0.3):
        rows += [f"{z},{a},0.0001" for a in range(0, 360, 10)]
    return rows


def bad_map_cases() -> dict[str, tuple[list[str], str]]:
    rows = good_map_rows()
    n = 36  # rows per station; line numbers are 1-based with the header on line 1
    return {
        "missing column": (
            ["z_m,angle,radial_deviation_m"] + rows[1:],
            r"line 1: missing column\(s\) \['angle_deg'\]",
        ),
        "NaN": (rows[:5] + ["0.1,40,nan"] + rows[6:], r"line 6: radial_deviation_m is nan"),
        "not a number": (rows[:5] + ["0.1,forty,0.0"] + rows[6:], r"line 6: angle_deg = 'forty'"),
        "half turn": (
            rows[: 1 + n // 2] + rows[1 + n :],
            r"lines 2-19: station z_m = 0.1 m: angles do not cover a full turn: "
            r"gap of 190 deg after 170 deg",
        ),
        "non-monotonic": (
            rows[:1] + rows[1 + n : 1 + 2 * n] + rows[1 : 1 + n] + rows[1 + 2 * n :],
            r"line 38: station z_m = 0.1 m comes after station z_m = 0.2 m.*"
            r"non-monotonic",
        ),
        "too large": (
            rows[:10] + ["0.1,90,0.0035"] + rows[11:],
            r"line 11: radial deviation of 3.5 mm exceeds 0.5 x thickness = 3 mm",
        ),
    }


@pytest.mark.parametrize("case", list(bad_map_cases()))
def test_bad_map_files(tp, tmp_path, case):
    assert read_deviation_map(_write(tmp_path, good_map_rows()), tp).z.size == 3
    rows, message = bad_map_cases()[case]
    path = _write(tmp_path, rows)
    with pytest.raises(ValueError, match=rf"{path}.*{message}"):
        read_deviation_map(path, tp)


def bad_scan_cases(tp: ConePart, tmp_path: Path) -> dict[str, tuple[list[str], str]]:
    path = tmp_path / "good_scans.csv"
    write_scans(path, tp, np.array([0.1, 0.12]), 2.0, np.array([0.0, 30.0]))
    rows = path.read_text().splitlines()
    per_loop = 371
    big = [
        r.rsplit(",", 1)[0] + f",{float(r.rsplit(',', 1)[1]) + 4e-3:.9f}"
        if r.startswith("0.1200,")
        else r
        for r in rows
    ]  # station 2 radius +4 mm
    return {
        "missing column": (
            ["z_m,loop,angle_deg"] + [r.rsplit(",", 1)[0] for r in rows[1:]],
            r"line 1: missing column\(s\) \['distance_m'\]",
        ),
        "NaN": (rows[:3] + ["0.1000,forward,2.0,nan"] + rows[4:], r"line 4: distance_m is nan"),
        "bad loop": (
            rows[:3] + ["0.1000,sideways,2.0,0.3"] + rows[4:],
            r"line 4: loop = 'sideways'",
        ),
        "no backward loop": (
            rows[: 1 + per_loop] + rows[1 + 2 * per_loop :],
            r"station z_m = 0.1 m has no backward loop",
        ),
        "half turn": (
            [
                r
                for r in rows
                if not (r.startswith("0.1200,forward") and float(r.split(",")[2]) > 200)
            ],
            r"station z_m = 0.12 m, forward loop angles do not cover a full turn",
        ),
        "non-monotonic": (
            rows[:1] + rows[1 + 2 * per_loop :] + rows[1 : 1 + 2 * per_loop],
            r"line 744: station z_m = 0.1 m comes after station z_m = 0.12 m",
        ),
        "too large": (
            big,
            r"lines 744-1485 \(station z_m = 0.12 m\): radial deviation of "
            r"[0-9.]+ mm exceeds 0.5 x thickness",
        ),
    }


@pytest.mark.parametrize(
    "case",
    [
        "missing column",
        "NaN",
        "bad loop",
        "no backward loop",
        "half turn",
        "non-monotonic",
        "too large",
    ],
)
def test_bad_scan_files(tp, tmp_path, case):
    rows, message = bad_scan_cases(tp, tmp_path)[case]
    path = _write(tmp_path, rows)
    with pytest.raises(ValueError, match=rf"{path}.*{message}"):
        process_ring_scans(path, tp)


def test_deviation_map_validation():
    with pytest.raises(ValueError, match="strictly increasing"):
        DeviationMap(np.array([0.2, 0.1]), np.zeros((2, 8)))
    with pytest.raises(ValueError, match="shape"):
        DeviationMap(np.array([0.1, 0.2]), np.zeros((3, 8)))


def _write(tmp_path: Path, rows: list[str]) -> Path:
    path = tmp_path / "file.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


def test_read_imperfection_tells_formats_apart(tp, tmp_path):
    scans = tmp_path / "scans.csv"
    write_scans(scans, tp, np.array([0.2, 0.22]), 1.0, np.array([0.0, 10.0]))
    processed = tmp_path / "map.csv"
    processed.write_text("\n".join(good_map_rows()) + "\n")
    assert np.allclose(
        read_imperfection(scans, tp).deviation, process_ring_scans(scans, tp).deviation
    )
    assert np.allclose(read_imperfection(processed, tp).deviation, 1e-4)
