"""S5: dismounting by a pull, alone and with vibration (docs/physics.md §5.5)."""

from typing import Any

import numpy as np

from benchmarks.atlas import figures
from benchmarks.atlas.context import Context, Scenario
from benchmarks.atlas.dismount import dismount_runs, lift_rate, released, separated
from benchmarks.atlas.outcome import Outcome, Row, verdict
from solver.dynamics.loads import eccentric_amplitude

__all__ = ["SCENARIO", "motors_rows", "release_word"]

PULL_FACTORS = (1.0, 1.25)  #: S5: pulls alone, multiples of the self-weight force
AMPLITUDE_N = 3600.0  #: S5: vibration amplitude (docs/physics.md §3) [N]


def _branch_state(b: dict[str, Any]) -> str:
    t, s, n = np.array(b["rows"]).T
    return (
        f"after {1e3 * (t[-1] - t[0]):.0f} ms the TP {s[0] - s[-1]:+.3f} mm up "
        f"({lift_rate(b['rows']):+.2f} mm/s over the second half), normal force "
        f"{1e-3 * n[-1]:.2f} kN"
    )


def release_word(b: dict[str, Any], settled_normal_N: float, slip_rate_mm_s: float) -> str:
    """How dismount branch ``b`` ends, in words: separated or released (by
    ``benchmarks.atlas.dismount.released``, from a state with the contact normal force
    ``settled_normal_N`` [N] and the event threshold ``slip_rate_mm_s`` [mm/s]), or it holds,
    lifting or not, and where it stands against its first-contact position."""
    rows = b["rows"]
    if separated(rows, settled_normal_N):
        return "separated"
    if released(rows, settled_normal_N, slip_rate_mm_s):
        return "released: above its first-contact position and lifting"
    place = "below" if rows[-1][1] >= 0.0 else "above"
    where = f"{abs(rows[-1][1]):.3f} mm {place} its first-contact position at the end"
    if lift_rate(rows) > slip_rate_mm_s:
        return f"holds, lifting, {where}"
    return f"holds, {where}"


def _dismount_rows(r: dict[str, Any], state: str, slip_rate_mm_s: float) -> list[Row]:
    """The S5 rows of the dismount runs ``r`` from ``state`` (words), with the case's event
    threshold ``slip_rate_mm_s`` [mm/s] (``release_word``)."""
    b, out = r["branches"], r["pull_out_N"]
    n0 = r["settled"]["normal_N"]
    settled = (
        f"{state} {r['settled']['settlement_mm']:.3f} mm, normal force "
        f"{1e-3 * r['settled']['normal_N']:.2f} kN, rigid Coulomb pull-out "
        f"{1e-3 * out['mu_d']:.2f} / {1e-3 * out['mu_s']:.2f} kN (mu_d / mu_s)"
    )
    pull = r["self_weight_N"] * PULL_FACTORS[0]
    first = b[f"pull {PULL_FACTORS[0]:g} x"]
    rows = [
        Row(
            f"{state}: pull alone at the self-weight force ({1e-3 * pull:g} kN) does not "
            "release (§5.5)",
            f"{_branch_state(first)}; {release_word(first, n0, slip_rate_mm_s)}; {settled}",
            verdict(not first["released"]),
        )
    ]
    for factor in PULL_FACTORS[1:]:
        branch = b[f"pull {factor:g} x"]
        rows.append(
            Row(
                f"{state}: pull alone at {factor:g} x the self-weight force "
                f"({1e-3 * factor * r['self_weight_N']:g} kN)",
                f"{_branch_state(branch)}; {release_word(branch, n0, slip_rate_mm_s)}",
                "measured",
            )
        )
    if "modal" not in b:  # the pull alone released the joint: no pulled state to vibrate
        rows.append(
            Row(
                f"{state}: pull + vibration: the best mode releases, the control does not",
                f"not run: the pull alone releases the joint (rigid pull-out with mu_s "
                f"{1e-3 * out['mu_s']:.2f} kN against the {1e-3 * pull:g} kN pull)",
                "not reproduced",
            )
        )
        return rows
    for name, wanted in (("modal", True), ("control", False)):
        branch = b[name]
        rows.append(
            Row(
                f"{state}: pull + {branch['amplitude_N'] / 1e3:g} kN at the "
                f"{'best mode' if wanted else 'control'} ({branch['frequency_Hz']:.2f} Hz, "
                f"driven at {branch['forcing_Hz']:.2f} Hz) "
                f"{'releases' if wanted else 'does not release'}",
                f"{_branch_state(branch)}; {release_word(branch, n0, slip_rate_mm_s)}",
                verdict(branch["released"] == wanted),
            )
        )
    lift = {k: b[k]["rows"][0][1] - b[k]["rows"][-1][1] for k in ("modal", "control")}
    rows.append(
        Row(
            f"{state}: pull + vibration lifts the TP more at the best mode than at the control",
            f"{lift['modal']:.3f} mm against {lift['control']:.3f} mm "
            f"({lift['modal'] / lift['control']:.1f} x)"
            if lift["control"] > 0
            else f"{lift['modal']:.3f} mm against {lift['control']:.3f} mm",
            "measured",
        )
    )
    rows.append(
        Row(
            f"{state}: resonance-selective release: the modal branch releases, the control "
            "does not",
            f"modal {release_word(b['modal'], n0, slip_rate_mm_s)}, control "
            f"{release_word(b['control'], n0, slip_rate_mm_s)}",
            verdict(b["modal"]["released"] and not b["control"]["released"]),
        )
    )
    return rows


