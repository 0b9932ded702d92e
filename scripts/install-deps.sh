#!/usr/bin/env bash
# Installs what `make test` needs, only when it is missing (Debian/Ubuntu; run as root or with
# sudo available): a C++ compiler, Eigen 3, pkg-config, binutils (readelf/nm), Python 3 with
# pip and venv (`make venv` installs the Python package, python/, into a virtual environment),
# NumPy + pytest for the Python package's tests, and vqf + ahrs (the peer filters of
# `make broad`, examples/python/broad.py).
set -euo pipefail

python=${PYTHON:-python3}
cxx=${CXX:-c++}
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"

missing=()
command -v "$cxx" >/dev/null 2>&1 || missing+=(g++)
[ -f /usr/include/eigen3/Eigen/Dense ] || [ -n "${EIGEN3_INCLUDE_DIR:-}" ] || missing+=(libeigen3-dev)
command -v pkg-config >/dev/null 2>&1 || missing+=(pkg-config)
command -v cmake >/dev/null 2>&1 || missing+=(cmake)  # install-test: the CMake package consumer
command -v readelf >/dev/null 2>&1 && command -v nm >/dev/null 2>&1 || missing+=(binutils)
command -v "$python" >/dev/null 2>&1 || missing+=(python3)
if ! "$python" -c 'import numpy, pytest, vqf, ahrs' >/dev/null 2>&1 && ! "$python" -m pip --version >/dev/null 2>&1; then
    missing+=(python3-pip)
fi
# `python3 -m venv` needs ensurepip, which Debian ships separately (python3-venv). A trial
# venv (about 10 s: it installs pip) is made only when ensurepip cannot be imported.
if command -v "$python" >/dev/null 2>&1; then
    if ! "$python" -c 'import ensurepip' >/dev/null 2>&1; then
        venv_probe=$(mktemp -d)
        "$python" -m venv "$venv_probe/v" >/dev/null 2>&1 || missing+=(python3-venv)
        rm -rf "$venv_probe"
    fi
else
    missing+=(python3-venv)
fi
if [ ${#missing[@]} -gt 0 ]; then
    echo "install-deps: installing ${missing[*]}"
    $sudo apt-get update
    $sudo apt-get install -y "${missing[@]}"
fi

if ! "$python" -c 'import numpy, pytest' >/dev/null 2>&1; then
    echo "install-deps: pip install numpy pytest"
    # a distribution's own Python may refuse plain `pip install` (PEP 668)
    "$python" -m pip install numpy pytest ||
        "$python" -m pip install --break-system-packages numpy pytest
fi

if ! "$python" -c 'import numpy, vqf, ahrs' >/dev/null 2>&1; then
    echo "install-deps: pip install numpy vqf ahrs"
    "$python" -m pip install numpy vqf ahrs ||
        "$python" -m pip install --break-system-packages numpy vqf ahrs
fi
