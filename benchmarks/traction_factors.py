"""Time of the inner problem's factors (``solver.dynamics.traction_jacobian``) on a synthetic
block of the size of the default run's vibration stages: ``--points`` active contact points, a
fraction ``--slipping`` of them slipping and the others stuck, a dense compliance G. Prints, in
turns, the mean wall time of ``TractionJacobian.factorise`` (the block reduced by the kernel of
the law's derivative) and of the LU of the whole block J = I + G_aa D, both once per node with a
BLAS thread per rank of the node, with the rows of each, and of one solve with each's factors.

    mpirun -n 2 python benchmarks/traction_factors.py [--points 680] [--slipping 0.98] \\
        [--repeats 10] [--rounds 2]
"""

import argparse
import sys
import time
from collections.abc import Callable

from common import backend  # noqa: F401

import numpy as np
import scipy.linalg
from mpi4py import MPI

from solver.contact.law import derivative
from solver.dynamics.node_memory import NodeMemory
from solver.dynamics.traction_jacobian import TractionJacobian


def main(argv: list[str] | None = None) -> int:
    """Run the timings (``argv``: the command line's arguments); returns the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--points", type=int, default=680, help="active points (default 680)")
    parser.add_argument("--slipping", type=float, default=0.98, help="their slipping fraction")
    parser.add_argument("--repeats", type=int, default=10, help="factorisations per timing")
    parser.add_argument("--rounds", type=int, default=2, help="timings of each way, in turns")
    args = parser.parse_args(argv)
    if args.points < 1 or args.repeats < 1 or args.rounds < 1:
        print("error: --points, --repeats and --rounds must be positive", file=sys.stderr)
        return 2
    if not 0.0 <= args.slipping <= 1.0:
        print("error: --slipping must lie in [0, 1]", file=sys.stderr)
        return 2
    comm = MPI.COMM_WORLD
    m, n = args.points, 3 * args.points
    rng = np.random.default_rng(0)  # the same block on every rank
    A = rng.random((n, n))
    G = np.asfortranarray(20.0 * A @ A.T / n)  # compliance-like: symmetric positive
    normal = rng.normal(size=(m, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    P_t = rng.normal(size=(m, 3))
    P_t -= np.einsum("pi,pi->p", P_t, normal)[:, None] * normal
    slip = np.arange(m) < round(args.slipping * m)
    D = derivative(normal, P_t, np.full(m, 0.5), np.ones(m), ~slip, slip)
    active, r = np.arange(m), rng.normal(size=n)

    jacobian = TractionJacobian(comm)
    jacobian.set_compliance(G)
    node = NodeMemory(comm)
    JT = (D.transpose(0, 2, 1) @ G.T.reshape(m, 3, n)).reshape(n, n).astype(np.float32)
    JT[np.diag_indices_from(JT)] += 1.0  # J^T in C order: J in Fortran order
    pivots = np.empty(n, dtype=np.int32)

    def whole() -> Callable:
        factors = node.get("whole", (n, n), np.float32)
        node.begin()
        if node.writer:
            factors[:] = JT
            with node.threads():
                _, pivots[:] = scipy.linalg.lu_factor(factors.T, overwrite_a=True)
        node.end()
        node.comm.Bcast(pivots)
        lu = (factors.T, pivots.copy())
        return lambda b: scipy.linalg.lu_solve(lu, b.astype(np.float32), check_finite=False)

    def reduced() -> Callable:
        return jacobian.factorise(active, D).solve

    if comm.rank == 0:
        print(f"{m} active points ({slip.sum()} slipping), {comm.size} rank(s)")
    for _ in range(args.rounds):
        for name, factorise, rows in (
            ("reduced by the kernel", reduced, lambda: jacobian.factor_rows),
            ("whole block", whole, lambda: n),
        ):
            comm.Barrier()
            start = time.perf_counter()
            for _ in range(args.repeats):
                solve = factorise()
                comm.Barrier()
            seconds = (time.perf_counter() - start) / args.repeats
            start = time.perf_counter()
            for _ in range(10 * args.repeats):
                solve(r)
            solve_s = (time.perf_counter() - start) / (10 * args.repeats)
            if comm.rank == 0:
                print(
                    f"  {name:21s} {rows():5d} rows: {1e3 * seconds:6.1f} ms per factorisation, "
                    f"{1e3 * solve_s:5.2f} ms per solve"
                )
    jacobian.free()
    node.free()
    return 0


if __name__ == "__main__":
    sys.exit(main())
