"""Reduced (lumped-element) model of the full-scale slip-joint installation (docs/physics.md §7).

Prints the shell-theory springs (full scale and 1:10), the self-weight settlement of
the five sensitivity cases, the settlement after a 10 cm drop, and maps the
settlement after harmonic axial loading over frequency x amplitude, with the
required slip L_slip drawn in. Writes CSV files (with units) and PNG plots.

The study's friction, damping and map are the case's [lumped] table (``LumpedStudy``;
cases/lumped.toml: the full-scale joint of cases/full_scale.toml with docs/physics.md §7's
values); each option below sets its entry, --set lumped.KEY=VALUE too. --quick: --case
lumped_quick (2 s of harmonic loading on a 5 x 3 map, a smoke run).

Usage: mpirun -n 2 python demos/lumped.py [--quick] [--output DIR] [--case lumped]
       [--set table.key=value ...] [--mu-s 0.5] [--mu-d 0.3] [--d-c inf] [--damping-ratio 0.01]
       [--duration 90] [--settle-time 1] [--f-max 20] [--amp-max 5e5] [--n-freq 41]
       [--n-amp 11] [--bvp-tol 1e-5]
The map's runs are shared out over the MPI ranks.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from pathlib import Path

from common import backend  # noqa: F401  (before mpi4py)
from mpi4py import MPI

import numpy as np

from common.case import read_case
from geometry.parameters import JointGeometry, geometry_from_case, load_geometry
from solver.installation import cli
from solver.post.csv import write_csv
from solver.reduced.lumped import GRAVITY, AxialLoad, LumpedModel, simulate
from solver.reduced.shell import JointStiffness, joint_stiffness
from solver.reduced.study import LumpedStudy, read_study

#: docs/physics.md §7 sensitivity cases: (alpha [deg], beta [deg], mu_d)
SENSITIVITY_CASES = (
    (1.05, 1.0, 0.3),
    (1.05, 1.0, 0.4),
    (1.05, 1.0, 0.2),
    (2.5, 1.5, 0.3),
    (2.5, 2.4, 0.3),
)
DROP_SPEED = math.sqrt(2 * GRAVITY * 0.1)  #: TP speed after a 10 cm free fall [m/s]
DEFAULT_CASE, QUICK_CASE = "lumped", "lumped_quick"
#: the demo's options and the [lumped] entries they set (--set lumped.KEY=VALUE wins)
STUDY_OPTIONS = {
    "mu_s": "mu_s",
    "mu_d": "mu_d",
    "d_c": "d_c",
    "damping_ratio": "damping_ratio",
    "duration": "duration_s",
    "settle_time": "settle_time_s",
    "f_max": "f_max_hz",
    "amp_max": "amplitude_max_N",
    "n_freq": "n_frequencies",
    "n_amp": "n_amplitudes",
    "bvp_tol": "bvp_tol",
}


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    p.add_argument(
        "--quick", action="store_true", help="coarse map grid and short runs (smoke test)"
    )
    p.add_argument("--output", default="output/lumped", help="output folder")
    p.add_argument("--case", help=f"case name or TOML file ({DEFAULT_CASE}; --quick: {QUICK_CASE})")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="TABLE.KEY=VALUE",
        help="override of --case (its [geometry.mp], [geometry.tp], [material], [lumped])",
    )
    p.add_argument(
        "--scaled-case", default="cases/scaled.toml", help="case whose springs are also printed"
    )
    p.add_argument("--mu-s", type=float, help="static friction coefficient (0.5)")
    p.add_argument("--mu-d", type=float, help="dynamic friction coefficient, base case (0.3)")
    p.add_argument(
        "--d-c",
        type=float,
        help="friction decay [s/m] of mu(v) (inf: step from mu_s to mu_d, docs/physics.md §7)",
    )
    p.add_argument("--damping-ratio", type=float, help="fraction of critical per dof (0.01)")
    p.add_argument("--duration", type=float, help="harmonic loading time [s] (90)")
    p.add_argument(
        "--settle-time", type=float, help="self-weight alone before the harmonic [s] (1)"
    )
    p.add_argument("--f-max", type=float, help="largest map frequency [Hz] (20)")
    p.add_argument("--amp-max", type=float, help="largest map amplitude [N] (5e5)")
    p.add_argument("--n-freq", type=int, help="map frequencies (41)")
    p.add_argument("--n-amp", type=int, help="map amplitudes (11)")
    p.add_argument("--bvp-tol", type=float, help="shell collocation tolerance (1e-5)")
    args = p.parse_args(argv)
    if args.quick and args.case not in (None, QUICK_CASE):
        p.error(f"--quick is --case {QUICK_CASE}; give one or the other")
    name = args.case or (QUICK_CASE if args.quick else DEFAULT_CASE)
    given = [
        f"lumped.{key}={getattr(args, option)}"
        for option, key in STUDY_OPTIONS.items()
        if getattr(args, option) is not None
    ]
    try:
        case = read_case(name, given + args.set)
        args.joint, args.material, _ = geometry_from_case(case)
        args.scaled_joint, args.scaled_material, _ = load_geometry(args.scaled_case)
    except ValueError as e:
        p.error(str(e))
    try:
        args.study = read_study(case)
        for _, _, mu_d in SENSITIVITY_CASES:
            args.study.friction(mu_d)
    except ValueError as e:
        p.error(f"{case['_source']}: {e}")
    return args


def with_angles(joint: JointGeometry, alpha_deg: float, beta_deg: float) -> JointGeometry:
    """The same joint with other cone half-angles (cone lengths and bottom diameters kept)."""
    return JointGeometry(
        mp=dataclasses.replace(joint.mp, half_angle_deg=alpha_deg),
        tp=dataclasses.replace(joint.tp, half_angle_deg=beta_deg),
    )


def required_slip(joint: JointGeometry, alpha_deg: float, beta_deg: float) -> float:
    """docs/physics.md §2.2: L_slip = L_overlap (1 - sin beta / sin alpha) [m], with the design overlap
    L_overlap of the case file's joint (its overlap at full contact, 1.5 D at full scale)."""
    ratio = math.sin(math.radians(beta_deg)) / math.sin(math.radians(alpha_deg))
    return joint.full_contact_overlap * (1.0 - ratio)


