//! The AHRS behind the opaque handle `bingham_ahrs` (the C side of [`crate::ahrs::Ahrs`]).
//! Thin wrappers: check pointers, read the samples, call the core, copy results out.

use super::args::{args, get_into, Arg, Fill};
use super::guard::{free_handle, guard, handle, handle_mut, FfiResult};
use super::status::bingham_status;
use crate::ahrs::{Ahrs, AhrsHealth, AhrsParams};

/// The C name of [`AhrsParams`] (cbindgen renames the struct itself; this alias is for Rust
/// code calling the C functions).
/// cbindgen:ignore
#[allow(non_camel_case_types)]
pub type bingham_ahrs_params = AhrsParams;

/// The C name of [`AhrsHealth`].
/// cbindgen:ignore
#[allow(non_camel_case_types)]
pub type bingham_ahrs_health_report = AhrsHealth;

/// An attitude and heading reference system on the recursive Bingham filter: gyroscope
/// propagation, accelerometer and magnetometer as exact Bayes updates of a Bingham distribution
/// of the orientation, with gyroscope-bias estimation, linear-acceleration and
/// magnetic-disturbance rejection. Opaque: create it with `bingham_ahrs_new()`, release it with
/// `bingham_ahrs_free()`; the caller owns it.
///
/// Conventions: the orientation q = (w, x, y, z) (scalar first) maps the sensor frame to the
/// world frame ENU (x east, y magnetic north, z up): `v_world = q v_sensor q*`. Units: gyroscope
/// rad/s, accelerometer m/s² (specific force, +g up at rest), magnetometer any consistent unit.
///
/// The first sample initializes the state (tilt from the accelerometer, heading from the
/// magnetometer; without a magnetometer the heading stays uniform, honestly unknown, and
/// `bingham_ahrs_quaternion()` returns one of the equally likely orientations).
///
/// Thread safety: one thread at a time per handle (functions taking `const bingham_ahrs *` may
/// run concurrently with each other); different handles are independent. Memory: no heap
/// allocation per sample.
#[allow(non_camel_case_types)]
pub struct bingham_ahrs {
    inner: Ahrs,
}

/// Fills `p` with the default parameters for the sampling period `sample_time` (seconds: the
/// period, not the rate; 0.01 for 100 Hz). The defaults are the tuned set. For the rate in Hz use
/// `bingham_ahrs_params_from_rate()`.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`p`), `BINGHAM_ERR_INVALID_ARGUMENT` (`sample_time`
/// outside 1e-6..1 s (`BINGHAM_AHRS_MIN_SAMPLE_TIME`..`BINGHAM_AHRS_MAX_SAMPLE_TIME`) or not
/// finite; above 1 s the message asks "did you pass a rate in Hz?"). On error `*p` is not
/// written.
///
/// # Safety
/// `p`: a writable `bingham_ahrs_params`.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_params_default(
    sample_time: f64,
    p: *mut AhrsParams,
) -> bingham_status {
    guard("bingham_ahrs_params_default", || {
        // SAFETY: caller contract.
        let (p,) = unsafe { args!(p: out).read()? };
        let params = AhrsParams::new(sample_time);
        params.validate()?;
        // SAFETY: checked place.
        unsafe { p.set(params) };
        Ok(())
    })
}

/// Fills `p` with the default parameters for the sample rate `hz` (samples per second, Hz):
/// those of `bingham_ahrs_params_default(1.0 / hz, p)`. E.g. `bingham_ahrs_params_from_rate(100,
/// &p)` gives `p.sample_time = 0.01`.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`p`), `BINGHAM_ERR_INVALID_ARGUMENT` (`hz` not finite,
/// ≤ 0, below 1 Hz = 1 / `BINGHAM_AHRS_MAX_SAMPLE_TIME`, or above 1e6 Hz = 1 /
/// `BINGHAM_AHRS_MIN_SAMPLE_TIME`). On error `*p` is not written.
///
/// # Safety
/// `p`: a writable `bingham_ahrs_params`.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_params_from_rate(
    hz: f64,
    p: *mut AhrsParams,
) -> bingham_status {
    guard("bingham_ahrs_params_from_rate", || {
        // SAFETY: caller contract.
        let (p,) = unsafe { args!(p: out).read()? };
        let params = AhrsParams::from_rate(hz)?;
        // SAFETY: checked place.
        unsafe { p.set(params) };
        Ok(())
    })
}

