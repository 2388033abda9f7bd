"""The numerical laws of the in-house solver, each written once for both backends.

Every law here is a plain function on numbers and arrays, compiled with numba (``study.kernels``) for the compiled
loop and called (compiled, or through the same source) by the reference loop. Neither ``study.solver`` (the
reference path) nor ``study.fast`` (the compiled path) defines a law of its own; both import them from here.

The homes, one module per law:

- ``events``: event location, the first crossing of a switching function within a step (a scan, then Brent's method)
- ``modes``: the mode switch, the mode at t0 and after a located crossing (at most ``MAX_EVENTS`` per run)
(filled in as each law moves here)
"""
