"""Table, pictures and ParaView files of a modal analysis of the joint.

One ``ModeRecord`` per mode: frequency, (m, n) of each part and of the part that
dominates the kinetic energy, and the settlement indicators of
:mod:`solver.modal.indicators` for two ways of loading the TP top:

* "face": a force spread uniformly over the TP top face (as in the dynamics,
  ``solver.dynamics.loads.TopFaceLoad``); on a perfectly axisymmetric joint it excites
  only m = 0 (axial) and m = 1 (lateral) modes;
* "point": a force at one point of the TP top edge (mid-wall, theta = 0, as an
  eccentric motor or shaker fixed to one side), which excites every m.

Modes are ranked by the resonant interface slip under the eccentric-motor force
amplitude 0.3632 f^2 N (SPEC 3) applied at the point, axially or laterally (the
larger of the two), with modal damping ``zeta``: rank 1 is the most promising
excitation frequency. Members of a degenerate pair (equal frequencies, cos/sin
orientations) share the pair's combined indicator and rank.
"""

import csv
import os
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path

from common import backend  # noqa: F401  (before dolfinx)

import numpy as np
from dolfinx import fem, io, plot
from mpi4py import MPI

from common.material import Material
from solver.modal.eigen import ModalResult
from solver.dynamics.loads import PointLoad, TopFaceLoad, eccentric_amplitude, shaker_point
from solver.modal.indicators import InterfaceSampler, energy_shares, modal_force, resonant_slip
from solver.modal.classify import classify


@dataclass(frozen=True)
class ModeRecord:
    """Classification and settlement indicators of one mode (units in the names)."""

    mode: int
    frequency_Hz: float
    m: int
    n: int
    dominant_part: str
    m_MP: int
    n_MP: int
    m_TP: int
    n_TP: int
    kinetic_share_TP: float
    strain_share_TP: float
    participation_axial_face_per_sqrtkg: float
    participation_lateral_face_per_sqrtkg: float
    participation_axial_point_per_sqrtkg: float
    participation_lateral_point_per_sqrtkg: float
    interface_slip_rms_per_sqrtkg: float
    resonant_slip_axial_um: float
    resonant_slip_lateral_um: float
    rank: int


@dataclass(frozen=True)
class JointParts:
    """Cell tags of the two parts, the unit loads on the TP top and the interface sampler."""

    cell_tags: object  #: dolfinx MeshTags of the cells
    mp_tag: int
    tp_tag: int
    face: TopFaceLoad  #: unit forces spread over the TP top face
    point: PointLoad  #: unit forces at one point of the TP top edge
    interface: InterfaceSampler

    @classmethod
    def for_joint(cls, V: fem.FunctionSpace, mesh_data, joint) -> "JointParts":
        """Standard set-up on a mesh from ``geometry.mesh.create_joint_mesh`` (collective)."""
        from geometry import tags

        top = shaker_point(joint.tp, joint.tp_offset, joint.tp.total_length, 0.0)
        top[2] -= 1e-6 * joint.tp.total_length  # just inside the top face
        return cls(
            mesh_data.cell_tags,
            tags.MP_VOLUME,
            tags.TP_VOLUME,
            TopFaceLoad(V, mesh_data.facet_tags, tags.TP_TOP),
            PointLoad(V, top),
            InterfaceSampler.for_joint(V, joint),
        )


def degenerate_groups(frequencies_hz: np.ndarray, rtol: float = 1e-6) -> list[list[int]]:
    """Indices of consecutive (sorted) frequencies equal to ``rtol``, grouped."""
    groups: list[list[int]] = []
    for i, f in enumerate(frequencies_hz):
        if groups and abs(f - frequencies_hz[groups[-1][-1]]) <= rtol * f:
            groups[-1].append(i)
        else:
            groups.append([i])
    return groups


