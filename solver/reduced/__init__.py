"""Reduced models (docs/lumped.md): shell-theory springs of the cones (``shell``), the
3/4-dof stick-slip model (``lumped``) and Sanders-Ritz frequencies of thin cylinders
(``cylinder_shell``)."""
