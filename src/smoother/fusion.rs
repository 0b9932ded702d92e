//! The product of the two passes at one sample: the fusion of two Gaussian estimates in the
//! tangent space (through a 3×3 Cholesky factor), for the orientation and the bias.

use nalgebra::{Matrix3, Matrix4, Vector3};

use super::store::{pack, unpack, Forward, ForwardBias};
use super::types::SmoothOptions;
use crate::linalg::{cholesky3, forward3};
use crate::quaternion::q4;

/// The fusion of two Gaussian estimates `(x_f, C_f)`, `(x_f + δ, C_b)`: the shift from `x_f`
/// and the fused covariance, `C_f (C_f + C_b)⁻¹ δ` and `C_f − C_f (C_f + C_b)⁻¹ C_f`. `None`
/// when `C_f + C_b` is not positive definite or the result not finite.
pub(super) fn fuse(
    cf: &Matrix3<f64>,
    cb: &Matrix3<f64>,
    delta: &Vector3<f64>,
) -> Option<(Vector3<f64>, Matrix3<f64>)> {
    let l = cholesky3(&(cf + cb))?;
    fuse_with(&l, cf, &forward3(&l, delta))
}

/// [`fuse`] with the Cholesky factor `l` of `S = C_f + C_b` ([`cholesky3`]) and `y = L⁻¹ δ`
/// given: with `W = L⁻¹ C_f`, the shift `C_f S⁻¹ δ = Wᵀ y` and the covariance
/// `C_f − C_f S⁻¹ C_f = C_f − Wᵀ W` (symmetric by construction; forward substitutions only).
fn fuse_with(
    l: &[f64; 6],
    cf: &Matrix3<f64>,
    y: &Vector3<f64>,
) -> Option<(Vector3<f64>, Matrix3<f64>)> {
    let w = Matrix3::from_columns(&[
        forward3(l, &cf.column(0).into_owned()),
        forward3(l, &cf.column(1).into_owned()),
        forward3(l, &cf.column(2).into_owned()),
    ]);
    let shift = w.tr_mul(y);
    let ww = w.tr_mul(&w);
    // C_f's symmetric part (the stored covariances are symmetric) minus WᵀW, mirrored
    let cs = Matrix3::from_fn(|i, j| {
        let (i, j) = if i <= j { (i, j) } else { (j, i) };
        0.5 * (cf[(i, j)] + cf[(j, i)]) - ww[(i, j)]
    });
    (shift.iter().all(|x| x.is_finite()) && cs.iter().all(|x| x.is_finite())).then_some((shift, cs))
}

/// The product at one sample (module documentation): the forward state `f` (and bias `fb`)
/// replaced by the smoothed one, from the backward prediction `b` (and `bb`); `exps` the two
/// Bingham exponents for [`Fusion::Bingham`].
///
/// [`Fusion::Bingham`]: super::types::Fusion::Bingham
pub(super) fn product(
    options: &SmoothOptions,
    f: &mut Forward,
    b: &Forward,
    exps: Option<(&Matrix4<f64>, &Matrix4<f64>)>,
    bias: Option<(&mut ForwardBias, &ForwardBias)>,
) {
    let qf = f.q;
    let cf = unpack(&f.c);
    let mut cb = unpack(&b.c);
    let d = q4::to_rotation_vector(&q4::mul(&b.q, &q4::conj(&qf)));
    let dv = Vector3::new(d[0], d[1], d[2]);
    // one Cholesky factor of C_f + C_b and L⁻¹δ serve the gate and the product
    let mut chol = cholesky3(&(cf + cb)).map(|l| (l, forward3(&l, &dv)));
    // the consistency gate: a backward state farther from the forward one than their
    // covariances allow (a start, a magnetic reference taken in a disturbance) is widened
    // until it is consistent (the squared Mahalanobis distance δᵀ(C_f + C_b)⁻¹δ = |L⁻¹δ|²)
    if options.gate > 0.0 {
        if let Some((_, y)) = &chol {
            let m2 = y.norm_squared();
            if m2 > options.gate {
                cb *= m2 / options.gate;
                chol = cholesky3(&(cf + cb)).map(|l| (l, forward3(&l, &dv)));
            }
        }
    }
    if let Some((shift, cs)) = chol.and_then(|(l, y)| fuse_with(&l, &cf, &y)) {
        let q = match exps {
            Some((ef, eb)) => {
                let a = ef + eb;
                let eig = a.symmetric_eigen();
                let i = eig.eigenvalues.imax();
                let v = eig.eigenvectors.column(i);
                [v[0], v[1], v[2], v[3]]
            }
            None => q4::mul(&q4::from_rotation_vector(&[shift.x, shift.y, shift.z]), &qf),
        };
        let nq = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        let s = if q[0] < 0.0 { -1.0 / nq } else { 1.0 / nq };
        f.q = q.map(|x| x * s);
        f.c = pack(&cs);
    }
    if let Some((fb, bb)) = bias {
        let bf = Vector3::new(fb.b[0], fb.b[1], fb.b[2]).map(f64::from);
        let pf = unpack(&fb.p);
        let bbv = Vector3::new(bb.b[0], bb.b[1], bb.b[2]).map(f64::from);
        let pb = unpack(&bb.p);
        if let Some((shift, ps)) = fuse(&pf, &pb, &(bbv - bf)) {
            let bsm = bf + shift;
            fb.b = [bsm.x as f32, bsm.y as f32, bsm.z as f32];
            fb.p = pack(&ps);
        }
    }
}
