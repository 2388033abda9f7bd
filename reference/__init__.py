"""The study's data: parameter files, case lists, tolerances and references (TOML), each with its provenance.

This folder is the package ``study._data`` (``pyproject.toml`` maps it; an installed wheel carries it as
``study/_data/``). Read it through :mod:`study.locations`, never by a path relative to the repository.
"""
