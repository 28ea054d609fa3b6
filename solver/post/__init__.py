"""Outputs of the runs: the one CSV writer (``csv``), reports of an installation run
(``report``), pictures (``plots``) and ParaView files (``paraview``)."""
