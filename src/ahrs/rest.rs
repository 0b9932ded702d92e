//! The gyroscope bias at rest: the raw gyroscope samples of a still phase, in blocks.
//!
//! At rest the gyroscope shows its bias plus its white noise, and the samples also give the
//! noise's variance. The mean of `n` samples is a measurement of the bias with variance
//! `var/n`, the bias's Kalman filter (module `bias`) weighs it against what it knows. The edges
//! of a still phase are not trusted: the rest test notices the start of a motion only after
//! the motion has begun (its samples are band-limited and compared with a 0.5-s average),
//! and the end of a motion decays into the phase. So the samples are collected in blocks of
//! [`BLOCK_TIME`]; the first block of a phase is dropped, and a block is used only once the
//! next block has been still too. The blocks so confirmed are held until the phase has been
//! still for `rest_time`, then applied as one measurement, and each further confirmed block
//! as another. Over a rest the bias is one constant: the AHRS holds the bias's random walk
//! while at rest and adds, when the rest ends, the variance of a random walk's end about its
//! mean over the phase (docs/accuracy.md, "The bias at rest").

use nalgebra::Vector3;

use super::bias::BiasState;
use super::lowpass::Coeffs;
use super::params::AhrsParams;
use super::vec3::norm3;

/// Length (s) of a block of the still phase: the time scale of the rest test's average.
pub(super) const BLOCK_TIME: f64 = 0.5;

/// The smallest variance per axis ((rad/s)²) taken for the gyroscope's noise at rest: a
/// noiseless (simulated or quantized) signal is then known to 1e-6 rad/s per sample.
const MIN_VAR: f64 = 1e-12;

/// The fewest samples from which their variance is taken as the gyroscope's noise at rest.
const MIN_SAMPLES: f64 = 10.0;

/// A sum of gyroscope samples, of their squared norms, and their number.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Sum {
    x: [f64; 3],
    sq: f64,
    n: f64,
}

impl Sum {
    fn push(&mut self, gyr: &[f64; 3]) {
        for (a, b) in self.x.iter_mut().zip(gyr) {
            *a += b;
        }
        self.sq += gyr.iter().map(|v| v * v).sum::<f64>();
        self.n += 1.0;
    }

    fn add(&mut self, other: &Sum) {
        for (a, b) in self.x.iter_mut().zip(&other.x) {
            *a += b;
        }
        self.sq += other.sq;
        self.n += other.n;
    }

    fn mean(&self) -> [f64; 3] {
        self.x.map(|v| v / self.n)
    }
}

/// The samples of the current still phase, summed about the phase's first sample (so that the
/// variance, a difference of the sums, does not lose to rounding what the bias's size would
/// cost: a bias far above the noise leaves the sums of the deviations small).
#[derive(Debug, Clone, PartialEq, Default)]
pub(super) struct RestWindow {
    /// The phase's first sample (rad/s).
    origin: Option<[f64; 3]>,
    /// Confirmed blocks not yet applied, the last complete block, the block being filled.
    held: Sum,
    pending: Sum,
    current: Sum,
    /// Every confirmed block of the phase (for the noise's variance).
    confirmed: Sum,
    /// Complete blocks so far in the phase.
    blocks: u32,
}

impl RestWindow {
    /// One sample: `still` whether the rest test passed, `gyr` the raw sample, `dt` the sample
    /// time (s). The phase ends (everything dropped) when the test fails.
    pub(super) fn push(&mut self, still: bool, gyr: &[f64; 3], dt: f64) {
        if !still {
            *self = RestWindow::default();
            return;
        }
        let o = *self.origin.get_or_insert(*gyr);
        self.current
            .push(&[gyr[0] - o[0], gyr[1] - o[1], gyr[2] - o[2]]);
        if self.current.n * dt >= BLOCK_TIME {
            // the previous block is confirmed by this one (the first block of the phase, which
            // nothing precedes, is dropped)
            if self.blocks >= 2 {
                let p = self.pending;
                self.held.add(&p);
                self.confirmed.add(&p);
            }
            self.pending = self.current;
            self.current = Sum::default();
            self.blocks += 1;
        }
    }

