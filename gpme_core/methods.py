"""The integrators of gpme_core.integrate.simulate, named once.

RK4       : classical Runge-Kutta, fixed step dt, compiled loop (gpme_core.kernels)
RadauIIA  : three-stage Radau IIA (order 5, implicit), fixed step dt, compiled loop
RK45, DOP853 : SciPy's explicit adaptive methods (their steps follow their error control;
               a given dt is their largest step)
Radau     : SciPy's implicit adaptive Radau
"""
RK4, RADAU_IIA, RK45, DOP853, RADAU = "RK4", "RadauIIA", "RK45", "DOP853", "Radau"
METHODS = (RK4, RADAU_IIA, RK45, DOP853, RADAU)
FIXED_STEP_METHODS = (RK4, RADAU_IIA)          # a step dt, compiled loops
EXPLICIT_ADAPTIVE_METHODS = (RK45, DOP853)     # SciPy; steps about the stability limit
IMPLICIT_METHODS = (RADAU,)                    # SciPy, with the Jacobian
