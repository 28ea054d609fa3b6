"""Modal analysis of the installed joint: mesh, clamp, bonded band, eigenpairs.

Settings come from the ``[modal]`` table of a case file (all optional)::

    [modal]
    degree = 3           # Lagrange degree of the displacement
    n_circumferential = 24  # elements around for the modal mesh (0: use [mesh])
    n_modes = 20         # modes wanted: the n_modes nearest to target_hz
    target_hz = 0.0      # shift of the spectral transformation [Hz] (0: the lowest modes)
    band_height = 0.05   # bonded band at the TP lower edge [m]
    gamma0 = 100.0       # Nitsche parameter of the tie [-]
    zeta = 0.01          # modal damping ratio for the resonant indicators [-]
    clamped = ["MP_CLAMPED"]  # facet groups held fixed: MP_CLAMPED and/or TP_TOP; [] = free
"""

import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

from common import backend  # noqa: F401  (before dolfinx)

from dolfinx import fem
from mpi4py import MPI

from common.case import construct
from common.material import Material
from geometry import tags
from geometry.mesh import create_joint_mesh
from geometry.parameters import JointGeometry, MeshOptions, geometry_from_tables
from solver.modal.eigen import EigenOptions, ModalResult, clamp, modal_analysis
from solver.modal.interface import ContactInterface, bonded_band


CLAMPABLE = ("MP_CLAMPED", "TP_TOP")  #: end conditions: facet groups that may be clamped


@dataclass(frozen=True)
class ModalSettings:
    """Discretisation and coupling of the joint's modal analysis (SI units)."""

    degree: int = 3  #: chosen from the convergence table in docs/modal.md
    n_circumferential: int = 24  #: elements around for the modal mesh; 0: the [mesh] value
    n_modes: int = 20
    target_hz: float = 0.0  #: [Hz]
    band_height: float = 0.05  #: [m]
    gamma0: float = 100.0  #: [-]
    zeta: float = 0.01  #: [-]
    clamped: tuple[str, ...] = ("MP_CLAMPED",)  #: names in geometry.tags of clamped facet groups

    def __post_init__(self) -> None:
        if self.degree not in (1, 2, 3, 4):
            raise ValueError(f"degree must be 1..4, got {self.degree}")
        if not (isinstance(self.n_circumferential, int) and self.n_circumferential >= 0):
            raise ValueError(
                f"n_circumferential must be an integer >= 0, got {self.n_circumferential!r}"
            )
        if not (isinstance(self.n_modes, int) and self.n_modes >= 1):
            raise ValueError(f"n_modes must be an integer >= 1, got {self.n_modes!r}")
        if not self.band_height > 0:
            raise ValueError(f"band_height must be positive, got {self.band_height} m")
        if not self.gamma0 > 0:
            raise ValueError(f"gamma0 must be positive, got {self.gamma0}")
        if not self.target_hz >= 0:
            raise ValueError(f"target_hz must be >= 0 Hz, got {self.target_hz}")
        if not 0 < self.zeta < 1:
            raise ValueError(f"zeta must lie in (0, 1), got {self.zeta}")
        unknown = set(self.clamped) - set(CLAMPABLE)
        if unknown:
            raise ValueError(
                f"clamped: unknown facet group(s) {sorted(unknown)}; choose from {CLAMPABLE}"
            )

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "ModalSettings":
        data = dict(data)
        if "clamped" in data:
            data["clamped"] = tuple(data["clamped"])
        return construct(cls, data, "modal")


@dataclass
class JointCase:
    """Everything a joint modal analysis reads from a case (checked on construction)."""

    joint: JointGeometry
    material: Material
    mesh: MeshOptions
    modal: ModalSettings

    @classmethod
    def from_dict(cls, case: dict[str, Any]) -> "JointCase":
        """Check the tables; a ValueError names the case file and the problem."""
        try:
            return cls(*geometry_from_tables(case), ModalSettings.from_dict(case.get("modal", {})))
        except ValueError as e:
            raise ValueError(f"{case.get('_source', 'case')}: {e}") from None


@dataclass
class JointModes:
    """Result of :func:`joint_modes` and the objects needed to post-process it."""

    result: ModalResult
    mesh_data: Any
    interface: ContactInterface
    timings_s: dict[str, float]


def joint_modes(
    comm: MPI.Comm, case: JointCase, log: Callable[[str], None] = lambda s: None
) -> JointModes:
    """Lowest modes of the installed joint: by default MP bottom clamped and TP top free; the
    TP tied to the MP over ``band_height`` at its lower edge (collective). The mesh is [mesh]
    without its contact zone's fine axial elements (a bonded band needs no contact resolution),
    with [modal] n_circumferential around."""
    t0 = time.perf_counter()
    mesh_options = replace(case.mesh, contact_axial_size=0.0)
    if case.modal.n_circumferential:
        mesh_options = replace(mesh_options, n_circumferential=case.modal.n_circumferential)
    mesh_data = create_joint_mesh(comm, case.joint, mesh_options)
    V = fem.functionspace(mesh_data.mesh, ("Lagrange", case.modal.degree, (3,)))
    n_dofs = V.dofmap.index_map.size_global * V.dofmap.index_map_bs
    t1 = time.perf_counter()
    log(
        f"mesh: {mesh_options.n_circumferential} around, {mesh_options.axial_size} m axially, "
        f"degree {case.modal.degree}: {n_dofs} dofs ({t1 - t0:.1f} s)"
    )
    clamped = [tags.BY_NAME[name] for name in case.modal.clamped]
    bcs = [clamp(V, mesh_data.facet_tags, clamped)] if clamped else []
    interface = bonded_band(
        V, mesh_data.facet_tags, case.material, case.modal.band_height, case.modal.gamma0
    )
    t2 = time.perf_counter()
    log(
        f"bonded band {1e3 * case.modal.band_height:.0f} mm: "
        f"{100 * interface.tied_fraction():.1f} % of the "
        f"TP contact points tied ({t2 - t1:.1f} s)"
    )
    options = EigenOptions(n_modes=case.modal.n_modes, target_hz=case.modal.target_hz)
    result = modal_analysis(V, case.material, bcs, [interface], options)
    t3 = time.perf_counter()
    log(f"eigenproblem: {len(result.frequencies_hz)} modes ({t3 - t2:.1f} s)")
    return JointModes(
        result, mesh_data, interface, {"mesh": t1 - t0, "interface": t2 - t1, "eigen": t3 - t2}
    )
