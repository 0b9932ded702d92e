"""The lifecycle shared by the classes that own a library handle (:class:`Filter`,
:class:`SpinFilter`, :class:`Ahrs`): the checked handle, an idempotent :meth:`close`, release on
garbage collection, and the ``with`` block."""

from __future__ import annotations

import ctypes
from typing import ClassVar, Optional, TypeVar

from ._library import lib

_T = TypeVar("_T", bound="_Handle")


class _Handle:
    #: The C function that releases the handle (``bingham_..._free``).
    _free: ClassVar[str]
    #: What the object is called in messages ("the filter has been closed").
    _what: ClassVar[str]

    _handle: Optional[ctypes.c_void_p]

    def _h(self) -> ctypes.c_void_p:
        if self._handle is None:
            raise ValueError(f"the {self._what} has been closed")
        return self._handle

    def close(self) -> None:
        """Releases the handle (idempotent)."""
        if getattr(self, "_handle", None) is not None:
            getattr(lib(), self._free)(self._handle)
            self._handle = None

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # interpreter shutdown: the library may be gone already
            pass

    def __enter__(self: _T) -> _T:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