def motors_rows(
    r: dict[str, Any], base: dict[str, Any], state: str, slip_rate_mm_s: float
) -> list[Row]:
    """S5 probe rows: the dismount runs ``r`` with the motors' force at the best mode, made where
    those at the atlas's amplitude (``base``) did not release; the peak upward force of both
    against the rigid Coulomb pull-out (``release_word`` with ``slip_rate_mm_s`` [mm/s])."""
    pull, out = base["self_weight_N"] * PULL_FACTORS[0], base["pull_out_N"]
    forces = (
        base["branches"]["modal"]["amplitude_N"],
        float(eccentric_amplitude(base["branches"]["modal"]["frequency_Hz"])),
    )
    peaks = "; ".join(f"pull + {f / 1e3:.2f} kN: peak {(pull + f) / 1e3:.2f} kN" for f in forces)
    rows = [
        Row(
            f"probe: {state}: the peak upward force of pull + vibration against the rigid "
            "Coulomb pull-out (a quasi-static pull above it releases)",
            f"{peaks}; pull-out {1e-3 * out['mu_d']:.2f} / {1e-3 * out['mu_s']:.2f} kN "
            "(mu_d / mu_s)",
            "measured",
        )
    ]
    b, n0 = r["branches"], r["settled"]["normal_N"]
    if "modal" not in b:  # the pull alone released the joint: no pulled state to vibrate
        return rows
    parts = [
        f"{name} ({b[name]['frequency_Hz']:.2f} Hz, driven at {b[name]['forcing_Hz']:.2f} Hz): "
        f"{_branch_state(b[name])}; {release_word(b[name], n0, slip_rate_mm_s)}"
        for name in ("modal", "control")
    ]
    rows.append(
        Row(
            f"probe: {state}: pull + the eccentric motors' force at the best mode, 0.3632 f^2 = "
            f"{forces[1] / 1e3:.2f} kN (the experiments' exciter, docs/physics.md §3), at the "
            "best mode and at the control with the same force: the modal branch releases, the "
            "control does not",
            "; ".join(parts),
            "measured",
        )
    )
    return rows


def _plot_dismount(ctx: Context, r: dict[str, Any], file: str, title: str) -> str:
    """Figure ``file`` of S5: settlement of every branch of the dismount runs ``r``."""
    path, name = ctx.figure("S5", file)

    def label(key: str, branch: dict[str, Any]) -> str:
        if key.startswith("pull"):
            return f"{key} the self-weight force alone"
        force, f = 1e-3 * branch["amplitude_N"], branch["frequency_Hz"]
        return f"pull + {force:.2f} kN, {key} ({f:.1f} Hz)"

    if ctx.comm.rank == 0:
        figures.plot_branches(
            {label(k, v): v["rows"] for k, v in r["branches"].items()}, path, title
        )
    return name


def s5_dismount(ctx: Context) -> Outcome:
    """S5: pulls alone at 1 and 1.25 times the self-weight force; the first pull plus vibration
    at the best mode and at the control frequency (``benchmarks.atlas.dismount``), each phase
    half as long as the case's vibration stages (0.05 s on the default joint): from the joint
    settled by self-weight and, where ``ctx.installed`` names an installation run of the case,
    from its last checkpoint."""
    half_stage = 0.5 * ctx.case().vibration.stage_duration_s
    runs = {
        "settled": dismount_runs(
            ctx.comm,
            ctx.case_name,
            ctx.overrides,
            ctx.output / "runs" / "dismount",
            PULL_FACTORS,
            AMPLITUDE_N,
            half_stage,
        )
    }
    slip_rate = ctx.case().output.slip_rate_mm_s
    rows = _dismount_rows(runs["settled"], "settled by self-weight", slip_rate)
    names = [
        _plot_dismount(ctx, runs["settled"], "dismount.png", "S5: dismount from the settled joint")
    ]
    if ctx.installed is not None:
        runs["installed"] = r = dismount_runs(
            ctx.comm,
            ctx.case_name,
            ctx.overrides,
            ctx.output / "runs" / "dismount_installed",
            PULL_FACTORS,
            AMPLITUDE_N,
            half_stage,
            ctx.installed,
        )
        state = f"installed (t = {r['settled']['time_s']:.2f} s)"
        rows += _dismount_rows(r, state, slip_rate)
        held = "modal" in r["branches"] and not r["branches"]["modal"]["released"]
        if held:  # the probe: the force of the experiments' exciter
            runs["installed, motors"] = motors = dismount_runs(
                ctx.comm,
                ctx.case_name,
                ctx.overrides,
                ctx.output / "runs" / "dismount_installed_motors",
                PULL_FACTORS[:1],
                None,
                half_stage,
                ctx.installed,
            )
            rows += motors_rows(motors, r, state, slip_rate)
            names.append(
                _plot_dismount(
                    ctx,
                    motors,
                    "dismount_motors.png",
                    "S5: dismount from the installed joint, the motors' force",
                )
            )
        names.append(
            _plot_dismount(
                ctx, r, "dismount_installed.png", "S5: dismount from the installed joint"
            )
        )
    return ctx.outcome(SCENARIO, rows, runs, names)


SCENARIO = Scenario(
    "S5",
    "dismount",
    "pull alone at 1 and 1.25 times the self-weight force; pull plus vibration at the best "
    "mode releases, at the control frequency it does not",
    s5_dismount,
)
