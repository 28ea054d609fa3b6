"""The joint of an installation case, set up for time stepping: mesh, space, clamp, matrices,
contact, damping, loads and the time-stepping problem (:func:`set_up_joint_model`); the modes
of the settled joint (:func:`settled_modes`) and the vibration forcing
(:func:`attach_vibration`)."""

from __future__ import annotations

import gc
import time
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from dolfinx import fem
from dolfinx.mesh import MeshTags
from mpi4py import MPI
from petsc4py import PETSc

from geometry import tags
from geometry.contact_map import tp_placement
from geometry.mesh import create_joint_mesh
from solver.contact import NitscheContact, Status
from solver.dynamics.damping import ModalDamping, RayleighDamping
from solver.dynamics.elastodynamics import Elastodynamics, assemble_structure
from solver.dynamics.loads import PointLoad, Schedule, TopFaceLoad, TPLoading, shaker_point
from solver.dynamics.time_loop import EventSteps, Observer, run
from solver.installation.case import InstallationCase
from solver.installation.observers import Settlement
from solver.modal.eigen import EigenOptions, ModalResult, clamp, modal_analysis
from solver.modal.interface import ContactInterface, bonded_band


@dataclass(frozen=True)
class PlacedJoint:
    """The joint's parts with the TP's lower end at ``tp_offset`` [m] as meshed: at the first
    contact of the (imperfect) surfaces, ``geometry.contact_map.tp_placement``. Used where a
    position on the TP is needed (settlement probes, point forces, plots)."""

    mp: Any
    tp: Any
    tp_offset: float


@dataclass
class JointModel:
    """Mesh, space, clamp, matrices, contact, loads and the time-stepping problem of a case."""

    case: InstallationCase
    mesh_data: Any
    V: fem.FunctionSpace
    bcs: list
    contact: NitscheContact
    top: TopFaceLoad
    static: Callable[[float], float]  #: static axial force [N] against time [s]
    problem: Elastodynamics
    settlement: Settlement
    damping: RayleighDamping | ModalDamping
    placed: PlacedJoint
    timings_s: dict[str, float] = field(default_factory=dict)

    @property
    def comm(self) -> MPI.Comm:
        return self.V.mesh.comm

    @property
    def n_dofs(self) -> int:
        return self.V.dofmap.index_map.size_global * self.V.dofmap.index_map_bs

    def run_self_weight(
        self, t_end: float | None = None, observers: Sequence[Observer] = ()
    ) -> list[dict[str, float]]:
        """Integrate the self-weight stage from the problem's time to t_end [s] (None: the
        stage's end) with its step, the case's smallest cut step and, with ``[self_weight]
        event_dt_s``, steps of event_dt_s where the settlement rate exceeds ``event_rate_mm_s``
        (``solver.dynamics.time_loop.run``). At the
        stage's end the problem keeps one step size's operator."""
        case, sw = self.case, self.case.self_weight
        events = None
        if sw.event_dt_s:
            events = EventSteps(
                sw.event_dt_s,
                sw.event_rate_mm_s,
                lambda problem: self.settlement(problem)["settlement_mm"],
                calm_steps=sw.event_calm_steps,
            )
        rows = run(
            self.problem,
            sw.duration_s if t_end is None else t_end,
            sw.dt_s,
            dt_min=sw.dt_s * case.time.dt_min_fraction,
            observers=observers,
            progress=False,
            events=events,
        )
        if self.problem.t >= sw.duration_s * (1 - 1e-12):  # the event step's operator is done
            self.problem.keep_operators(1)
        return rows


def _lu_package(case: InstallationCase, comm: MPI.Comm) -> str:
    """The PETSc LU package of ``[contact] lu_solver`` ("auto": SuperLU_DIST, which repeats its
    arithmetic, on several ranks if PETSc has it and the self-weight stage takes no event steps,
    with which SuperLU_DIST crashes (``InstallationCase.from_dict``); MUMPS otherwise)."""
    choice = case.contact.lu_solver
    if choice != "auto":
        return choice
    several = comm.size > 1 and PETSc.Sys.hasExternalPackage("superlu_dist")
    return "superlu_dist" if several and not case.self_weight.event_dt_s else "mumps"


def _newton_options(case: InstallationCase, comm: MPI.Comm) -> dict[str, Any]:
    """The options of the case's contact solver ([contact])."""
    c = case.contact
    options = {
        "max_iterations": c.max_iterations,
        "rtol": c.newton_rtol,
        "lu_solver": _lu_package(case, comm),
    }
    if c.solver == "points":
        return options | {"candidate_gap": c.candidate_gap}
    return options | {
        "max_backtracks": c.max_backtracks,
        "max_gap_change": c.max_gap_change or None,
    }


#: each joint set up (weakly) with the communicator of its PETSc objects: ``free_dropped_joints``
_JOINTS: list[tuple[weakref.ref, PETSc.Comm]] = []


def free_dropped_joints() -> None:
    """Destroy the PETSc objects of the joints Python has dropped (collective on the ranks that
    set them up; call it where no joint is in the middle of a step).

    petsc4py hands a parallel PETSc object that Python drops to the garbage of the object's
    communicator, which only ``PETSc.garbage_cleanup`` on that communicator empties. A joint's
    objects live on its mesh's own duplicate of the communicator it was set up on, which a
    clean-up on that communicator does not reach: a process that sets up joint after joint
    (the atlas, the parameter study, the test suite) would keep every joint's matrices and
    factorisations to its end."""
    gc.collect()
    alive = []
    for joint, objects_comm in _JOINTS:
        PETSc.garbage_cleanup(objects_comm)
        if joint() is not None:
            alive.append((joint, objects_comm))
    _JOINTS[:] = alive


