"""The numerical laws of the in-house solver, each written once for both backends.

Every law here is a plain function on numbers and arrays, compiled with numba (``study.kernels``) for the compiled
loop and called (compiled, or through the same source) by the reference loop. Neither ``study.solver`` (the
reference path) nor ``study.fast`` (the compiled path) defines a law of its own; both import them from here.

The homes, one module per law:

stabilization
    The stabilization biases b(Phi, Phidot) of none, Baumgarte and the sliding mode, with their parameter layouts.
projection
    The post-step projection: the minimum-norm or mass-weighted correction (truncated least squares) and the
    position and velocity iterations with their tolerance and iteration bound.
"""
