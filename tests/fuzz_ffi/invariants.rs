//! The invariants of a successful call's outputs, per function.

use bingham::ffi::bingham_status::*;
use bingham::ffi::*;
use testkit::fuzz::{check_omega_tol, check_state, check_unit, congruence, STATE_TOL};

use crate::case::{Attack, Case};
use crate::kinds::Kind::*;
use crate::kinds::SPECS;
use crate::status::last_error;

/// The tolerance on Σω: 1e-12, or 1e-9 when some shifted concentration is beyond 1e300 (far
/// outside the documented exact range |z| ≤ 1e6; for d = 4 and |z| near the largest double the
/// quadrature loses some digits, e.g. Σω = 1 − 9e-12 for z = (−MAX, −MAX, −3.6e6, −1.35)).
fn omega_tol(c: &Case) -> f64 {
    let spec = &SPECS[c.spec];
    let extreme = spec.inputs.iter().zip(&c.inputs).any(|(a, v)| {
        a.0 == Z
            && v.as_ref().is_some_and(|z| {
                let mx = z.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
                z.iter().any(|&x| x - mx < -1e300)
            })
    });
    if extreme {
        1e-9
    } else {
        STATE_TOL
    }
}

pub(crate) fn check_nc(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let f = o[0].as_ref().unwrap()[0];
    if f.is_nan() || f <= 0.0 || !f.is_normal() {
        return Err(format!("F = {f:e} is not a positive normal number"));
    }
    if let Some(df) = &o[1] {
        let w: Vec<f64> = df.iter().map(|v| v / f).collect();
        check_omega_tol(&w, omega_tol(c)).map_err(|e| format!("df/F: {e}"))?;
    }
    Ok(())
}

pub(crate) fn check_lnc(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    if let Some(w) = &o[1] {
        check_omega_tol(w, omega_tol(c)).map_err(|e| format!("dlog_f: {e}"))?;
    }
    Ok(())
}

pub(crate) fn check_lnc_sp(_c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    if let Some(w) = &o[1] {
        if let Some(i) = w.iter().position(|v| *v < 0.0) {
            return Err(format!("saddlepoint dlog_f[{i}] = {} < 0", w[i]));
        }
    }
    Ok(())
}

pub(crate) fn check_hess(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let d = c.d;
    if let Some(w) = &o[1] {
        check_omega_tol(w, omega_tol(c)).map_err(|e| format!("dlog_f: {e}"))?;
    }
    let h = o[2].as_ref().unwrap();
    for i in 0..d {
        // variances of x_i² ≥ 0 up to rounding (-1e-15; -1e-12 for concentrations beyond
        // 1e300, where d = 4 loses digits, e.g. -1.9e-14 at z = (−MAX, −MAX, −3.6e6, 0))
        let hii = h[i * d + i];
        if hii < -omega_tol(c) * 1e-3 {
            return Err(format!("Hessian diagonal [{i}] = {hii:e} < 0"));
        }
        let scale = (0..d).map(|j| h[i * d + j].abs()).fold(0.0, f64::max);
        let row: f64 = (0..d).map(|j| h[i * d + j]).sum();
        if row.abs() > 1e-10 * scale + 1e-14 {
            return Err(format!("Hessian row {i} sums to {row:e} (scale {scale:e})"));
        }
        for j in 0..i {
            let (a, b) = (h[i * d + j], h[j * d + i]);
            if (a - b).abs() > 1e-12 * a.abs().max(b.abs()) {
                return Err(format!(
                    "Hessian not symmetric at ({i},{j}): {a:e} vs {b:e}"
                ));
            }
        }
    }
    Ok(())
}

pub(crate) fn check_sm(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let d = c.d;
    let s = o[0].as_ref().unwrap();
    let tr: f64 = (0..d).map(|i| s[i * d + i]).sum();
    if (tr - 1.0).abs() > omega_tol(c) {
        return Err(format!("trace S = 1 + {:e}", tr - 1.0));
    }
    for i in 0..d {
        if s[i * d + i] < 0.0 {
            return Err(format!("S[{i},{i}] = {:e} < 0", s[i * d + i]));
        }
        for j in 0..i {
            if (s[i * d + j] - s[j * d + i]).abs() > 1e-15 {
                return Err(format!("S not symmetric at ({i},{j})"));
            }
        }
    }
    Ok(())
}