/// Creates an AHRS with the parameters `p` (validated: every field finite, periods, noises,
/// thresholds and `bias_std` > 0, `bias_time` and `gyro_scale_noise` ≥ 0, `gyro_scale_std` in
/// 0..0.05, `sample_time` within
/// 1e-6..1 s (above 1 s the message asks "did you pass a rate in Hz?"), the process noise per
/// step `gyro_noise·sqrt(sample_time)` at least 1e-6 rad).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`p`, `out`), `BINGHAM_ERR_INVALID_ARGUMENT` (a bad
/// field; the message names it). On error `*out` is not written.
///
/// # Safety
/// `p`: a readable `bingham_ahrs_params`; `out`: a writable `bingham_ahrs *`.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_new(
    p: *const AhrsParams,
    out: *mut *mut bingham_ahrs,
) -> bingham_status {
    guard("bingham_ahrs_new", || {
        // SAFETY: caller contract.
        let params = unsafe { handle("p", p)? };
        // SAFETY: caller contract.
        let (out,) = unsafe { args!(out: out).read()? };
        let inner = Ahrs::new(params)?;
        // SAFETY: checked place, written last.
        unsafe { out.set_handle(bingham_ahrs { inner }) };
        Ok(())
    })
}

/// Releases an AHRS. `NULL` is a no-op. The handle must not be used afterwards.
///
/// # Safety
/// `a` must be `NULL` or a live handle from this library, not freed before and not in use by
/// another thread.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_free(a: *mut bingham_ahrs) {
    let _ = std::panic::catch_unwind(|| {
        // SAFETY: caller contract.
        unsafe { free_handle(a) }
    });
}

/// Creates an independent copy of an AHRS (state, bias, disturbance tracking).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`a`, `out`). On error `*out` is not written.
///
/// # Safety
/// `a`: a live handle; `out`: a writable `bingham_ahrs *`.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_clone(
    a: *const bingham_ahrs,
    out: *mut *mut bingham_ahrs,
) -> bingham_status {
    guard("bingham_ahrs_clone", || {
        // SAFETY: caller contract.
        let ahrs = unsafe { handle("a", a)? };
        // SAFETY: caller contract.
        let (out,) = unsafe { args!(out: out).read()? };
        let copy = bingham_ahrs {
            inner: ahrs.inner.clone(),
        };
        // SAFETY: checked place.
        unsafe { out.set_handle(copy) };
        Ok(())
    })
}

