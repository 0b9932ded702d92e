//! The handoff: what the backward pass takes of the forward pass (its bias estimate, magnetic
//! reference, latency estimate and heading coupling), and the sample at which it is taken.

use super::types::SmoothOptions;
use crate::ahrs::{Ahrs, AhrsParams, MagReference, StatedCoupling, LATENCY_ESTIMATE};
use crate::error::Result;

/// The seconds of recording the forward pass runs alone before it hands its bias estimate,
/// magnetic reference and latency estimate to the backward pass, which then runs concurrently
/// with it (module documentation, "Threads").
pub const HANDOFF_TIME: f64 = 30.0;

/// The seconds of recording after [`HANDOFF_TIME`] below which the passes run one after the
/// other, the backward pass starting from the forward pass's final values (a second thread
/// would gain little).
pub const PARALLEL_TIME: f64 = 30.0;

/// The forward pass's values the backward pass starts from, taken after sample
/// [`handoff_index`].
#[derive(Debug, Clone, Copy)]
pub(super) struct Handoff {
    /// The bias estimate taken out of the backward pass's gyroscope.
    pub(super) bias: [f64; 3],
    /// The magnetic reference (norm, dip) the backward pass's disturbance test compares with,
    /// and the field's variation the forward pass measured.
    pub(super) mag_reference: Option<MagReference>,
    /// The magnetometer's latency (s) by which the backward pass shifts the field samples.
    pub(super) mag_latency: f64,
    /// Without a magnetometer: the forward pass's final state, the backward pass's start.
    pub(super) state: Option<([f64; 16], [f64; 4])>,
    /// The forward pass's heading coupling, which the smoothed covariance takes.
    coupling: StatedCoupling,
}

impl Handoff {
    pub(super) fn take(
        ahrs: &Ahrs,
        params: &AhrsParams,
        options: &SmoothOptions,
        has_mag: bool,
    ) -> Result<Handoff> {
        let mag_latency = if params.mag_latency == LATENCY_ESTIMATE {
            ahrs.mag_latency_estimate().unwrap_or(0.0)
        } else {
            params.mag_latency
        };
        let state = if has_mag {
            None
        } else {
            let mut m = [0.0; 16];
            let mut z = [0.0; 4];
            ahrs.state_into(&mut m, &mut z)?;
            Some((m, z))
        };
        Ok(Handoff {
            bias: if options.bias_start {
                ahrs.gyro_bias()
            } else {
                [0.0; 3]
            },
            mag_reference: if options.forward_mag_reference {
                ahrs.mag_reference()
            } else {
                None
            },
            mag_latency,
            state,
            coupling: if options.forward_mag_reference {
                ahrs.stated_coupling()
            } else {
                StatedCoupling::NONE
            },
        })
    }
}

/// The earliest sample after which the forward pass hands its values to the backward pass
/// (later while it has no latency estimate, [`latency_ready`]): [`HANDOFF_TIME`] into the recording (in nominal periods) when a magnetometer is present and
/// at least [`PARALLEL_TIME`] follows; otherwise the last sample (without a magnetometer the
/// backward pass starts from the forward pass's final state, its heading convention). A
/// function of the recording alone: the result does not depend on whether the passes run
/// concurrently.
pub(super) fn handoff_index(n: usize, nominal: f64, has_mag: bool) -> usize {
    let warm = (HANDOFF_TIME / nominal).ceil();
    let rest = (PARALLEL_TIME / nominal).ceil();
    if has_mag && (n as f64) > warm + rest {
        warm as usize
    } else {
        n.saturating_sub(1)
    }
}

/// Whether the forward pass has the magnetometer's latency the backward pass needs: the
/// parameter, or the forward pass's estimate once there is one.
pub(super) fn latency_ready(ahrs: &Ahrs, params: &AhrsParams) -> bool {
    params.mag_latency != LATENCY_ESTIMATE || ahrs.mag_latency_estimate().is_some()
}

/// The heading's coupling to the tilt (module `ahrs::uncertainty`) with the magnetic reference
/// of the handoff (0 without one).
pub(super) fn coupling(handoff: Option<&Handoff>) -> StatedCoupling {
    handoff.map_or(StatedCoupling::NONE, |h| h.coupling)
}
