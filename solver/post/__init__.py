"""Outputs of the runs: reports of an installation run (``report``)."""
