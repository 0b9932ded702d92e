"""Status codes and errors: :class:`Status`, :class:`BinghamError`, the library's messages
(:func:`status_str`, :func:`last_error_message`) and the check that turns a status other than
``BINGHAM_OK`` into a :class:`BinghamError`."""

from __future__ import annotations

import ctypes
import enum
from typing import Union

from ._library import _SIZE, lib

__all__ = ["Status", "BinghamError", "status_str", "last_error_message"]


class Status(enum.IntEnum):
    """The values of ``bingham_status`` (stable; new codes are only appended)."""

    OK = 0
    ERR_NULL_ARGUMENT = 1
    ERR_INVALID_DIMENSION = 2
    ERR_INVALID_ARGUMENT = 3
    ERR_NOT_CONVERGED = 4
    ERR_NUMERICAL = 5
    ERR_PANIC = 6
    ERR_CALLBACK = 7


class BinghamError(Exception):
    """A call returned a status other than ``BINGHAM_OK``.

    Attributes: ``status`` (int, a :class:`Status` value when known), ``status_name`` (the
    library's ``bingham_status_str``) and ``message`` (the library's last error message).
    """

    def __init__(self, status: int, message: str) -> None:
        self.status: Union[Status, int] = Status(status) if status in Status._value2member_map_ else status
        self.status_name = status_str(status)
        self.message = message
        super().__init__(f"{self.status_name} ({int(status)}): {message}")


def _check(status: int) -> None:
    if status != Status.OK:
        raise BinghamError(status, last_error_message())


def status_str(status: int) -> str:
    """The library's static description of a status code (any int)."""
    return str(lib().bingham_status_str(int(status)).decode())


def last_error_message() -> str:
    """This thread's last error message ('' if no call failed yet)."""
    n = _SIZE(0)
    _check_raw(lib().bingham_last_error_message(None, 0, ctypes.byref(n)))
    buf = ctypes.create_string_buffer(n.value + 1)
    _check_raw(lib().bingham_last_error_message(buf, len(buf), ctypes.byref(n)))
    return buf.value.decode("utf-8", errors="replace")


def _check_raw(status: int) -> None:
    if status != Status.OK:  # only possible on misuse; do not recurse into last_error_message
        raise BinghamError(status, "bingham_last_error_message failed")
