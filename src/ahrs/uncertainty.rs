//! The stated uncertainty of the orientation: the Bingham state's covariance in the units the
//! sensors show, tilt and heading apart.
//!
//! The Bingham state's concentrations come from the noise parameters (`gyro_noise`,
//! `acc_noise`, `mag_noise`, ...), which are one set for every sensor and recording. They set
//! how the filter weighs the sensors against each other (its gain), but not how large the
//! errors are: a clean sensor has errors many times smaller than the defaults assume, a
//! rough recording larger ones. In a linear-Gaussian filter, multiplying every noise
//! variance by one factor `s` leaves the gain and the estimate unchanged and multiplies every
//! covariance by `s`; and the innovations measure `s`: the normalized innovation squared per
//! degree of freedom (module `health`), over its mean when the model holds (`expected_nis` in
//! module `health`: the low-passed measurement's error is correlated with the state that
//! followed it), has mean `s` when the true noises are `s` times the model's. So the AHRS
//! states the covariance of the filter with its noises scaled by the innovations' own average,
//! tilt and heading apart (the accelerometer and the magnetometer are different sensors with
//! different errors): `s_t` and `s_h`, averages of those ratios over [`CALIBRATION_TIME`],
//! blended in from 1 over [`STARTUP_TIME`] of corrections. An innovation enters those averages
//! with the same blend's weight: while the state settles, its innovations show its start (a
//! bias being learned, the first seconds' error), not the noises' scale, and at full weight
//! they would hold the stated spread up for the averages' whole memory after the start. The
//! estimate does not change; the stated spread does.
//!
//! A principal direction `u` of the state (world frame) takes the factor
//! `s(u) = s_t (1 − u_z²) + s_h u_z²`, the share of its variance in tilt and in heading.
//!
//! What the innovations cannot show is an error the sensors share with the state. The tilt's
//! reference is the low-passed specific force, which the state follows: what linear
//! acceleration has not averaged out, and an accelerometer's scale and offset errors, tilt
//! the state with it. The accelerometer shows such an error in what it can see — the
//! low-passed norm's deviation from gravity — and an error with no preferred direction is as
//! large across the vertical (tilt) as along it (norm), and the state follows it as far as the
//! evidence it gives counts (the rejection divides that by `1 + x²`, `x = (|ā| − g)/acc_reject`):
//! each horizontal axis's variance gains the mean over [`CALIBRATION_TIME`] of the squared
//! relative deviation `((|ā| − g)/g)²` times that weight squared.
//!
//! Likewise the heading's reference is the local magnetic field, which indoors deviates from
//! the Earth's by degrees from place to place; the state follows the local field, so the
//! innovations stay small while the heading is off by the deviation. The magnetometer shows the field's
//! inhomogeneity in what it can see — the changes of the field's dip and norm as the sensor
//! moves — and a deviation with no preferred direction is as large in the horizontal
//! direction (heading) as in the vertical (dip) and along the field (norm). So the heading's
//! variance gains the field's directional variance ([`Inhomogeneity`]: the variance over
//! [`CALIBRATION_TIME`] of the dip and of the relative norm, each smoothed over
//! [`SMOOTH_TIME`] so that the sensor's white noise does not count), over `cos²(dip)` (a
//! horizontal deviation `δ` turns the heading by `δ/(|m| cos dip)`), or the field's deviation
//! now where that is larger ([`Inhomogeneity::evidence_variance`]). The dip is measured
//! against the state's "up", so its variance also holds the state's own tilt error; the
//! stated covariance takes the dip's variance less the average stated tilt variance
//! ([`Inhomogeneity::field_variance`]), because it carries that error itself, as follows.
//!
//! The heading the magnetometer gives is the azimuth of the averaged field mapped to the world
//! with the state's tilt, and a tilt error `φ_y` about north (the reference field's horizontal
//! direction, world y) turns that azimuth: the heading the filter settles on is off by
//! `tan(dip)·φ_y` beyond what its heading evidence shows (`dip` above the horizon: a field
//! pointing down, as in the northern hemisphere, gives `−tan|dip|`). The filter's own
//! covariance takes the heading evidence as independent of the tilt; the stated one is
//! `A C Aᵀ`, `A = I + tan(dip) e_z e_yᵀ` (2.1 at a dip of 65°: a tilt error there is twice as
//! large in the heading), for a tilt error that changes slower than the heading's average: the
//! tilt reference's steady part, the squared mean of the norm's deviation (an accelerometer's
//! offset or scale error, which tilts the state unseen by the innovations). The filter's own
//! tilt error is correlated over about the tilt average's `acc_tau`, and so is what varies
//! with the motion about that mean; of such an error the heading's average over `mag_tau`
//! passes only the share `f = acc_tau/(acc_tau + mag_tau)` (1/3 by default): `(1 − f) C +
//! f A C Aᵀ` ([`Coupling`]).
//!
//! Two parts of the filter's covariance are not white noise in the parameters' units, so the
//! innovations' factor does not describe them and they are stated at their size: the variance
//! gyroscope gaps add ([`Parts::gap`]), and the part the gyroscope's scale error explains
//! ([`Parts::scale_root`]), a constant of the sensor whose prior the corrections barely narrow:
//! the heading drift it brings in a long magnetic rejection is as large as that prior says,
//! however clean the sensor's noises are.

