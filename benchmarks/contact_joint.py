"""Cost of the Nitsche contact operations and of the contact Newton solve on the scaled joint.

Prints: DOFs and slave points; wall time of pairing + state update, residual, Jacobian and
interface_stiffness assembly; then one implicit step of the joint from rest (A = K + M /
(beta dt^2), the Newmark effective stiffness at rest, axial load on the TP top) solved
with a fresh LU factorisation at every Newton iteration (``refactor_after = 0``) and with
the reused-factorisation GMRES strategy of ``solver.dynamics.newton``, with iterations,
factorisations and the time per phase.

    python benchmarks/contact_joint.py                  # default discretisation (48 around, 80 mm, P2)
    mpirun -n 2 python benchmarks/contact_joint.py --n-circumferential 24 --steps 3

With ``--self-weight T``: instead, the self-weight stage by ``solver.dynamics`` (10 kN
ramped over T seconds on the TP top, generalised-alpha (``--rho-inf``, default 0.8), Rayleigh 1 % at
120 Hz, steps of ``--dt``), printing Newton iterations and settlement per step.
"""

import argparse
import sys
import time

from common import backend  # noqa: F401

import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

import dolfinx
import dolfinx.fem.petsc

from common.case import read_case
from geometry import tags
from geometry.mesh import create_joint_mesh
from geometry.parameters import MeshOptions, geometry_from_case
from solver.contact import FrictionLaw, NitscheContact
from solver.dynamics.newton import ContactNewtonSolver
from solver.elasticity import epsilon, sigma
from solver.modal.interface import band_status


