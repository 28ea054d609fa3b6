"""S4: which modes work, and the direction of the force (docs/physics.md §5.4)."""

from pathlib import Path

from benchmarks.atlas import figures
from benchmarks.atlas.context import Context, Scenario
from benchmarks.atlas.direction import direction_runs
from benchmarks.atlas.installed import installed_state, modal_table
from benchmarks.atlas.outcome import Outcome, Row, verdict
from solver.dynamics.loads import eccentric_amplitude
from solver.installation.frequencies import Excitation
from solver.post import report

__all__ = ["SCENARIO"]


def s4_modes(ctx: Context) -> Outcome:
    """S4 on the installation run ``ctx.installed``: the settlement rate over the second half of
    each of its modal stages (S2's, all at the modal amplitude) by the rank of the mode, whether
    the (m, n) = (2, 1) mode is the most effective (a probe: the modal stage's indicator of
    those modes, ``_resonant_slip_rows``), and from the installed state, at the lowest
    anti-symmetric mode, axial forcing against axial plus the case's lateral fraction
    (``benchmarks.atlas.direction``)."""
    if ctx.installed is None:
        raise ValueError("S4 reads an installation run: --installed RUN")
    case = ctx.case()
    amplitude = case.vibration.amplitude_N
    manifest = installed_state(ctx.comm, case, ctx.installed)
    excitations = [Excitation(**e) for e in manifest["excitations"]]
    modal = sorted(
        (
            (report.sustained_rate_mm_s(s), excitations[s["stage"] - 1])
            for s in manifest["stages"]
            if s["stage"] >= 1 and s["steps"] and excitations[s["stage"] - 1].role == "modal"
        ),
        key=lambda p: p[1].rank,
    )
    rows = []
    if modal:
        rows.append(
            Row(
                f"settlement rate over the second half per ranked mode at {amplitude / 1e3:g} kN "
                "(S2's stages, each from the state the one before left)",
                "; ".join(
                    f"rank {e.rank}, ({e.m}, {e.n}), {e.frequency_Hz:.2f} Hz: {rate:.3f} mm/s"
                    for rate, e in modal
                ),
                "measured",
            )
        )
        best_rate, best = max(modal, key=lambda p: p[0])
        measured = (
            f"the fastest: ({best.m}, {best.n}) at {best.frequency_Hz:.2f} Hz, {best_rate:.3f} mm/s"
        )
        m2n1 = [(rate, e) for rate, e in modal if (e.m, e.n) == (2, 1)]
        if m2n1 and (best.m, best.n) != (2, 1):
            rate, e = m2n1[0]
            ratio = f" ({rate / best_rate:.2f} x)" if best_rate > 0 else ""
            measured += f"; (2, 1) at {e.frequency_Hz:.2f} Hz {rate:.3f} mm/s{ratio}"
        elif not m2n1:
            measured += "; no (2, 1) stage in the run"
        rows.append(
            Row(
                "the most effective mode is (m, n) = (2, 1) (§5.4; stages in the order of S2)",
                measured,
                verdict((best.m, best.n) == (2, 1)),
            )
        )
        rows += _resonant_slip_rows(ctx.installed, modal, amplitude, case.vibration.direction)
    r = direction_runs(
        ctx.comm,
        ctx.case_name,
        ctx.overrides,
        ctx.output / "runs" / "direction_installed",
        ctx.installed,
        amplitude,
    )
    lateral = f"axial + {100 * r['lateral_fraction']:g} % lateral"
    names = []
    if r["mode"] is None:
        rows.append(
            Row(
                f"{lateral} settles more than axial alone at an anti-symmetric mode (§5.4)",
                "not run: the run has no m = 1 mode among the modes of its modal stage (or no "
                "modal stage)",
                "not reproduced",
            )
        )
    else:
        e = Excitation(**r["mode"])
        gain = {d: b[-1][1] - b[0][1] for d, b in r["branches"].items()}
        ratio = f" ({gain['both'] / gain['axial']:.2f} x)" if gain["axial"] > 0 else ""
        rows.append(
            Row(
                f"from the installed state (t = {r['request']['time_s']:.2f} s), at the lowest "
                f"anti-symmetric mode (m, n) = (1, {e.n}), {e.frequency_Hz:.2f} Hz (rank "
                f"{e.rank}, driven at {e.drive_Hz:.2f} Hz), {amplitude / 1e3:g} kN: {lateral} "
                "settles more than axial alone (§5.4)",
                f"{1e3 * gain['both']:.1f} um against {1e3 * gain['axial']:.1f} um{ratio} in "
                f"{1e3 * case.vibration.stage_duration_s:g} ms",
                verdict(gain["both"] > gain["axial"]),
            )
        )
        reversed_ratio = (
            f" ({gain['both reversed'] / gain['axial']:.2f} x)" if gain["axial"] > 0 else ""
        )
        rows.append(
            Row(
                "probe: the same with the lateral part reversed (the modal force of a lateral "
                "part adds to the axial part's or opposes it, by the orientation of the mode)",
                f"{1e3 * gain['both reversed']:.1f} um against {1e3 * gain['axial']:.1f} um"
                f"{reversed_ratio}",
                "measured",
            )
        )
        path, name = ctx.figure("S4", "direction.png")
        if ctx.comm.rank == 0:
            figures.plot_branches(
                {
                    "axial": r["branches"]["axial"],
                    lateral: r["branches"]["both"],
                    f"{lateral}, reversed": r["branches"]["both reversed"],
                },
                path,
                f"S4: the ({e.m}, {e.n}) mode at {e.frequency_Hz:.1f} Hz from the installed state",
            )
        names.append(name)
    return ctx.outcome(SCENARIO, rows, {"direction": r}, names)


def _resonant_slip_rows(
    run_folder: Path, modal: list[tuple[float, Excitation]], amplitude_N: float, direction: str
) -> list[Row]:
    """S4 probe: the linear indicator the modal stage ranks the modes by (the resonant interface
    slip, docs/modal.md, in its ``modes.csv`` for the motors' amplitude 0.3632 f^2 at the
    eccentric point; it scales with the force) for each modal stage's mode at the stages'
    amplitude ``amplitude_N`` [N] and at the motors' (none where the run kept no table)."""
    table = {int(r["mode"]): r for r in modal_table(run_folder)}
    part = "lateral" if direction == "lateral" else "axial"  # "both": its axial part
    column = f"resonant_slip_{part}_um"
    parts = []
    for _, e in modal:
        if e.mode in table:
            motors_N = float(eccentric_amplitude(e.frequency_Hz))
            slip = float(table[e.mode][column])
            parts.append(
                f"({e.m}, {e.n}) at {e.frequency_Hz:.2f} Hz: {slip * amplitude_N / motors_N:.1f} "
                f"um ({slip:.1f} um at {motors_N / 1e3:.2f} kN)"
            )
    if not parts:
        return []
    return [
        Row(
            f"probe: the modal stage's indicator for each mode, the linear resonant interface slip "
            f"(modal force / (2 zeta omega^2) x slip per unit modal amplitude, zeta the case's "
            "damping ratio), "
            f"{part} at the eccentric point, at {amplitude_N / 1e3:g} kN (and at the motors' "
            "0.3632 f^2)",
            "; ".join(parts),
            "measured",
        )
    ]


SCENARIO = Scenario(
    "S4",
    "which modes work",
    "settlement rate per ranked mode at equal force; axial against axial plus 5 % lateral "
    "at an anti-symmetric mode",
    s4_modes,
    installed=True,
)
