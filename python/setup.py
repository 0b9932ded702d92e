"""Build configuration that pyproject.toml cannot express: the Rust library as a ctypes-loaded
shared library inside the package, and the version read from the crate's Cargo.toml."""

import os
import sys

from setuptools import setup
from setuptools_rust import Binding, RustExtension, Strip

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

setup(
    version=VERSION,
    rust_extensions=[
        # The crate's cdylib, without Python bindings (Binding.NoBinding): cargo builds it in
        # release mode and setuptools-rust puts it at bingham/_lib/libbingham.abi3.so, where
        # bingham/_library.py loads it with ctypes.
        RustExtension(
            "bingham._lib.libbingham",
            path=CARGO_TOML,
            binding=Binding.NoBinding,
            strip=Strip.Debug,  # the release profile keeps line tables (debug = 1) for profiling
        )
    ],
    # The library does not use the Python C API: one wheel serves every CPython >= 3.9
    # (tag cp39-abi3-<platform>; a platform wheel, since it holds native code).
    options={"bdist_wheel": {"py_limited_api": "cp39"}},
)
