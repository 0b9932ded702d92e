//! The magnetometer's latency behind the gyroscope, estimated online from the IMU alone, and
//! the turn that compensates a known latency.
//!
//! In a homogeneous field the field seen in the sensor frame obeys `dm/dt = −ω × m`. Over a
//! span of `s` samples this holds exactly in the form of the Cayley transform: with `Q` the
//! rotation the gyroscope increments compose from `t_{k−s}` to `t_k` and `φ = 2 Q_v / Q_w`
//! (`2 tan(angle/2)` along its axis), `m_k − m_{k−s} = −φ × (m_k + m_{k−s})/2`. If the
//! magnetometer lags the gyroscope by `L`, the pair `(m_k, m_{k−s})` obeys it with the
//! rotation of the gyroscope samples `k−j−s+1 … k−j` for `L = j·dt`. The residual of lag `j`,
//!
//! `r_j = (m_k − m_{k−s})/(s·dt) + φ_{k−j}/(s·dt) × (m_k + m_{k−s})/2`,
//!
//! divided by `|m̄|` (rad/s, whatever the field's unit), is smallest at the true lag; its
//! exponentially forgotten mean square over the samples, `S_j`, is a parabola in `j` near its
//! minimum, and the estimate is the vertex of the parabola through the smallest `S_j` and its
//! neighbours, in seconds.
//!
//! Time convention: gyroscope sample `k` is the mean rate over `(t_{k−1}, t_k]` (the interval
//! over which the prediction turns the state with it), so the difference quotient of the field
//! and the span rotation of lag `j` are centred on the same instant when `L = j·dt`: there is no
//! half-sample offset. (For a gyroscope that samples the rate at `t_k` instead, the estimate is
//! the magnetometer's latency plus half a sample, which is the latency the compensation then
//! needs.)
//!
//! Choices (see docs/accuracy.md for the measurements behind them):
//! - lags `0 … W` and the span `s = W`, `W` = 40 ms in samples (rounded up), at least 2 and at
//!   most 32: a single consecutive difference (`s = 1`) amplifies the magnetometer's noise by
//!   `1/dt` and its product with the gyroscope's noise does not average out across lags; a
//!   40 ms span cut the scatter of the estimate by 3–10× on the simulated IMU;
//! - weight of a pair `w = g²/(g² + g₀²)`, `g = |(ω_k − ω_{k−W}) × m̂| / (W·dt)` the change of the
//!   rate across the lags perpendicular to the field (rad/s²), `g₀` = 1 rad/s²: lags are told
//!   apart only by a changing rate (a constant rotation fits every lag), so still or steadily
//!   turning samples carry little weight, and the forgetting advances with the weight: the
//!   memory is [`MEMORY`] seconds of informative motion, not of time;
//! - the estimate exists once [`MIN_EVIDENCE`] weighted seconds have been seen and the
//!   parabola is convex; only pairs whose samples both passed the AHRS's magnetic disturbance
//!   test are used (the relation needs a homogeneous field).

use super::vec3::{cross3, dot3, scale3};
use crate::quaternion::q4;

/// The lag window and span in seconds (rounded up to whole samples).
const WINDOW_TIME: f64 = 0.04;
/// The largest lag window and span in samples.
const MAX_WINDOW: usize = 32;
/// Ring length: lags `0 … MAX_WINDOW`.
const RING: usize = MAX_WINDOW + 1;
/// Memory of the forgotten sums, in seconds of informative motion (weight 1).
pub(super) const MEMORY: f64 = 30.0;
/// The weighted seconds of motion needed before there is an estimate.
pub(super) const MIN_EVIDENCE: f64 = 5.0;
/// The rate change (rad/s²) across the lag window at which a pair has half weight.
const RATE_CHANGE_REF: f64 = 1.0;
/// `cos(1)`: spans that turn by more than 2 rad (`Q_w` below it) are not used (`tan(angle/2)` of
/// the Cayley form grows without bound toward half a turn).
const MIN_SPAN_COS_HALF: f64 = 0.540_302_305_868_139_8;

