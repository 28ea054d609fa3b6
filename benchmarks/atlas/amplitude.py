"""The amplitude runs of the atlas (docs/physics.md §5.3): from the installed state (the last
checkpoint of an installation run of the case), at each of two non-modal frequencies of the run
(its control and its highest lead-in), branches of ``BRANCH_PERIODS`` excitation periods at
amplitudes k A (A: the modal stages' amplitude, ``vibration.amplitude_N``), each from the same
state, and a baseline branch without excitation (k = 0): the installed state still settles for
a few periods after the last stage. A branch settles when the settlement it adds to the
baseline holds a stick-slip event as the installation run counts them (``solver.post.report``:
the rate averaged over one period above ``output.slip_rate_mm_s``). The factor k is doubled (or
halved) from 1 until the answer changes, then bisected geometrically until the threshold is
bracketed to ``BRACKET``.

The branches of one frequency share the step, so they share the operator and the contact
solver's factors and compliance blocks (the state they start from is the same). Kept as
``run.json`` in its folder, rewritten after each branch (a later call with the same request,
the installed state's time included, runs only the branches it lacks).
"""

import math
import time
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from benchmarks.atlas.installed import restore_installed
from benchmarks.atlas.kept import frees_joints, keep_run, kept_run
from benchmarks.atlas.stepping import run_schedule
from common.case import read_case
from solver.dynamics.loads import Schedule, Stage
from solver.installation import checkpoint
from solver.installation.case import InstallationCase
from solver.installation.frequencies import Excitation
from solver.installation.model import JointModel
from solver.installation.planning import stage_step
from solver.post import report

__all__ = [
    "BRACKET",
    "BRANCH_PERIODS",
    "added_settlement",
    "amplitude_runs",
    "next_factor",
    "non_modal_frequencies",
    "settles",
]

BRANCH_PERIODS = 5  #: excitation periods per branch
BRACKET = 1.1  #: the threshold's bracket: smallest factor that settles / largest that does not
FACTOR_RANGE = (1 / 8, 8.0)  #: factors k tried, at most


def non_modal_frequencies(excitations: list[Excitation]) -> list[float]:
    """The run's control frequency and its highest lead-in frequency [Hz] (those it has)."""
    control = [e.drive_Hz for e in excitations if e.role == "control"]
    lead_in = [e.drive_Hz for e in excitations if e.role == "lead-in"]
    return control[:1] + ([max(lead_in)] if lead_in else [])


def added_settlement(rows: list, baseline: list) -> tuple[np.ndarray, np.ndarray]:
    """Time [s] and the settlement [mm] a branch adds to the baseline branch from its start, of
    their (time [s], settlement [mm], normal force [N]) rows (the baseline interpolated to the
    branch's times)."""
    t, s, _ = np.array(rows).T
    t_0, s_0, _ = np.array(baseline).T
    return t, (s - s[0]) - (np.interp(t, t_0, s_0) - s_0[0])


def settles(rows: list, baseline: list, steps_per_period: int, slip_rate_mm_s: float) -> bool:
    """Whether the settlement a branch adds to the baseline (``added_settlement``) holds a
    stick-slip event."""
    t, s = added_settlement(rows, baseline)
    return bool(report.slip_episodes(t[1:], s[1:], s[0], t[0], steps_per_period, slip_rate_mm_s))


def next_factor(results: dict[float, bool]) -> float | None:
    """The next factor to run given the branches run so far (factor -> settles), or None when
    the threshold is bracketed to ``BRACKET`` or lies outside ``FACTOR_RANGE``."""
    if not results:
        return 1.0
    settling = [k for k, s in results.items() if s]
    holding = [k for k, s in results.items() if not s]
    if not settling:
        k = 2.0 * max(holding)
        return k if k <= FACTOR_RANGE[1] else None
    if not holding:
        k = 0.5 * min(settling)
        return k if k >= FACTOR_RANGE[0] else None
    low, high = max(holding), min(settling)
    if high / low <= BRACKET:
        return None
    return math.sqrt(low * high)


