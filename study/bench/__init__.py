"""The benchmark (``python -m study bench``, ``make bench``): accuracy per CPU second of the
in-house solver, side by side with Exudyn, written to ``reports/benchmarks/*.csv``.

In one process on one machine it measures

(a) the cost of one acceleration evaluation, reference and compiled (:mod:`.evaluations`);
(b) CPU time to reach max |dq| <= 1e-4, 1e-6, 1e-8 against a high-accuracy reference for each
    in-house method and each Exudyn solver (:mod:`.sweeps`), and from those runs the cheapest run
    per level (:mod:`.accuracy`);
(c) two ratios at each accuracy, compiled in-house / tuned Exudyn and the reference in-house path /
    Exudyn with Python user functions (:mod:`.accuracy`);
(d) CPU time against simulated time and against output density, (e) peak memory (tracemalloc)
    against the output size (:mod:`.scaling`);
(f) the quick-return over 20 s to max |dq| <= 1e-8 (:mod:`.quick_return`);
(g) where the compiled loop's time goes (:mod:`.profile`);
(h) compiled / reference CPU at the same method and tolerance (the sweeps' pairs and the studies'
    sampled cases);

plus the one-off compile time (:mod:`.compile_time`). Every simulation run is a case of the
benchmark's own case list ``reference/cases/bench.toml`` (standalone: the pipeline's run, reproduce
and verify leave it out), run through the pipeline's store; :mod:`.summary` makes the work-precision
tables from the saved runs. Every benchmark target is judged from these
tables by :func:`study.bench.targets.evaluate_targets` into ``targets.csv``. The timing harness
(medians of repeats, the error measure) is :mod:`.harness`, every planning number :mod:`.settings`,
the command :mod:`.command`, the benchmark's own figure :mod:`.figure`.
"""
