"""What the wheel holds, which pyproject.toml cannot compute: the packages under study/ (found), and the study's data.

The data is the repository's top-level ``reference/`` folder, installed as the package ``study._data`` (its
sub-folders, e.g. ``cases/``, as its sub-packages) with every ``.toml`` file in it; an editable install maps
``study._data`` onto ``reference/`` itself. ``study/locations.py`` finds it through importlib.resources.
"""

from setuptools import find_namespace_packages, find_packages, setup

DATA, DATA_PACKAGE = "reference", "study._data"
data_packages = [DATA_PACKAGE] + [f"{DATA_PACKAGE}.{sub}"
                                 for sub in find_namespace_packages(DATA, exclude=["*__pycache__*"])]

setup(packages=find_packages(include=["study", "study.*"]) + data_packages,
      package_dir={DATA_PACKAGE: DATA},
      package_data={package: ["*.toml"] for package in data_packages})
