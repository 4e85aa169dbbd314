"""The one import root: the repository's top-level folders become subpackages of ``agrobot``.

``agrobot/__init__.py`` lives in ``src/agrobot``; ``components/`` installs as ``agrobot.components``,
``orchestrator/`` as ``agrobot.orchestrator`` and so on (``package_dir``), so the repository keeps
the layout its design names while a user's site-packages gains one name. Everything else is in
pyproject.toml.
"""
from setuptools import find_packages, setup

FOLDERS = ["orchestrator", "components", "measurements", "analysis", "identification", "diagnosis", "fmu_export",
           "fields", "studies"]

packages = ["agrobot"]
package_dir = {"agrobot": "src/agrobot"}
for folder in FOLDERS:
    package_dir[f"agrobot.{folder}"] = folder
    packages += [f"agrobot.{folder}"] + [f"agrobot.{folder}.{sub}" for sub in find_packages(folder)]

setup(packages=packages, package_dir=package_dir)
