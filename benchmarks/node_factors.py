"""Time of the inner problem's single-precision LU on the ranks of one node: every rank factorising
alike with one BLAS thread, against once per node in shared memory by its first rank with a
thread per rank while the others sleep (``solver.dynamics.node_memory``, as in
``solver.dynamics.traction_jacobian``). Prints the mean wall time per factorisation [ms] of each
way, in turns.

    mpirun -n 2 python benchmarks/node_factors.py [--rows 2000] [--repeats 10] [--rounds 2]
"""

import argparse
import sys
import time

from common import backend  # noqa: F401

import numpy as np
import scipy.linalg
from mpi4py import MPI

from solver.dynamics.node_memory import NodeMemory


def main(argv: list[str] | None = None) -> int:
    """Run the timings (``argv``: the command line's arguments); returns the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rows", type=int, default=2000, help="rows of the matrix (default 2000)")
    parser.add_argument("--repeats", type=int, default=10, help="factorisations per timing")
    parser.add_argument("--rounds", type=int, default=2, help="timings of each way, in turns")
    args = parser.parse_args(argv)
    if args.rows < 1 or args.repeats < 1 or args.rounds < 1:
        print("error: --rows, --repeats and --rounds must be positive", file=sys.stderr)
        return 2
    comm = MPI.COMM_WORLD
    n = args.rows
    rng = np.random.default_rng(0)
    J = (rng.random((n, n)) + n * np.eye(n)).astype(np.float32)  # J^T in C order: J in F order
    node = NodeMemory(comm)

    def alike() -> None:
        scipy.linalg.lu_factor(J.T.copy(order="F"), overwrite_a=True, check_finite=False)

    def once_per_node() -> None:
        factors = node.get("factors", (n, n), np.float32)
        node.begin()
        if node.writer:
            factors[:] = J
            with node.threads():
                scipy.linalg.lu_factor(factors.T, overwrite_a=True, check_finite=False)
        node.end()

    if comm.rank == 0:
        print(f"{n} x {n} single-precision LU, {comm.size} rank(s), {node.comm.size} on this node")
    for _ in range(args.rounds):
        for name, factorise in (("every rank alike", alike), ("once per node", once_per_node)):
            comm.Barrier()
            start = time.perf_counter()
            for _ in range(args.repeats):
                factorise()
                comm.Barrier()
            seconds = (time.perf_counter() - start) / args.repeats
            if comm.rank == 0:
                print(f"  {name:17s} {1e3 * seconds:6.1f} ms per factorisation")
    node.free()
    return 0


if __name__ == "__main__":
    sys.exit(main())
