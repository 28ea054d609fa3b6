"""The vibration-assisted installation run (docs/physics.md §3, 5; docs/install.md).

=================  ================================================================
``settings``       the [contact], [damping], [time], ... tables of a case
``case``           InstallationCase: a whole case, checked before computing
``model``          the joint set up for time stepping, settled modes, vibration forcing
``observers``      settlement of the TP, the contact-zone guard
``frequencies``    excitation frequencies chosen from the ranked modes
``runner``         Installation: the staged run with its outputs and checkpoints
``checkpoint``     checkpoint and resume of the time stepping
``dismount``       the dismount sequence and its table
``parameter_study``  one-at-a-time variants of a case
``cli``            the command line shared by the demos
=================  ================================================================
"""

from solver.installation.case import InstallationCase
from solver.installation.runner import Installation

__all__ = ["Installation", "InstallationCase"]
