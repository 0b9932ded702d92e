//! The smoother's public input, output and option types, and the options' defaults.

/// One recording: timestamps (optional), gyroscope, accelerometer and magnetometer samples.
#[derive(Debug, Clone, Copy)]
pub struct SmoothInput<'a> {
    /// The timestamp (s, strictly increasing, any origin) of each sample; `None`: uniformly
    /// spaced by [`AhrsParams::sample_time`].
    ///
    /// [`AhrsParams::sample_time`]: crate::ahrs::AhrsParams::sample_time
    pub time: Option<&'a [f64]>,
    /// The gyroscope (rad/s), one row per sample; a non-finite row: no sample (a gap).
    pub gyr: &'a [[f64; 3]],
    /// The accelerometer (m/s²), the same length; a non-finite row: no sample.
    pub acc: &'a [[f64; 3]],
    /// The magnetometer (any unit), the same length, or `None`; a non-finite row: no sample.
    pub mag: Option<&'a [[f64; 3]]>,
}

/// Where the smoother writes, each one row per sample (the inputs' length).
#[derive(Debug)]
pub struct SmoothOutput<'a> {
    /// The smoothed orientation (sensor → world ENU, scalar first, `w ≥ 0`).
    pub quat: &'a mut [[f64; 4]],
    /// The total angular spread (rad) of the smoothed orientation: the square root of the
    /// trace of its covariance.
    pub spread: Option<&'a mut [f64]>,
    /// The smoothed gyroscope bias (rad/s, sensor frame).
    pub bias: Option<&'a mut [[f64; 3]]>,
    /// The covariance (rad², 3×3 row-major) of the smoothed orientation's error as a rotation
    /// vector in the world frame, as [`Ahrs::orientation_covariance`] defines it.
    ///
    /// [`Ahrs::orientation_covariance`]: crate::ahrs::Ahrs::orientation_covariance
    pub covariance: Option<&'a mut [[f64; 9]]>,
}

/// How the bias is smoothed (docs/accuracy/ahrs.md, "The offline smoother", compares them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BiasMode {
    /// One forward and one backward pass; the bias output is the two estimates fused by their
    /// covariances.
    Fused,
    /// Then both passes again on the gyroscope minus the fused bias (twice the time).
    SecondPass,
}

/// The smoother's options besides the AHRS parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoothOptions {
    /// How the bias is smoothed; default [`BiasMode::Fused`].
    pub bias: BiasMode,
    /// How the two passes' orientations are multiplied; default [`Fusion::Tangent`].
    pub fusion: Fusion,
    /// Whether the backward pass starts from a uniform orientation (true) or, as the online
    /// AHRS does, from its first sample's accelerometer and magnetometer (false, the default).
    pub uniform_start: bool,
    /// Whether the backward pass takes the forward pass's magnetic reference at the handoff (the
    /// field's norm and dip its disturbance test compares with, and the variation of the field
    /// measured so far) instead of its first sample's (default true).
    pub forward_mag_reference: bool,
    /// Whether the backward pass's gyroscope has the forward pass's bias estimate at the handoff
    /// taken out (default true).
    pub bias_start: bool,
    /// The consistency gate: the squared Mahalanobis distance between the two passes above
    /// which the backward covariance is widened by `distance² / gate` (0: no gate; default
    /// [`DEFAULT_GATE`]).
    pub gate: f64,
}

/// The default consistency gate of [`SmoothOptions::gate`].
pub const DEFAULT_GATE: f64 = 16.0;

/// How the forward posterior and the backward prediction are multiplied (docs/accuracy/ahrs.md,
/// "The offline smoother", compares them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fusion {
    /// In the tangent space of the forward mode, with both passes' stated (calibrated)
    /// covariances.
    Tangent,
    /// The exact product of the two Bingham states (their exponents added) for the mode; the
    /// covariance as [`Fusion::Tangent`] states it.
    Bingham,
}

impl Default for SmoothOptions {
    fn default() -> SmoothOptions {
        SmoothOptions {
            bias: BiasMode::Fused,
            fusion: Fusion::Tangent,
            uniform_start: false,
            forward_mag_reference: true,
            bias_start: true,
            gate: DEFAULT_GATE,
        }
    }
}