def joint_contact(
    V: fem.FunctionSpace, facet_tags: MeshTags | None, case: InstallationCase, theta: int
) -> NitscheContact:
    """The Nitsche frictional contact of ``case`` between its slave and master surfaces, with the
    Nitsche variant ``theta`` (1 symmetric, 0 skew-free, -1 skew-symmetric)."""
    c = case.contact
    return NitscheContact(
        V,
        facet_tags,
        tags.BY_NAME[c.slave],
        tags.BY_NAME[c.master],
        case.material,
        case.friction,
        gamma0=c.gamma0,
        theta=theta,
        quadrature_degree=c.quadrature_degree or None,
        lagged_friction=c.lagged_friction,
    )


def set_up_joint_model(comm: MPI.Comm, case: InstallationCase) -> JointModel:
    """Set up the joint of ``case`` at rest in its first-contact position (collective)."""
    t0 = time.perf_counter()
    deviations = case.deviations()
    placed = PlacedJoint(case.joint.mp, case.joint.tp, tp_placement(case.joint, deviations))
    mesh_data = create_joint_mesh(comm, case.joint, case.mesh, deviations)
    V = fem.functionspace(mesh_data.mesh, ("Lagrange", case.contact.degree, (3,)))
    bcs = [clamp(V, mesh_data.facet_tags, [tags.MP_CLAMPED])]
    M, K = assemble_structure(V, case.material, bcs)
    contact = joint_contact(V, mesh_data.facet_tags, case, case.contact.theta)
    d = case.damping
    if d.model == "rayleigh":
        damping = RayleighDamping.at_frequency(d.zeta, d.frequency_hz)
    else:
        band = bonded_band(
            V, mesh_data.facet_tags, case.material, d.band_height, case.contact.gamma0
        )
        modes = modal_analysis(V, case.material, bcs, [band], EigenOptions(n_modes=d.n_modes))
        damping = ModalDamping(
            M, [u.x.petsc_vec for u in modes.modes], modes.frequencies_hz, d.zeta
        )
        damping.check_step(case.self_weight.dt_s)  # explicit in time: fail before the time loop
    sw = case.self_weight
    static = case.static_force.history(sw)
    top = TopFaceLoad(V, mesh_data.facet_tags, tags.TP_TOP)
    problem = Elastodynamics(
        V,
        M,
        K,
        bcs,
        load=TPLoading(top, static_axial=static),
        scheme=case.self_weight_scheme(),
        damping=damping,
        contact=contact,
        newton_options=_newton_options(case, comm),
        condense_bulk=case.contact.condense_bulk,
        contact_solver=case.contact.solver,
        operators_kept=2 if sw.event_dt_s else 1,  # the nominal and the event step
    )
    problem.initialise(0.0)
    settlement = Settlement(problem.u, placed, mesh_data.cell_tags)
    model = JointModel(
        case,
        mesh_data,
        V,
        bcs,
        contact,
        top,
        static,
        problem,
        settlement,
        damping,
        placed,
        {"set-up": time.perf_counter() - t0},
    )
    if comm.size > 1:  # serial PETSc objects are destroyed as Python drops them
        _JOINTS.append((weakref.ref(model), M.getComm()))
    return model


def settled_modes(model: JointModel, n_modes: int) -> tuple[ModalResult, ContactInterface]:
    """The ``n_modes`` lowest modes of the joint in its current contact state (collective).

    Small vibrations about the settled, resting joint: every slave point in contact is tied
    normally and tangentially (STICK), the others are free. (A point that slipped in the
    last step is at rest now; tying only its normal motion would let the TP slide and rock
    on the thin contact band: spurious modes near 0 Hz.) The interface tangent is the
    symmetric Nitsche one (theta = 1) at the same pairing, as the eigenproblem needs.
    """
    contact = model.contact
    if contact.theta != 1:
        contact = joint_contact(model.V, model.mesh_data.facet_tags, model.case, theta=1)
        contact.update(model.problem.u)
    status = np.where(model.contact.state.status == Status.OPEN, Status.OPEN, Status.STICK)
    interface = ContactInterface(contact, status)
    result = modal_analysis(
        model.V, model.case.material, model.bcs, [interface], EigenOptions(n_modes=n_modes)
    )
    return result, interface


def attach_vibration(model: JointModel, schedule: Schedule) -> None:
    """Apply the harmonic ``schedule`` to the TP through the case's forcing ([vibration]):
    "face" spreads it over the TP top face, "eccentric" puts it at a point of the top edge,
    "shaker" at ``shaker_height_m`` above the TP's lower end (both at ``angle_deg``)."""
    vib = model.case.vibration
    loading: TPLoading = model.problem.load
    if vib.forcing == "face":
        loading.schedule = schedule
    else:
        j = model.placed
        if vib.forcing == "eccentric":
            point = shaker_point(j.tp, j.tp_offset, j.tp.total_length, vib.angle_deg)
            point[2] -= 1e-6 * j.tp.total_length  # just inside the top face
        else:
            point = shaker_point(j.tp, j.tp_offset, vib.shaker_height_m, vib.angle_deg)
        loading.shaker = (PointLoad(model.V, point), schedule)
    model.problem.refresh_load()
