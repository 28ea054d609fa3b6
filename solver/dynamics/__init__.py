"""Time stepping of the linear structure with frictional contact (docs/dynamics.md).

======================  ==============================================================
``schemes``             Newmark / generalised-alpha / quasi-static: coefficients, updates
``elastodynamics``      Elastodynamics: state (u, v, a) and the step u_n -> u_{n+1}
``time_loop``           run: the time loop with step cutting, observers
``newton``              generalized Newton for A u + r_c(u) = b with reused LU factors
``point_newton``        Newton on the contact points' tractions, the linear zone in fixed factors
``compliance``          the contact compliance G = E A^-1 F^T W of the contact points
``traction_jacobian``   the inner Newton's linear solves: FGMRES with kept LU factors
``residual``            the residual of a contact step and its Dirichlet rows
``factor_store``        the LU factorisations of A + J_c kept per contact state
``linear_algebra``      LU solvers, the block-LU preconditioner, the operator A + J
``condensation``        static condensation of the linear bulk away from the contact zone
``loads``               axial forces, harmonic schedules, unit loads on the TP
``damping``             Rayleigh and modal damping
======================  ==============================================================
"""