def build_model(
    joint: JointGeometry, springs: JointStiffness, mass: float, study: LumpedStudy, mu_d: float
) -> LumpedModel:
    """The lumped model of ``joint`` with the study's friction (dynamic coefficient ``mu_d``)
    and damping."""
    return LumpedModel(
        mass=mass,
        springs=springs,
        alpha=joint.mp.half_angle,
        lever=0.5 * joint.tp.thickness,
        friction=study.friction(mu_d),
        damping_ratio=study.damping_ratio,
    )


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    comm = MPI.COMM_WORLD
    root = comm.rank == 0
    try:
        out = cli.prepare_output(comm, args.output)
    except ValueError as e:
        return cli.fail(comm, str(e))
    t_start = time.perf_counter()
    study = args.study

    joint, material = args.joint, args.material
    scaled_joint, scaled_material = args.scaled_joint, args.scaled_material
    mass = joint.tp.mass(material)  # kept for all sensitivity cases [kg]
    weight = mass * GRAVITY

    # --- springs: shell statics, shared out over the ranks -------------------------------
    angle_cases = sorted({(a, b) for a, b, _ in SENSITIVITY_CASES})
    jobs = [(ab, with_angles(joint, *ab), material) for ab in angle_cases]
    jobs.append(("scaled", scaled_joint, scaled_material))
    mine = {
        key: joint_stiffness(j, mat, tol=study.bvp_tol)
        for n, (key, j, mat) in enumerate(jobs)
        if n % comm.size == comm.rank
    }
    springs = {k: v for part in comm.allgather(mine) for k, v in part.items()}
    base = (SENSITIVITY_CASES[0][0], SENSITIVITY_CASES[0][1])
    base_model = build_model(joint, springs[base], mass, study, study.mu_d)
    if root:
        rows = []
        print("Shell-theory springs (totals over the circumference; off-diagonal terms dropped):")
        for key, s in [(base, springs[base]), ("scaled", springs["scaled"])]:
            name = "scaled 1:10" if key == "scaled" else "full scale"
            print(
                f"  {name:12s} K_r = {s.K_r:.4e} N/m   K_rot = {s.K_rot:.4e} N m/rad   "
                f"K_N = {s.K_N:.4e} N/m   K_T = {s.K_T:.4e} N/m   "
                f"(free-edge TP radial {s.K_r_free:.4e} N/m)"
            )
            rows.append([name, s.K_r, s.K_rot, s.K_N, s.K_T, s.K_r_free, s.m_r, s.J_rot, s.m_T])
        write_csv(
            out / "stiffness.csv",
            [
                "case",
                "K_r_N_per_m",
                "K_rot_Nm_per_rad",
                "K_N_N_per_m",
                "K_T_N_per_m",
                "K_r_free_edge_N_per_m",
                "m_r_kg",
                "J_rot_kgm2",
                "m_T_kg",
            ],
            rows,
            digits=None,
        )
        freqs = ", ".join(f"{f:.1f}" for f in base_model.stick_frequencies())
        print(f"  full-scale joint in stick: natural frequencies {freqs} Hz")

    # --- self-weight (five cases) and the drop, shared out over the ranks ---------------
    runs = [(case, 0.0) for case in SENSITIVITY_CASES] + [(SENSITIVITY_CASES[0], DROP_SPEED)]
    mine = {}
    for n, ((alpha, beta, mu_d), v0) in enumerate(runs):
        if n % comm.size == comm.rank:
            model = build_model(
                with_angles(joint, alpha, beta), springs[(alpha, beta)], mass, study, mu_d
            )
            mine[n] = simulate(model, AxialLoad(static=weight), 10.0, initial_velocity=v0)
    trajs = {k: v for part in comm.gather(mine, root=0) or [] for k, v in part.items()}
    histories = {}
    if root:
        print(
            f"\nSelf-weight {weight / 1e3:.0f} kN (TP mass {mass / 1e3:.1f} t) "
            "released at first contact, "
            f"mu_s = {study.mu_s}:"
        )
        rows = []
        for n, (alpha, beta, mu_d) in enumerate(SENSITIVITY_CASES):
            s, l_slip = trajs[n].final_settlement, required_slip(joint, alpha, beta)
            print(
                f"  alpha/beta = {alpha}/{beta} deg, mu_d = {mu_d}: settlement {1e3 * s:7.1f} mm"
                f"   (L_slip {1e3 * l_slip:6.1f} mm, {'reached' if s >= l_slip else 'not reached'})"
            )
            rows.append([alpha, beta, study.mu_s, mu_d, 1e3 * s, 1e3 * l_slip, int(s >= l_slip)])
        write_csv(
            out / "self_weight.csv",
            ["alpha_deg", "beta_deg", "mu_s", "mu_d", "settlement_mm", "L_slip_mm", "reached"],
            rows,
            digits=None,
        )
        histories = {"self-weight": trajs[0], "10 cm drop": trajs[len(SENSITIVITY_CASES)]}
        print(
            f"\n10 cm drop (v0 = {DROP_SPEED:.2f} m/s), base case: settlement "
            f"{1e3 * histories['10 cm drop'].final_settlement:.1f} mm "
            f"(L_slip {1e3 * joint.required_slip:.1f} mm)"
        )
        for name, traj in histories.items():
            write_csv(
                out / f"history_{name.replace(' ', '_')}.csv",
                ["time_s", "settlement_mm", "edge_radial_mm", "mode"],
                zip(traj.t, 1e3 * traj.q[0], 1e3 * traj.q[1], traj.mode),
                digits=None,
            )

    # --- settlement map: runs shared over ranks --------------------------------------
    freqs = np.linspace(0.0, study.f_max_hz, study.n_frequencies)
    amps = np.linspace(0.0, study.amplitude_max_N, study.n_amplitudes)
    grid = [(i, k) for i in range(freqs.size) for k in range(amps.size)]
    model = base_model
    mine = []
    for n, (i, k) in enumerate(grid):
        if n % comm.size != comm.rank:
            continue
        load = AxialLoad(
            static=weight,
            amplitude=amps[k],
            frequency=freqs[i],
            harmonic_start=study.settle_time_s,
        )
        traj = simulate(model, load, study.settle_time_s + study.duration_s)
        mine.append((i, k, traj.final_settlement, traj.stuck_forever, len(traj.events), traj.t[-1]))
    gathered = comm.gather(mine, root=0)
    if root:
        settlement = np.full((freqs.size, amps.size), np.nan)
        rows = []
        for i, k, s, stuck, n_events, t_last in sorted(r for part in gathered for r in part):
            settlement[i, k] = s
            rows.append([freqs[i], amps[k] / 1e3, 1e3 * s, int(stuck), n_events, t_last])
        write_csv(
            out / "settlement_map.csv",
            [
                "frequency_Hz",
                "amplitude_kN",
                "settlement_mm",
                "proven_stuck",
                "transitions",
                "end_time_s",
            ],
            rows,
            digits=None,
        )
        l_slip = joint.required_slip
        reached = settlement >= l_slip
        print(
            f"\nSettlement after {study.duration_s:g} s of harmonic loading "
            f"(after {study.settle_time_s:g} s of self-weight), "
            f"{freqs[0]:g}-{freqs[-1]:g} Hz x {amps[0] / 1e3:g}-{amps[-1] / 1e3:g} kN, "
            f"{freqs.size} x {amps.size} runs:"
        )
        print(
            f"  min {1e3 * np.nanmin(settlement):.1f} mm, max {1e3 * np.nanmax(settlement):.1f} mm "
            f"at {freqs[np.nanargmax(settlement) // amps.size]:g} Hz, "
            f"{amps[np.nanargmax(settlement) % amps.size] / 1e3:g} kN; "
            f"L_slip = {1e3 * l_slip:.1f} mm reached in {int(reached.sum())} of {reached.size} runs"
        )
        print(f"  runs that ended proven stuck: {sum(r[3] for r in rows)} of {len(rows)}")
        plot(out, freqs, amps, settlement, l_slip, histories, study.duration_s)
        print(f"\nwrote {out}/ in {time.perf_counter() - t_start:.1f} s")
    return 0


