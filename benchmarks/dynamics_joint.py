"""Time per step and Newton iterations per step of the joint dynamics.

Stage 1: self-weight emulation, axial -10 kN ramped over ``--ramp`` s on the TP top.
Stage 2: harmonic axial forcing of ``--amplitude`` N at ``--frequency`` Hz on top of
the held self-weight, ``--steps-per-period`` steps per period, for ``--forcing`` s.
Prints the figures; writes the settlement history (CSV) to --output.

    mpirun -n 2 python benchmarks/dynamics_joint.py --ramp 2.0 --forcing 0.5
    python benchmarks/dynamics_joint.py --quick
    python benchmarks/dynamics_joint.py --max-steps 5     # per-step profile of the first steps

Default discretisation: 48 around, 0.08 m axially, 0.01 m in the contact zone, P2. One
line per accepted step (wall time, GMRES iterations, factorisations) and, after each
stage, the wall and CPU time per phase (the phases of ``benchmarks/phase_timer.py``).
``--max-steps N`` stops each stage after N steps (profiling; the harmonic stage then starts
where the ramp stopped). ``--save-displacement`` writes the final displacement per rank
(to compare two versions of the code). The installation demo's contact settings are
``--theta -1 --gamma0 1 --max-gap-change 1e-5 --backtracks 4 --rho-inf 0 --lagged-friction``.
The bulk away from the contact surfaces is condensed (``solver/dynamics/condensation.py``;
``--no-condense-bulk`` to compare). The converged joint, 2 s of self-weight ramp and 0.5 s of
forcing:

    mpirun -n 2 python benchmarks/dynamics_joint.py --theta -1 --gamma0 1 --max-gap-change 1e-5 \
        --backtracks 4 --rho-inf 0 --lagged-friction --dt-ramp 0.01 --forcing 0.5 --contact-zone-above 0.08
"""

import argparse
import os
import pathlib
import sys
import time

from common import backend  # noqa: F401

import numpy as np
from mpi4py import MPI

from dolfinx import fem

from common.case import resolve_case_path
from common.timing import recording
from geometry import tags
from geometry.mesh import create_joint_mesh
from geometry.parameters import MeshOptions, load_geometry
from solver.contact import FrictionLaw, NitscheContact
from solver.dynamics.damping import RayleighDamping
from solver.dynamics.elastodynamics import Elastodynamics, assemble_structure
from solver.dynamics.loads import RampedAxialForce, Schedule, Stage, TopFaceLoad, TPLoading
from solver.dynamics.schemes import GeneralisedAlpha
from solver.dynamics.time_loop import run
from solver.installation import checkpoint, cli
from solver.installation.observers import ContactZoneGuard, Settlement
from solver.modal.eigen import clamp
from solver.post.csv import CsvWriter

from benchmarks.phase_timer import PhaseTimer