use nalgebra::{Matrix3, Vector3};

use super::health::{Average, Innovations};

/// The time constant (s) of the innovation averages that scale the stated covariance: long
/// enough to hold hundreds of corrections' worth of independent innovations (the tilt's and
/// heading's low-pass averages decorrelate within a few seconds), short enough to follow a
/// change of the motion (a walk, then a run) within a minute.
pub(super) const CALIBRATION_TIME: f64 = 30.0;

/// The time constant (s) over which the norm and dip are smoothed before their variation
/// counts as the field's inhomogeneity: the sensor's white noise averages out over it (50
/// samples at 50 Hz), while the changes of the field with the position, which a hand-held or
/// robot-borne sensor crosses at up to a few metres per second over structures of a metre or
/// more, take longer.
pub(super) const SMOOTH_TIME: f64 = 1.0;

/// The time (s) over which the variance factor moves from 1 (the model's own spread) to the
/// innovations' average. Their average measures the noises' scale once the state has settled
/// to the steady state its gain implies: after a start, or while a bias of degrees per second
/// is being learned, the innovations show the start, and the state's error is still what the
/// model's initial spread says. The state settles within a few of the accelerometer's and the
/// magnetometer's averaging times (`acc_tau` 1.5 s, `mag_tau` 3 s).
const STARTUP_TIME: f64 = 5.0;

/// The smallest and the largest variance factor: a state whose innovations vanish (a
/// simulated, noise-free stream) keeps a hundredth of its modelled spread; a model a hundred
/// times too optimistic is a wrong input, which the health readout flags.
const MIN_SCALE: f64 = 1e-4;
const MAX_SCALE: f64 = 1e4;

/// The running averages of the innovations, part of the AHRS's per-sample state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct Calibration {
    tilt: Average,
    heading: Average,
    /// The seconds of corrections each average has seen.
    tilt_time: f64,
    heading_time: f64,
    /// [`Calibration::scales`] as of the last correction (`None` before the first), so that a
    /// readout between corrections does not recompute it.
    cached: Option<(f64, f64)>,
    /// The low-passed accelerometer's squared relative deviation from gravity.
    gravity: Average,
    /// The low-passed accelerometer's relative deviation from gravity.
    gravity_mean: Average,
}

impl Calibration {
    /// The innovations of one correction of period `t` (s), and the low-passed
    /// accelerometer's relative deviation from gravity `(|ā| − g)/g`, weighted as its evidence
    /// (module documentation), if it observed the tilt.
    pub(super) fn correction(&mut self, t: f64, nu: &Innovations, gravity_dev: Option<f64>) {
        let alpha = (t / CALIBRATION_TIME).min(1.0);
        if let Some(x) = gravity_dev {
            self.gravity.push(x * x, alpha);
            self.gravity_mean.push(x, alpha);
        }
        let settled = |time: f64| 1.0 - (-time / STARTUP_TIME).exp();
        if let Some(x) = nu.tilt_scale {
            self.tilt_time += t;
            self.tilt.push(x, alpha * settled(self.tilt_time));
        }
        if let Some(x) = nu.heading_scale {
            self.heading_time += t;
            self.heading.push(x, alpha * settled(self.heading_time));
        }
        self.cached = Some(self.compute_scales());
    }

    /// The variance factors `(s_t, s_h)`: 1 before the sensor's first innovation, then
    /// moving to the innovations' average over [`STARTUP_TIME`] (module documentation).
    pub(super) fn scales(&self) -> (f64, f64) {
        self.cached.unwrap_or((1.0, 1.0))
    }

    /// [`Calibration::scales`] from the averages.
    fn compute_scales(&self) -> (f64, f64) {
        let s = |a: &Average, time: f64| {
            if a.is_empty() || !a.value().is_finite() {
                1.0
            } else {
                let w = 1.0 - (-time / STARTUP_TIME).exp();
                (1.0 - w + w * a.value()).clamp(MIN_SCALE, MAX_SCALE)
            }
        };
        (
            s(&self.tilt, self.tilt_time),
            s(&self.heading, self.heading_time),
        )
    }

    /// The variance (rad² per horizontal axis) of the tilt reference's error: the mean
    /// squared relative deviation of the low-passed accelerometer's norm from gravity (module
    /// documentation).
    pub(super) fn tilt_reference_variance(&self) -> f64 {
        self.gravity.value()
    }

    /// The part of [`Calibration::tilt_reference_variance`] that is steady: the squared mean
    /// deviation (an accelerometer's offset and scale error at the motion's attitudes); the
    /// rest varies about it with the motion.
    pub(super) fn steady_tilt_reference_variance(&self) -> f64 {
        let m = self.gravity_mean.value();
        (m * m).min(self.gravity.value())
    }
}

