"""Shared base of the slip-joint code: the DOLFINx stack's loading order (``common.backend``),
case files (``common.case``) and the elastic material (``common.material``).

Imported by ``geometry`` and ``solver``; imports neither.
"""
