//! The saddlepoint approximation (`Method::Saddlepoint`) is APPROXIMATE by design: on a grid of
//! z for d = 3, 4, 6 its relative error against the exact method must be clearly non-zero (it is
//! not accidentally the exact method) and bounded (it is not wildly wrong). Prints the table.

use bingham::normalization::{evaluate, Method};

/// Values for the sorted grids (0 included, up to strong concentration).
const VALUES: [f64; 8] = [0.0, -0.1, -1.0, -5.0, -20.0, -100.0, -1e3, -1e6];

/// All ascending `z` of length `d` with entries from `values` and `z_d = 0`.
fn grid(d: usize, values: &[f64]) -> Vec<Vec<f64>> {
    fn rec(
        prefix: &mut Vec<f64>,
        left: usize,
        start: usize,
        values: &[f64],
        out: &mut Vec<Vec<f64>>,
    ) {
        if left == 0 {
            let mut z = prefix.clone();
            z.reverse(); // prefix is descending
            z.push(0.0);
            out.push(z);
            return;
        }
        for k in start..values.len() {
            prefix.push(values[k]);
            rec(prefix, left - 1, k, values, out);
            prefix.pop();
        }
    }
    let mut out = Vec::new();
    rec(&mut Vec::new(), d - 1, 0, values, &mut out);
    out
}

struct Stats {
    min_f: f64,
    max_f: f64,
    max_w: f64,
    max_sum: f64,
}

fn table(d: usize, zs: &[Vec<f64>]) -> Stats {
    let mut st = Stats {
        min_f: f64::INFINITY,
        max_f: 0.0,
        max_w: 0.0,
        max_sum: 0.0,
    };
    println!("d = {d}: relative error of F, max relative error of ω, Σω − 1 (saddlepoint)");
    for z in zs {
        let exact = evaluate(z, Method::Exact, false).unwrap();
        let sp = evaluate(z, Method::Saddlepoint, true).unwrap();
        let ef = (sp.log_f - exact.log_f).exp_m1();
        let ew = sp
            .grad
            .iter()
            .zip(&exact.grad)
            .map(|(a, b)| ((a - b) / b).abs())
            .fold(0.0, f64::max);
        let sum = sp.grad.iter().sum::<f64>() - 1.0;
        assert!(sp.hess.iter().all(|v| v.is_finite()));
        println!("  z = {z:?}: {ef:+.3e}  {ew:.3e}  {sum:+.2e}");
        st.min_f = st.min_f.min(ef.abs());
        st.max_f = st.max_f.max(ef.abs());
        st.max_w = st.max_w.max(ew);
        st.max_sum = st.max_sum.max(sum.abs());
    }
    println!(
        "  range of |rel. error of F|: [{:.2e}, {:.2e}], max ω error {:.2e}, max |Σω − 1| {:.2e}",
        st.min_f, st.max_f, st.max_w, st.max_sum
    );
    st
}

fn assert_approximate(st: &Stats) {
    // Not exact: every grid point is off by more than 1e-5 (the smallest errors are near the
    // uniform distribution); not wildly wrong: below 10 % (the largest are at moderate
    // concentration around one direction). Measured values: docs/accuracy/normalization.md.
    assert!(st.min_f > 1e-5, "suspiciously exact: {:e}", st.min_f);
    assert!(st.max_f < 1e-1, "too inaccurate: {:e}", st.max_f);
    assert!(st.max_w < 1e-1, "ω too inaccurate: {:e}", st.max_w);
    assert!(st.max_sum > 1e-6 && st.max_sum < 5e-2);
}

#[test]
fn saddlepoint_d3_is_approximate_within_bounds() {
    let st = table(3, &grid(3, &VALUES));
    assert_approximate(&st);
}

#[test]
fn saddlepoint_d4_is_approximate_within_bounds() {
    let st = table(4, &grid(4, &VALUES));
    assert_approximate(&st);
}

#[test]
fn saddlepoint_d6_is_approximate_within_bounds() {
    let st = table(6, &grid(6, &[0.0, -1.0, -20.0, -1e3, -1e6]));
    assert_approximate(&st);
}

#[test]
fn saddlepoint_is_shift_and_permutation_invariant() {
    let z = [-7.0, -0.5, -30.0, 0.0, -2.0];
    let a = evaluate(&z, Method::Saddlepoint, true).unwrap();
    let zs: Vec<f64> = z.iter().rev().map(|v| v + 11.5).collect();
    let b = evaluate(&zs, Method::Saddlepoint, true).unwrap();
    assert!((b.log_f - 11.5 - a.log_f).abs() < 1e-12);
    for i in 0..5 {
        assert!((b.grad[4 - i] - a.grad[i]).abs() < 1e-12);
    }
}
