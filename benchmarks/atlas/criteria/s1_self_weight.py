"""S1: the self-weight ramp on two axial mesh sizes (docs/physics.md §5.1)."""

from benchmarks.atlas import figures
from benchmarks.atlas.context import Context, Scenario, events_text
from benchmarks.atlas.outcome import Outcome, Row, verdict

__all__ = ["SCENARIO"]

MESH_AGREEMENT = 0.05  #: S1: settlement of the two meshes within this fraction [-]


def s1_self_weight(ctx: Context) -> Outcome:
    """S1: the self-weight ramp on the case's mesh and on one with half its axial size."""
    axial = ctx.case().mesh.axial_size
    labels = (f"{1e3 * axial:g} mm", f"{0.5e3 * axial:g} mm")
    runs = {
        labels[0]: ctx.reference(),
        labels[1]: ctx.self_weight("half_axial", [f"mesh.axial_size={0.5 * axial}"]),
    }
    rows = [
        Row(
            f"stick-slip steps under the ramp, {label} mesh (at least 2 events, §5.1)",
            f"{events_text(r)}; settlement {r['settlement_mm'][-1]:.4f} mm",
            verdict(len(r["events_mm"]) >= 2),
        )
        for label, r in runs.items()
    ]
    s = [r["settlement_mm"][-1] for r in runs.values()]
    rows.append(
        Row(
            f"settlement of the two meshes within {100 * MESH_AGREEMENT:g} %",
            f"{s[0]:.4f} mm against {s[1]:.4f} mm ({100 * (s[1] / s[0] - 1):+.2f} %)",
            verdict(abs(s[1] / s[0] - 1) < MESH_AGREEMENT),
        )
    )
    path, name = ctx.figure("S1", "settlement.png")
    if ctx.comm.rank == 0:
        figures.plot_settlement(runs, path, "S1: self-weight ramp, two axial mesh sizes")
    return ctx.outcome(SCENARIO, rows, runs, [name, "../runs/reference/contact_status.png"])


SCENARIO = Scenario(
    "S1",
    "self-weight ramp, two axial mesh sizes",
    "stick-slip steps (count and size of the events); settlement of both meshes; the same "
    "qualitative behaviour",
    s1_self_weight,
)
