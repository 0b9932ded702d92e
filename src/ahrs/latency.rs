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
//! - lags `0 … W` and the span `s = W`, `W` = 40 ms in samples (rounded up to an even number,
//!   see the estimate's uncertainty below), at least 2 and at most 32: a single consecutive
//!   difference (`s = 1`) amplifies the magnetometer's noise by `1/dt` and its product with
//!   the gyroscope's noise does not average out across lags; a 40 ms span cut the scatter of
//!   the estimate 6× (100 Hz) to 18× (286 Hz) on the simulated IMU;
//! - weight of a pair `w = g²/(g² + g₀²)`, `g = |(ω_k − ω_{k−W}) × m̂| / (W·dt)` the change of the
//!   rate across the lags perpendicular to the field (rad/s²), `g₀` = 1 rad/s²: lags are told
//!   apart only by a changing rate (a constant rotation fits every lag), so still or steadily
//!   turning samples carry little weight, and the forgetting advances with the weight: the
//!   memory is [`MEMORY`] seconds of informative motion, not of time;
//! - the estimate exists once [`MIN_EVIDENCE`] weighted seconds have been seen and the
//!   parabola is convex; only pairs whose samples both passed the AHRS's magnetic disturbance
//!   test are used (the relation needs a homogeneous field);
//! - the estimate's uncertainty, and what is compensated: consecutive pairs go alternately into
//!   two halves of the sums (each forgetting twice as fast, so that their mean remembers what
//!   one sum did). The span `W` is even, so a magnetometer sample's two pairs (`k` and `k + W`)
//!   are in the same half and the halves share none of the magnetometer's noise, which is what
//!   scatters the estimate (without it the scatter on the simulated IMU is 0.1 ms or less,
//!   with or without the gyroscope's); the squared difference of their vertices,
//!   `(L_A − L_B)²`, taken every [`BLOCK_TIME`] and averaged over [`MEMORY`] seconds, is then
//!   four times the variance `σ²` of the estimate `L` (the vertex of their mean). It errs on
//!   the safe side: on the simulated `spin4_latency10` over six seeds a first version (the
//!   halves' own vertices, not linearized) read 0.4–1.1 ms where the estimates scatter by about
//!   0.4 ms; at four times the magnetometer's noise the linearized one reads about 2.6 ms
//!   (median) where the estimates' RMS error is 2.3 ms. What is compensated (and reported) is
//!   `L·max(0, 1 − σ²/L²)`: `E[L²] = L_true² + σ²`, so `L² − σ²` estimates `L_true²` without
//!   bias, and the shrinkage `L_true²/(L_true² + σ²)` that minimizes the compensation's mean
//!   square error becomes `1 − σ²/L²` (none when the scatter explains the whole estimate).
//!   Without it a steady spin, whose pairs carry little weight, compensated the scatter of an
//!   estimate that reads ±1–2 ms on a stream without latency (the simulated
//!   `reject180_nomag`; docs/accuracy/ahrs.md); a latency measured well (BROAD's 12 ms) is not
//!   changed by it.

use super::lowpass::CORRECTION_PERIOD;
use super::vec3::{cross3, dot3, scale3};
use crate::quaternion::q4;