class StepLog:
    """Observer printing one line per accepted step (one per stage, after ``timer.reset``): wall time,
    GMRES iterations and factorisations since the previous step (failed attempts included)."""

    def __init__(self, timer: PhaseTimer, say):
        self.timer, self.say = timer, say
        self._last = (time.perf_counter(), 0, 0)

    def __call__(self, problem) -> dict[str, float]:
        now, gmres, factorisations = (
            time.perf_counter(),
            self.timer.gmres,
            self.timer.calls["factorisation"],
        )
        t0, g0, f0 = self._last
        self._last = (now, gmres, factorisations)
        self.say(
            f"    t = {problem.t:.6f} s: {now - t0:6.2f} s wall, GMRES {gmres - g0}, "
            f"factorisations {factorisations - f0}",
        )
        return {}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--case", default="scaled")
    p.add_argument("--n-circumferential", type=int, default=48)
    p.add_argument("--axial-size", type=float, default=0.08, help="[m]")
    p.add_argument(
        "--contact-axial-size", type=float, default=0.01, help="axial size in the contact zone [m]"
    )
    p.add_argument(
        "--contact-zone-above",
        type=float,
        default=MeshOptions.contact_zone_above,
        help="contact zone (and contact surfaces) up to this height above the TP's lower edge [m]",
    )
    p.add_argument("--degree", type=int, default=2)
    p.add_argument(
        "--condense-bulk",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="Newton on the contact zone with the linear bulk condensed (solver.dynamics.condensation)",
    )
    p.add_argument(
        "--partition",
        choices=("sectors", "graph"),
        default="sectors",
        help="parallel distribution of the cells (geometry.parameters.MeshOptions)",
    )
    p.add_argument(
        "--newton-rtol",
        type=float,
        default=None,
        help="relative Newton tolerance (default: solver.dynamics.newton's)",
    )
    p.add_argument("--mu", type=float, nargs=2, default=(0.5, 0.4), metavar=("MU_S", "MU_D"))
    p.add_argument("--d-c", type=float, default=100.0, help="friction decay [s/m]")
    p.add_argument("--gamma0", type=float, default=10.0)
    p.add_argument("--theta", type=int, default=1, help="Nitsche variant (1, 0, -1)")
    p.add_argument(
        "--max-gap-change", type=float, default=None, help="gap-limited Newton steps [m]"
    )
    p.add_argument("--ramp", type=float, default=2.0, help="self-weight ramp time [s]")
    p.add_argument(
        "--dt-ramp", type=float, default=2e-3, help="time step of the self-weight stage [s]"
    )
    p.add_argument("--forcing", type=float, default=0.5, help="duration of the harmonic stage [s]")
    p.add_argument("--frequency", type=float, default=300.0, help="[Hz]")
    p.add_argument("--amplitude", type=float, default=3600.0, help="[N]")
    p.add_argument("--steps-per-period", type=int, default=30)
    p.add_argument(
        "--rho-inf",
        type=float,
        default=0.8,
        help="generalised-alpha spectral radius (harmonic stage)",
    )
    p.add_argument(
        "--rho-inf-ramp",
        type=float,
        default=None,
        help="spectral radius of the self-weight stage (default: --rho-inf)",
    )
    p.add_argument(
        "--zeta", type=float, default=0.01, help="Rayleigh damping ratio at --zeta-frequency"
    )
    p.add_argument("--zeta-frequency", type=float, default=120.0, help="[Hz]")
    p.add_argument(
        "--lagged-friction", action="store_true", help="mu from the previous step's slip speed"
    )
    p.add_argument(
        "--backtracks", type=int, default=4, help="Newton step halvings when ||F|| grows"
    )
    p.add_argument(
        "--no-reversal-limit",
        action="store_true",
        help="Newton steps may reverse a slipping point's friction (solver.dynamics.newton)",
    )
    p.add_argument(
        "--stall-iterations",
        type=int,
        default=None,
        help="give up a Newton attempt when its smallest ||F|| is this many iterations old "
        "(default: solver.dynamics.newton's)",
    )
    p.add_argument(
        "--refactor-after",
        type=int,
        default=25,
        help="GMRES iterations before refactorising A + J_c (0: LU every Newton iteration)",
    )
    p.add_argument(
        "--lu-solver",
        choices=("mumps", "superlu_dist"),
        default="mumps",
        help="LU package of the Newton corrections (superlu_dist: repeatable on several ranks)",
    )
    p.add_argument(
        "--krylov-rtol",
        type=float,
        default=1e-11,
        help="tightest GMRES tolerance of the Newton corrections",
    )
    p.add_argument(
        "--forcing-max",
        type=float,
        default=None,
        help="largest GMRES tolerance (Eisenstat-Walker; 0: every correction to --krylov-rtol; "
        "default: solver.dynamics.newton's)",
    )
    p.add_argument(
        "--max-steps",
        type=int,
        default=0,
        help="stop each stage after this many steps (0: no limit)",
    )
    p.add_argument("--quick", action="store_true", help="short stages (smoke run)")
    p.add_argument("--output", default="output/dynamics_joint")
    p.add_argument(
        "--ramp-checkpoint",
        default=None,
        metavar="DIR",
        help="after the self-weight stage write its state to DIR; if DIR holds one (same rank count "
        "and options), start from it and skip the stage (for experiments on the forcing stage)",
    )
    p.add_argument(
        "--save-displacement",
        action="store_true",
        help="write the final owned node coordinates and displacements per rank (.npy) to --output",
    )
    a = p.parse_args(argv)
    if a.quick:
        a.ramp, a.dt_ramp, a.forcing = 0.02, 2e-3, 5 / a.frequency
    comm = MPI.COMM_WORLD

    joint, material, _ = load_geometry(resolve_case_path(a.case))
    options = MeshOptions(
        n_circumferential=a.n_circumferential,
        axial_size=a.axial_size,
        contact_axial_size=a.contact_axial_size,
        contact_zone_above=a.contact_zone_above,
        partition=a.partition,
    )
    t0 = time.perf_counter()
    data = create_joint_mesh(comm, joint, options)
    V = fem.functionspace(data.mesh, ("Lagrange", a.degree, (3,)))
    bcs = [clamp(V, data.facet_tags, [tags.MP_CLAMPED])]
    M, K = assemble_structure(V, material, bcs)
    contact = NitscheContact(
        V,
        data.facet_tags,
        tags.TP_CONTACT,
        tags.MP_CONTACT,
        material,
        FrictionLaw(*a.mu, d_c=a.d_c),
        gamma0=a.gamma0,
        theta=a.theta,
        lagged_friction=a.lagged_friction,
    )
    from_checkpoint = bool(a.ramp_checkpoint) and checkpoint.exists(a.ramp_checkpoint, comm)
    ramp_end = (
        min(a.ramp, a.max_steps * a.dt_ramp) if a.max_steps and not from_checkpoint else a.ramp
    )
    harmonic = (
        Schedule([Stage(a.forcing, a.frequency, a.amplitude)], start_s=ramp_end)
        if a.forcing > 0
        else None
    )
    loading = TPLoading(
        TopFaceLoad(V, data.facet_tags, tags.TP_TOP),
        static_axial=RampedAxialForce(-10e3, a.ramp),
        schedule=harmonic,
    )
    rho_ramp = a.rho_inf if a.rho_inf_ramp is None else a.rho_inf_ramp
    problem = Elastodynamics(
        V,
        M,
        K,
        bcs,
        load=loading,
        scheme=GeneralisedAlpha.from_spectral_radius(rho_ramp),
        damping=RayleighDamping.at_frequency(a.zeta, a.zeta_frequency),
        contact=contact,
        newton_options={
            "max_backtracks": a.backtracks,
            "refactor_after": a.refactor_after,
            "max_gap_change": a.max_gap_change,
            "krylov_rtol": a.krylov_rtol,
            "lu_solver": a.lu_solver,
            "limit_reversal": not a.no_reversal_limit,
        }
        | ({} if a.forcing_max is None else {"forcing_max": a.forcing_max})
        | ({} if a.newton_rtol is None else {"rtol": a.newton_rtol})
        | ({} if a.stall_iterations is None else {"stall_iterations": a.stall_iterations}),
        condense_bulk=a.condense_bulk,
    )
    problem.initialise(0.0)
    settlement = Settlement(problem.u, joint, data.cell_tags)
    dofs = V.dofmap.index_map.size_global * 3
    per_rank = comm.allgather(contact.slave.num_points)
    points = sum(per_rank)
    setup = time.perf_counter() - t0
    say = cli.say(comm)
    say(
        f"joint: {dofs} dofs, degree {a.degree}, {a.n_circumferential} around, {a.axial_size} m axial "
        f"({a.contact_axial_size} m in the contact zone), {points} slave points, "
        f"{contact.master.num_facets} master facets, {comm.size} rank(s) ({a.partition} partition, slave "
        f"points per rank {per_rank}); set-up {setup:.1f} s"
    )

    out = pathlib.Path(a.output)
    stages = [
        ("self-weight", ramp_end, a.dt_ramp),
        ("harmonic", ramp_end + a.forcing, 1 / (a.frequency * a.steps_per_period)),
    ]
    if a.max_steps:
        stages[1] = (
            "harmonic",
            ramp_end + min(a.forcing, a.max_steps * stages[1][2]),
            stages[1][2],
        )
    if a.forcing <= 0:
        stages = stages[:1]
    if from_checkpoint:
        checkpoint.restore(a.ramp_checkpoint, problem)
        say(f"self-weight stage skipped: state at t = {problem.t:.6g} s from {a.ramp_checkpoint}")
        stages = stages[1:]
    observers = [settlement]
    if a.contact_axial_size > 0:
        observers.append(ContactZoneGuard(contact, a.contact_axial_size, a.contact_zone_above))
    timer = PhaseTimer()
    for name, t_end, dt in stages:
        if name == "harmonic":
            problem.set_scheme(GeneralisedAlpha.from_spectral_radius(a.rho_inf))
        timer.reset()
        t0, cpu0 = time.perf_counter(), time.process_time()
        with CsvWriter(out / f"{name}.csv", comm=comm) as writer, recording(timer):
            rows = run(
                problem,
                t_end,
                dt,
                observers=[*observers, StepLog(timer, say)],
                on_row=writer.write,
                progress=False,
            )
        if name == "self-weight" and a.ramp_checkpoint:
            checkpoint.save(a.ramp_checkpoint, problem, {"stage": name})
        wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
        its = np.array([r["newton_iterations"] for r in rows])
        say(
            f"{name}: {len(rows)} steps of {dt:.3g} s, {wall / len(rows):.3f} s/step, Newton iterations "
            f"mean {its.mean():.2f} max {its.max()} ({' '.join(map(str, its))}), "
            f"settlement {rows[-1]['settlement_mm']:.6f} mm, wall {wall:.1f} s (rank 0 CPU {cpu:.1f} s; "
            f"load average {os.getloadavg()[0]:.1f})"
        )
        timer.report(comm, len(rows), int(its.sum()), say)
    if a.save_displacement:
        np.save(
            out / f"displacement_rank{comm.rank}_of_{comm.size}.npy",
            np.column_stack(
                [
                    V.tabulate_dof_coordinates()[: V.dofmap.index_map.size_local],
                    problem.u.x.array.reshape(-1, 3)[: V.dofmap.index_map.size_local],
                ]
            ),
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