/// Processes one sample, taken `sample_time` (the parameters') after the previous one; with
/// its own time step: `bingham_ahrs_update_dt()`.
///
/// - `gyr`: angular rate, rad/s, sensor frame (3 doubles). A NaN or ±Inf entry means "no
///   gyroscope sample" at this time (a gap, not an error): the orientation is carried on with
///   the last rate, and what that cannot know widens the spread (`gyr_missing_time` of the
///   health readout counts the gap).
/// - `acc`: specific force, m/s², sensor frame (+g up at rest). A NaN or ±Inf entry means "no
///   accelerometer sample" at this time (not an error): the gyroscope and the magnetometer of
///   the sample are still used. Its update is also skipped (not an error) when
///   `|acc| < gravity/4` (free fall). The very first sample must have a finite accelerometer
///   showing gravity (`|acc| >= gravity/4`): it initializes the tilt.
/// - `mag`: magnetic field, any consistent unit (3 doubles), or `NULL` (6-D filter: no heading
///   information). A NaN or ±Inf entry means "no magnetometer sample" at this time, as `NULL`
///   (not an error). A zero field, a field along the vertical or a disturbed field is skipped.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`a`, `gyr`, `acc`), `BINGHAM_ERR_INVALID_ARGUMENT`
/// (a gyroscope sample turning by more than 1e6 rad in one sample: not a rate; a
/// first sample without a finite accelerometer showing gravity), `BINGHAM_ERR_NOT_CONVERGED`
/// / `BINGHAM_ERR_NUMERICAL` (internal). On error the AHRS is unchanged: the sample is
/// refused.
///
/// # Safety
/// `a`: a live handle; `gyr`, `acc`: 3 readable doubles each; `mag`: `NULL` or 3 readable
/// doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_update(
    a: *mut bingham_ahrs,
    gyr: *const f64,
    acc: *const f64,
    mag: *const f64,
) -> bingham_status {
    guard("bingham_ahrs_update", || {
        // SAFETY: forwarded caller contract.
        unsafe { one_sample(a, None, gyr, acc, mag) }
    })
}

/// Shared body of `bingham_ahrs_update` (`dt` `None`: the nominal period) and
/// `bingham_ahrs_update_dt`.
///
/// # Safety
/// The callers' contract.
unsafe fn one_sample(
    a: *mut bingham_ahrs,
    dt: Option<f64>,
    gyr: *const f64,
    acc: *const f64,
    mag: *const f64,
) -> FfiResult<()> {
    // SAFETY: caller contract.
    let ahrs = unsafe { handle_mut("a", a)? };
    // SAFETY: caller contract; 3 doubles each. NaN/Inf in any of them means "no sample" of that
    // sensor (the core decides).
    let (g, ac, m) = unsafe { args!(gyr: raw [3], acc: raw [3], mag: opt raw [3]).read()? };
    let m = m.map(vec3);
    match dt {
        None => ahrs.inner.update(&vec3(g), &vec3(ac), m.as_ref())?,
        Some(dt) => ahrs.inner.update_dt(dt, &vec3(g), &vec3(ac), m.as_ref())?,
    }
    Ok(())
}

/// Processes one sample taken `dt` seconds after the previous one (its own time step: jitter,
/// dropped packets, a variable rate), otherwise as `bingham_ahrs_update()`. The gyroscope's
/// turn, the process noise, the bias's random walk and the filters' time constants use `dt`;
/// a gyroscope sample is taken to cover one `sample_time`, and a longer interval's remainder
/// (dropped samples) is bridged with the mean of the last and this rate, its uncertainty added
/// to the spread. `dt` of the very first sample is not used; a `dt` within a millionth of
/// `sample_time` is taken as `sample_time` (uniformly spaced timestamps then give the results of
/// `bingham_ahrs_update()` bit for bit).
///
/// Errors: those of `bingham_ahrs_update()`, and `BINGHAM_ERR_INVALID_ARGUMENT` for `dt` not
/// finite or outside `BINGHAM_AHRS_MIN_SAMPLE_TIME` (1e-6 s) to `BINGHAM_AHRS_MAX_STEP_TIME`
/// (10 s). On error the AHRS is unchanged.
///
/// # Safety
/// `a`: a live handle; `gyr`, `acc`: 3 readable doubles each; `mag`: `NULL` or 3 readable
/// doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_update_dt(
    a: *mut bingham_ahrs,
    dt: f64,
    gyr: *const f64,
    acc: *const f64,
    mag: *const f64,
) -> bingham_status {
    guard("bingham_ahrs_update_dt", || {
        // SAFETY: forwarded caller contract.
        unsafe { one_sample(a, Some(dt), gyr, acc, mag) }
    })
}

fn vec3(s: &[f64]) -> [f64; 3] {
    [s[0], s[1], s[2]]
}