/// The lag window and span in seconds (rounded up to whole samples).
const WINDOW_TIME: f64 = 0.04;
/// The largest lag window and span in samples.
const MAX_WINDOW: usize = 32;
/// Ring length: lags `0 … MAX_WINDOW`.
const RING: usize = MAX_WINDOW + 1;
/// Memory of the forgotten sums, in seconds of informative motion (weight 1).
const MEMORY: f64 = 30.0;
/// How often (s) the halves' vertices update the estimate's scatter (module documentation,
/// "the estimate's uncertainty").
const BLOCK_TIME: f64 = 1.0;
/// How often (s) the estimate the compensation turns the field samples by is refitted: once a
/// correction period ([`CORRECTION_PERIOD`]), not at every sample. The fit reads every lag's
/// sums (a tenth of a sample's work at 1 kHz); the sums forget over [`MEMORY`] seconds, so
/// the estimate moves by a small fraction of its scatter in a period, and the field samples
/// of one period all take one latency. A reader ([`LatencyEstimator::estimate`]) gets the fit
/// of the sums as they are.
const REFIT_TIME: f64 = CORRECTION_PERIOD;
/// The weighted seconds of motion needed before there is an estimate.
const MIN_EVIDENCE: f64 = 5.0;
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
    /// `W`: lags `0 … W`, span `W` samples; the rings hold `len = W + 1` entries (slots), the
    /// newest in slot `head`, the sample `k − j` in slot `head − j` (mod `len`).
    window: usize,
    dt: f64,
    /// The forgetting per unit weight, `dt / MEMORY`.
    forget: f64,
    /// The gyroscope increments composed since the start (or the last reset), unit.
    orient: [f64; 4],
    /// Per slot: the composed orientation, the magnetometer sample (valid where its bit in
    /// `mag_valid` is set: present and undisturbed) and the span rate `φ_i/(W·dt)` (one array
    /// per component, so that the loop over the lags is over contiguous memory).
    ring_orient: [[f64; 4]; RING],
    ring_mag: [[f64; 3]; RING],
    mag_valid: u64,
    ring_rate: [[f64; RING]; 3],
    head: usize,
    /// Consecutive samples pushed since the last reset (saturating at `2·len`).
    pushed: usize,
    /// The forgotten weighted means of `|r_j|²/|m̄|²` ((rad/s)²) by slot offset: `sums[u]` is
    /// `S_j` of the lag `j = W − u`, so that slots `head + 1 …` and `sums[0 …]` both ascend.
    sums: [[f64; RING]; 2],
    /// Weighted seconds of motion seen (`Σ w·dt`).
    evidence: f64,
    /// Samples pushed since the scatter's last update, and the half the current sample's pair
    /// goes to.
    block_samples: usize,
    half: usize,
    /// The mean of `(L_A − L_B)²` (s²) over the blocks, and the blocks averaged so far.
    scatter: f64,
    blocks: f64,
    /// [`LatencyEstimator::estimate`] as of the last refit ([`REFIT_TIME`]): what the
    /// compensation reads at every sample.
    current: Option<f64>,
    /// Whether the sums, the evidence or the scatter changed in this push.
    changed: bool,
    /// Whether they changed since the last refit, the pushes since it, and the pushes between
    /// refits (`REFIT_TIME / dt`, rounded, at least 1).
    stale: bool,
    since_refit: usize,
    refit_every: usize,
}

impl LatencyEstimator {
    /// An empty estimator for the sample time `dt` (s).
    pub(super) fn new(dt: f64) -> LatencyEstimator {
        let window = ((WINDOW_TIME / dt) - 1e-9)
            .ceil()
            .clamp(2.0, MAX_WINDOW as f64) as usize;
        // even (MAX_WINDOW is): the halves then share no magnetometer sample
        let window = window + window % 2;
        LatencyEstimator {
            window,
            dt,
            forget: dt / MEMORY,
            orient: [1.0, 0.0, 0.0, 0.0],
            ring_orient: [[1.0, 0.0, 0.0, 0.0]; RING],
            ring_mag: [[0.0; 3]; RING],
            mag_valid: 0,
            ring_rate: [[0.0; RING]; 3],
            head: 0,
            pushed: 0,
            sums: [[0.0; RING]; 2],
            evidence: 0.0,
            block_samples: 0,
            half: 0,
            scatter: 0.0,
            blocks: 0.0,
            current: None,
            changed: false,
            stale: false,
            since_refit: 0,
            refit_every: ((REFIT_TIME / dt).round() as usize).max(1),
        }
    }

    /// One sample: `dq` the bias-corrected gyroscope increment the prediction used, `mag` the
    /// raw magnetometer sample if it passed the disturbance test.
    pub(super) fn push(&mut self, dq: &[f64; 4], mag: Option<&[f64; 3]>) {
        self.changed = false;
        self.push_sample(dq, mag);
        self.stale |= self.changed;
        self.since_refit += 1;
        if self.stale && self.since_refit >= self.refit_every {
            self.current = self.compute_estimate();
            self.stale = false;
            self.since_refit = 0;
        }
    }