/// `v` turned forward by the rotation vector `w·lead` (`w` the bias-corrected gyroscope
/// increment of the sample, `lead` = latency / sample time): the sample as it would read at
/// the end of its gyroscope interval, `exp(−[w·lead]×) v`. Exactly `v` for `lead = 0`.
pub(super) fn turn_forward(v: &[f64; 3], w: &[f64; 3], lead: f64) -> [f64; 3] {
    if lead == 0.0 {
        return *v;
    }
    q4::rotate_inverse(&q4::from_rotation_vector(&scale3(w, lead)), v)
}

/// The online estimator of the magnetometer's latency (fixed size, no allocation).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct LatencyEstimator {
    /// `W`: lags `0 … W`, span `W` samples; the rings hold `W + 1` entries.
    window: usize,
    dt: f64,
    /// The forgetting per unit weight, `dt / MEMORY`.
    forget: f64,
    /// The gyroscope increments composed since the start (or the last reset), unit.
    orient: [f64; 4],
    /// Per sample `i` of the last `W + 1`: the composed orientation, the span rate
    /// `φ_i/(W·dt)` and the magnetometer sample (`None`: absent or disturbed).
    ring_orient: [[f64; 4]; RING],
    ring_rate: [[f64; 3]; RING],
    ring_mag: [Option<[f64; 3]>; RING],
    /// The newest entry.
    head: usize,
    /// Consecutive samples pushed since the last reset (saturating).
    pushed: usize,
    /// `S_j`, the forgotten weighted mean of `|r_j|²/|m̄|²` ((rad/s)²).
    sums: [f64; RING],
    /// Weighted seconds of motion seen (`Σ w·dt`).
    evidence: f64,
}

impl LatencyEstimator {
    /// An empty estimator for the sample time `dt` (s).
    pub(super) fn new(dt: f64) -> LatencyEstimator {
        let window = ((WINDOW_TIME / dt) - 1e-9)
            .ceil()
            .clamp(2.0, MAX_WINDOW as f64) as usize;
        LatencyEstimator {
            window,
            dt,
            forget: dt / MEMORY,
            orient: [1.0, 0.0, 0.0, 0.0],
            ring_orient: [[1.0, 0.0, 0.0, 0.0]; RING],
            ring_rate: [[0.0; 3]; RING],
            ring_mag: [None; RING],
            head: 0,
            pushed: 0,
            sums: [0.0; RING],
            evidence: 0.0,
        }
    }

    /// One sample: `dq` the bias-corrected gyroscope increment the prediction used, `mag` the
    /// raw magnetometer sample if it passed the disturbance test.
    pub(super) fn push(&mut self, dq: &[f64; 4], mag: Option<&[f64; 3]>) {
        let len = self.window + 1;
        let o = q4::mul(&self.orient, dq);
        let n = dot4(&o, &o).sqrt();
        if !(n.is_finite() && n > 0.0) {
            // an increment that cannot be composed: start over
            self.orient = [1.0, 0.0, 0.0, 0.0];
            self.pushed = 0;
            return;
        }
        self.orient = [o[0] / n, o[1] / n, o[2] / n, o[3] / n];
        self.head = next(self.head, len);
        let head = self.head;
        let oldest = next(head, len); // sample k − W
        self.ring_orient[head] = self.orient;
        self.ring_mag[head] = mag.copied();
        self.pushed = (self.pushed + 1).min(2 * len);
        if self.pushed < len {
            return;
        }
        // The span rotation from k − W to k and its Cayley vector, as a rate.
        let q = q4::mul(&q4::conj(&self.ring_orient[oldest]), &self.orient);
        let span = self.window as f64 * self.dt;
        if !(q[0].is_finite() && q[0] >= MIN_SPAN_COS_HALF) {
            self.pushed = 0;
            return;
        }
        let c = 2.0 / (q[0] * span);
        self.ring_rate[head] = [q[1] * c, q[2] * c, q[3] * c];
        if self.pushed < 2 * len {
            return; // the rates of lags up to W are not all there yet
        }
        if let (Some(m1), Some(m0)) = (self.ring_mag[head], self.ring_mag[oldest]) {
            self.accumulate(&m1, &m0, span);
        }
    }

