"""Time stepping of the linear structure with frictional contact (docs/dynamics.md).

==================  ==============================================================
``schemes``         Newmark / generalised-alpha / quasi-static: coefficients, updates
``elastodynamics``  Elastodynamics: state (u, v, a), the step u_n -> u_{n+1}, the time loop
``newton``          generalized Newton for A u + r_c(u) = b with reused LU factors
``condensation``    static condensation of the linear bulk away from the contact zone
``loads``           axial forces, harmonic schedules, unit loads on the TP
``damping``         Rayleigh and modal damping
==================  ==============================================================
"""