def describe_modes(
    result: ModalResult,
    material: Material,
    parts: JointParts,
    zeta: float = 0.01,
    n_stations: int = 24,
    m_max: int = 12,
) -> list[ModeRecord]:
    """Classify every mode and compute its indicators (collective)."""
    if not 0 < zeta < 1:
        raise ValueError(f"damping ratio zeta must lie in (0, 1), got {zeta}")
    mp_cells = parts.cell_tags.find(parts.mp_tag)
    tp_cells = parts.cell_tags.find(parts.tp_tag)
    rows = []
    for i, (f, u) in enumerate(zip(result.frequencies_hz, result.modes)):
        w_mp = classify(u, mp_cells, n_stations, m_max)
        w_tp = classify(u, tp_cells, n_stations, m_max)
        kinetic, strain = energy_shares(u, material, parts.cell_tags, [parts.mp_tag, parts.tp_tag])
        dominant, w = ("TP", w_tp) if kinetic[1] >= 0.5 else ("MP", w_mp)
        g = {
            f"{d}_{kind}": modal_force(u, load.vectors[c])
            for kind, load in (("face", parts.face), ("point", parts.point))
            for d, c in (("axial", 2), ("lateral", 0))
        }
        rows.append(
            dict(
                mode=i + 1,
                frequency_Hz=float(f),
                m=w.m,
                n=w.n,
                dominant_part=dominant,
                m_MP=w_mp.m,
                n_MP=w_mp.n,
                m_TP=w_tp.m,
                n_TP=w_tp.n,
                kinetic_share_TP=float(kinetic[1]),
                strain_share_TP=float(strain[1]),
                **{f"participation_{k}_per_sqrtkg": abs(v) for k, v in g.items()},
                interface_slip_rms_per_sqrtkg=parts.interface.rms_slip(u),
            )
        )
    # The orientation of a degenerate pair (cos/sin of the same m) is arbitrary: a force
    # excites the pair's combination, so resonant slips use the group's root-sum-square.
    for group in degenerate_groups(result.frequencies_hz):
        f = float(np.mean(result.frequencies_hz[group]))
        force = float(eccentric_amplitude(f))
        slip = float(
            np.sqrt(np.mean([rows[k]["interface_slip_rms_per_sqrtkg"] ** 2 for k in group]))
        )
        for d in ("axial", "lateral"):
            g = float(
                np.sqrt(sum(rows[k][f"participation_{d}_point_per_sqrtkg"] ** 2 for k in group))
            )
            for k in group:
                rows[k][f"resonant_slip_{d}_um"] = 1e6 * resonant_slip(g, slip, f, force, zeta)
    score = np.array(
        [max(r["resonant_slip_axial_um"], r["resonant_slip_lateral_um"]) for r in rows]
    )
    distinct = np.unique(np.round(-score, 12))
    rank = 1 + np.searchsorted(distinct, np.round(-score, 12))
    return [ModeRecord(**r, rank=int(k)) for r, k in zip(rows, rank)]


def write_csv(records: list[ModeRecord], path: str | Path, comm: MPI.Comm) -> None:
    """CSV with a header naming units (rank 0 writes)."""
    if comm.rank == 0 and records:
        with open(path, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(asdict(records[0])))
            writer.writeheader()
            for r in records:
                writer.writerow(
                    {k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in asdict(r).items()}
                )


def format_table(records: list[ModeRecord]) -> str:
    """Human-readable table of the records (participations in 1/sqrt(kg), slips in um)."""
    head = (
        f"{'mode':>4} {'f [Hz]':>9} {'m':>2} {'n':>2} {'part':>4} {'MP m,n':>7} {'TP m,n':>7} "
        f"{'KE_TP':>5} {'Gax_face':>8} {'Glat_face':>9} {'Gax_pt':>8} {'Glat_pt':>8} {'slip':>8} "
        f"{'s_ax[um]':>9} {'s_lat[um]':>9} {'rank':>4}"
    )
    lines = [head]
    for r in records:
        lines.append(
            f"{r.mode:4d} {r.frequency_Hz:9.2f} {r.m:2d} {r.n:2d} {r.dominant_part:>4} "
            f"{f'{r.m_MP},{r.n_MP}':>7} {f'{r.m_TP},{r.n_TP}':>7} {r.kinetic_share_TP:5.2f} "
            f"{r.participation_axial_face_per_sqrtkg:8.1e} "
            f"{r.participation_lateral_face_per_sqrtkg:9.1e} "
            f"{r.participation_axial_point_per_sqrtkg:8.1e} "
            f"{r.participation_lateral_point_per_sqrtkg:8.1e} "
            f"{r.interface_slip_rms_per_sqrtkg:8.1e} {r.resonant_slip_axial_um:9.3g} "
            f"{r.resonant_slip_lateral_um:9.3g} {r.rank:4d}"
        )
    return "\n".join(lines)