/// Processes `n` samples and writes the orientation after each: as `n` calls of
/// `bingham_ahrs_update()` followed by `bingham_ahrs_quaternion()`.
///
/// - `gyr`, `acc`: n×3 row-major; `mag`: n×3 row-major or `NULL`.
/// - `quat`: n×4 row-major output (w, x, y, z per row, sensor → world ENU, w ≥ 0).
///
/// Per channel, as in `bingham_ahrs_update()`: a row of `gyr`, `acc` or `mag` holding NaN (or
/// ±Inf) means "no sample" of that sensor at that time, so sensors sampled at lower rates than
/// the gyroscope, or with gaps, fit in one batch (fill their missing rows with NaN); a missing
/// gyroscope row is a gap the AHRS carries the orientation through.
///
/// A refused sample (see `bingham_ahrs_update()`: a gyroscope row turning by more than
/// 1e6 rad, or a first sample without a finite accelerometer showing gravity)
/// stops the batch: the samples before it are
/// processed and their rows of `quat` written, the refused one changes nothing, the rest are
/// untouched; the error message names the sample's index ("sample k: ..."). `n = 0` does
/// nothing.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT`, `BINGHAM_ERR_INVALID_DIMENSION` (n×4 overflows),
/// those of `bingham_ahrs_update()`.
///
/// # Safety
/// `a`: a live handle; `gyr`, `acc`: n*3 readable doubles; `mag`: `NULL` or n*3 readable
/// doubles; `quat`: n*4 writable doubles, not overlapping the inputs.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_update_batch(
    a: *mut bingham_ahrs,
    n: usize,
    gyr: *const f64,
    acc: *const f64,
    mag: *const f64,
    quat: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_update_batch", || {
        // SAFETY: forwarded caller contract.
        unsafe {
            batch_health(
                a,
                n,
                gyr,
                acc,
                mag,
                quat,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            )
        }
    })
}

/// As `bingham_ahrs_update_batch()`, also writing the total angular spread (radians, see
/// `bingham_ahrs_angular_spread()`) after each sample into `spread` (n doubles, or `NULL`). A
/// sample whose spread cannot be evaluated (`BINGHAM_ERR_NUMERICAL`) is refused like a bad one:
/// it changes nothing and stops the batch.
///
/// # Safety
/// As `bingham_ahrs_update_batch()`; `spread`: `NULL` or n writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_update_batch_spread(
    a: *mut bingham_ahrs,
    n: usize,
    gyr: *const f64,
    acc: *const f64,
    mag: *const f64,
    quat: *mut f64,
    spread: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_update_batch_spread", || {
        // SAFETY: forwarded caller contract.
        unsafe { batch_health(a, n, gyr, acc, mag, quat, spread, std::ptr::null_mut()) }
    })
}

/// As `bingham_ahrs_update_batch_spread()`, also writing the health score
/// (`bingham_ahrs_health()`'s `score`: about 1 when the sensors agree with the model, above
/// `BINGHAM_AHRS_HEALTH_THRESHOLD` an input mistake is likely) after each sample into
/// `health` (n doubles, or `NULL`).
///
/// # Safety
/// As `bingham_ahrs_update_batch_spread()`; `health`: `NULL` or n writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_update_batch_health(
    a: *mut bingham_ahrs,
    n: usize,
    gyr: *const f64,
    acc: *const f64,
    mag: *const f64,
    quat: *mut f64,
    spread: *mut f64,
    health: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_update_batch_health", || {
        // SAFETY: forwarded caller contract.
        unsafe { batch_health(a, n, gyr, acc, mag, quat, spread, health) }
    })
}

