"""Table, pictures and ParaView files of a modal analysis of the joint: ``modes.csv``,
the printed table, ``modes.png`` (deformed shapes) and ``modes.bp`` (VTX, "time" = mode
number)."""

import os
from collections.abc import Mapping
from dataclasses import asdict
from pathlib import Path

import numpy as np
from dolfinx import plot
from mpi4py import MPI

from solver.modal.eigen import ModalResult
from solver.modal.ranking import ModeRecord
from solver.post.csv import write_csv as write_table
from solver.post.paraview import write_functions


def write_csv(records: list[ModeRecord], path: str | Path, comm: MPI.Comm) -> None:
    """``modes.csv``: one row per record, a header naming units, floats to 6 digits (rank 0
    writes; nothing without records)."""
    if records:
        rows = [asdict(r) for r in records]
        write_table(path, list(rows[0]), rows, comm, digits=6)


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
    return write_functions(path, result.modes, range(1, len(result.modes) + 1), "mode_shape")


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
