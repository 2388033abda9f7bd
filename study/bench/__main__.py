"""``python -m study.bench``: the benchmark's command (:mod:`study.bench.command`)."""

from study.bench.command import main

raise SystemExit(main())