/// As `bingham_ahrs_update_batch_health()`, with a timestamp per sample: `t` (n doubles,
/// seconds, strictly increasing, any origin) is when each sample was taken, and each is
/// processed with its own time step, as `bingham_ahrs_update_dt()`: `t[k] - t[k-1]`; for
/// `t[0]`, the step from the last timestamp of the previous timed batch on this AHRS, or
/// `sample_time` if there was none (or an untimed update came since). So dropped packets,
/// jitter and a variable rate are modelled; a batch may be split anywhere.
///
/// Errors: those of `bingham_ahrs_update_batch_health()`, and `BINGHAM_ERR_INVALID_ARGUMENT`
/// for a timestamp that is not finite or not after the previous one, or a step above
/// `BINGHAM_AHRS_MAX_STEP_TIME` (10 s): the batch stops there, as for any refused sample
/// (the rows before it written, the message names the index).
///
/// # Safety
/// As `bingham_ahrs_update_batch_health()`; `t`: n readable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_update_batch_timed(
    a: *mut bingham_ahrs,
    n: usize,
    t: *const f64,
    gyr: *const f64,
    acc: *const f64,
    mag: *const f64,
    quat: *mut f64,
    spread: *mut f64,
    health: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_update_batch_timed", || {
        // SAFETY: caller contract.
        let ahrs = unsafe { handle_mut("a", a)? };
        // SAFETY: caller contract: n timestamps, n rows of 3 readable and of 4 (and n)
        // writable doubles, not overlapping.
        let (t, g, ac, q, m, s, h) = unsafe {
            args!(
                t: raw [n],
                gyr: rows [n; 3],
                acc: rows [n; 3],
                quat: mut rows [n; 4],
                mag: opt rows [n; 3],
                spread: opt mut [n],
                health: opt mut [n]
            )
            .read()?
        };
        ahrs.inner.update_batch_timed(t, g, ac, m, q, s, h)?;
        Ok(())
    })
}

/// Shared body of the three batch entry points (`spread`, `health`: `NULL` when not wanted).
///
/// # Safety
/// The callers' contract.
#[allow(clippy::too_many_arguments)]
unsafe fn batch_health(
    a: *mut bingham_ahrs,
    n: usize,
    gyr: *const f64,
    acc: *const f64,
    mag: *const f64,
    quat: *mut f64,
    spread: *mut f64,
    health: *mut f64,
) -> FfiResult<()> {
    // SAFETY: caller contract.
    let ahrs = unsafe { handle_mut("a", a)? };
    // SAFETY: caller contract: n rows of 3 readable and of 4 (and n) writable doubles, not
    // overlapping.
    let (g, ac, q, m, s, h) = unsafe {
        args!(
            gyr: rows [n; 3],
            acc: rows [n; 3],
            quat: mut rows [n; 4],
            mag: opt rows [n; 3],
            spread: opt mut [n],
            health: opt mut [n]
        )
        .read()?
    };
    ahrs.inner.update_batch_health(g, ac, m, q, s, h)?;
    Ok(())
}

/// Shared body of the getters: borrows the AHRS, checks the outputs `outs`, lets `get` compute
/// their values (one after another, in the order of `outs`) and only then writes them.
///
/// # Safety
/// `a`: NULL or a live handle; the caller's contract for `outs`.
unsafe fn getter<O>(
    a: *const bingham_ahrs,
    outs: O,
    get: impl FnOnce(&Ahrs, &mut [f64]) -> crate::error::Result<()>,
) -> FfiResult<()>
where
    O: Arg,
    O::Value: Fill,
{
    // SAFETY: caller contract.
    let ahrs = unsafe { handle("a", a)? };
    // SAFETY: forwarded contract.
    unsafe { get_into(outs, |v| get(&ahrs.inner, v)) }
}

/// The current orientation estimate (the mode of the Bingham state): sensor → world (ENU),
/// scalar first `(w, x, y, z)`, with w ≥ 0. Before the first sample: the identity.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`a`, `q`). On error nothing is written.
///
/// # Safety
/// `a`: a live handle; `q`: 4 writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_quaternion(
    a: *const bingham_ahrs,
    q: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_quaternion", || {
        // SAFETY: forwarded caller contract.
        unsafe {
            getter(a, args!(q: out [4]), |ahrs, v| {
                v.copy_from_slice(&ahrs.quaternion());
                Ok(())
            })
        }
    })
}