def timed(comm, f):
    comm.Barrier()
    t0 = time.perf_counter()
    out = f()
    comm.Barrier()
    return out, time.perf_counter() - t0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--case", default="scaled")
    p.add_argument("--n-circumferential", type=int, default=48)
    p.add_argument("--axial-size", type=float, default=0.08, help="[m]")
    p.add_argument("--degree", type=int, default=2)
    p.add_argument("--gamma0", type=float, default=10.0)
    p.add_argument("--theta", type=int, default=1)
    p.add_argument("--force", type=float, default=10e3, help="axial load on the TP top [N]")
    p.add_argument(
        "--dt", type=float, default=2e-2, help="time step of the effective stiffness [s]"
    )
    p.add_argument("--steps", type=int, default=4, help="load steps (force / steps each)")
    p.add_argument(
        "--max-backtracks", type=int, default=0, help="Newton step halvings (line search)"
    )
    p.add_argument(
        "--rho-inf",
        type=float,
        default=0.8,
        help="generalised-alpha spectral radius (--self-weight)",
    )
    p.add_argument(
        "--max-gap-change",
        type=float,
        default=None,
        help="limit of a point's gap change per Newton iteration [m] (solver.dynamics.newton)",
    )
    p.add_argument("--lagged-friction", action="store_true")
    p.add_argument(
        "--self-weight",
        type=float,
        default=0.0,
        metavar="T",
        help="run the dynamic self-weight ramp of T seconds instead [s]",
    )
    p.add_argument(
        "--strategies",
        nargs="+",
        default=["fresh", "reuse"],
        choices=["fresh", "reuse"],
        help="fresh: LU at every Newton iteration; reuse: reused LU + GMRES",
    )
    a = p.parse_args(argv)
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *args, **kw: None)

    case = read_case(a.case)
    joint, material, _ = geometry_from_case(case)
    options = MeshOptions(n_circumferential=a.n_circumferential, axial_size=a.axial_size)
    data, t = timed(comm, lambda: create_joint_mesh(comm, joint, options))
    mesh, facet_tags = data.mesh, data.facet_tags
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", a.degree, (3,)))
    say(
        f"mesh: {a.n_circumferential} around, {a.axial_size} m, P{a.degree}: "
        f"{V.dofmap.index_map.size_global * 3} dofs, {comm.size} rank(s), built in {t:.1f} s"
    )

    friction = FrictionLaw()  # docs/physics.md §4 reference: mu_s = 0.5, mu_d = 0.4, d_c = 100 s/m
    contact, t = timed(
        comm,
        lambda: NitscheContact(
            V,
            facet_tags,
            tags.TP_CONTACT,
            tags.MP_CONTACT,
            material,
            friction,
            gamma0=a.gamma0,
            theta=a.theta,
            lagged_friction=a.lagged_friction,
        ),
    )
    n_points = comm.allreduce(contact.slave.num_points, op=MPI.SUM)
    say(
        f"contact set-up: {t:.2f} s; {n_points} slave points, {contact.master.num_facets} master facets"
    )
    if a.self_weight > 0:
        return self_weight(a, V, data, joint, material, contact)
    u = dolfinx.fem.Function(V)
    for name, f in [
        ("pairing + state update", lambda: contact.update(u)),
        ("residual", contact.residual),
        ("jacobian", contact.jacobian),
        (
            "interface_stiffness(band 0.1 m)",
            lambda: contact.interface_stiffness(band_status(contact, 0.1)),
        ),
    ]:
        _, t = timed(comm, f)
        say(f"  {name:34s} {t:7.2f} s")

    # implicit step from rest: A = K + M / (beta dt^2), beta = 1/4
    du, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    c_m = 1.0 / (0.25 * a.dt**2)
    form = dolfinx.fem.form(
        ufl.inner(sigma(du, material), epsilon(v)) * ufl.dx
        + c_m * material.rho * ufl.inner(du, v) * ufl.dx
    )
    clamped = dolfinx.fem.locate_dofs_topological(V, 2, facet_tags.find(tags.MP_CLAMPED))
    bcs = [dolfinx.fem.dirichletbc(np.zeros(3), clamped, V)]
    A = dolfinx.fem.petsc.assemble_matrix(form, bcs=bcs)
    A.assemble()
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    area = comm.allreduce(
        dolfinx.fem.assemble_scalar(dolfinx.fem.form(1.0 * ds(tags.TP_TOP))), op=MPI.SUM
    )
    load = dolfinx.fem.Constant(mesh, np.zeros(3))
    L = dolfinx.fem.form(ufl.inner(load, v) * ds(tags.TP_TOP))

    strategies = {"fresh": ("LU every iteration", 0), "reuse": ("reused LU + GMRES", 25)}
    for label, refactor in (strategies[name] for name in a.strategies):
        u.x.array[:] = 0.0
        u_old = dolfinx.fem.Function(V)
        newton = ContactNewtonSolver(
            A,
            bcs,
            refactor_after=refactor,
            max_iterations=40,
            max_backtracks=a.max_backtracks,
            max_gap_change=a.max_gap_change,
        )
        total = {}
        t_all = 0.0
        say(f"{label}:")
        for k in range(1, a.steps + 1):
            load.value = np.array([0.0, 0.0, -a.force * k / a.steps / area])
            b = dolfinx.fem.petsc.assemble_vector(L)
            dolfinx.fem.petsc.apply_lifting(b, [form], [bcs])
            b.ghostUpdate(PETSc.InsertMode.ADD, PETSc.ScatterMode.REVERSE)
            dolfinx.fem.petsc.set_bc(b, bcs)
            # b += M/(beta dt^2) u_old (the step's inertia term at rest velocity/acceleration)
            Mu = A.createVecLeft()
            A.mult(u_old.x.petsc_vec, Mu)
            b.axpy(1.0, Mu)
            K_only = dolfinx.fem.petsc.assemble_vector(
                dolfinx.fem.form(ufl.inner(sigma(u_old, material), epsilon(v)) * ufl.dx)
            )
            K_only.ghostUpdate(PETSc.InsertMode.ADD, PETSc.ScatterMode.REVERSE)
            b.axpy(-1.0, K_only)
            dolfinx.fem.petsc.set_bc(b, bcs)
            contact.set_reference(u_old, a.dt)
            result, t = timed(comm, lambda newton=newton, b=b: newton.solve(b, contact, u))
            t_all += t
            for key, value in result.timings.items():
                total[key] = total.get(key, 0.0) + value
            status = np.bincount(np.concatenate(comm.allgather(contact.state.status)), minlength=3)
            say(
                f"  step {k}: converged={result.converged} iterations={result.iterations} "
                f"factorisations={result.factorizations} GMRES={sum(result.linear_iterations)} "
                f"time={t:.1f} s  open/stick/slip={status.tolist()}  "
                f"||F||: {' '.join(f'{x:.1e}' for x in result.residual_norms)} {result.message}"
            )
            u_old.x.array[:] = u.x.array
        say(
            f"  total {t_all:.1f} s; "
            + ", ".join(f"{key} {value:.1f} s" for key, value in total.items())
        )
        newton.destroy()
    return 0