    /// [`LatencyEstimator::push`] without the estimate's update.
    fn push_sample(&mut self, dq: &[f64; 4], mag: Option<&[f64; 3]>) {
        self.block_samples += 1;
        // consecutive pairs alternate between the halves: with an even span, the two pairs a
        // magnetometer sample is in (k and k + W) fall into the same half
        self.half = 1 - self.half;
        if self.block_samples as f64 * self.dt >= BLOCK_TIME {
            self.end_block();
        }
        let len = self.window + 1;
        let o = q4::mul(&self.orient, dq);
        // back to unit length (one Newton step for 1/|o|: the increments are unit to rounding,
        // and the Cayley vector below does not depend on the scale anyway)
        let k = 1.5 - 0.5 * dot4(&o, &o);
        if !(k.is_finite() && k > 0.0) {
            // an increment that cannot be composed: start over
            self.orient = [1.0, 0.0, 0.0, 0.0];
            self.pushed = 0;
            return;
        }
        self.orient = [o[0] * k, o[1] * k, o[2] * k, o[3] * k];
        self.head = next(self.head, len);
        let head = self.head;
        let oldest = next(head, len); // sample k − W
        self.ring_orient[head] = self.orient;
        match mag {
            Some(m) => {
                self.ring_mag[head] = *m;
                self.mag_valid |= 1 << head;
            }
            None => self.mag_valid &= !(1 << head),
        }
        self.pushed = (self.pushed + 1).min(2 * len);
        if self.pushed < len {
            return;
        }
        // The span rotation from k − W to k and its Cayley vector, as a rate (at most
        // 2 tan(1)/span: finite and bounded).
        let q = q4::mul(&q4::conj(&self.ring_orient[oldest]), &self.orient);
        let span = self.window as f64 * self.dt;
        if !(q[0].is_finite() && q[0] >= MIN_SPAN_COS_HALF) {
            self.pushed = 0;
            return;
        }
        let c = 2.0 / (q[0] * span);
        for (ring, v) in self.ring_rate.iter_mut().zip(&q[1..]) {
            ring[head] = v * c;
        }
        if self.pushed < 2 * len {
            return; // the rates of lags up to W are not all there yet
        }
        let both = (1 << head) | (1 << oldest);
        if self.mag_valid & both == both {
            let (m1, m0) = (self.ring_mag[head], self.ring_mag[oldest]);
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
        // A finite field whose change over the span is at most 1e8 times its mean per second
        // (anything else is no rotation of a field): then every residual below is finite.
        if !(n2.is_finite() && n2 > 0.0 && dot3(&d, &d) <= 1e16 * n2) {
            return;
        }
        let inv_n2 = 1.0 / n2;
        // the weight: the rate change across the lags, perpendicular to the field
        let oldest = next(head, len);
        let [rx, ry, rz] = &self.ring_rate;
        let dr = [
            rx[head] - rx[oldest],
            ry[head] - ry[oldest],
            rz[head] - rz[oldest],
        ];
        let gv = cross3(&dr, &mb);
        let g2 = dot3(&gv, &gv) * inv_n2 / (span * span);
        let w = g2 / (g2 + RATE_CHANGE_REF * RATE_CHANGE_REF);
        if !(w.is_finite() && w > 0.0) {
            return;
        }
        // each half forgets twice as fast: it receives half of the pairs
        let a = 2.0 * self.forget * w;
        // slots head + 1 … len − 1 are the lags W … head + 1 (sums[0 …]), slots 0 … head the
        // lags head … 0 (the rest of sums)
        let (lower, upper) = self.sums[self.half][..len].split_at_mut(len - 1 - head);
        let r =
            |range: std::ops::Range<usize>| (&rx[range.clone()], &ry[range.clone()], &rz[range]);
        accumulate_lags(lower, r(head + 1..len), &d, &mb, inv_n2, a);
        accumulate_lags(upper, r(0..head + 1), &d, &mb, inv_n2, a);
        self.evidence += w * self.dt;
        self.changed = true;
    }

    /// Every [`BLOCK_TIME`]: the halves' vertices update the scatter. Each half's vertex is
    /// taken at the mean's parabola, linearized (`i + ½ (s_h(i−1) − s_h(i+1))/den`, with the
    /// mean's lag `i` and curvature `den`), so that the difference of the halves is the noise of
    /// the mean's vertex and not the jumps of a noisier half's own smallest lag.
    fn end_block(&mut self) {
        self.block_samples = 0;
        if self.evidence < MIN_EVIDENCE {
            return;
        }
        let w = self.window;
        let Some((_, i, den)) = self.fit() else {
            return;
        };
        let slope = |h: usize| self.sums[h][w - (i - 1)] - self.sums[h][w - (i + 1)];
        let d = 0.5 * (slope(0) - slope(1)) / den * self.dt;
        if d.is_finite() {
            self.blocks += 1.0;
            // a running mean until MEMORY seconds of blocks, then exponential forgetting
            let alpha = (1.0 / self.blocks).max(BLOCK_TIME / MEMORY);
            self.scatter += alpha * (d * d - self.scatter);
            self.changed = true;
        }
    }

    /// The parabola through the smallest of the halves' mean `s(j) = ½(S_A(j) + S_B(j))` (lag
    /// `j`) and its neighbours: its vertex (s), not clamped (it may lie up to a lag beyond
    /// `0 … W·dt`), the middle lag `i` and the second difference `den`; `None` if it is not
    /// convex there.
    fn fit(&self) -> Option<(f64, usize, f64)> {
        let w = self.window;
        // s(j) for j = 0 … W, from sums[W − j], formed once per fit
        let mut s = [0.0; RING];
        for (j, v) in s[..=w].iter_mut().enumerate() {
            *v = 0.5 * (self.sums[0][w - j] + self.sums[1][w - j]);
        }
        let (mut best, mut min) = (0, f64::INFINITY);
        for (j, &v) in s[..=w].iter().enumerate() {
            if v < min {
                (best, min) = (j, v);
            }
        }
        let i = best.clamp(1, w - 1);
        let (y0, y1, y2) = (s[i - 1], s[i], s[i + 1]);
        let den = y0 - 2.0 * y1 + y2;
        if !(den > 0.0 && den.is_finite()) {
            return None;
        }
        let x = i as f64 + 0.5 * (y0 - y2) / den;
        Some((x * self.dt, i, den))
    }

    /// The latency estimate (s, within 0 … `W·dt`), once [`MIN_EVIDENCE`] weighted seconds have
    /// been seen and the sums single out a lag (a convex parabola at the smallest): the vertex
    /// `L` of the two halves' mean, shrunk by its scatter to `L·max(0, 1 − σ²/L²)` (module
    /// documentation), from the sums as they are.
    pub(super) fn estimate(&self) -> Option<f64> {
        self.compute_estimate()
    }

    /// [`LatencyEstimator::estimate`] as of the last refit, at most [`REFIT_TIME`] old: what
    /// the compensation turns the field samples by.
    pub(super) fn compensated(&self) -> Option<f64> {
        self.current
    }

    /// [`LatencyEstimator::estimate`] from the sums, the evidence and the scatter.
    fn compute_estimate(&self) -> Option<f64> {
        if self.evidence < MIN_EVIDENCE {
            return None;
        }
        let w = self.window;
        let (l, _, _) = self.fit()?;
        let var = 0.25 * self.scatter;
        // E[L²] = L_true² + σ²: L² − σ² estimates L_true² without bias, and the shrinkage
        // L_true²/(L_true² + σ²) that minimizes the compensation's mean square error becomes
        // (L² − σ²)/L² (positive part: none when the scatter explains the whole estimate)
        let shrunk = if l * l > var {
            l * (1.0 - var / (l * l))
        } else {
            0.0
        };
        Some(shrunk.clamp(0.0, w as f64 * self.dt))
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

/// `S ← S + a·(|d + rate × m|²/|m|² − S)` for the lags of one contiguous run of slots.
fn accumulate_lags(
    sums: &mut [f64],
    (rx, ry, rz): (&[f64], &[f64], &[f64]),
    d: &[f64; 3],
    m: &[f64; 3],
    inv_n2: f64,
    a: f64,
) {
    for (((s, &x), &y), &z) in sums.iter_mut().zip(rx).zip(ry).zip(rz) {
        let r0 = d[0] + (y * m[2] - z * m[1]);
        let r1 = d[1] + (z * m[0] - x * m[2]);
        let r2 = d[2] + (x * m[1] - y * m[0]);
        let e = (r0 * r0 + r1 * r1 + r2 * r2) * inv_n2;
        *s += a * (e - *s);
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