def plot(out: Path, freqs, amps, settlement, l_slip, histories, duration_s: float) -> None:
    """The settlement map [mm] over frequency x amplitude with L_slip in red, and the
    self-weight and drop histories."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    top = 1e3 * max(np.nanmax(settlement), 1.05 * l_slip)  # L_slip always on the colour scale
    mesh = ax.pcolormesh(
        freqs, amps / 1e3, 1e3 * settlement.T, shading="nearest", cmap="viridis", vmin=0.0, vmax=top
    )
    bar = fig.colorbar(mesh, ax=ax, label="settlement [mm]")
    if np.nanmax(settlement) >= l_slip > np.nanmin(settlement):
        ax.contour(freqs, amps / 1e3, settlement.T, levels=[l_slip], colors="red", linewidths=2)
    bar.ax.axhline(1e3 * l_slip, color="red", linewidth=2)
    ax.set_title(
        f"Settlement after {duration_s:g} s harmonic axial load "
        f"(red: L_slip = {1e3 * l_slip:.0f} mm"
        + ("" if np.nanmax(settlement) >= l_slip else ", not reached")
        + ")",
        fontsize=9,
    )
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("amplitude [kN]")
    fig.tight_layout()
    fig.savefig(out / "settlement_map.png", dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7, 4))
    for name, traj in histories.items():
        ax.plot(traj.t, 1e3 * traj.q[0], label=name)
    ax.axhline(1e3 * l_slip, color="red", linestyle="--", label="L_slip")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("settlement [mm]")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "self_weight_and_drop.png", dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