def self_weight(a, V, data, joint, material, contact) -> int:
    """Dynamic self-weight ramp (solver.dynamics) with this contact; prints one line per step."""
    from solver.dynamics.damping import RayleighDamping
    from solver.dynamics.elastodynamics import assemble_structure, Elastodynamics
    from solver.installation.observers import Settlement
    from solver.dynamics.time_loop import run
    from solver.dynamics.loads import RampedAxialForce, TopFaceLoad, TPLoading
    from solver.dynamics.schemes import GeneralisedAlpha

    comm = V.mesh.comm
    clamped = dolfinx.fem.locate_dofs_topological(V, 2, data.facet_tags.find(tags.MP_CLAMPED))
    bcs = [dolfinx.fem.dirichletbc(np.zeros(3), clamped, V)]
    M, K = assemble_structure(V, material, bcs)
    loading = TPLoading(
        TopFaceLoad(V, data.facet_tags, tags.TP_TOP),
        static_axial=RampedAxialForce(-a.force, a.self_weight),
    )
    problem = Elastodynamics(
        V,
        M,
        K,
        bcs,
        load=loading,
        scheme=GeneralisedAlpha.from_spectral_radius(a.rho_inf),
        damping=RayleighDamping.at_frequency(0.01, 120.0),
        contact=contact,
        newton_options={
            "max_backtracks": a.max_backtracks,
            "refactor_after": 0,
            "max_iterations": 40,
            "max_gap_change": a.max_gap_change,
        },
    )
    problem.initialise(0.0)
    settlement = Settlement(problem.u, joint, data.cell_tags)

    def report(problem) -> dict:
        row = settlement(problem)
        status = np.bincount(np.concatenate(comm.allgather(contact.state.status)), minlength=3)
        normal, _ = contact.forces()
        if comm.rank == 0:
            print(
                f"  t={problem.t:.4f} s settlement={row['settlement_mm']:.4f} mm "
                f"open/stick/slip={'/'.join(map(str, status))} N={normal:.4g} N",
                flush=True,
            )
        return row

    step = problem.step

    def logged_step(dt):
        result = step(dt)
        if comm.rank == 0:
            print(
                f"    step of {dt:.4g} s: converged={result.converged} iterations={result.iterations} ||F||: "
                + " ".join(f"{x:.1e}" for x in result.residual_norms),
                flush=True,
            )
        return result

    problem.step = logged_step
    t0 = time.perf_counter()
    rows = run(problem, a.self_weight, a.dt, observers=[report], progress=False)
    wall = time.perf_counter() - t0
    if comm.rank == 0:
        print("dt_s:", " ".join(f"{r['dt_s']:.3g}" for r in rows))
        print("iterations:", " ".join(str(r["newton_iterations"]) for r in rows))
        its = np.array([r["newton_iterations"] for r in rows])
        print(
            f"self-weight: {len(rows)} steps, Newton iterations mean {its.mean():.2f} max {its.max()}, "
            f"settlement {rows[-1]['settlement_mm']:.4f} mm, wall {wall:.1f} s"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