    /// The bias measurement the phase holds, taken out (`(mean, variance per axis)`, rad/s and
    /// (rad/s)²), or `None`. `fallback_var` is the variance per sample used when the phase has
    /// fewer than `MIN_SAMPLES` samples.
    pub(super) fn take(&mut self, fallback_var: f64) -> Option<([f64; 3], f64)> {
        if self.held.n == 0.0 {
            return None;
        }
        let h = std::mem::take(&mut self.held);
        let c = &self.confirmed;
        let var = if c.n >= MIN_SAMPLES {
            // the samples' variance about their mean (the bias is constant over a rest)
            let m2: f64 = c.mean().iter().map(|v| v * v).sum();
            ((c.sq / c.n - m2) / 3.0).max(MIN_VAR)
        } else {
            fallback_var
        };
        let (m, o) = (h.mean(), self.origin.unwrap_or_default());
        Some(([o[0] + m[0], o[1] + m[1], o[2] + m[2]], var / h.n))
    }
}

/// The rest detection's state in the AHRS (step 1 of the module `ahrs`): the gyroscope and
/// the accelerometer low-passed (`REST_FILTER_TIME`) and band-limited (`REST_NOISE_TIME`),
/// how long the sensor has been still, the samples of the still phase, and the time over
/// which the bias's random walk has been held.
#[derive(Debug, Clone, PartialEq, Default)]
pub(super) struct Rest {
    gyr_lp: [f64; 3],
    acc_lp: [f64; 3],
    /// The samples band-limited for the rest test (`REST_NOISE_TIME`).
    gyr_fast: [f64; 3],
    acc_fast: [f64; 3],
    /// Seconds the sensor has been still.
    pub(super) timer: f64,
    /// The raw gyroscope samples of the current still phase.
    window: RestWindow,
    /// Seconds of the current rest (past `rest_time`) over which the bias's random walk is
    /// held (module `gyro`).
    pub(super) held: f64,
}

impl Rest {
    /// The rest detection started from the first sample's raw `gyr` and `acc`.
    pub(super) fn start(gyr: &[f64; 3], acc: &[f64; 3]) -> Rest {
        Rest {
            gyr_lp: *gyr,
            acc_lp: *acc,
            gyr_fast: *gyr,
            acc_fast: *acc,
            ..Rest::default()
        }
    }

