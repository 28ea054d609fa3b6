"""The vibration-assisted installation run (SPEC 3, 5; docs/install.md): ``runner`` (case,
model, frequency choice and the staged run), ``checkpoint``, ``dismount``,
``parameter_study`` and ``cli``, the command line shared by the demos."""

from solver.installation.runner import Installation, InstallationCase

__all__ = ["Installation", "InstallationCase"]
