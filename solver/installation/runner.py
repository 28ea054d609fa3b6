"""Vibration-assisted installation of the slip-joint: the staged run (docs/physics.md §3, 5).

Stages of :class:`Installation`:

1. ``self-weight``: axial force on the TP top ramped 0 -> ``force_N`` over ``ramp_time_s``,
   then held for ``hold_s`` (dynamic by default); the TP settles in stick-slip steps.
2. ``modal``: natural frequencies of the settled joint, with the contact tangent at the
   settled status (``solver.modal.interface.ContactInterface``), ranked by
   ``solver.modal.ranking.describe_modes``; the excitation frequencies are chosen from the
   ranking (``solver.installation.frequencies.choose_frequencies``), each with its reason.
3. ``vibration``: the harmonic schedule (lead-in stages, the chosen natural frequencies and
   a non-modal control frequency, or an explicit ``[[schedule]]``) on top of the held force.
4. the report (``solver.post.report``): settlement per stage, stick-slip events, contact status.

Settlement is ``solver.installation.observers.Settlement``: the axial slide [mm] of the TP's lower edge
relative to the MP wall beside it, positive down. After the self-weight stage the static axial
force may follow a piecewise-linear history (``[static_force]``, e.g. a dismount pull), and the
cones may carry radial imperfections (``[imperfections.mp]``, ``[imperfections.tp]``: ovality or
a measured map/scan file, ``geometry.imperfections``). All settings come from a case file
(tables below the geometry ones), checked as a whole by
``solver.installation.case.InstallationCase.from_dict``
before anything is computed. SI units; frequencies in Hz, forces in N.
"""

from __future__ import annotations

import json
import math
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

from mpi4py import MPI

from solver.dynamics.elastodynamics import Elastodynamics
from solver.dynamics.loads import Schedule, TPLoading
from solver.dynamics.time_loop import run
from solver.installation import checkpoint
from solver.installation.case import InstallationCase, case_differences
from solver.installation.frequencies import Excitation, choose_frequencies, schedule_excitations
from solver.installation.model import (
    JointModel,
    attach_vibration,
    set_up_joint_model,
    settled_modes,
)
from solver.installation.observers import ContactZoneGuard
from solver.installation.planning import StagePlan, compensate, format_fidelity, plan_vibration
from solver.modal.eigen import ModalResult
from solver.modal.outputs import write_csv, write_outputs
from solver.modal.ranking import JointParts, ModeRecord, describe_modes
from solver.post import paraview, plots, report
from solver.post.csv import CsvWriter


