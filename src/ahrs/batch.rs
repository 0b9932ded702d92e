//! The AHRS's batch calls: many samples per call, with or without timestamps, spreads and
//! health scores.

use crate::error::{Error, Result};

use super::estimator::Ahrs;

impl Ahrs {
    /// Processes `gyr.len()` samples (`acc` the same length, `mag` too or `None`), writing the
    /// quaternion after each into `quat` (and, if given, the total angular spread into
    /// `spread`, see [`Ahrs::update_spread`]). A row of NaN in `acc` or `mag` means "no sample"
    /// for that sensor at that time (see [`Ahrs::update`]). Stops at the first refused sample:
    /// the samples before it are processed and their outputs written, the refused one changes
    /// nothing; the error names the index.
    pub fn update_batch(
        &mut self,
        gyr: &[[f64; 3]],
        acc: &[[f64; 3]],
        mag: Option<&[[f64; 3]]>,
        quat: &mut [[f64; 4]],
        spread: Option<&mut [f64]>,
    ) -> Result<()> {
        self.update_batch_health(gyr, acc, mag, quat, spread, None)
    }

    /// [`Ahrs::update_batch`], also writing the health score ([`Ahrs::health`]`.score`) after
    /// each sample into `health` if given (the same length).
    pub fn update_batch_health(
        &mut self,
        gyr: &[[f64; 3]],
        acc: &[[f64; 3]],
        mag: Option<&[[f64; 3]]>,
        quat: &mut [[f64; 4]],
        spread: Option<&mut [f64]>,
        health: Option<&mut [f64]>,
    ) -> Result<()> {
        self.batch(None, gyr, acc, mag, quat, spread, health)
    }

    /// [`Ahrs::update_batch_health`] with a timestamp per sample: `time[k]` (s, strictly
    /// increasing, any origin) is when sample `k` was taken, and each sample is processed with
    /// its own time step ([`Ahrs::update_dt`]): `time[k] − time[k−1]`, for the first sample
    /// `time[0]` minus the last timestamp of the previous timed batch, or the nominal period if
    /// there was none (or a sample without a timestamp came since). A row of NaN in `gyr`,
    /// `acc` or `mag` means "no sample" of that sensor. Stops at the first refused sample (a
    /// timestamp not after the previous one, a step above [`MAX_STEP_TIME`](super::params::MAX_STEP_TIME)), as
    /// [`Ahrs::update_batch`] does.
    #[allow(clippy::too_many_arguments)]
    pub fn update_batch_timed(
        &mut self,
        time: &[f64],
        gyr: &[[f64; 3]],
        acc: &[[f64; 3]],
        mag: Option<&[[f64; 3]]>,
        quat: &mut [[f64; 4]],
        spread: Option<&mut [f64]>,
        health: Option<&mut [f64]>,
    ) -> Result<()> {
        self.batch(Some(time), gyr, acc, mag, quat, spread, health)
    }

    /// The batch calls: each sample with the nominal period or its timestamp's step.
    #[allow(clippy::too_many_arguments)]
    fn batch(
        &mut self,
        time: Option<&[f64]>,
        gyr: &[[f64; 3]],
        acc: &[[f64; 3]],
        mag: Option<&[[f64; 3]]>,
        quat: &mut [[f64; 4]],
        mut spread: Option<&mut [f64]>,
        mut health: Option<&mut [f64]>,
    ) -> Result<()> {
        let n = gyr.len();
        let lengths_ok = acc.len() == n
            && quat.len() == n
            && time.is_none_or(|t| t.len() == n)
            && mag.is_none_or(|m| m.len() == n)
            && spread.as_ref().is_none_or(|s| s.len() == n)
            && health.as_ref().is_none_or(|h| h.len() == n);
        if !lengths_ok {
            return Err(Error::InvalidDimension(
                "batch arrays must all have the same number of samples".into(),
            ));
        }
        for k in 0..n {
            let m = mag.map(|m| &m[k]);
            match time {
                Some(t) => {
                    let tk = t[k];
                    let dt = match self.last_time {
                        Some(last) => tk - last,
                        None => self.params.sample_time,
                    };
                    if !tk.is_finite() || dt <= 0.0 {
                        return Err(prefix(
                            Error::InvalidArgument(format!(
                                "timestamp {tk} s is not finite or not after the previous one \
                                 (timestamps must increase strictly)"
                            )),
                            k,
                        ));
                    }
                    self.step_dt(dt, &gyr[k], &acc[k], m, None)
                        .map_err(|e| prefix(e, k))?;
                    self.last_time = Some(tk);
                }
                None => self.update(&gyr[k], &acc[k], m).map_err(|e| prefix(e, k))?,
            }
            if let Some(s) = spread.as_deref_mut() {
                let mut out = [0.0; 4];
                self.angular_spread(&mut out).map_err(|e| prefix(e, k))?;
                s[k] = out[3];
            }
            quat[k] = self.quaternion();
            if let Some(h) = health.as_deref_mut() {
                h[k] = self
                    .sample_state
                    .health
                    .readout(None, &self.sample_state.times)
                    .score;
            }
        }
        Ok(())
    }

    /// [`Ahrs::update`] followed by the total angular spread (radians) of the new state, as one
    /// step (the spread comes from quantities the update keeps; it cannot fail once the
    /// update succeeded).
    pub fn update_spread(
        &mut self,
        gyr: &[f64; 3],
        acc: &[f64; 3],
        mag: Option<&[f64; 3]>,
    ) -> Result<f64> {
        self.update(gyr, acc, mag)?;
        let mut out = [0.0; 4];
        self.angular_spread(&mut out)?;
        Ok(out[3])
    }
}

/// `e` with "sample k: " in front of its message.
fn prefix(e: Error, k: usize) -> Error {
    e.prefixed(&format!("sample {k}"))
}
