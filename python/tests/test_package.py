"""The installed package: its version is the crate's and the bundled library's, the library is
the one shipped inside the package, and the public API is typed and documented."""

import inspect
import os
import re

import numpy as np
import pytest

import bingham as bh

REPO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")


def crate_version():
    with open(os.path.join(REPO, "Cargo.toml"), encoding="utf-8") as f:
        return re.search(r'^version\s*=\s*"([^"]+)"', f.read(), re.M).group(1)


def test_version_is_the_crates_and_the_librarys():
    assert bh.__version__ == crate_version()
    assert bh.__version__ == bh.version()


@pytest.mark.skipif("BINGHAM_LIB" in os.environ, reason="BINGHAM_LIB overrides the bundled library")
def test_the_bundled_library_is_loaded():
    package_dir = os.path.dirname(os.path.abspath(bh.__file__))
    path = bh.library_path()
    assert os.path.dirname(path) == os.path.join(package_dir, "_lib"), path
    assert os.path.basename(path).startswith("libbingham") and path.endswith(".so")
    # the installed package, not the source tree next to this file
    assert os.path.realpath(package_dir) != os.path.realpath(os.path.join(REPO, "python", "bingham"))


def test_py_typed_marker_is_installed():
    assert os.path.isfile(os.path.join(os.path.dirname(bh.__file__), "py.typed"))


def test_public_api_has_type_hints_and_docstrings():
    for name in bh.__all__:
        obj = getattr(bh, name)
        if inspect.isfunction(obj):
            members = [(name, obj)]
        elif inspect.isclass(obj) and obj.__module__.split(".")[0] == bh.__name__:  # or a submodule
            assert obj.__doc__, name
            members = [
                (f"{name}.{k}", v.__func__ if isinstance(v, classmethod) else v)
                for k, v in vars(obj).items()
                if not k.startswith("_") and isinstance(v, (classmethod, type(crate_version)))
            ]
        else:
            continue
        for qual, fn in members:
            assert fn.__doc__, f"{qual} has no docstring"
            sig = inspect.signature(fn)
            assert sig.return_annotation is not inspect.Signature.empty, f"{qual}: no return type"
            for p in sig.parameters.values():
                if p.name not in ("self", "cls"):
                    assert p.annotation is not inspect.Parameter.empty, f"{qual}({p.name}): no type"


def test_numpy_in_and_out():
    m, z = bh.noise_from_angle_std(4, 0.1)
    assert isinstance(m, np.ndarray) and m.dtype == np.float64 and m.shape == (4, 4)
    with bh.Filter(np.eye(4), [-1.0, -1.0, -1.0, 0.0]) as f:
        f.update(np.array([1.0, 0.0, 0.0, 0.0], dtype=np.float32), m, z)  # any float input
        q = f.mode()
    assert isinstance(q, np.ndarray) and q.dtype == np.float64 and q.shape == (4,)
    assert abs(q[0]) == pytest.approx(1.0, abs=1e-6)
    # Fortran-ordered and strided inputs are accepted (copied to C order)
    f2 = bh.Filter(np.asfortranarray(np.eye(4)[:, ::-1]), np.array([0.0, -1.0, 0.0, -1.0, 0.0, -1.0, 0.0, 0.0])[::2])
    assert f2.dim() == 4


def test_errors_carry_status_and_message():
    with pytest.raises(bh.BinghamError) as e:
        bh.noise_from_angle_std(3, 0.1)
    assert e.value.status == bh.Status.ERR_INVALID_DIMENSION
    assert e.value.message.startswith("bingham_noise_from_angle_std")
    assert e.value.status_name == "invalid dimension"


def test_a_library_of_another_minor_version_is_refused_before_1_0():
    # 0.x releases may change the layout of the structs passed by value (0.3 removed a field of
    # the AHRS parameters): the loader refuses a library whose major.minor differs
    from bingham._library import compatible
    assert compatible("0.3.0", "0.3.0") and compatible("0.3.2", "0.3.0")
    assert not compatible("0.2.0", "0.3.0") and not compatible("0.3.0", "0.2.1")
    assert compatible("1.2.0", "1.4.0") and not compatible("2.0.0", "1.4.0")
    assert compatible("unknown", "0.3.0") and compatible("0.3.0", "unknown")
    # the library in use is compatible with the package
    assert compatible(bh.version(), bh.__version__)
