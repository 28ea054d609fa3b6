"""Vibration-assisted installation of the scaled slip-joint (placeholder).

Usage: mpirun -n 2 python demos/install.py [--quick] [--output DIR]
"""

import argparse
import sys


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="coarse smoke run")
    parser.add_argument("--output", default="output/install", help="output folder")
    parser.parse_args(argv)
    print("install demo: not yet available (the contact/dynamics solver has not landed yet)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
