"""``docs/scenarios.md``: the atlas page, rebuilt from the outcomes found in the output folder
(every scenario run so far with the same output folder) and, for the other scenarios, from the
outcomes kept beside the page (``docs/scenarios/<key>.json``, the last of each scenario written
to the page), with their figures copied beside it."""

import shutil
from pathlib import Path

from benchmarks.atlas.catalogue import SCENARIOS
from benchmarks.atlas.outcome import Outcome

__all__ = ["write_page"]

HEADER = """# Scenario atlas

The observations of docs/physics.md §5 run on one joint, each against its criterion. The page is
written by

    mpirun -n 2 python benchmarks/scenarios.py --all          # or a list: S1 S8
    mpirun -n 2 python benchmarks/scenarios.py --all --installed output/install
    mpirun -n 2 python benchmarks/scenarios.py S2 S4 --case scaled_full --installed output/full

which runs the scenarios on the default case (`--case` and `--set` choose another; the joint of each
row below names the case and the overrides it ran with), keeps each one's outputs in
`output/atlas/<scenario>/` (runs that scenarios share, in `output/atlas/runs/`, are made once) and
rebuilds this page from all the scenarios found there; the other scenarios' rows are their last
outcomes written to this page, kept in `docs/scenarios/<scenario>.json`. With `--installed RUN` (the
output folder of a `demos/install.py` run of the same case on as many ranks, e.g. `mpirun -n 2
python demos/install.py --full --set output.stage_states=true --output output/full` for
`scaled_full`), S2 and S4 read that
run's stages (those up to its last checkpoint: all of them once it has finished), and S3, S4, S5 and
S8 also start from the installed state: the run's last checkpoint, after its last completed stage;
S8 also after each vibration stage whose state the run kept (`--set output.stage_states=true`), as
the stage left it and brought to rest; S4 also reads the run's modal table. The installation run's
own time (the sum of its stages' wall times) counts in S2 only (docs/install.md, "Cost"). A verdict
is "reproduced" or "not reproduced" where the criterion is a test, "measured" where it is a figure
to report, "not run" where the run it needs was not made.
Wall times are on {ranks} MPI rank(s) of the machine that ran it.

Shortened, S1, the two-stage S2 (from the end of the ramp a lead-in at the control, then the
best mode and the control, 0.05 s each), the friction half of S6, S8 and S5's release (from the
end of the ramp a pull between the pull-out forces with mu_d and with mu_s minus 3.6 kN alone,
then with 3.6 kN at the best mode) run in the test suite (`make test`,
`tests/solver/installation/test_install_scenarios.py`, on 2 ranks; the serial run skips them) on
the default joint with its outer Newton tolerance and the stepping of
`cases/scaled_lagged.toml`, an 80 mm contact zone and the self-weight ramped over 1 s
(`cases/suite.toml`). In
the 2-rank run of `make test` from a fresh clone (its slowest tests are listed in
`build/Testing/Temporary/LastTest.log`) the ramp with its two modal analyses takes 2.1 min, the
low-friction ramp 0.9 min, the two-stage S2 3.3 min and S5's release 0.9 min. What they measure
(the mode 7.8 times the control's rate; the pull alone lifts the TP 0.4 um, and with the
vibration it is released 35 ms on) is printed by
`mpirun -n 2 python -m mpi4py -m pytest -s tests/solver/installation/test_install_scenarios.py`.
"""


def _figure_name(key: str, relative: str) -> str:
    return f"{key}_{Path(relative).name}"


def write_page(output: Path, page: Path) -> None:
    """Rebuild ``page`` from the outcomes in ``output`` and, for the scenarios not there, the
    outcomes kept beside it; keep the new ones there too (call on one rank)."""
    kept = page.with_suffix("")
    figures = page.parent / "figures" / "scenarios"
    figures.mkdir(parents=True, exist_ok=True)
    outcomes = {}
    for k in SCENARIOS:
        if (o := Outcome.load(output / k / "outcome.json")) is not None:
            o.save(kept / f"{k}.json")
            for relative in o.figures:
                shutil.copyfile(output / k / relative, figures / _figure_name(k, relative))
        elif (o := Outcome.load(kept / f"{k}.json")) is None:
            continue
        outcomes[k] = o
    ranks = {o.ranks for o in outcomes.values()} or {0}
    runs: dict[str, float] = {}
    for o in outcomes.values():
        runs |= o.runs
    lines = [HEADER.format(ranks=", ".join(map(str, sorted(ranks))))]
    joints: dict[str, list[str]] = {}
    for key, o in outcomes.items():
        joints.setdefault(o.joint, []).append(key)
    if len(joints) == 1:
        lines.append(f"Joint: {next(iter(joints))}.\n")
    else:
        lines += [f"Joint of {', '.join(keys)}: {j}.\n" for j, keys in joints.items()]
    lines += [
        f"Wall time of the scenarios below: {sum(runs.values()) / 60:.1f} min "
        f"({len(runs)} runs, each counted once).\n",
        "| scenario | criterion | measured | verdict | wall time |",
        "|---|---|---|---|---|",
    ]
    for key, o in outcomes.items():
        for i, row in enumerate(o.rows):
            head = f"{key}: {o.title}" if i == 0 else ""
            wall = f"{o.wall_s / 60:.1f} min" if i == 0 else ""
            lines.append(f"| {head} | {row.criterion} | {row.measured} | {row.verdict} | {wall} |")
    for key, o in outcomes.items():
        lines.append(f"\n## {key}: {o.title}\n")
        lines.append(f"Criterion: {SCENARIOS[key].criterion}.\n")
        for relative in o.figures:
            name = _figure_name(key, relative)
            lines.append(f"![{key} {Path(relative).stem}](figures/scenarios/{name})\n")
    missing = [k for k in SCENARIOS if k not in outcomes]
    if missing:
        lines.append("\n## Not run yet\n")
        lines.append("| scenario | criterion |")
        lines.append("|---|---|")
        lines += [f"| {k}: {SCENARIOS[k].title} | {SCENARIOS[k].criterion} |" for k in missing]
    page.write_text("\n".join(lines) + "\n")