/// What the stated covariance is made of (module documentation), besides the principal
/// directions: the filter's variances along them, the factors, the references' variances and
/// the gaps' variance.
pub(super) struct Parts {
    /// The filter's variances (rad²) along the principal directions (`4 ω_i`).
    pub(super) var: [f64; 3],
    /// The innovations' factors `(s_t, s_h)` ([`Calibration::scales`]).
    pub(super) scales: (f64, f64),
    /// The tilt reference's variance (rad² per horizontal axis).
    pub(super) tilt_ref: f64,
    /// Its steady part ([`Calibration::steady_tilt_reference_variance`]: from 0 to `tilt_ref`).
    pub(super) tilt_ref_steady: f64,
    /// The heading reference's variance (rad²).
    pub(super) heading_ref: f64,
    /// The variance (rad² per axis) that gyroscope gaps have added: physical, in the filter's
    /// covariance unscaled, so stated as it is, not scaled.
    pub(super) gap: f64,
    /// A root `X` of the part `XᵀX` of the filter's covariance (rad², body frame) that the
    /// gyroscope's scale error explains (`BiasState::scale_root`): one constant of the sensor,
    /// so stated unscaled, as the gaps' variance is.
    pub(super) scale_root: Matrix3<f64>,
    /// The heading's coupling to the tilt ([`Coupling::NONE`] for the covariance of the errors
    /// the filter models).
    pub(super) coupling: Coupling,
}

impl Parts {
    /// The factor `s_t (1 − u_z²) + s_h u_z²` of a world-frame unit direction `u` whose
    /// vertical component squared is `z2`.
    fn scale_along(&self, z2: f64) -> f64 {
        let (st, sh) = self.scales;
        let z2 = z2.min(1.0);
        st * (1.0 - z2) + sh * z2
    }
}

/// The stated variances along the principal directions, from their world-frame vertical
/// components `z`, the pending noise's variances along them `noise` and the scale error's part
/// `scale` (rad², [`Parts::scale_root`]'s part along them): `v_i = s_i (var_i + noise_i) + (1 − s_i)
/// (gap + scale_i) + heading_ref z_i² + tilt_ref (1 − z_i²)`, `s_i` the direction's factor
/// (`(1 − s_i)` at least 0: a factor above 1 widens those parts with the rest): the diagonal of
/// [`stated`]'s covariance, in the principal basis, before the heading's coupling to the tilt.
fn stated_variances(z: &[f64; 3], noise: &[f64; 3], scale: &[f64; 3], parts: &Parts) -> [f64; 3] {
    let tilt_ref = parts.tilt_ref;
    std::array::from_fn(|i| {
        let z2 = (z[i] * z[i]).min(1.0);
        let s = parts.scale_along(z2);
        // the gaps' and the scale error's variances are in `var` scaled by s: state them at
        // their physical size
        let g = ((parts.gap + scale[i].max(0.0)) * (1.0 - s)).max(0.0);
        (s * (parts.var[i].max(0.0) + noise[i])).max(0.0)
            + g
            + parts.heading_ref * z2
            + tilt_ref * (1.0 - z2)
    })
}

/// The stated covariance (rad², world frame): `dirs` the principal directions at the mode in
/// the body frame (orthonormal), `r` the mode's rotation (body → world), `extra` the pending
/// process noise in the body frame, `parts` the rest. The pending noise enters in the principal
/// basis scaled as `D^½ Ñ D^½` (a congruence: it stays positive semi-definite); the references'
/// variances about the world axes. With `U` the directions as columns and `K` the covariance in
/// the principal basis (its diagonal [`stated_variances`] without the references, its
/// off-diagonal the pending noise's `(UᵀNU)_ij √(s_i s_j)`), `C = (RU) K (RU)ᵀ` plus the
/// references (`trace = Σ v` of [`stated_variances`]), each with the heading's coupling to the
/// tilt ([`Coupling`]; none: the covariance of the errors the filter models). The quadratic forms of the noise are taken in the body frame
/// (`Uᵀ N U`, what the world frame's `(RU)ᵀ (R N Rᵀ)(RU)` is in exact arithmetic).
pub(super) fn stated(
    r: &Matrix3<f64>,
    dirs: &[Vector3<f64>; 3],
    extra: &Matrix3<f64>,
    parts: &Parts,
) -> Matrix3<f64> {
    let u = Matrix3::from_columns(dirs);
    let n = u.transpose() * extra * u;
    let xu = parts.scale_root * u;
    let m = xu.transpose() * xu;
    let d = r * u;
    let z = [d[(2, 0)], d[(2, 1)], d[(2, 2)]];
    let noise = [n[(0, 0)], n[(1, 1)], n[(2, 2)]];
    let scale = [m[(0, 0)], m[(1, 1)], m[(2, 2)]];
    let v = stated_variances(&z, &noise, &scale, parts);
    let s: [f64; 3] = std::array::from_fn(|i| parts.scale_along(z[i] * z[i]));
    let w: [f64; 3] = std::array::from_fn(|i| (1.0 - s[i]).max(0.0));
    let tilt_ref = parts.tilt_ref;
    let k = Matrix3::from_fn(|i, j| {
        if i == j {
            // the diagonal as stated_variances has it, the references' parts apart
            let z2 = (z[i] * z[i]).min(1.0);
            v[i] - parts.heading_ref * z2 - tilt_ref * (1.0 - z2)
        } else {
            0.5 * (n[(i, j)] + n[(j, i)]) * (s[i] * s[j]).sqrt()
                + 0.5 * (m[(i, j)] + m[(j, i)]) * (w[i] * w[j]).sqrt()
        }
    });
    // the filter's own errors (correlated over about acc_tau), the tilt reference's (its
    // steady part, an accelerometer's offset and scale error, changes slower than the heading's
    // average; what varies with the motion about it, as fast as the filter's own), the heading
    // reference's (a heading error itself: the coupling leaves it as it is)
    let own = parts.coupling.fast(&(d * k * d.transpose()));
    let steady = parts.tilt_ref_steady;
    let varying = tilt_ref - steady;
    let tilt = parts
        .coupling
        .slow(&Matrix3::from_diagonal(&Vector3::new(steady, steady, 0.0)))
        + parts.coupling.fast(&Matrix3::from_diagonal(&Vector3::new(
            varying, varying, 0.0,
        )));
    let mut c = own + tilt;
    c[(2, 2)] += parts.heading_ref;
    c
}