pub(crate) fn check_dist_out(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    check_state(o[0].as_ref().unwrap(), o[1].as_ref().unwrap(), c.d)
}

pub(crate) fn check_mle(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    check_dist_out(c, o)?;
    if c.moderate && c.attack == Attack::None && c.d <= 4 {
        // round trip: the fit's second moment equals the normalized input
        let d = c.d;
        let (m, z) = (o[0].as_ref().unwrap(), o[1].as_ref().unwrap());
        let mut lf = 0.0;
        let mut w = vec![0.0; d];
        // SAFETY: valid buffers of length d.
        let st =
            unsafe { bingham_log_normalization_constant(d, z.as_ptr(), &mut lf, w.as_mut_ptr()) };
        if st != BINGHAM_OK {
            return Err(format!("log F of the fit failed: {}", last_error()));
        }
        let s_fit = congruence(m, &w, d);
        let s_in = c.inputs[0].as_ref().unwrap();
        let tr: f64 = (0..d).map(|i| s_in[i * d + i]).sum();
        for (a, b) in s_fit.iter().zip(s_in) {
            if (a - b / tr).abs() > 1e-9 {
                return Err(format!(
                    "MLE round trip: |S_fit − S| = {:e}",
                    (a - b / tr).abs()
                ));
            }
        }
    }
    Ok(())
}

pub(crate) fn check_pdf(_c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let Some(p) = o[0].as_ref() else {
        return Ok(()); // n = 0: NULL allowed
    };
    if let Some(i) = p.iter().position(|v| v.is_nan() || *v < 0.0) {
        return Err(format!("p[{i}] = {} is not a density value", p[i]));
    }
    Ok(())
}

pub(crate) fn check_log_pdf(_c: &Case, _o: &[Option<Vec<f64>>]) -> Result<(), String> {
    Ok(()) // finiteness is checked for every output
}

pub(crate) fn check_finite_out(_c: &Case, _o: &[Option<Vec<f64>>]) -> Result<(), String> {
    Ok(())
}

pub(crate) fn check_kl(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let kl = o[0].as_ref().unwrap()[0];
    // KL ≥ 0; rounding of terms as large as the concentrations allows a little below
    let scale: f64 = [1, 3]
        .iter()
        .filter_map(|&i| c.inputs[i].as_ref())
        .flat_map(|z| {
            let mx = z.iter().cloned().fold(f64::MIN, f64::max);
            z.iter().map(move |v| (v - mx).abs())
        })
        .fold(1.0, f64::max);
    if kl < -1e-12 * scale {
        return Err(format!("KL = {kl:e} < 0 (scale {scale:e})"));
    }
    Ok(())
}

pub(crate) fn check_sample(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let Some(x) = o[0].as_ref() else {
        return Ok(()); // n = 0: NULL allowed
    };
    for (k, row) in x.chunks_exact(c.d).enumerate() {
        check_unit(row, 1e-12).map_err(|e| format!("sample {k}: {e}"))?;
    }
    Ok(())
}

pub(crate) fn check_mode(c: &Case, o: &[Option<Vec<f64>>]) -> Result<(), String> {
    let v = o[0].as_ref().unwrap();
    check_unit(v, 1e-12)?;
    if c.moderate && c.attack == Attack::None {
        // the mode is the column of the input M with the largest z (when that is unique)
        let (m, z) = (c.inputs[0].as_ref().unwrap(), c.inputs[1].as_ref().unwrap());
        let d = c.d;
        let top = (0..d).max_by(|&a, &b| z[a].total_cmp(&z[b])).unwrap();
        if (0..d).filter(|&i| z[i] == z[top]).count() == 1 {
            let dot: f64 = (0..d).map(|r| m[r * d + top] * v[r]).sum();
            if (dot.abs() - 1.0).abs() > 1e-9 {
                return Err(format!(
                    "mode is not column {top} of M: |dot| = {}",
                    dot.abs()
                ));
            }
        }
    }
    Ok(())
}