    /// Adds the residuals of the pair `(m_k, m_{k−W})`.
    fn accumulate(&mut self, m1: &[f64; 3], m0: &[f64; 3], span: f64) {
        let len = self.window + 1;
        let head = self.head;
        let d = [
            (m1[0] - m0[0]) / span,
            (m1[1] - m0[1]) / span,
            (m1[2] - m0[2]) / span,
        ];
        let mb = [
            0.5 * (m1[0] + m0[0]),
            0.5 * (m1[1] + m0[1]),
            0.5 * (m1[2] + m0[2]),
        ];
        let n2 = dot3(&mb, &mb);
        if !(n2.is_finite() && n2 > 0.0) {
            return;
        }
        let inv_n2 = 1.0 / n2;
        // the weight: the rate change across the lags, perpendicular to the field
        let newest = self.ring_rate[head];
        let oldest = self.ring_rate[next(head, len)];
        let dr = [
            newest[0] - oldest[0],
            newest[1] - oldest[1],
            newest[2] - oldest[2],
        ];
        let gv = cross3(&dr, &mb);
        let g2 = dot3(&gv, &gv) * inv_n2 / (span * span);
        let w = g2 / (g2 + RATE_CHANGE_REF * RATE_CHANGE_REF);
        if !(w.is_finite() && w > 0.0) {
            return;
        }
        let mut e = [0.0; RING];
        let mut idx = head; // lag j: sample k − j
        for ej in e.iter_mut().take(len) {
            let x = cross3(&self.ring_rate[idx], &mb);
            let r = [d[0] + x[0], d[1] + x[1], d[2] + x[2]];
            *ej = dot3(&r, &r) * inv_n2;
            idx = if idx == 0 { len - 1 } else { idx - 1 };
        }
        if !e[..len].iter().all(|v| v.is_finite()) {
            return;
        }
        let a = self.forget * w;
        for (s, ej) in self.sums.iter_mut().zip(&e).take(len) {
            *s += a * (ej - *s);
        }
        self.evidence += w * self.dt;
    }

    /// The latency estimate (s, within 0 … `W·dt`), once [`MIN_EVIDENCE`] weighted seconds have
    /// been seen and the sums single out a lag (a convex parabola at the smallest).
    pub(super) fn estimate(&self) -> Option<f64> {
        if self.evidence < MIN_EVIDENCE {
            return None;
        }
        let s = &self.sums[..=self.window];
        let (mut best, mut min) = (0, f64::INFINITY);
        for (j, &v) in s.iter().enumerate() {
            if v < min {
                (best, min) = (j, v);
            }
        }
        let i = best.clamp(1, self.window - 1);
        let (y0, y1, y2) = (s[i - 1], s[i], s[i + 1]);
        let den = y0 - 2.0 * y1 + y2;
        if !(den > 0.0 && den.is_finite()) {
            return None;
        }
        let x = i as f64 + 0.5 * (y0 - y2) / den;
        Some(x.clamp(0.0, self.window as f64) * self.dt)
    }

    /// Why [`estimate`](Self::estimate) gives none (a message for the C API).
    pub(super) fn why_none(&self) -> String {
        if self.evidence < MIN_EVIDENCE {
            format!(
                "no magnetometer latency estimate yet: {:.2} s of informative motion (a changing \
                 rotation rate in an undisturbed field) seen, {MIN_EVIDENCE} s needed",
                self.evidence
            )
        } else {
            "no magnetometer latency estimate: the residuals do not single out a lag".into()
        }
    }
}

/// The ring index after `i` (ring length `len`).
fn next(i: usize, len: usize) -> usize {
    if i + 1 == len {
        0
    } else {
        i + 1
    }
}

fn dot4(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]
}