/// `cos²` of 85°, the least `cos²(dip)` by which a heading's variance is divided: the heading
/// reference's variance (module `magnetic`) and the heading's coupling to the tilt
/// ([`heading_per_tilt`]); a field within 5° of the vertical gives no heading.
pub(super) const MIN_COS2_DIP: f64 = 0.0076;

/// `tan` of the reference field's dip `dip` (rad above the horizon): how far a tilt error
/// about north turns the heading the magnetometer gives ([`with_heading_from_tilt`]). The
/// cosine is held at cos 85° or more, as the heading reference's variance holds it (a field
/// within 5° of the vertical gives no heading).
pub(crate) fn heading_per_tilt(dip: f64) -> f64 {
    dip.sin() / dip.cos().max(MIN_COS2_DIP.sqrt())
}

/// The covariance `c` (world frame) of errors the filter models — the tilt and the heading the
/// magnetometer shows — turned into the orientation's: the heading the magnetometer shows is
/// the averaged field's azimuth, which a tilt error `φ_y` about north turns by `−k φ_y` (`k` =
/// `tan` of the field's dip above the horizon), so the heading the filter settles on is off by
/// `k φ_y` more: `φ = A φ_filter`, `A = I + k e_z e_yᵀ`, and `A c Aᵀ` (module documentation).
/// For a tilt error that changes slower than the heading's average.
pub(crate) fn with_heading_from_tilt(c: &Matrix3<f64>, k: f64) -> Matrix3<f64> {
    coupled(c, k, 1.0)
}

/// `c + w (A c Aᵀ − c)`, `A = I + k e_z e_yᵀ`, from `A`'s structure: `(A c Aᵀ)_ij = c_ij +
/// k δ_i2 c_1j + k δ_j2 c_i1 + k² δ_i2 δ_j2 c_11` (rows and columns from 0; nine operations
/// instead of two matrix products).
fn coupled(c: &Matrix3<f64>, k: f64, w: f64) -> Matrix3<f64> {
    let mut out = *c;
    if k == 0.0 || w == 0.0 {
        return out;
    }
    let wk = w * k;
    for j in 0..3 {
        out[(2, j)] += wk * c[(1, j)];
        out[(j, 2)] += wk * c[(j, 1)];
    }
    out[(2, 2)] += wk * k * c[(1, 1)];
    out
}

/// The heading's coupling to the tilt (module documentation): `k` = `tan` of the reference
/// field's dip above the horizon ([`heading_per_tilt`]), and the share `f` of the filter's own
/// tilt error's variance that the heading's average passes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Coupling {
    /// `tan` of the reference field's dip (0: no coupling).
    pub(crate) k: f64,
    /// `acc_tau/(acc_tau + mag_tau)`: the filter's own tilt error is correlated over about the
    /// tilt average's time constant `acc_tau`, and the heading takes the field averaged over
    /// `mag_tau`; a first-order average of time constant `τ_m` passes the share `τ_a/(τ_a + τ_m)`
    /// of the variance of an error correlated over `τ_a` (exponentially), and that share of its
    /// covariance with the error itself.
    pub(crate) fast: f64,
}

/// The coupling of an AHRS's stated covariance as of one moment (module `smoother`: the forward
/// pass's at the handoff, applied to the smoothed covariance): the [`Coupling`] and the tilt
/// reference's steady variance (rad² per horizontal axis), which takes the whole coupling.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct StatedCoupling {
    pub(crate) coupling: Coupling,
    pub(crate) steady: f64,
}

impl StatedCoupling {
    /// No coupling.
    pub(crate) const NONE: StatedCoupling = StatedCoupling {
        coupling: Coupling::NONE,
        steady: 0.0,
    };

    /// A covariance `c` of the errors the filter models, whose tilt reference's steady part is
    /// `steady`, with the coupling: the steady part the whole ([`Coupling::slow`]), the rest
    /// the filter's share ([`Coupling::fast`]). A `c` narrower than the steady part (a product
    /// of two passes, which counts their shared error as independent) keeps as steady at most
    /// its smallest eigenvalue, so that `c − steady` and the result stay positive
    /// semi-definite.
    pub(crate) fn apply(&self, c: &Matrix3<f64>) -> Matrix3<f64> {
        let diag = |v: f64| Matrix3::from_diagonal(&Vector3::new(v, v, 0.0));
        let mut steady = self.steady.max(0.0);
        if steady > 0.0 && (c - diag(steady)).cholesky().is_none() {
            steady = steady.min(c.symmetric_eigenvalues().min().max(0.0));
        }
        let s = diag(steady);
        self.coupling.fast(&(c - s)) + self.coupling.slow(&s)
    }
}

