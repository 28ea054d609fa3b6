"""Imperfect cones (docs/physics.md §6; docs/install.md "Imperfect cones"): rigid contact map and an
installation run of a TP with a measured (or synthetic) imperfection map.

The TP's inner surface comes from --scan FILE (raw laser ring scans ``z_m, loop, angle_deg,
distance_m`` or a processed map ``z_m, angle_deg, radial_deviation_m``, read by
``geometry.imperfections.read_imperfection``). The repository has no measured scans, so without
--scan the demo first writes a synthetic raw scan file, synthetic_scan_tp.csv, into the output
folder: an m = 2 ovality (--ovality-mm, default 0.3 mm), an m = 3 term, a weld seam bump at
75 deg, stations every 20 mm, each ring scanned 370 deg forward and back with a lagging
backward loop, junk at the turn-around and a random arm rotation per station, as the docs/physics.md §6
rig records them. --mp-ovality-mm adds an m = 2 ovality to the MP.

Outputs in --output: the processed TP map (tp_deviation_map.csv, tp_deviation.png), the rigid
contact map of the imperfect and of the perfect cones (contact_map.png, contact_map_perfect.png,
contact_fraction.csv), and the installation run of the imperfect joint (placed at its own first
contact): self-weight, then the docs/physics.md §3 lead-in stages 68 Hz and 100 Hz at the eccentric
amplitude (history.csv, stages.csv, contact_status_<k>.png, summary.txt, ...). --no-run: only the
maps. The modal stage is off by default (--modal turns it on): while the imperfect TP rests on a
few points it is a mechanism with zero-frequency modes, on which the mode ranking fails.

Without options: cases/imperfections.toml (the coarse frictional joint, 8 around,
0.25 m, whose shell modes lock: docs/install.md "Discretisation"). --quick: coarser contact map grids and --case
imperfections_quick (the demos' smoke-run joint with 4 ms stages; not physics).

Usage: mpirun -n 2 python demos/imperfections.py [--scan FILE] [--ovality-mm 0.3]
       [--mp-ovality-mm 0] [--no-run] [--case imperfections] [--set table.key=value ...]
       [--quick] [--output DIR]
"""

import math
import sys
from pathlib import Path

from common import backend  # noqa: F401  (before dolfinx)

import numpy as np
from mpi4py import MPI

from geometry.contact_map import plot_contact_map, rigid_contact_map
from geometry.imperfections import DeviationMap, ovality, read_imperfection
from geometry.parameters import ConePart
from solver.installation import cli

DEFAULT_CASE = "imperfections"
QUICK_CASE = "imperfections_quick"
#: the run after self-weight: the docs/physics.md §3 lead-in stages at the eccentric amplitude
LEAD_IN_HZ = (68.0, 100.0)


def lead_in(data: dict) -> None:
    """[[schedule]]: the lead-in frequencies, each vibration.stage_duration_s long."""
    duration = data.get("vibration", {}).get("stage_duration_s", 0.1)
    data["schedule"] = [
        {"duration_s": duration, "frequency_hz": f, "amplitude_N": "eccentric"} for f in LEAD_IN_HZ
    ]


def synthetic_shape(ovality_m: float):
    """Radial deviation [m] of the synthetic TP (angle [deg], part-local z [m]): ovality
    growing along the axis, an m = 3 term and a weld seam bump at 75 deg."""

    def shape(angle_deg: np.ndarray, z: float) -> np.ndarray:
        phi = np.radians(angle_deg)
        seam = (np.mod(angle_deg - 75.0 + 180.0, 360.0) - 180.0) / 4.0
        return (
            ovality_m * (0.8 + 0.3 * z) * np.cos(2 * (phi - math.radians(20.0)))
            + 0.1e-3 * np.cos(3 * phi + 0.4)
            + 0.15e-3 * np.exp(-0.5 * seam**2)
        )

    return shape


