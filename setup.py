"""Package discovery; everything else is in pyproject.toml.

The repository's top level shows the data flow (``gateware/``, ``platforms/``, ``formal/``
beside the host package ``galvoscan/``); installed, they are subpackages of ``galvoscan`` so
nothing generic lands in site-packages. setuptools finds every package under each folder, so a
new subpackage can never be left out of the wheel (as ``galvoscan.correction`` once was).
"""

from setuptools import find_packages, setup


#: Installed package → the folder that holds it.
ROOTS = {
    "galvoscan": "galvoscan",
    "galvoscan.gateware": "gateware",
    "galvoscan.platforms": "platforms",
    "galvoscan.formal": "formal",
}

setup(
    package_dir=ROOTS,
    packages=[f"{package}.{sub}" if sub else package
              for package, folder in ROOTS.items()
              for sub in ["", *find_packages(folder)]],
)
