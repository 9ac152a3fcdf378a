"""Map the repository's top-level folders under the ``trackreplay`` namespace.

``schemas/ recorder/ replay/ trackers/`` install as ``trackreplay.schemas`` … ``trackreplay.trackers``
and nothing else: bare ``trackers``, ``schemas``, ``replay`` and ``recorder`` are other projects'
names on PyPI. Every sub-package (a folder with ``__init__.py``) is found, so a new one needs no edit here.
"""

from setuptools import find_packages, setup

FOLDERS = ("schemas", "recorder", "replay", "trackers")

packages = ["trackreplay"]
for folder in FOLDERS:
    packages += [f"trackreplay.{folder}"] + [f"trackreplay.{folder}.{sub}" for sub in find_packages(folder)]

setup(
    packages=packages,
    package_dir={"trackreplay": "trackreplay", **{f"trackreplay.{folder}": folder for folder in FOLDERS}},
)
