"""ParaView files: VTX (.bp) series of displacement fields and VTK PolyData (.vtp) of the
contact points with their state.

VTX files are written collectively; the .vtp file by rank 0 from the gathered points.
"""

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from dolfinx import fem, io

from solver.contact import NitscheContact

__all__ = ["write_contact_points", "write_functions", "write_state"]


def write_functions(
    path: str | Path, functions: Sequence[fem.Function], times: Sequence[float], name: str
) -> Path:
    """The fields ``functions`` (of one space) as one VTX (.bp) series named ``name``, the k-th
    at "time" ``times[k]`` (e.g. mode shapes numbered 1, 2, ...)."""
    path = Path(path).with_suffix(".bp")
    V = functions[0].function_space
    shape = fem.Function(V, name=name)
    with io.VTXWriter(V.mesh.comm, path, [shape], engine="BP4") as writer:
        for u, t in zip(functions, times):
            shape.x.array[:] = u.x.array
            writer.write(float(t))
    return path


def write_state(u: fem.Function, t: float, contact: NitscheContact, folder: Path, k: int) -> None:
    """The displacement ``u`` [m] (VTX, "time" = the simulated time ``t`` [s]) and the contact
    points (.vtp) after stage k (collective)."""
    comm = u.function_space.mesh.comm
    with io.VTXWriter(comm, folder / f"displacement_{k}.bp", [u], engine="BP4") as writer:
        writer.write(t)
    write_contact_points(contact, folder / f"contact_{k}.vtp")


def write_contact_points(contact: NitscheContact, path) -> None:
    """Write the slave points with their state as VTK PolyData (.vtp) for ParaView (rank 0 writes).

    Point data: status (0 open, 1 stick, 2 slip), gap_m, pressure_Pa,
    tangential_traction_Pa (vector), slip_velocity_m_s (vector), at the deformed points.
    """
    comm = contact.V.mesh.comm
    st = contact.state
    fields = {
        "status": st.status.astype(np.int32),
        "gap_m": st.gap,
        "pressure_Pa": st.pressure,
        "tangential_traction_Pa": st.tangential_traction,
        "slip_velocity_m_s": st.slip_velocity,
    }
    points = comm.gather(st.coordinates, root=0)
    data = {name: comm.gather(a, root=0) for name, a in fields.items()}
    if comm.rank == 0:
        import pyvista

        cloud = pyvista.PolyData(np.concatenate(points))
        for name, parts in data.items():
            cloud.point_data[name] = np.concatenate(parts)
        cloud.save(str(path))
