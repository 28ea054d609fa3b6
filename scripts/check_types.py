"""Type check of solver/ and geometry/ (mypy) against a baseline that may only shrink.

``python scripts/check_types.py`` runs mypy and compares its error count per file with
``scripts/mypy_baseline.txt``: it fails (exit 1) if any file has more errors than its
baseline, and prints the files that have fewer. ``--update`` writes the present counts as the
baseline.
"""

import argparse
import os
import re
import sys
from collections import Counter
from pathlib import Path

from mypy import api

ROOT = Path(__file__).resolve().parents[1]
BASELINE = ROOT / "scripts" / "mypy_baseline.txt"
PACKAGES = ["solver", "geometry"]


def error_counts() -> Counter:
    """mypy's error count per file of PACKAGES (paths relative to the repository); raises
    RuntimeError when mypy itself fails."""
    os.chdir(ROOT)
    stdout, stderr, status = api.run(["--ignore-missing-imports", "--no-error-summary", *PACKAGES])
    if status not in (0, 1):
        raise RuntimeError(
            f"mypy failed (exit status {status}): {stderr.strip() or stdout.strip()}"
        )
    return Counter(m.group(1) for m in re.finditer(r"^(\S+\.py):\d+: error:", stdout, re.M))


def read_baseline() -> Counter:
    counts = Counter()
    for line in BASELINE.read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            path, n = line.split()
            counts[path] = int(n)
    return counts


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--update", action="store_true", help="write the present counts as the baseline")
    args = p.parse_args(argv)
    counts, baseline = error_counts(), read_baseline()
    grown = {f: (baseline[f], n) for f, n in counts.items() if n > baseline[f]}
    shrunk = {f: (n, counts[f]) for f, n in baseline.items() if counts[f] < n}
    for f, (old, new) in sorted(grown.items()):
        print(f"error: {f}: {new} type errors, baseline {old}")
    for f, (old, new) in sorted(shrunk.items()):
        print(f"{f}: {new} type errors, baseline {old} (lower it: --update)")
    print(f"mypy: {sum(counts.values())} errors, baseline {sum(baseline.values())}")
    if args.update:
        lines = [f"{f} {n}" for f, n in sorted(counts.items()) if n]
        BASELINE.write_text(
            "# mypy errors per file (scripts/check_types.py); may only shrink\n"
            + "\n".join(lines)
            + "\n"
        )
        return 0
    return 1 if grown else 0


if __name__ == "__main__":
    sys.exit(main())