impl Coupling {
    /// No coupling: the covariance of the errors the filter models.
    pub(crate) const NONE: Coupling = Coupling { k: 0.0, fast: 0.0 };

    /// The coupling of a reference dip (rad above the horizon) with the tilt's and the
    /// heading's averaging times `acc_tau`, `mag_tau` (s).
    pub(crate) fn new(dip: f64, acc_tau: f64, mag_tau: f64) -> Coupling {
        let t = acc_tau + mag_tau;
        Coupling {
            k: heading_per_tilt(dip),
            fast: if t > 0.0 { acc_tau / t } else { 1.0 },
        }
    }

    /// A tilt error that changes slower than the heading's average (the references'):
    /// [`with_heading_from_tilt`].
    pub(crate) fn slow(&self, c: &Matrix3<f64>) -> Matrix3<f64> {
        with_heading_from_tilt(c, self.k)
    }

    /// The filter's own tilt error, of which the heading's average passes the share `f`: the
    /// heading gains `k L`, `L` the averaged `φ_y` with `Var L = f c_yy` and `Cov(L, φ) ≈ f
    /// c_y·`, which is `(1 − f) c + f A c Aᵀ` (positive semi-definite with `c`).
    pub(crate) fn fast(&self, c: &Matrix3<f64>) -> Matrix3<f64> {
        coupled(c, self.k, self.fast)
    }
}

/// The variation of the field's norm and dip over the motion, which shows how far the local
/// field's direction varies (module documentation): the norm (relative) and the dip of the
/// undisturbed samples, smoothed over [`SMOOTH_TIME`], and their exponentially weighted mean and
/// mean square over [`CALIBRATION_TIME`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct Inhomogeneity {
    /// The smoothed norm and dip, and the seconds smoothed so far.
    smooth: (f64, f64),
    smoothed: f64,
    /// The averages of the smoothed norm, the dip and their squares.
    norm: Average,
    norm2: Average,
    dip: Average,
    dip2: Average,
    /// The average of the state's stated tilt variance (rad² per axis) at the samples: the
    /// part of the dip's variance that is the state's own tilt error.
    tilt: Average,
    /// The smoothed norm's and dip's current deviation from their means, as a directional
    /// variance `((n/n̄ − 1)² + (dip − dip̄)²)/2` (rad²), low-passed over the heading average's
    /// time constant.
    current: f64,
}

impl Inhomogeneity {
    /// One undisturbed sample of norm `norm` and dip `dip` (rad, measured against the
    /// state's "up"), `h` seconds long, taken while the state's stated tilt variance is
    /// `tilt_var` (rad² per axis); `tau` (s) the heading average's time constant, over which
    /// the current deviation is low-passed ([`Inhomogeneity::evidence_variance`]).
    pub(super) fn push(&mut self, norm: f64, dip: f64, h: f64, tilt_var: f64, tau: f64) {
        if self.smoothed == 0.0 {
            self.smooth = (norm, dip);
        } else {
            let a = h / (SMOOTH_TIME + h);
            self.smooth.0 += a * (norm - self.smooth.0);
            self.smooth.1 += a * (dip - self.smooth.1);
        }
        self.smoothed += h;
        // the smoothing starts from one raw sample: its noise counts until it has averaged out
        if self.smoothed < 2.0 * SMOOTH_TIME
            || self.smooth.0.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        {
            return;
        }
        let alpha = (h / CALIBRATION_TIME).min(1.0);
        let n = self.smooth.0;
        let mean = self.norm.value();
        if mean > 0.0 {
            let dn = n / mean - 1.0;
            let dd = self.smooth.1 - self.dip.value();
            let d2 = 0.5 * (dn * dn + dd * dd);
            self.current += h / (tau + h) * (d2 - self.current);
        }
        self.norm.push(n, alpha);
        self.norm2.push(n * n, alpha);
        self.dip.push(self.smooth.1, alpha);
        self.dip2.push(self.smooth.1 * self.smooth.1, alpha);
        self.tilt.push(tilt_var, alpha);
    }

    /// `self` with the averages of `learned` (another pass over the same recording, module
    /// `smoother`): the variation it measured, kept as this pass goes on learning; this pass's
    /// own smoothing of the norm and dip (where the sensor is now) is kept.
    pub(super) fn with_averages_of(self, learned: &Inhomogeneity) -> Inhomogeneity {
        Inhomogeneity {
            norm: learned.norm,
            norm2: learned.norm2,
            dip: learned.dip,
            dip2: learned.dip2,
            tilt: learned.tilt,
            ..self
        }
    }

    /// The field's directional variance per direction (rad²): the mean of the relative
    /// norm's and the dip's variances (0 before there are any).
    pub(super) fn variance(&self) -> f64 {
        let (norm, dip) = self.variances();
        0.5 * (norm + dip)
    }