/// The Bingham state of the orientation: `m` 4×4 row-major (last column the mode), `z` 4
/// concentrations ascending with `z[3] = 0`. Before the first sample: uniform (M = I, z = 0).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`a`, `m`, `z`). On error nothing is written.
///
/// # Safety
/// `a`: a live handle; `m`: 16 and `z`: 4 writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_state(
    a: *const bingham_ahrs,
    m: *mut f64,
    z: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_state", || {
        // SAFETY: forwarded caller contract.
        unsafe {
            getter(a, args!(m: out [16], z: out [4]), |ahrs, v| {
                let (m, z) = v.split_at_mut(16);
                ahrs.state_into(m, z)
            })
        }
    })
}

/// Replaces the orientation estimate by `Bingham(m, z)`: a known start or a re-initialization.
/// The bias estimate, the low-pass filters and the magnetic reference are kept (the new
/// state's coupling to the bias estimate's error starts afresh). Called before
/// the first sample, it replaces the self-initialization (the first sample then only primes
/// the low-pass filters).
///
/// - `m`: 4×4 row-major orthogonal (within `BINGHAM_ORTHOGONALITY_TOL`); `z`: 4 concentrations,
///   any order and shift (e.g. from `bingham_noise_from_angle_std()` rotated to the start with
///   `bingham_rotate_left()`).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`a`, `m`, `z`), `BINGHAM_ERR_INVALID_ARGUMENT` (NaN/Inf,
/// `m` not orthogonal, the entries of `z` spanning more than the largest double). On error the
/// AHRS is unchanged.
///
/// # Safety
/// `a`: a live handle; `m`: 16 and `z`: 4 readable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_set_state(
    a: *mut bingham_ahrs,
    m: *const f64,
    z: *const f64,
) -> bingham_status {
    guard("bingham_ahrs_set_state", || {
        // SAFETY: caller contract.
        let ahrs = unsafe { handle_mut("a", a)? };
        // SAFETY: caller contract; 16 and 4 doubles.
        let (ms, zs) = unsafe { args!(m: [16], z: [4]).read()? };
        ahrs.inner.set_state(ms, zs)?;
        Ok(())
    })
}

/// The stated angular spread of the orientation (radians): `spread[0..3]` the standard
/// deviations along the state's principal directions (columns 0..2 of the state's M),
/// `spread[3]` the total (≈ the RMS angle between the truth and the estimate): the square roots
/// of the variances of `bingham_ahrs_orientation_covariance()` along those directions and of its
/// trace. The state's own spread (`bingham_angular_spread()` of the state, plus the process
/// noise since the last correction) scaled by what the accelerometer's and the magnetometer's
/// innovations show (tilt and heading apart), widened by the errors of the tilt and heading
/// references that the sensors show, and with the heading error a tilt error brings through the
/// magnetometer (`tan(dip)` times the tilt about north: tilt and heading are correlated); the
/// variance of gyroscope gaps and the drift the gyroscope's scale error explains are stated
/// unscaled (docs/design.md, "Stated uncertainty"; coverage measured in docs/accuracy/ahrs.md, "The
/// stated uncertainty").
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`a`, `spread`), `BINGHAM_ERR_NUMERICAL` (the moments
/// of an extremely concentrated state, e.g. one set with `bingham_ahrs_set_state()` near the
/// largest double, cannot be evaluated). On error nothing is written.
///
/// # Safety
/// `a`: a live handle; `spread`: 4 writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_angular_spread(
    a: *const bingham_ahrs,
    spread: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_angular_spread", || {
        // SAFETY: forwarded caller contract.
        unsafe {
            getter(a, args!(spread: out [4]), |ahrs, v| {
                ahrs.angular_spread(v.try_into().expect("4 values"))
            })
        }
    })
}