def write_synthetic_scans(
    path: Path, part: ConePart, ovality_m: float, spacing_m: float, seed: int = 1
) -> None:
    """Raw ring scans of ``synthetic_shape`` at stations ``spacing_m`` apart over the part: 370
    deg forward and back every degree, backward loop lagging 3 deg, junk readings where the
    sensor dwells at the turn-around (360-370 deg backward), random arm rotation per station."""
    rng = np.random.default_rng(seed)
    shape = synthetic_shape(ovality_m)
    forward = np.arange(0.0, 371.0)
    lines = [
        "# synthetic laser ring scans of the TP inner surface (demos/imperfections.py)",
        "z_m,loop,angle_deg,distance_m",
    ]
    for z in np.arange(0.0, part.total_length + 1e-9, spacing_m):
        offset = rng.uniform(-30.0, 30.0)  # the arm's 0 deg at this station

        def radius(a: np.ndarray, z: float = z, offset: float = offset) -> np.ndarray:
            return float(part.inner_radius(z)) + shape(a + offset, z)

        lines += [f"{z:.4f},forward,{a:.1f},{r:.9f}" for a, r in zip(forward, radius(forward))]
        backward = forward[::-1]
        r_back = radius(backward - 3.0)
        r_back[backward >= 360.0] += 2e-3  # dwell at the turn-around: junk
        lines += [f"{z:.4f},backward,{a:.1f},{r:.9f}" for a, r in zip(backward, r_back)]
    path.write_text("\n".join(lines) + "\n")


def write_map(deviation: DeviationMap, path: Path) -> None:
    """The processed map as ``z_m, angle_deg, radial_deviation_m`` (readable back as a map)."""
    rows = ["z_m,angle_deg,radial_deviation_m"]
    for z, ring in zip(deviation.z, deviation.deviation):
        rows += [f"{z:.6f},{a:.4f},{d:.9e}" for a, d in zip(deviation.angles_deg, ring)]
    path.write_text("\n".join(rows) + "\n")