    /// The directional variance (rad²) the heading evidence takes: [`Inhomogeneity::variance`],
    /// or the current deviation of the smoothed norm and dip from their means over the heading
    /// average's time where that is larger. A field whose norm or dip is off its usual value
    /// now — a magnet near enough to move them, not enough to fail the disturbance test — is
    /// likely as far off in its direction, and the heading average holds it for `mag_tau`.
    pub(super) fn evidence_variance(&self) -> f64 {
        self.variance().max(self.current)
    }

    /// The local field's own directional variance per direction (rad²): as
    /// [`Inhomogeneity::evidence_variance`], with the dip's part less the state's own tilt
    /// error's variance (the dip is measured against the state's "up"; the stated covariance
    /// has that error in its tilt, and turns it into the heading's error itself).
    pub(super) fn field_variance(&self) -> f64 {
        let (norm, dip) = self.variances();
        let tilt = self.tilt.value();
        // the current deviation as the evidence takes it ([`Inhomogeneity::evidence_variance`]),
        // its dip's part less the tilt error too
        (0.5 * (norm + (dip - tilt).max(0.0))).max(self.current - 0.5 * tilt)
    }

    /// The relative norm's variance (relative to its mean's square) and the dip's (rad²); 0
    /// before there are any.
    fn variances(&self) -> (f64, f64) {
        let var = |m: &Average, m2: &Average| (m2.value() - m.value() * m.value()).max(0.0);
        let mean = self.norm.value();
        let norm = if mean > 0.0 {
            var(&self.norm, &self.norm2) / (mean * mean)
        } else {
            0.0
        };
        (norm, var(&self.dip, &self.dip2))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A field whose norm and dip vary with the position (norm ±5 %, dip ±3°, over a period of
    /// `period` s), pushed at 100 Hz for `seconds`.
    fn varying(seconds: f64, period: f64) -> Inhomogeneity {
        let mut m = Inhomogeneity::default();
        let h = 0.01;
        for k in 0..(seconds / h) as usize {
            let phase = 2.0 * std::f64::consts::PI * k as f64 * h / period;
            m.push(
                1.0 + 0.05 * phase.sin(),
                1.0 + 0.05 * phase.cos(),
                h,
                0.0,
                3.0,
            );
        }
        m
    }

    /// The handed-over averages give the learned variance at once (what a pass that starts
    /// fresh learns only over tens of seconds), and the receiver's own smoothing of the norm
    /// and dip is kept: where its sensor is now, not where the other pass's was.
    #[test]
    fn handed_over_averages_carry_the_learned_variance() {
        let learned = varying(60.0, 10.0);
        // variance of 0.05·sin (relative norm) and of 0.05·cos (dip, rad), smoothed over 1 s:
        // about 0.05²/2 each, so their mean is about 1.25e-3
        let v = learned.variance();
        assert!((0.8e-3..1.3e-3).contains(&v), "{v:e}");
        let mut fresh = Inhomogeneity::default();
        fresh.push(1.0, 0.9, 0.01, 0.0, 3.0);
        assert_eq!(fresh.variance(), 0.0);
        let handed = fresh.with_averages_of(&learned);
        assert_eq!(handed.variance(), v);
        assert_eq!(handed.smooth, (1.0, 0.9));
        assert_eq!(handed.smoothed, 0.01);
        // and it goes on learning: a homogeneous field (at the old mean) from now on lowers
        // the variance
        let mut later = handed;
        for _ in 0..6000 {
            later.push(1.0, 1.0, 0.01, 0.0, 3.0);
        }
        assert!(
            later.variance() < 0.5 * v,
            "{:e} vs {v:e}",
            later.variance()
        );
    }

    /// The coupling against the geometry it stands for: a tilt error `a` about north maps the
    /// reference field off its azimuth; the heading correction that brings the azimuth back
    /// leaves a heading error, which must be `tan(dip)·a` ([`heading_per_tilt`]), for fields
    /// of either hemisphere. And the covariance of the filter's errors is carried over to the
    /// orientation's as that map says.
    /// The heading evidence's variance follows a field that moves off its usual norm now (a
    /// magnet's edge within the disturbance test's tolerances) and is the field's variance
    /// where the field only varies as it always has.
    #[test]
    fn a_field_off_its_usual_norm_now_widens_the_heading_evidence() {
        let h = 0.01;
        let mut m = Inhomogeneity::default();
        for _ in 0..6000 {
            m.push(1.0, 1.0, h, 0.0, 3.0);
        }
        assert!(m.evidence_variance() < 1e-20);
        // 6 s at a norm 5 % off: the deviation's square, (0.05²)/2, smoothed over 1 s and
        // low-passed over 3 s, reaches most of itself; the 30-s variance a fraction of it
        for _ in 0..600 {
            m.push(1.05, 1.0, h, 0.0, 3.0);
        }
        let d2 = 0.5 * 0.05 * 0.05;
        let e = m.evidence_variance();
        assert!(e > 0.5 * d2 && e < d2, "{e} vs {d2}");
        assert!(e > 3.0 * m.variance(), "{e} vs {}", m.variance());
        // a field that varies as it always has (±5 %, ±0.05 rad over 10 s): the evidence takes
        // about its variance, not a multiple of it
        let v = varying(300.0, 10.0);
        assert!(
            v.evidence_variance() < 2.0 * v.variance(),
            "{} vs {}",
            v.evidence_variance(),
            v.variance()
        );
        assert!(v.evidence_variance() >= v.variance());
    }

    #[test]
    fn a_tilt_error_about_north_turns_the_heading_by_tan_dip() {
        use nalgebra::{Rotation3, Vector3};
        for dip_deg in [-70.0f64, -45.0, -10.0, 0.0, 30.0, 65.0] {
            let dip = dip_deg.to_radians();
            let field = Vector3::new(0.0, dip.cos(), dip.sin());
            for a in [1e-4f64, -3e-4] {
                let truth_to_estimate = Rotation3::from_scaled_axis(Vector3::new(0.0, -a, 0.0));
                let mapped = truth_to_estimate * field;
                // the heading correction Rz(γ) that brings the mapped field's azimuth to 0
                let gamma = mapped.x.atan2(mapped.y);
                let settled =
                    Rotation3::from_scaled_axis(Vector3::new(0.0, 0.0, gamma)) * truth_to_estimate;
                // the error rotation vector φ of q_true = exp(φ/2) ⊗ q̂
                let phi = settled.inverse().scaled_axis();
                let k = heading_per_tilt(dip);
                assert!(
                    (phi.y - a).abs() < 1e-9 * (1.0 + k.abs()),
                    "{dip_deg}: {phi:?}"
                );
                assert!(
                    (phi.z - k * a).abs() < 2e-7 * a.abs() * (1.0 + k.abs()),
                    "{dip_deg}: {} vs {}",
                    phi.z,
                    k * a
                );
            }
            let mut c = Matrix3::from_diagonal(&Vector3::new(2e-4, 3e-4, 5e-4));
            c[(1, 2)] = 1e-5;
            c[(2, 1)] = 1e-5;
            let k = heading_per_tilt(dip);
            let out = with_heading_from_tilt(&c, k);
            let heading = 5e-4 + 2.0 * k * 1e-5 + k * k * 3e-4;
            assert!((out[(2, 2)] - heading).abs() < 1e-15 * (1.0 + k * k));
            assert!((out[(1, 2)] - (1e-5 + k * 3e-4)).abs() < 1e-17 * (1.0 + k.abs()));
            assert_eq!((out[(0, 0)], out[(1, 1)]), (2e-4, 3e-4));
        }
        // a field within 5° of the vertical: the factor is held
        assert!(heading_per_tilt(89.9f64.to_radians()) < 11.5);
    }

    /// The dip is measured against the state's "up": the field's own variance leaves out the
    /// state's tilt variance, which the stated covariance carries itself; the filter's
    /// [`Inhomogeneity::evidence_variance`] keeps it.
    #[test]
    fn the_fields_own_variance_leaves_out_the_states_tilt_error() {
        let h = 0.01;
        let mut m = Inhomogeneity::default();
        let mut still = Inhomogeneity::default();
        for k in 0..12_000 {
            // the dip moves by a state's tilt error of about 0.02 rad RMS, the norm not at all
            let e = 0.02 * 2f64.sqrt() * (2.0 * std::f64::consts::PI * k as f64 * h / 10.0).sin();
            m.push(1.0, 0.9 + e, h, 4e-4, 3.0);
            still.push(1.0, 0.9 + e, h, 0.0, 3.0);
        }
        // the smoothed dip's variance: 0.02² through the 1-s smoothing, 1/(1 + (2π/10)²)
        let dip = 2.0 * m.variance();
        assert!((2.7e-4..3.0e-4).contains(&dip), "{dip:e}");
        assert_eq!(still.variance(), m.variance());
        assert!(
            m.field_variance() < 0.1 * m.variance(),
            "{:e}",
            m.field_variance()
        );
        // without a tilt error the two agree, the current deviation included where it is larger
        assert_eq!(still.field_variance(), still.evidence_variance());
        assert!(still.evidence_variance() >= still.variance());
    }

    /// The filter's own tilt error reaches the heading through its average: `(1 − f) c +
    /// f A c Aᵀ`, the heading's variance gaining `f k² c_yy` (and `2 f k c_yz`), its covariance
    /// with the tilt about north `f k c_yy`; the references' errors the whole `A c Aᵀ`; none
    /// without a reference.
    #[test]
    fn the_filters_own_tilt_error_reaches_the_heading_through_its_average() {
        let c = Matrix3::new(2e-4, 1e-5, -2e-5, 1e-5, 3e-4, 4e-5, -2e-5, 4e-5, 5e-4);
        let dip = (-65.0f64).to_radians();
        let cp = Coupling::new(dip, 1.5, 3.0);
        assert!((cp.fast - 1.0 / 3.0).abs() < 1e-15);
        assert_eq!(cp.k, heading_per_tilt(dip));
        let (k, f) = (cp.k, cp.fast);
        let out = cp.fast(&c);
        let heading = 5e-4 + f * (2.0 * k * 4e-5 + k * k * 3e-4);
        assert!(
            (out[(2, 2)] - heading).abs() < 1e-18,
            "{} vs {heading}",
            out[(2, 2)]
        );
        assert!((out[(1, 2)] - (4e-5 + f * k * 3e-4)).abs() < 1e-18);
        assert!((out[(0, 2)] - (-2e-5 + f * k * 1e-5)).abs() < 1e-18);
        for (i, j) in [(0, 0), (1, 1), (0, 1)] {
            assert!((out[(i, j)] - c[(i, j)]).abs() < 1e-19, "({i}, {j})");
        }
        assert!(out.symmetric_eigenvalues().min() > 0.0);
        assert_eq!(cp.slow(&c), with_heading_from_tilt(&c, k));
        assert_eq!(Coupling::NONE.fast(&c), c);
        assert_eq!(Coupling::NONE.slow(&c), c);
    }

    /// The tilt reference's steady part is the squared mean deviation: all of it for a
    /// constant deviation (an accelerometer's offset), none of it for one that alternates about
    /// 0 (linear acceleration that averages out over the motion).
    #[test]
    fn the_tilt_references_steady_part_is_its_squared_mean() {
        let mut offset = Calibration::default();
        let mut moving = Calibration::default();
        let nu = Innovations::default();
        for k in 0..2000 {
            offset.correction(0.05, &nu, Some(0.01));
            moving.correction(0.05, &nu, Some(if k % 2 == 0 { 0.01 } else { -0.01 }));
        }
        for c in [&offset, &moving] {
            assert!((c.tilt_reference_variance() - 1e-4).abs() < 1e-12);
        }
        assert!((offset.steady_tilt_reference_variance() - 1e-4).abs() < 1e-12);
        assert!(moving.steady_tilt_reference_variance() < 1e-8);
    }

    /// The smoother's coupling keeps its output a covariance when the product is narrower
    /// than the steady tilt error it is given, and applies the whole coupling to that error
    /// otherwise.
    #[test]
    fn a_stated_coupling_keeps_a_narrow_covariance_positive_semi_definite() {
        let sc = StatedCoupling {
            coupling: Coupling::new((-65.0f64).to_radians(), 1.5, 3.0),
            steady: 1e-4,
        };
        let narrow = Matrix3::from_diagonal(&Vector3::new(4e-5, 5e-5, 2e-5));
        let out = sc.apply(&narrow);
        assert!(out.symmetric_eigenvalues().min() >= -1e-18, "{out}");
        let wide = Matrix3::from_diagonal(&Vector3::new(3e-4, 4e-4, 2e-4));
        let s = Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 0.0));
        let expected = sc.coupling.fast(&(wide - s)) + sc.coupling.slow(&s);
        assert!((sc.apply(&wide) - expected).norm() < 1e-20);
        assert!(sc.apply(&wide).symmetric_eigenvalues().min() > 0.0);
        assert_eq!(StatedCoupling::NONE.apply(&wide), wide);
    }