/// The health readout: how well the sensors have agreed with the model over the last
/// `BINGHAM_AHRS_HEALTH_TIME` (5 s). `score` is about 1 when they agree; above
/// `BINGHAM_AHRS_HEALTH_THRESHOLD` (10) the input is likely wrong — a gyroscope in °/s instead
/// of rad/s, a wrong `sample_time`, swapped or mirrored magnetometer axes. `mag_rejected`
/// near 1 for long: the magnetometer is disturbed or its axes are wrong. `mag_dip` of the
/// wrong sign for the place (negative north of the magnetic equator): the accelerometer's
/// (or magnetometer's) sign is flipped, which no other signal shows. Definitions in
/// docs/guide.md ("Health readout"). All zero before the first correction (one correction
/// period, 50 ms, after the first sample).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`a`, `out`). On error `*out` is not written.
///
/// # Safety
/// `a`: a live handle; `out`: a writable `bingham_ahrs_health_report`.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_health(
    a: *const bingham_ahrs,
    out: *mut AhrsHealth,
) -> bingham_status {
    guard("bingham_ahrs_health", || {
        // SAFETY: caller contract.
        let ahrs = unsafe { handle("a", a)? };
        // SAFETY: caller contract.
        let (out,) = unsafe { args!(out: out).read()? };
        // SAFETY: checked place.
        unsafe { out.set(ahrs.inner.health()) };
        Ok(())
    })
}

/// The gyroscope bias estimate (rad/s, sensor frame), subtracted from the rates.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`a`, `bias`). On error nothing is written.
///
/// # Safety
/// `a`: a live handle; `bias`: 3 writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_gyro_bias(
    a: *const bingham_ahrs,
    bias: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_gyro_bias", || {
        // SAFETY: forwarded caller contract.
        unsafe {
            getter(a, args!(bias: out [3]), |ahrs, v| {
                v.copy_from_slice(&ahrs.gyro_bias());
                Ok(())
            })
        }
    })
}

/// The gyroscope scale-error estimate (relative, per sensor axis): the gyroscope reads
/// `(1 + scale[i])` times the rate about its axis `i` (plus the bias); the AHRS turns the state
/// by `gyr − bias − scale ∘ gyr` (componentwise). Estimated with the bias from the corrections
/// during rotation, starting from 0 with the standard deviation `gyro_scale_std` (see
/// `bingham_ahrs_params`; default 0.001, i.e. 0.1 %) and never walking; exactly 0 when
/// `gyro_scale_std` is 0. Each component stays within ±0.05.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`a`, `scale`). On error nothing is written.
///
/// # Safety
/// `a`: a live handle; `scale`: 3 writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_gyro_scale(
    a: *const bingham_ahrs,
    scale: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_gyro_scale", || {
        // SAFETY: forwarded caller contract.
        unsafe {
            getter(a, args!(scale: out [3]), |ahrs, v| {
                v.copy_from_slice(&ahrs.gyro_scale());
                Ok(())
            })
        }
    })
}

/// The covariance of the gyroscope bias estimate, in (rad/s)², sensor frame: a 3×3 matrix
/// written row-major into `cov` (9 doubles; `cov[3*i + j]` is the covariance of the bias
/// components i and j), symmetric positive semi-definite. The square roots of its diagonal
/// are the standard deviations (rad/s) of the components of `bingham_ahrs_gyro_bias()`.
///
/// It is `bias_std²·I` (see `bingham_ahrs_params`) on creation and until the first sample has
/// been processed; then it shrinks as the corrections during motion and the rests teach the
/// bias, and grows by `bias_std²/bias_time` per second (not at all with `bias_time = 0`); over
/// a rest the growth is held, and a third of it is added when the rest ends (the bias is taken
/// as one constant over a rest, which the rest's samples measure).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`a`, `cov`). On error nothing is written.
///
/// # Safety
/// `a`: a live handle; `cov`: 9 writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_gyro_bias_covariance(
    a: *const bingham_ahrs,
    cov: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_gyro_bias_covariance", || {
        // SAFETY: forwarded caller contract.
        unsafe {
            getter(a, args!(cov: out [9]), |ahrs, v| {
                v.copy_from_slice(&ahrs.gyro_bias_covariance());
                Ok(())
            })
        }
    })
}

