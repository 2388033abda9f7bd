"""The numerical laws of the in-house solver, each written once for both backends.

Every law here is a plain function on numbers and arrays: compiled with numba (``study.kernels``) for the compiled
loop and called (compiled, or through the same source) by the reference loop; or, for the run's bookkeeping between
segments (``events.crossing_finder`` built on a Python function, ``modes``: the mode at t0 and after a crossing),
plain Python that both loops call. Neither ``study.solver`` (the
reference path) nor ``study.fast`` (the compiled path) defines a law of its own; both import them from here.

The homes, one module per law:

friction
    The friction level (R + mu |N|, T0 + mu r |R|_delta, and the static limits), a pin's smooth reaction norm
    |R|_delta, the friction treatments' phases (stick flags and slip factors), and the exact treatment's switching
    functions of an entry (a stuck entry's margin limit - |f|, a sliding one's -direction v_t; then the direction).
contact
    The contact and pin solve: the normal-force sign hypotheses of the sliding contacts and their consistency rule
    (``CONSISTENCY_RTOL``), the choice of exactly one (else Painleve), and the Newton step of the pins' friction
    torques (``PIN_MAX_ITERATIONS``).
stabilization
    The stabilization biases b(Phi, Phidot) of none, Baumgarte and the sliding mode, with their parameter layouts.
projection
    The post-step projection: the minimum-norm or mass-weighted correction (truncated least squares) and the
    position and velocity iterations with their tolerance and iteration bound.
events
    Event location: the first crossing of a switching function within a step (a scan at ``SCAN_POINTS``, then
    Brent's method to ``BRENT_XTOL``/``BRENT_RTOL``).
modes
    The mode switch: the mode at t0 (signs, zeros settled by a look-ahead) and after a located crossing (the entry
    flipped or the rule's own switch; at most ``MAX_EVENTS`` per run).
"""