    /// A direction whose variance the gyroscope's scale error explains is stated at that
    /// variance whatever the innovations' factor below 1 is (a constant of the sensor, not a
    /// white noise the factor measures), and widened with the rest by a factor above 1; the
    /// other directions keep their scaled variances, and the covariance stays one.
    #[test]
    fn the_scale_errors_part_is_stated_unscaled() {
        let a = 4e-4;
        let dirs = [Vector3::x(), Vector3::y(), Vector3::z()];
        let part = |sh: f64, scale_root: Matrix3<f64>| Parts {
            var: [1e-4, 1e-4, a],
            scales: (0.5, sh),
            tilt_ref: 0.0,
            tilt_ref_steady: 0.0,
            heading_ref: 0.0,
            gap: 0.0,
            scale_root,
            coupling: Coupling::NONE,
        };
        // roots: the part a e_z e_zᵀ, and a v vᵀ
        let along_z = Matrix3::from_diagonal(&Vector3::new(0.0, 0.0, a.sqrt()));
        let z = Matrix3::zeros();
        let i = Matrix3::identity();
        for sh in [0.1, 0.25, 0.9] {
            let c = stated(&i, &dirs, &z, &part(sh, along_z));
            assert!((c[(2, 2)] - a).abs() < 1e-18, "s_h {sh}: {}", c[(2, 2)]);
            assert!((c[(0, 0)] - 0.5e-4).abs() < 1e-18);
            let without = stated(&i, &dirs, &z, &part(sh, Matrix3::zeros()));
            assert!((without[(2, 2)] - sh * a).abs() < 1e-18);
        }
        let c = stated(&i, &dirs, &z, &part(2.0, along_z));
        assert!((c[(2, 2)] - 2.0 * a).abs() < 1e-18);
        // a part across directions of unequal factors stays positive semi-definite
        let v = Vector3::new(0.0, 0.6, 0.8);
        let root = Matrix3::from_rows(&[
            v.transpose() * a.sqrt(),
            Vector3::zeros().transpose(),
            Vector3::zeros().transpose(),
        ]);
        let c = stated(&i, &dirs, &z, &part(0.1, root));
        assert!(c.symmetric_eigenvalues().min() > 0.0, "{c}");
    }
}