def plot_map(deviation: DeviationMap, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4))
    mesh = ax.pcolormesh(
        deviation.angles_deg,
        deviation.z * 1e3,
        deviation.deviation * 1e3,
        shading="nearest",
        cmap="RdBu_r",
    )
    fig.colorbar(mesh, ax=ax, label="radial deviation [mm]")
    ax.set(
        xlabel="angle [deg]",
        ylabel="height above the TP lower end [mm]",
        title="TP inner surface: processed imperfection map",
    )
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    p = cli.parser(__doc__.splitlines()[0], "output/imperfections", DEFAULT_CASE, QUICK_CASE)
    p.add_argument("--scan", help="TP scan or map file (CSV); default: write a synthetic scan")
    p.add_argument(
        "--ovality-mm", type=float, default=0.3, help="synthetic scan: m = 2 ovality [mm]"
    )
    p.add_argument("--mp-ovality-mm", type=float, default=0.0, help="m = 2 ovality of the MP [mm]")
    p.add_argument("--no-run", action="store_true", help="only the maps, no installation run")
    p.add_argument("--modal", action="store_true", help="modal stage after self-weight (modes.csv)")
    args = p.parse_args(argv)
    comm = MPI.COMM_WORLD
    log = cli.say(comm)
    out = Path(args.output)
    before = ["vibration.modal_stage=true"] if args.modal else []
    try:
        if args.scan is not None and not Path(args.scan).is_file():
            raise ValueError(f"--scan {args.scan}: no such file")
        if not 0 < args.ovality_mm <= 2.0 or not 0 <= args.mp_ovality_mm <= 2.0:
            raise ValueError("--ovality-mm must lie in (0, 2] mm and --mp-ovality-mm in [0, 2] mm")
        joint = cli.load_case(
            args, before, edit=lead_in
        ).joint  # without imperfections: check options
        cli.prepare_output(comm, out)
    except ValueError as e:
        return cli.fail(comm, str(e))

    scan = Path(args.scan) if args.scan else out / "synthetic_scan_tp.csv"
    if comm.rank == 0:
        if args.scan is None:
            write_synthetic_scans(scan, joint.tp, 1e-3 * args.ovality_mm, 0.02)
            print(f"wrote synthetic laser ring scans of the TP: {scan}", flush=True)
    comm.barrier()
    mp = [f"imperfections.mp.amplitude_m={1e-3 * args.mp_ovality_mm}"] if args.mp_ovality_mm else []
    try:
        case = cli.load_case(
            args, before, [f"imperfections.tp.file='{scan.resolve()}'"] + mp, lead_in
        )
    except ValueError as e:
        return cli.fail(comm, str(e))
    joint = case.joint

    if comm.rank == 0:  # maps: analytic surfaces, serial numpy
        deviation = read_imperfection(scan, joint.tp)
        write_map(deviation, out / "tp_deviation_map.csv")
        plot_map(deviation, out / "tp_deviation.png")
        dev = deviation.deviation
        print(
            f"processed TP map: {deviation.z.size} stations x {dev.shape[1]} angles, "
            f"deviation {dev.min() * 1e3:+.3f} .. {dev.max() * 1e3:+.3f} mm",
            flush=True,
        )
        imperfections = {"tp": deviation}
        if args.mp_ovality_mm:
            imperfections["mp"] = ovality(1e-3 * args.mp_ovality_mm)
        grid = {"n_theta": 180, "n_zeta": 100} if args.quick else {}
        imperfect = rigid_contact_map(joint, imperfections, **grid)
        perfect = rigid_contact_map(joint, **grid)
        plot_contact_map(imperfect, out / "contact_map")
        plot_contact_map(perfect, out / "contact_map_perfect")
        first = imperfect.first_contact_overlap
        k = np.unravel_index(np.nanargmin(imperfect.onset_overlap), imperfect.onset_overlap.shape)
        print(
            f"rigid contact: first contact at overlap {first * 1e3:.2f} mm (perfect cones "
            f"{joint.overlap * 1e3:.2f} mm): the imperfect TP sits "
            f"{(first - joint.overlap) * -1e3:.2f} mm higher; first touch at "
            f"{math.degrees(imperfect.theta[k[1]]):.0f} deg, "
            f"{imperfect.zeta[k[0]] * 1e3:.0f} mm above the TP's lower edge",
            flush=True,
        )
        for target in (0.05, 0.25, 0.5):
            rows = []
            for name, cmap in (("imperfect", imperfect), ("perfect", perfect)):
                reached = cmap.overlaps[cmap.contact_fraction >= target]
                first_touch = cmap.first_contact_overlap
                slide = (reached[0] - first_touch) * 1e3 if reached.size else math.nan
                rows.append(f"{name} {slide:.1f} mm")
            print(
                f"  {target:.0%} of the TP cone in contact after sliding: " + ", ".join(rows),
                flush=True,
            )
        with open(out / "contact_fraction.csv", "w") as f:
            f.write(
                "overlap_mm,imperfect_contact_fraction_percent,perfect_contact_fraction_percent\n"
            )
            lo = max(imperfect.overlaps[0], perfect.overlaps[0])
            hi = min(imperfect.overlaps[-1], perfect.overlaps[-1])
            for o in np.linspace(lo, hi, 201):
                a = np.interp(o, imperfect.overlaps, imperfect.contact_fraction)
                b = np.interp(o, perfect.overlaps, perfect.contact_fraction)
                f.write(f"{o * 1e3:.6f},{100 * a:.6f},{100 * b:.6f}\n")
        print(
            f"maps: {out / 'contact_map.png'}, {out / 'contact_map_perfect.png'}, "
            f"{out / 'contact_fraction.csv'}, {out / 'tp_deviation.png'}",
            flush=True,
        )
    if args.no_run:
        return 0
    log(
        "installation run of the imperfect joint"
        + (" [--quick: tiny joint, very short stages, a smoke run]" if args.quick else "")
    )
    runner, code = cli.run(comm, case, out, progress=not args.no_progress)
    return code


if __name__ == "__main__":
    sys.exit(main())
