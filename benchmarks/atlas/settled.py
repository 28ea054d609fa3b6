"""The joint settled by its self-weight stage, with the frequency choice of the installation
run (``solver.installation.frequencies``): the state most scenarios of the atlas branch from."""

from dataclasses import dataclass

import numpy as np
from mpi4py import MPI

from common.case import read_case
from solver.installation.case import InstallationCase
from solver.installation.frequencies import Excitation, choose_frequencies
from solver.installation.model import JointModel, set_up_joint_model, settled_modes
from solver.modal.ranking import JointParts, describe_modes

__all__ = ["SettledJoint", "choose", "settle"]


@dataclass
class SettledJoint:
    """The joint after its self-weight stage, its natural frequencies [Hz] and the frequencies
    chosen from its modes."""

    model: JointModel
    frequencies_hz: np.ndarray  #: natural frequencies of the settled joint [Hz]
    chosen: list[Excitation]  #: the installation run's frequency choice


def settle(comm: MPI.Comm, overrides: list[str], case_name: str) -> SettledJoint:
    """Build the joint of the case (a preset name or a TOML file) with ``overrides``, run its
    self-weight stage as the installation run does (its step, event steps and cut steps) and
    choose the frequencies as it does (collective)."""
    case = InstallationCase.from_dict(read_case(case_name, overrides))
    model = set_up_joint_model(comm, case)
    model.run_self_weight()
    return choose(model)


def choose(model: JointModel) -> SettledJoint:
    """The modes of the joint in its present state (``vibration.n_modes``) and the frequencies
    chosen from them as the installation run does (collective)."""
    case = model.case
    result, _ = settled_modes(model, case.vibration.n_modes)
    parts = JointParts.for_joint(model.V, model.mesh_data, model.placed)
    records = describe_modes(
        result,
        case.material,
        parts,
        zeta=case.damping.zeta,
        m_max=min(12, (2 * case.mesh.n_circumferential - 1) // 2),
    )
    return SettledJoint(model, result.frequencies_hz, choose_frequencies(records, case.vibration))