/// The covariance of the orientation error, 3×3 row-major in rad², for
/// `sensor_msgs/Imu.orientation_covariance`: the error as a rotation vector `phi` in the world
/// frame (ENU: x east, y north, z up; REP 103), `q_true = exp(phi/2) ⊗ q_est`, with `q_est`
/// the orientation of `bingham_ahrs_quaternion()` (sensor → world). From the state's second
/// moments plus the process noise since the last correction, scaled and widened as
/// `bingham_ahrs_angular_spread()` says: its trace is the square of the total angular spread
/// (`spread[3]`). Before the first sample: the identity (a uniform orientation's spread).
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`a`, `cov`), `BINGHAM_ERR_NUMERICAL` (internal). On
/// error nothing is written.
///
/// # Safety
/// `a`: a live handle; `cov`: 9 writable doubles.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_orientation_covariance(
    a: *const bingham_ahrs,
    cov: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_orientation_covariance", || {
        // SAFETY: forwarded caller contract.
        unsafe {
            getter(a, args!(cov: out [9]), |ahrs, v| {
                v.copy_from_slice(&ahrs.orientation_covariance()?);
                Ok(())
            })
        }
    })
}

/// The online estimate of the magnetometer's latency behind the gyroscope, in seconds, from the
/// IMU alone: the lag at which the change of the field best fits the rotation the gyroscope
/// measures (in a homogeneous field `dm/dt = -w x m` in the sensor frame). A readout: the
/// filter does not use it; to compensate a latency, set `mag_latency` in
/// `bingham_ahrs_params`. It estimates the latency of the raw samples, whatever `mag_latency`
/// is. Range: 0 to 40 ms in samples rounded up to an even number, at least 2 and at most 32
/// samples. Time convention: gyroscope sample k is the rate over the interval (t_{k-1}, t_k], as in the
/// prediction (for a gyroscope that samples the rate at t_k the estimate is the latency plus
/// half a sample, which is what the compensation needs). The value is shrunk towards 0 by the
/// estimate's own standard error (from two halves of the data): L * max(0, 1 - s^2/L^2), so
/// that a latency the data cannot tell from none reads 0; this is also the value the default
/// (`mag_latency` = `BINGHAM_AHRS_LATENCY_ESTIMATE`) compensates.
///
/// Available once 5 s of informative motion have been seen: seconds of samples with the
/// magnetometer present and undisturbed, weighted by g^2/(g^2 + 1), g the change of the
/// rotation rate across the lag window perpendicular to the field in rad/s^2 (a sensor at rest
/// or turning at a constant rate tells the lags apart poorly and counts little). The memory is
/// about 30 s of such motion.
///
/// Errors: `BINGHAM_ERR_NULL_ARGUMENT` (`a`, `latency`), `BINGHAM_ERR_NOT_CONVERGED` (no
/// estimate yet; the message says how much informative motion has been seen, or that the
/// residuals do not single out a lag). On error `*latency` is not written.
///
/// # Safety
/// `a`: a live handle; `latency`: 1 writable double.
#[no_mangle]
pub unsafe extern "C" fn bingham_ahrs_mag_latency_estimate(
    a: *const bingham_ahrs,
    latency: *mut f64,
) -> bingham_status {
    guard("bingham_ahrs_mag_latency_estimate", || {
        // SAFETY: forwarded caller contract.
        unsafe {
            getter(a, args!(latency: out [1]), |ahrs, v| {
                v[0] = ahrs.mag_latency_estimate_or_error()?;
                Ok(())
            })
        }
    })
}