def write_paraview(result: ModalResult, path: str | Path) -> Path:
    """All mode shapes in one VTX (.bp) file; 'time' is the mode number (1, 2, ...)."""
    path = Path(path).with_suffix(".bp")
    shape = fem.Function(result.V, name="mode_shape")
    with io.VTXWriter(result.V.mesh.comm, path, [shape], engine="BP4") as writer:
        for i, u in enumerate(result.modes):
            shape.x.array[:] = u.x.array
            writer.write(float(i + 1))
    return path


def plot_modes(
    result: ModalResult,
    records: list[ModeRecord],
    path: str | Path,
    n_cols: int = 5,
    window: tuple[int, int] = (1600, 1000),
) -> None:
    """PNG grid of the deformed shapes, coloured by |u| and labelled f, m, n (rank 0 draws)."""
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    if not os.environ.get("DISPLAY"):  # headless: VTK would try X first and print a warning
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    V = result.V
    comm = V.mesh.comm
    topology, cell_types, x = plot.vtk_mesh(V)
    n_nodes = x.shape[0]
    pieces = comm.gather(
        (topology, cell_types, x, [u.x.array.reshape(-1, 3)[:n_nodes] for u in result.modes])
    )
    if comm.rank != 0:
        return
    import pyvista

    pyvista.OFF_SCREEN = True
    offset, topo, types, xs = 0, [], [], []
    shapes = [[] for _ in result.modes]
    for t, c, xx, us in pieces:
        # topology: [n, i0, ..., in-1, n, ...]; shift node indices by the offset
        t = t.copy().reshape(len(c), -1)
        t[:, 1:] += offset
        topo.append(t.ravel())
        types.append(c)
        xs.append(xx)
        for k, u in enumerate(us):
            shapes[k].append(u)
        offset += len(xx)
    grid = pyvista.UnstructuredGrid(np.concatenate(topo), np.concatenate(types), np.concatenate(xs))
    size = np.ptp(grid.points, axis=0).max()
    n_rows = int(np.ceil(len(records) / n_cols))
    plotter = pyvista.Plotter(
        shape=(n_rows, n_cols), off_screen=True, window_size=window, border=False
    )
    for k, r in enumerate(records):
        u = np.concatenate(shapes[k])
        grid.point_data["u"] = u
        grid.point_data["|u|"] = np.linalg.norm(u, axis=1)
        warped = grid.warp_by_vector("u", factor=0.1 * size / max(np.abs(u).max(), 1e-300))
        plotter.subplot(k // n_cols, k % n_cols)
        plotter.add_mesh(
            warped.extract_surface(algorithm="dataset_surface", nonlinear_subdivision=1),
            scalars="|u|",
            cmap="viridis",
            show_scalar_bar=False,
        )
        plotter.add_text(
            f"{r.mode}: {r.frequency_Hz:.1f} Hz  m={r.m} n={r.n} ({r.dominant_part})", font_size=8
        )
        plotter.view_isometric()
    plotter.screenshot(str(path))
    plotter.close()


def write_outputs(
    result: ModalResult,
    records: list[ModeRecord],
    folder: str | Path,
    names: Mapping[str, str] | None = None,
) -> dict[str, Path]:
    """CSV, PNG and VTX files of a modal analysis in ``folder``; returns their paths."""
    names = {"csv": "modes.csv", "png": "modes.png", "vtx": "modes.bp", **(names or {})}
    folder = Path(folder)
    comm = result.V.mesh.comm
    if comm.rank == 0:
        folder.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    paths = {k: folder / v for k, v in names.items()}
    write_csv(records, paths["csv"], comm)
    plot_modes(result, records, paths["png"])
    write_paraview(result, paths["vtx"])
    return paths
