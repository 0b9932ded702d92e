"""Python callables called by the library (the nonlinear filter steps): :class:`_Callback`
keeps their exceptions from crossing into C and re-raises them after the call."""

from __future__ import annotations

from typing import Callable, Optional

from .errors import BinghamError, Status, last_error_message


class _Callback:
    """Runs a Python callable for the library without letting an exception cross into C.

    The first exception raised by the callable (or by checking its result) is stored and the
    callback returns 1 (failure); the library then stops and returns ``BINGHAM_ERR_CALLBACK``
    with the filter unchanged, and :meth:`check` raises :class:`BinghamError` from the stored
    exception (``KeyboardInterrupt`` and other non-``Exception`` exceptions are re-raised as
    they are).
    """

    def __init__(self) -> None:
        self.error: Optional[BaseException] = None

    def run(self, body: Callable[[], None]) -> int:
        if self.error is not None:  # the library stops at the first failure; be safe anyway
            return 1
        try:
            body()
        except BaseException as e:  # nothing may unwind into C
            self.error = e
            return 1
        return 0

    def check(self, status: int) -> None:
        err = self.error
        if err is not None and not isinstance(err, Exception):
            raise err
        if status != Status.OK:
            exc = BinghamError(status, last_error_message())
            if err is not None:
                raise exc from err
            raise exc
