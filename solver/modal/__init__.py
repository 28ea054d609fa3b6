"""Modal analysis of the joint (docs/modal.md).

==============  ==================================================================
``eigen``       the eigen-solve K x = omega^2 M x (SLEPc), clamps, operators
``interface``   interface stiffness of the contact at a fixed status, bonded band
``classify``    (m, n) wave numbers of a mode shape
``indicators``  energy shares, participation, interface slip of a mode
``ranking``     ModeRecord per mode and the ranking by resonant interface slip
``outputs``     modes.csv, the printed table, mode pictures and ParaView files
``joint``       the installed joint's modes from a case's [modal] table
==============  ==================================================================
"""
