"""Where the study's data is, and where its commands write by default.

The data (parameter files, case lists, tolerances, verify rules, printed formulas, benchmark references) is the
package ``study._data``, found through :mod:`importlib.resources`:

- in the repository it is the top-level folder ``reference/`` (``pyproject.toml`` maps the package there, so the
  editable install of ``make`` reads the checkout's files, edits included);
- in an installed wheel it is the folder ``study/_data/`` inside the package (package data).

Output defaults follow the same distinction. A repository checkout (the data beside the package, as
``reference/`` beside ``study/``) writes into its own ``reports/``; an installed package writes into ``reports/``
under the current working directory, never into the installation.
"""

from __future__ import annotations

import importlib.resources
from pathlib import Path

#: The package that holds the study's data.
DATA_PACKAGE = "study._data"
PACKAGE_DIR = Path(__file__).resolve().parent


def _data_dir() -> Path:
    """The folder of :data:`DATA_PACKAGE` on disk; an error naming the cause when there is none."""
    try:
        root = importlib.resources.files(DATA_PACKAGE)
    except ModuleNotFoundError:
        raise ModuleNotFoundError(
            f"the study's data ({DATA_PACKAGE}) is not importable next to {PACKAGE_DIR}: a repository checkout must be "
            f"installed (make .venv/.installed, or pip install -e .), which maps {DATA_PACKAGE} to reference/; "
            f"an installed package carries it as study/_data/") from None
    if not isinstance(root, Path):
        raise ModuleNotFoundError(f"the study's data ({DATA_PACKAGE}) is not a folder on disk but {root!r} (the "
                                  f"package imported from an archive?); install the package with pip")
    return root.resolve()


#: The study's data folder: the repository's ``reference/``, or ``study/_data/`` of an installed package.
REFERENCE_DIR: Path = _data_dir()
#: The case lists of the studies (``reference/cases/*.toml``).
CASES_DIR: Path = REFERENCE_DIR / "cases"
#: The repository's root when this is a checkout (its data folder beside the package), else None.
CHECKOUT: Path | None = REFERENCE_DIR.parent if REFERENCE_DIR.parent == PACKAGE_DIR.parent else None
#: The default output folder: the checkout's ``reports/``; for an installed package ``reports/`` under the
#: working directory (relative, so it is the working directory when the command writes).
REPORTS_DIR: Path = CHECKOUT / "reports" if CHECKOUT is not None else Path("reports")