    /// One gyroscope sample `gyr` (and the accelerometer's `acc`, if usable) `h` seconds
    /// after the previous one (step 1): the rest test and, after `rest_time` of stillness,
    /// the bias measured at rest (a Kalman step of `bias`).
    pub(super) fn step(
        &mut self,
        p: &AhrsParams,
        c: &Coeffs,
        h: f64,
        gyr: &[f64; 3],
        acc: Option<&[f64; 3]>,
        bias: &mut BiasState,
    ) {
        // The deviations are taken from the samples band-limited to REST_NOISE_TIME, so that
        // the test sees the same noise at every sample rate (a raw sample's noise grows with
        // √rate: at 1 kHz a MEMS gyroscope's alone exceeds the threshold now and then, and no
        // rest lasts).
        let dt = p.sample_time;
        let mut da = f64::INFINITY;
        for ((lp, fast), x) in self
            .gyr_lp
            .iter_mut()
            .zip(self.gyr_fast.iter_mut())
            .zip(gyr)
        {
            *lp += c.rest_filter * (x - *lp);
            *fast += c.rest_noise * (x - *fast);
        }
        if let Some(a) = acc {
            for ((lp, fast), x) in self.acc_lp.iter_mut().zip(self.acc_fast.iter_mut()).zip(a) {
                *lp += c.rest_filter * (x - *lp);
                *fast += c.rest_noise * (x - *fast);
            }
            let (f, l) = (&self.acc_fast, &self.acc_lp);
            da = norm3(&[f[0] - l[0], f[1] - l[1], f[2] - l[2]]);
        }
        let (f, g) = (&self.gyr_fast, &self.gyr_lp);
        let dg = norm3(&[f[0] - g[0], f[1] - g[1], f[2] - g[2]]);
        let still = dg < p.rest_gyro && da < p.rest_acc && norm3(g) < 2.0 * p.bias_max;
        self.timer = if still { self.timer + h } else { 0.0 };
        self.window.push(still, gyr, h);
        if self.timer >= p.rest_time {
            if let Some((mean, var)) = self.window.take(p.gyro_noise * p.gyro_noise / dt) {
                bias.rest(&Vector3::from(mean), var);
                bias.clip(p.bias_max);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A still phase whose first and last half seconds hold motion: neither reaches the
    /// measurements; the mean and the variance are those of the samples in between.
    #[test]
    fn the_edges_of_a_still_phase_are_left_out() {
        let dt = 0.01;
        let (b, sd) = ([0.01, -0.02, 0.005], 0.003);
        let mut w = RestWindow::default();
        let mut taken = Vec::new();
        let mut feed = |w: &mut RestWindow, still: bool, g: [f64; 3]| {
            w.push(still, &g, dt);
            if let Some(m) = w.take(1.0) {
                taken.push(m);
            }
        };
        // the end of a motion (first block), 3 s of rest (noise ±sd alternating), the start of
        // the next motion still passing the test for 0.3 s, then failing it
        for _ in 0..50 {
            feed(&mut w, true, [0.3, 0.2, -0.1]);
        }
        for k in 0..300 {
            let s = if k % 2 == 0 { sd } else { -sd };
            feed(&mut w, true, [b[0] + s, b[1] + s, b[2] + s]);
        }
        for k in 0..30 {
            feed(&mut w, true, [0.01 * f64::from(k), 0.0, 0.0]);
        }
        feed(&mut w, false, [1.0, 0.0, 0.0]);
        // blocks 2..6 (the rest's first 2.5 s) are confirmed; the last rest block and the
        // motion's start wait for a confirmation that never comes
        assert_eq!(taken.len(), 5);
        for (m, var) in &taken {
            for i in 0..3 {
                assert!((m[i] - b[i]).abs() < 1e-12, "{m:?}");
            }
            assert!(
                (var * 50.0 - sd * sd).abs() < 1e-12 * sd * sd * 50.0 + 1e-15,
                "{var}"
            );
        }
        // the phase ended: nothing left
        assert!(w.take(1.0).is_none());
    }

    /// A bias 3000× the noise: the variance comes out to rounding (summed about the phase's
    /// first sample; from the plain sums, `E[x²] − mean²` cancelled to 6e-9 of it, a loss that
    /// grows with the square of the bias over the noise).
    #[test]
    fn a_large_bias_does_not_cost_the_variance_its_precision() {
        let (b, sd) = ([0.03, -0.035, 0.02], 1e-5);
        let mut w = RestWindow::default();
        for k in 0..300 {
            let s = if k % 2 == 0 { sd } else { -sd };
            w.push(true, &[b[0] + s, b[1] + s, b[2] + s], 0.01);
        }
        let (m, var) = w.take(1.0).unwrap();
        // blocks 2..5 confirmed: 200 samples, half at +sd, half at −sd
        assert!(
            (var * 200.0 - sd * sd).abs() < 1e-9 * sd * sd,
            "{}",
            var * 200.0 / (sd * sd)
        );
        for i in 0..3 {
            assert!((m[i] - b[i]).abs() < 1e-15, "{m:?}");
        }
    }

    #[test]
    fn a_short_phase_uses_the_fallback_variance() {
        // 1 Hz samples: blocks of one sample, too few for a variance
        let mut w = RestWindow::default();
        for _ in 0..3 {
            w.push(true, &[0.01, 0.0, 0.0], 1.0);
        }
        let (m, var) = w.take(0.04).unwrap();
        assert!((m[0] - 0.01).abs() < 1e-15 && var == 0.04);
    }
}
