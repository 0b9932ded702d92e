"""Build configuration that pyproject.toml cannot express: the Rust library as a ctypes-loaded
shared library inside the package, and the version read from the crate's Cargo.toml."""

import os
import shutil
import subprocess
import sys

from setuptools import Distribution, setup
from setuptools.command.build_py import build_py

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

# setuptools runs this file with python/ as the working directory; the crate is its parent.
CARGO_TOML = os.path.join("..", "Cargo.toml")
if not os.path.isfile(CARGO_TOML):
    sys.exit(
        "bingham: ../Cargo.toml not found -- build the Python package from a checkout of the "
        "repository (`pip install ./python`), not from a copy of python/ alone"
    )

with open(CARGO_TOML, "rb") as f:
    VERSION = tomllib.load(f)["package"]["version"]

# `make venv` (and anyone who has built the crate already) sets BINGHAM_PREBUILT_LIB to the
# libbingham.so cargo made: the package ships that file instead of compiling the crate a second
# time with another crate-type configuration (which also made cargo rebuild the C library on
# its next run). Without it, setuptools-rust builds the crate as before.
PREBUILT = os.environ.get("BINGHAM_PREBUILT_LIB", "")
LIB_NAME = "libbingham.abi3.so"


class BinaryDistribution(Distribution):
    """A distribution with native code (a platform wheel) though it has no extension modules."""

    def has_ext_modules(self) -> bool:
        return True


class BuildPyWithLibrary(build_py):
    """build_py that also copies the prebuilt shared library to bingham/_lib/."""

    def run(self) -> None:
        super().run()
        target = os.path.join(self.build_lib, "bingham", "_lib")
        os.makedirs(target, exist_ok=True)
        dest = os.path.join(target, LIB_NAME)
        self.copy_file(PREBUILT, dest)
        # as setuptools-rust's Strip.Debug: the release profile keeps line tables (debug = 1)
        strip = shutil.which("strip")
        if strip:
            subprocess.run([strip, "--strip-debug", dest], check=True)


if PREBUILT:
    if not os.path.isfile(PREBUILT):
        sys.exit(f"bingham: BINGHAM_PREBUILT_LIB={PREBUILT} is not a file")
    extra = {"distclass": BinaryDistribution, "cmdclass": {"build_py": BuildPyWithLibrary}}
else:
    from setuptools_rust import Binding, RustExtension, Strip

    extra = {
        "rust_extensions": [
            # The crate's cdylib, without Python bindings (Binding.NoBinding): cargo builds it
            # in release mode and setuptools-rust puts it at bingham/_lib/libbingham.abi3.so,
            # where bingham/_library.py loads it with ctypes.
            RustExtension(
                "bingham._lib.libbingham",
                path=CARGO_TOML,
                binding=Binding.NoBinding,
                strip=Strip.Debug,  # the release profile keeps line tables (debug = 1)
            )
        ]
    }

setup(
    version=VERSION,
    # The library does not use the Python C API: one wheel serves every CPython >= 3.9
    # (tag cp39-abi3-<platform>; a platform wheel, since it holds native code).
    options={"bdist_wheel": {"py_limited_api": "cp39"}},
    **extra,
)
