"""Status codes and errors: :class:`Status`, :class:`BinghamError`, the library's messages
(:func:`status_str`, :func:`last_error_message`) and the check that turns a status other than
``BINGHAM_OK`` into a :class:`BinghamError`, whose text names the Python function
(:data:`_PYTHON_NAMES`) where the library's message names the C one."""

from __future__ import annotations

import ctypes
import enum
import re
from typing import Dict, Optional, Union

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


# The Python name of each C function the package calls: the library's messages begin with the C
# function's name ("bingham_ahrs_update: ..."); BinghamError's text leads with the Python name.
_PYTHON_NAMES: Dict[str, str] = {
    "bingham_normalization_constant": "normalization_constant",
    "bingham_log_normalization_constant": "log_normalization_constant",
    "bingham_log_normalization_constant_saddlepoint": "log_normalization_constant_saddlepoint",
    "bingham_log_normalization_hessian": "log_normalization_hessian",
    "bingham_second_moment": "second_moment",
    "bingham_mle": "mle",
    "bingham_mle_samples": "mle_samples",
    "bingham_multiply": "multiply",
    "bingham_compose": "compose",
    "bingham_pdf": "pdf",
    "bingham_log_pdf": "log_pdf",
    "bingham_entropy": "entropy",
    "bingham_kl_divergence": "kl_divergence",
    "bingham_sample": "sample",
    "bingham_rotate_left": "rotate_left",
    "bingham_rotate_right": "rotate_right",
    "bingham_mode": "mode",
    "bingham_deterministic_sample_count": "deterministic_samples",
    "bingham_deterministic_samples": "deterministic_samples",
    "bingham_vector_observation": "vector_observation",
    "bingham_noise_from_angle_std": "noise_from_angle_std",
    "bingham_angular_spread": "angular_spread",
    "bingham_filter_new": "Filter",
    "bingham_filter_clone": "Filter.clone",
    "bingham_filter_dim": "Filter.dim",
    "bingham_filter_set_state": "Filter.set_state",
    "bingham_filter_get_state": "Filter.state",
    "bingham_filter_mode": "Filter.mode",
    "bingham_filter_predict": "Filter.predict",
    "bingham_filter_predict_rotation": "Filter.predict_rotation",
    "bingham_filter_update": "Filter.update",
    "bingham_filter_log_likelihood": "Filter.log_likelihood",
    "bingham_filter_surprise": "Filter.surprise",
    "bingham_filter_update_gated": "Filter.update_gated",
    "bingham_filter_update_vector": "Filter.update_vector",
    "bingham_filter_log_likelihood_vector": "Filter.log_likelihood_vector",
    "bingham_filter_predict_nonlinear": "Filter.predict_nonlinear",
    "bingham_filter_update_nonlinear": "Filter.update_nonlinear",
    "bingham_filter_predict_nonlinear_opts": "Filter.predict_nonlinear",
    "bingham_filter_update_nonlinear_opts": "Filter.update_nonlinear",
    "bingham_nonlinear_options_default": "Filter.update_nonlinear",
    "bingham_filter_angular_spread": "Filter.angular_spread",
    "bingham_filter_predict_world": "Filter.predict_world",
    "bingham_filter_update_world": "Filter.update_world",
    "bingham_filter_log_likelihood_world": "Filter.log_likelihood_world",
    "bingham_ahrs_params_default": "AhrsParams.default",
    "bingham_ahrs_params_from_rate": "AhrsParams.from_rate",
    "bingham_ahrs_new": "Ahrs",
    "bingham_ahrs_update": "Ahrs.update",
    "bingham_ahrs_update_dt": "Ahrs.update",
    "bingham_ahrs_update_batch_timed": "Ahrs.update_batch",
    "bingham_ahrs_smooth_ex": "smooth",
    "bingham_ahrs_update_batch": "Ahrs.update_batch",
    "bingham_ahrs_update_batch_spread": "Ahrs.update_batch",
    "bingham_ahrs_update_batch_health": "Ahrs.update_batch",
    "bingham_ahrs_health": "Ahrs.health",
    "bingham_ahrs_quaternion": "Ahrs.quaternion",
    "bingham_ahrs_state": "Ahrs.state",
    "bingham_ahrs_set_state": "Ahrs.set_state",
    "bingham_ahrs_angular_spread": "Ahrs.angular_spread",
    "bingham_ahrs_gyro_bias": "Ahrs.gyro_bias",
    "bingham_ahrs_gyro_bias_covariance": "Ahrs.gyro_bias_covariance",
    "bingham_ahrs_gyro_scale": "Ahrs.gyro_scale",
    "bingham_ahrs_orientation_covariance": "Ahrs.orientation_covariance",
    "bingham_ahrs_mag_latency_estimate": "Ahrs.mag_latency_estimate",
    "bingham_spin_filter_new": "SpinFilter",
    "bingham_spin_filter_clone": "SpinFilter.clone",
    "bingham_spin_filter_step": "SpinFilter.step",
    "bingham_spin_filter_log_likelihood": "SpinFilter.log_likelihood",
    "bingham_spin_filter_set_state": "SpinFilter.set_state",
    "bingham_spin_filter_get_state": "SpinFilter.state",
    "bingham_spin_filter_orientation_mode": "SpinFilter.orientation_mode",
    "bingham_spin_filter_spin_mode": "SpinFilter.spin_mode",
    "bingham_spin_filter_angular_spread": "SpinFilter.angular_spread",
}

_C_NAME = re.compile(r"(bingham_\w+): ")


class BinghamError(Exception):
    """A call returned a status other than ``BINGHAM_OK``.

    Attributes: ``status`` (int, a :class:`Status` value when known), ``status_name`` (the
    library's ``bingham_status_str``), ``message`` (the library's last error message, verbatim:
    it begins with the C function's name, e.g. ``"bingham_ahrs_update: ..."``) and
    ``function`` (the Python function or method that called it, e.g. ``"Ahrs.update"``, or
    ``None`` if unknown). ``str(error)`` leads with ``function``:
    ``"Ahrs.update: invalid argument (3): `gyr[0]` = NaN is not finite"``.
    """

    def __init__(self, status: int, message: str) -> None:
        self.status: Union[Status, int] = Status(status) if status in Status._value2member_map_ else status
        self.status_name = status_str(status)
        self.message = message
        c_name = _C_NAME.match(message)
        self.function: Optional[str] = _PYTHON_NAMES.get(c_name.group(1)) if c_name else None
        if c_name and self.function:
            text = f"{self.function}: {self.status_name} ({int(status)}): {message[c_name.end():]}"
        else:
            text = f"{self.status_name} ({int(status)}): {message}"
        super().__init__(text)


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