class Installation:
    """The staged installation run of one case, writing its outputs to ``output`` as it goes.

    ``run(resume=False, stop_after_checkpoints=None)``: the whole pipeline; with ``resume``
    it continues from the checkpoint in ``output/checkpoint``, which records the fingerprint of
    its case (``InstallationCase.fingerprint``): a case that would compute something else is
    refused before anything is computed (ValueError naming the keys that differ; output-only
    keys may differ). ``stop_after_checkpoints`` ends the run early after that many
    checkpoints (used to test resuming).
    """

    def __init__(
        self,
        comm: MPI.Comm,
        case: InstallationCase,
        output: str | Path,
        log: Callable[[str], None] | None = None,
        progress: bool = True,
        on_stage: Callable[[str, Any], None] | None = None,
    ):
        self.comm, self.case = comm, case
        #: instrumentation: called with ("start", plan) before and ("end", summary) after each
        #: time-stepping stage, and ("modal", seconds) after the modal stage
        self.on_stage = on_stage or (lambda event, data: None)
        self.output = Path(output)
        self.log = log or (_write_line if comm.rank == 0 else (lambda s: None))
        self.progress = progress and comm.rank == 0
        self.model: JointModel | None = None
        self.history: list[dict[str, float]] = []
        self.stages: list[dict[str, Any]] = []
        self.plans: list[StagePlan] = []
        self.excitations: list[Excitation] = []
        self.modal: tuple[ModalResult, list[ModeRecord]] | None = None
        self.natural_frequencies: list[float] = []
        self._checkpoints = 0
        self._stop_after: int | None = None
        self._fingerprint: dict[str, Any] = {}

    # paths
    @property
    def checkpoint_dir(self) -> Path:
        return self.output / "checkpoint"

    def _record(self, next_stage: int, chunk: int) -> dict[str, Any]:
        return {
            "case": self._fingerprint,
            "next_stage": next_stage,
            "next_chunk": chunk,
            "history": self.history,
            "stages": self.stages,
            "plans": [asdict(p) for p in self.plans],
            "excitations": [asdict(e) for e in self.excitations],
            "natural_frequencies_Hz": self.natural_frequencies,
        }

    def stage_state_dir(self, stage: int) -> Path:
        """Where ``[output] stage_states`` keeps the state after stage ``stage`` (0: self-weight)."""
        return self.output / "states" / str(stage)

    def _checkpoint(self, next_stage: int, chunk: int) -> None:
        problem = self.model.problem
        # a resumed run starts with a fresh factorisation, so does the uninterrupted one
        problem.reset_operator()
        record = self._record(next_stage, chunk)
        checkpoint.save(self.checkpoint_dir, problem, record)
        if chunk == 0 and self.case.output.stage_states:
            checkpoint.save(self.stage_state_dir(next_stage - 1), problem, record)
        self._checkpoints += 1
        if self._stop_after is not None and self._checkpoints >= self._stop_after:
            raise _Stopped()

    # stages
    def _observer(self, stage_index: int, plan: StagePlan, writer: CsvWriter, bar):
        model = self.model
        loading: TPLoading = model.problem.load
        failed = [model.problem.failed_steps]  # failed attempts before the last accepted step

        def observe(problem: Elastodynamics) -> dict[str, float]:
            t = problem.t
            cuts, failed[0] = problem.failed_steps - failed[0], problem.failed_steps
            prev_t = self.history[-1]["time_s"] if self.history else 0.0
            schedule = loading.schedule or (loading.shaker[1] if loading.shaker else None)
            fractions = report.contact_counts(model.contact)
            normal, _ = model.contact.forces()
            row = {
                "time_s": t,
                "dt_s": t - prev_t,
                "stage": stage_index,
                "frequency_Hz": schedule.frequency(t) if schedule else 0.0,
                "amplitude_N": schedule.amplitude(t) if schedule else 0.0,
                "axial_force_N": float(
                    model.static(t) + (schedule.force(t)[2] if schedule else 0.0)
                ),
                **model.settlement(problem),
                "newton_iterations": problem.last_result.iterations if problem.last_result else 0,
                "step_cuts": cuts,
                "stick_fraction": fractions["stick_fraction"],
                "slip_fraction": fractions["slip_fraction"],
                "normal_force_N": normal,
            }
            self.history.append(row)
            writer.write(row)
            if bar is not None:
                bar.update(min(row["dt_s"], bar.total - bar.n))  # sums of dt overshoot by round-off
                bar.set_postfix_str(
                    f"{plan.name}, dt {row['dt_s']:.3g} s, "
                    f"settlement {row['settlement_mm']:.4f} mm, Newton {row['newton_iterations']}",
                    refresh=False,
                )
            return {}

        return observe

    def _run_stage(self, index: int, first_chunk: int, writer, bar) -> None:
        plan, model = self.plans[index], self.model
        assert model is not None  # set up by run()
        problem = model.problem
        steps = self.case.output.checkpoint_every
        n_chunks = max(1, math.ceil((plan.end_s - plan.start_s) / (steps * plan.dt_s) - 1e-9))
        if index == 0 and self.case.self_weight.event_dt_s:
            n_chunks = 1  # the event steps' state (step, calm steps, grid) lives in one call of run
        if index > 0:  # one step size per stage from here (also in a run resumed after stage 0)
            problem.keep_operators(1)
        self.on_stage("start", plan)
        observers = [self._observer(index, plan, writer, bar)]
        mesh = self.case.mesh
        if mesh.contact_axial_size > 0:
            observers.append(
                ContactZoneGuard(model.contact, mesh.contact_axial_size, mesh.contact_zone_above)
            )
        wall0 = time.perf_counter()
        rows0 = len(self.history)
        for chunk in range(first_chunk, n_chunks):
            t_end = min(plan.start_s + (chunk + 1) * steps * plan.dt_s, plan.end_s)
            if chunk == n_chunks - 1:
                t_end = plan.end_s
            if t_end > problem.t + 1e-12 * max(t_end, 1.0):
                if index == 0:  # with its fine steps within settling events
                    model.run_self_weight(t_end, observers)
                else:
                    run(
                        problem,
                        t_end,
                        plan.dt_s,
                        dt_min=plan.dt_s * self.case.time.dt_min_fraction,
                        observers=observers,
                        progress=False,
                    )
            if chunk < n_chunks - 1:
                self._checkpoint(index, chunk + 1)
        rows = [r for r in self.history if r["stage"] == index]
        summary = report.stage_summary(
            index, plan, rows, self.history, self.case.output.slip_rate_mm_s
        )
        summary["wall_s"] = (
            time.perf_counter() - wall0 if len(self.history) > rows0 else float("nan")
        )
        self.stages.append(summary)
        self.on_stage("end", summary)
        report.write_stage_table(self.stages, self.output / "stages.csv", self.comm)
        self._write_state(plan.name)
        self.log(report.format_stage(summary))

    def _write_state(self, name: str) -> None:
        """ParaView files and the contact-status plot of the state after stage ``name``."""
        model, k = self.model, len(self.stages)
        assert model is not None  # set up by run()
        if self.case.output.paraview:
            paraview.write_state(model.problem.u, model.problem.t, model.contact, self.output, k)
        if self.case.output.plots:
            plots.plot_contact_status(
                model.contact,
                model.placed,
                self.output / f"contact_status_{k}.png",
                f"after {name}, t = {model.problem.t:.4g} s",
            )

    def _schedule(self, start_s: float) -> Schedule:
        """The vibration schedule from ``start_s``: the automatic one (from the chosen excitations)
        or the case's [[schedule]] with 'mode k' / 'ranked k' set to the settled joint's
        frequencies."""
        vib = self.case.vibration
        if self.case.schedule is None:
            stages = [
                vib.stage(vib.stage_duration_s, e.drive_Hz, e.amplitude_N) for e in self.excitations
            ]
        else:  # 'mode k' / 'ranked k' stages at the frequencies found by the modal stage
            stages = [
                replace(s, frequency_hz=e.drive_Hz) if isinstance(s.frequency_hz, str) else s
                for s, e in zip(self.case.schedule.stages, self.excitations)
            ]
        return Schedule(stages, start_s=start_s)

    def _stage_durations(self) -> list[float]:
        """Duration [s] of each vibration stage (one per excitation)."""
        if self.case.schedule is None:
            return [self.case.vibration.stage_duration_s] * len(self.excitations)
        return [s.duration_s for s in self.case.schedule.stages]

    def _modal_stage(self) -> None:
        """Modes of the settled joint (contact tangent at its current status); frequency choice.

        With ``vibration.modal_stage = false`` only the explicit [[schedule]] is planned."""
        model, vib = self.model, self.case.vibration
        t0 = time.perf_counter()
        records: list[ModeRecord] = []
        if vib.modal_stage:
            result, interface = settled_modes(model, vib.n_modes)
            parts = JointParts.for_joint(model.V, model.mesh_data, model.placed)
            nodes_around = self.case.mesh.n_circumferential * self.case.contact.degree
            records = describe_modes(
                result,
                self.case.material,
                parts,
                zeta=max(self.case.damping.zeta, 1e-4),
                m_max=min(12, (nodes_around - 1) // 2),
            )
            if self.case.output.plots:
                write_outputs(result, records, self.output)
            else:
                write_csv(records, self.output / "modes.csv", self.comm)
            self.modal = (result, records)
            self.natural_frequencies = [float(f) for f in result.frequencies_hz]
        chosen = choose_frequencies(records, vib)
        if self.case.schedule is None:
            self.excitations = chosen
        else:
            self.excitations = schedule_excitations(
                self.case.schedule, self.natural_frequencies, chosen
            )
        scheme, steps = self.case.vibration_scheme(), self.case.time.steps_per_period
        self.excitations = compensate(self.excitations, self._stage_durations(), scheme, steps)
        if self.excitations:  # (none: the run ends after the modal stage)
            self.plans += plan_vibration(
                self._schedule(model.problem.t),
                scheme,
                steps,
                model.damping.ratio,
                self.excitations,
            )
        report.write_choice(self.excitations, self.output / "frequencies.csv", self.comm)
        self.on_stage("modal", time.perf_counter() - t0)
        if vib.modal_stage:
            self.log(
                f"modal stage: {len(records)} modes of the settled joint "
                f"({100 * interface.tied_fraction():.1f} % of the contact points tied) in "
                f"{time.perf_counter() - t0:.1f} s; excitation:"
            )
        else:
            self.log("no modal stage (vibration.modal_stage = false); excitation:")
        for e in self.excitations:
            amp = e.amplitude_N if isinstance(e.amplitude_N, str) else f"{e.amplitude_N:.0f} N"
            self.log(f"  {e.frequency_Hz:8.2f} Hz  {amp:>9}  {e.role:8} {e.reason}")
        if self.plans[1:]:
            self.log(
                "time discretisation of the vibration stages (docs/dynamics.md, resonance fidelity):"
            )
        for plan in self.plans[1:]:
            self.log("  " + format_fidelity(plan))

    def _install_schedule(self) -> None:
        """Attach the vibration schedule to the loads through the chosen forcing."""
        model = self.model
        plans = self.plans[1:]
        if not plans:
            return
        attach_vibration(model, self._schedule(plans[0].start_s))

    def _check_same_case(self, manifest: dict[str, Any]) -> None:
        """ValueError naming the keys in which this run's case differs from the checkpoint's
        (``InstallationCase.fingerprint``): a resumed run must compute what the killed one did."""
        if "case" not in manifest:
            raise ValueError(
                f"checkpoint {self.checkpoint_dir} does not record its case: rerun without --resume"
            )
        differences = case_differences(manifest["case"], self._fingerprint)
        if differences:
            raise ValueError(
                f"the case differs from the one of the checkpoint in {self.checkpoint_dir} "
                f"(checkpoint -> now): {', '.join(differences)}; resume with the case of the run "
                "that wrote it, or rerun without --resume"
            )

    def run(
        self, resume: bool = False, stop_after_checkpoints: int | None = None
    ) -> dict[str, Any]:
        """Run (or resume) the installation; returns the summary (collective)."""
        self._stop_after = stop_after_checkpoints
        case, comm = self.case, self.comm
        manifest = checkpoint.read_manifest(self.checkpoint_dir, comm) if resume else None
        self._fingerprint = case.fingerprint()
        if manifest is not None:
            self._check_same_case(manifest)
        if comm.rank == 0:
            self.output.mkdir(parents=True, exist_ok=True)
            (self.output / "case.json").write_text(
                json.dumps(case.describe(), indent=1, default=str)
            )
        self.model = set_up_joint_model(comm, case)
        model = self.model
        self.log(
            f"joint: {model.n_dofs} dofs (degree {case.contact.degree}, "
            f"{case.mesh.n_circumferential} around, {case.mesh.axial_size} m axially), "
            f"{comm.size} rank(s), damping {case.damping.model}; "
            f"set-up {model.timings_s['set-up']:.1f} s"
        )
        sw = case.self_weight
        self.plans = [
            StagePlan(
                "self-weight",
                0.0,
                sw.duration_s,
                sw.dt_s,
                0.0,
                0.0,
                f"{-sw.force_N:.0f} N down over {sw.ramp_time_s} s, held {sw.hold_s} s",
            )
        ]
        next_stage, next_chunk = 0, 0
        if manifest is not None:
            checkpoint.restore(self.checkpoint_dir, model.problem)
            self.history, self.stages = manifest["history"], manifest["stages"]
            self.plans = [StagePlan(**p) for p in manifest["plans"]]
            self.excitations = [Excitation(**e) for e in manifest["excitations"]]
            self.natural_frequencies = manifest["natural_frequencies_Hz"]
            next_stage, next_chunk = manifest["next_stage"], manifest["next_chunk"]
            self.log(
                f"resumed at t = {model.problem.t:.6g} s "
                f"(stage {next_stage + 1}, chunk {next_chunk})"
            )
        writer = CsvWriter(self.output / "history.csv", report.HISTORY_COLUMNS, comm, self.history)
        bar = None
        try:
            if next_stage == 0:
                bar = self._bar(sw.duration_s)
                self._run_stage(0, next_chunk, writer, bar)
                next_stage, next_chunk = 1, 0
                if bar is not None:
                    bar.close()
                    bar = None
                self._modal_stage()
                self._checkpoint(1, 0)
            self._install_schedule()
            if len(self.plans) > 1 and next_stage < len(self.plans):
                if case.self_weight_scheme() != case.vibration_scheme():
                    model.problem.set_scheme(case.vibration_scheme())
                bar = self._bar(self.plans[-1].end_s - model.problem.t)
                for index in range(next_stage, len(self.plans)):
                    self._run_stage(index, next_chunk if index == next_stage else 0, writer, bar)
                    self._checkpoint(index + 1, 0)  # after the last: the installed state
        except _Stopped:
            return {}
        finally:
            writer.close()
            if bar is not None:
                bar.close()
        summary = report.summary(self.stages, model.contact, self.history)
        report.write_summary(
            summary, self.stages, self.excitations, self.output / "summary.txt", comm
        )
        if case.output.plots:
            plots.plot_history(self.history, self.stages, self.output, comm)
        self.log(report.format_summary(summary, self.stages, self.excitations))
        return summary

    def _bar(self, total: float):
        if not self.progress or total <= 0:
            return None
        from tqdm import tqdm

        return tqdm(
            total=total,
            unit="s",
            bar_format="{l_bar}{bar}| {n:.4g}/{total:.4g} s simulated {postfix}",
        )


def _write_line(text: str) -> None:
    """Print a line of the run's log without breaking an active progress bar (rank 0)."""
    from tqdm import tqdm

    tqdm.write(text)
    sys.stdout.flush()


class _Stopped(Exception):
    """Raised after ``stop_after_checkpoints`` checkpoints (simulated kill)."""