class _Branches:
    """The branches of the atlas's amplitude runs: the joint restored once from the installed
    state (on the first branch to run), each branch from that state, the results written after
    each branch."""

    def __init__(self, comm: MPI.Comm, case_name: str, overrides: list[str], installed: Path):
        self.comm, self.case_name, self.overrides, self.installed = (
            comm,
            case_name,
            overrides,
            installed,
        )
        self.case = InstallationCase.from_dict(read_case(case_name, overrides))
        self._model: JointModel | None = None
        self._saved: Path | None = None
        self._step: float | None = None  # the step the operator was built at

    def run(self, folder: Path, frequency_hz: float, factor: float) -> list:
        """(time [s], settlement [mm], normal force [N]) rows of a branch of ``BRANCH_PERIODS``
        periods at ``frequency_hz`` [Hz] and ``factor`` times the modal amplitude, from the
        installed state (kept in ``folder``/installed)."""
        if self._model is None:
            self._model = restore_installed(
                self.comm, self.case_name, self.overrides, self.installed
            )[0]
            self._saved = folder / "installed"
            checkpoint.save(self._saved, self._model.problem, {})
        model, problem = self._model, self._model.problem
        assert self._saved is not None
        duration = BRANCH_PERIODS / frequency_hz
        dt = stage_step(duration, frequency_hz, self.case.time.steps_per_period)
        checkpoint.restore(self._saved, problem)
        if dt != self._step:  # the branches at one step share the operator and the solver
            problem.set_scheme(self.case.vibration_scheme())
            self._step = dt
        amplitude = factor * self.case.vibration.amplitude_N
        schedule = Schedule([Stage(duration, frequency_hz, amplitude)], start_s=problem.t)
        return run_schedule(model, schedule, dt)


@frees_joints
def amplitude_runs(
    comm: MPI.Comm,
    case_name: str,
    overrides: list[str],
    folder: Path,
    installed: Path,
) -> dict[str, Any]:
    """From the installed state of ``installed`` (an installation run's output folder), at each
    of its ``non_modal_frequencies``, the branches that bracket the amplitude threshold. Returns
    (and keeps in ``folder``/run.json, rewritten after each branch) the request (with the
    state's time [s] and the amplitude A [N]), per frequency (as text, [Hz]) the (time [s],
    settlement [mm], normal force [N]) rows of each factor k (as text; "0": the baseline), the branch that failed
    (its factor and the error) of each frequency where one did (its search stops there) and the
    wall time [s] (collective)."""
    branches = _Branches(comm, case_name, overrides, installed)
    case = branches.case
    manifest = checkpoint.read_manifest(installed / "checkpoint", comm)
    request = {
        "case": case_name,
        "overrides": overrides,
        "installed": str(installed),
        "time_s": manifest["time_s"],
        "amplitude_N": case.vibration.amplitude_N,
        "periods": BRANCH_PERIODS,
    }
    result: dict[str, Any] = {"request": request, "name": folder.name, "frequencies": {}}
    wall_kept = 0.0
    if (kept := kept_run(folder, request)) is not None:
        result["frequencies"], wall_kept = kept["frequencies"], kept["wall_s"]
        result["failed"] = kept.get("failed", {})
    wall = time.perf_counter()
    excitations = [Excitation(**e) for e in manifest["excitations"]]
    steps, slip_rate = case.time.steps_per_period, case.output.slip_rate_mm_s
    failed = result.setdefault("failed", {})
    for f in non_modal_frequencies(excitations):
        runs = result["frequencies"].setdefault(f"{f:.6g}", {})
        results: dict[float, bool] = {}
        k: float | None = 0.0  # the baseline first
        while f"{f:.6g}" not in failed and k is not None:
            k = float(f"{k:.6g}")  # as kept in run.json
            if f"{k:.6g}" not in runs:
                try:
                    runs[f"{k:.6g}"] = branches.run(folder, f, k)
                except RuntimeError as e:  # Newton failed at the minimum step: the search stops
                    failed[f"{f:.6g}"] = {"factor": k, "message": str(e)}
                    break
                result["wall_s"] = wall_kept + time.perf_counter() - wall
                keep_run(comm, folder, result)
            if k > 0:
                results[k] = settles(runs[f"{k:.6g}"], runs["0"], steps, slip_rate)
            k = next_factor(results)
    result["wall_s"] = wall_kept + time.perf_counter() - wall
    keep_run(comm, folder, result)
    return result
