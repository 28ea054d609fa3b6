"""Time per step and Newton iterations per step of the joint dynamics (issue 4).

Stage 1: self-weight emulation, axial -10 kN ramped over ``--ramp`` s on the TP top.
Stage 2: harmonic axial forcing of ``--amplitude`` N at ``--frequency`` Hz on top of
the held self-weight, ``--steps-per-period`` steps per period, for ``--forcing`` s.
Prints the figures; writes the settlement history (CSV) to --output.

    mpirun -n 2 python benchmarks/dynamics_joint.py --ramp 2.0 --forcing 0.5
    python benchmarks/dynamics_joint.py --quick
"""

import argparse
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

from solver import backend  # noqa: E402,F401

import numpy as np  # noqa: E402
from mpi4py import MPI  # noqa: E402

from dolfinx import fem  # noqa: E402

from geometry import tags  # noqa: E402
from geometry.mesh import create_joint_mesh  # noqa: E402
from geometry.parameters import MeshOptions, load_geometry  # noqa: E402
from solver.case import resolve_case_path  # noqa: E402
from solver.contact import NitscheContact  # noqa: E402
from solver.damping import RayleighDamping  # noqa: E402
from solver.dynamics import Elastodynamics, Settlement, assemble_structure, run  # noqa: E402
from solver.friction import FrictionLaw  # noqa: E402
from solver.loads import RampedAxialForce, Schedule, Stage, TopFaceLoad, TPLoading  # noqa: E402
from solver.modal import clamp  # noqa: E402
from solver.newmark import GeneralisedAlpha  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--case", default="scaled")
    p.add_argument("--n-circumferential", type=int, default=16)
    p.add_argument("--axial-size", type=float, default=0.1, help="[m]")
    p.add_argument("--degree", type=int, default=2)
    p.add_argument("--mu", type=float, nargs=2, default=(0.5, 0.4), metavar=("MU_S", "MU_D"))
    p.add_argument("--d-c", type=float, default=100.0, help="friction decay [s/m]")
    p.add_argument("--gamma0", type=float, default=10.0)
    p.add_argument("--ramp", type=float, default=2.0, help="self-weight ramp time [s]")
    p.add_argument("--dt-ramp", type=float, default=2e-3, help="time step of the self-weight stage [s]")
    p.add_argument("--forcing", type=float, default=0.5, help="duration of the harmonic stage [s]")
    p.add_argument("--frequency", type=float, default=300.0, help="[Hz]")
    p.add_argument("--amplitude", type=float, default=3600.0, help="[N]")
    p.add_argument("--steps-per-period", type=int, default=30)
    p.add_argument("--rho-inf", type=float, default=0.8, help="generalised-alpha spectral radius")
    p.add_argument("--zeta", type=float, default=0.01, help="Rayleigh damping ratio at --zeta-frequency")
    p.add_argument("--zeta-frequency", type=float, default=120.0, help="[Hz]")
    p.add_argument("--lagged-friction", action="store_true", help="mu from the previous step's slip speed")
    p.add_argument("--backtracks", type=int, default=4, help="Newton step halvings when ||F|| grows")
    p.add_argument("--refactor-after", type=int, default=0,
                   help="GMRES iterations before refactorising A + J_c (0: LU every Newton iteration; "
                        "> 0 may deadlock on several ranks, see docs/dynamics.md)")
    p.add_argument("--quick", action="store_true", help="short stages (smoke run)")
    p.add_argument("--output", default="output/dynamics_joint")
    a = p.parse_args(argv)
    if a.quick:
        a.ramp, a.dt_ramp, a.forcing = 0.02, 2e-3, 5 / a.frequency
    comm = MPI.COMM_WORLD

    joint, material, _ = load_geometry(resolve_case_path(a.case))
    options = MeshOptions(n_circumferential=a.n_circumferential, axial_size=a.axial_size)
    t0 = time.perf_counter()
    data = create_joint_mesh(comm, joint, options)
    V = fem.functionspace(data.mesh, ("Lagrange", a.degree, (3,)))
    bcs = [clamp(V, data.facet_tags, [tags.MP_CLAMPED])]
    M, K = assemble_structure(V, material, bcs)
    contact = NitscheContact(V, data.facet_tags, tags.TP_CONTACT, tags.MP_CONTACT, material,
                             FrictionLaw(*a.mu, d_c=a.d_c), gamma0=a.gamma0, theta=1,
                             lagged_friction=a.lagged_friction)
    harmonic = Schedule([Stage(a.forcing, a.frequency, a.amplitude)], start_s=a.ramp) if a.forcing > 0 else None
    loading = TPLoading(TopFaceLoad(V, data.facet_tags, tags.TP_TOP), static_axial=RampedAxialForce(-10e3, a.ramp),
                        schedule=harmonic)
    problem = Elastodynamics(V, M, K, bcs, load=loading, scheme=GeneralisedAlpha.from_spectral_radius(a.rho_inf),
                             damping=RayleighDamping.at_frequency(a.zeta, a.zeta_frequency), contact=contact,
                             newton_options={"max_backtracks": a.backtracks, "refactor_after": a.refactor_after})
    problem.initialise(0.0)
    settlement = Settlement(problem.u, joint, data.cell_tags)
    dofs = V.dofmap.index_map.size_global * 3
    setup = time.perf_counter() - t0
    if comm.rank == 0:
        print(f"joint: {dofs} dofs, degree {a.degree}, {a.n_circumferential} around, {a.axial_size} m axial, "
              f"{comm.size} rank(s); set-up {setup:.1f} s")

    out = pathlib.Path(a.output)
    stages = [("self-weight", a.ramp, a.dt_ramp), ("harmonic", a.ramp + a.forcing, 1 / (a.frequency * a.steps_per_period))]
    for name, t_end, dt in stages[: 2 if a.forcing > 0 else 1]:
        t0 = time.perf_counter()
        rows = run(problem, t_end, dt, observers=[settlement], csv_path=out / f"{name}.csv",
                   progress=comm.rank == 0)
        wall = time.perf_counter() - t0
        its = np.array([r["newton_iterations"] for r in rows])
        if comm.rank == 0:
            print(f"{name}: {len(rows)} steps of {dt:.3g} s, {wall / len(rows):.3f} s/step, Newton iterations "
                  f"mean {its.mean():.2f} max {its.max()}, settlement {rows[-1]['settlement_mm']:.4f} mm, "
                  f"wall {wall:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
