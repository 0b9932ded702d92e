//! Accuracy of `bingham::special` against the independent 50-digit mpmath reference
//! `tests/data/bessel_reference.csv` (written by `scripts/bessel_reference.py`), plus identities.
//!
//! Error bounds. The reference values are the doubles nearest to the exact values (17 significant
//! digits, round-trip exact), so the measured error is the error relative to the correctly rounded
//! result. `cargo test --release --test special -- --nocapture` prints the maxima over the 11224
//! reference points per range (relative error / in ulps of the reference value); they are
//! recorded in `docs/accuracy/normalization.md` (§ "Bessel functions").
//!
//! The asserted bound, 1e-15 relative for all four (about 4.5 ulp at the bottom of a binade), is
//! 2.5 times the worst measured error: room for other compilers and platforms (nothing here depends
//! on FMA contraction or on the libm), yet a wrong piece index, threshold or leading coefficient
//! fails it by orders of magnitude, and so does the cancellation the dedicated differences avoid
//! (`i0e − i1e` is off by ~1e-10 at x = 1e6, see `plain_difference_would_fail_at_large_x`).

use bingham::special::{bessel_q, i01e, i0e, i0e_minus_i1e, i1e};

struct Row {
    x: f64,
    vals: [f64; 4],
}

fn reference() -> Vec<Row> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/bessel_reference.csv"
    );
    let text = std::fs::read_to_string(path).expect("tests/data/bessel_reference.csv is missing");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("x,i0e,i1e,i0e_minus_i1e,bessel_q"),
        "unexpected header"
    );
    let rows: Vec<Row> = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .map(|f| f.trim().parse::<f64>().expect("bad number"))
                .collect();
            assert_eq!(v.len(), 5, "bad row {l}");
            Row {
                x: v[0],
                vals: [v[1], v[2], v[3], v[4]],
            }
        })
        .collect();
    assert!(
        rows.len() > 5000,
        "reference grid too small: {}",
        rows.len()
    );
    rows
}

/// Spacing of the doubles at `v` (ulp of `v`), for reporting.
fn ulp(v: f64) -> f64 {
    let v = v.abs();
    if v == 0.0 {
        f64::from_bits(1)
    } else {
        f64::from_bits(v.to_bits() + 1) - v
    }
}

struct Worst {
    rel: f64,
    ulps: f64,
    x_rel: f64,
}

fn worst(rows: &[Row], col: usize, f: impl Fn(f64) -> f64) -> Worst {
    let mut w = Worst {
        rel: 0.0,
        ulps: 0.0,
        x_rel: f64::NAN,
    };
    for r in rows {
        let want = r.vals[col];
        let got = f(r.x);
        assert!(got.is_finite(), "non-finite result {got} at x = {}", r.x);
        let err = (got - want).abs();
        let rel = if want == 0.0 { err } else { err / want.abs() };
        if rel > w.rel {
            w.rel = rel;
            w.x_rel = r.x;
        }
        w.ulps = w.ulps.max(err / ulp(want));
    }
    w
}

fn check(name: &str, col: usize, bound: f64, f: impl Fn(f64) -> f64) {
    let rows = reference();
    let w = worst(&rows, col, &f);
    println!(
        "{name:>14}: max rel. error {:.3e} (at x = {}), max {:.2} ulp over {} points",
        w.rel,
        w.x_rel,
        w.ulps,
        rows.len()
    );
    for (lo, hi) in [(0.0, 8.0), (8.0, 128.0), (128.0, f64::INFINITY)] {
        let part: Vec<Row> = rows
            .iter()
            .filter(|r| r.x >= lo && r.x < hi)
            .map(|r| Row {
                x: r.x,
                vals: r.vals,
            })
            .collect();
        let p = worst(&part, col, &f);
        println!(
            "{:>14}  x in [{lo}, {hi}): max rel. error {:.3e} (at x = {}), max {:.2} ulp ({} points)",
            "",
            p.rel,
            p.x_rel,
            p.ulps,
            part.len()
        );
    }
    assert!(
        w.rel <= bound,
        "{name}: max relative error {:.3e} at x = {} exceeds {bound:e}",
        w.rel,
        w.x_rel
    );
}

#[test]
fn i0e_matches_reference() {
    check("i0e", 0, 1e-15, i0e);
}

#[test]
fn i1e_matches_reference() {
    check("i1e", 1, 1e-15, i1e);
}

#[test]
fn i0e_minus_i1e_matches_reference() {
    check("i0e_minus_i1e", 2, 1e-15, i0e_minus_i1e);
}

#[test]
fn bessel_q_matches_reference() {
    check("bessel_q", 3, 1e-15, bessel_q);
}

#[test]
fn plain_difference_would_fail_at_large_x() {
    // Guards the test itself: the bound above must be able to catch the cancellation the
    // dedicated difference avoids.
    let rows = reference();
    let w = worst(&rows, 2, |x| i0e(x) - i1e(x));
    assert!(w.rel > 1e-12, "reference grid lacks large x ({:e})", w.rel);
    let w = worst(&rows, 3, |x| {
        if x == 0.0 {
            3.0
        } else {
            4.0 * i0e_minus_i1e(x) - 2.0 * i1e(x) / x
        }
    });
    assert!(
        w.rel > 1e-10,
        "reference grid lacks large x for Q ({:e})",
        w.rel
    );
}

fn grid() -> Vec<f64> {
    let mut xs = vec![0.0, 1e-300, 1e-10, 0.25, 8.0, 128.0, 1e3, 1e300, f64::MAX];
    let mut x = 1e-3;
    while x < 1e8 {
        xs.push(x);
        x *= 1.0137;
    }
    xs.extend((0..13000).map(|k| k as f64 / 100.0 + 0.003));
    xs
}

#[test]
fn i01e_is_bit_identical_to_the_separate_functions() {
    for &a in &grid() {
        for x in [a, -a] {
            let (i0, i1, d) = i01e(x);
            assert_eq!(i0.to_bits(), i0e(x).to_bits(), "i0e at {x}");
            assert_eq!(i1.to_bits(), i1e(x).to_bits(), "i1e at {x}");
            assert_eq!(
                d.to_bits(),
                i0e_minus_i1e(x).to_bits(),
                "i0e_minus_i1e at {x}"
            );
        }
    }
}

#[test]
fn symmetry() {
    for &x in &grid() {
        assert_eq!(i0e(-x).to_bits(), i0e(x).to_bits(), "i0e even at {x}");
        assert_eq!(i1e(-x), -i1e(x), "i1e odd at {x}");
        assert_eq!(i0e_minus_i1e(-x), i0e_minus_i1e(x));
        assert_eq!(bessel_q(-x), bessel_q(x));
    }
    assert!(i1e(-0.0).is_sign_negative() && i1e(-0.0) == 0.0);
}

#[test]
fn special_values() {
    assert_eq!(i01e(0.0), (1.0, 0.0, 1.0));
    assert_eq!(bessel_q(0.0), 3.0);
    assert_eq!(i1e(1e-300), 5e-301);
    assert_eq!(i01e(f64::INFINITY), (0.0, 0.0, 0.0));
    assert_eq!(bessel_q(f64::INFINITY), 0.0);
    let (a, b, c) = i01e(f64::NAN);
    assert!(a.is_nan() && b.is_nan() && c.is_nan());
    assert!(bessel_q(f64::NAN).is_nan() && i0e(f64::NAN).is_nan() && i1e(f64::NAN).is_nan());
    // Huge arguments: no overflow, and no underflow of the O(x^-1/2) values.
    for x in [1e200, 1e300, f64::MAX] {
        let want = 1.0 / (2.0 * std::f64::consts::PI).sqrt() / x.sqrt();
        assert!((i0e(x) / want - 1.0).abs() < 1e-15, "i0e at {x}");
        assert!((i1e(x) / want - 1.0).abs() < 1e-15, "i1e at {x}");
    }
    let x: f64 = 1e200; // i0e − i1e ≈ 2e-301 is still a normal double
    let want = 1.0 / (2.0 * std::f64::consts::PI).sqrt() / x.sqrt() / (2.0 * x);
    assert!((i0e_minus_i1e(x) / want - 1.0).abs() < 1e-15);
    assert_eq!(i0e_minus_i1e(1e300), 0.0); // ≈ 2e-451 underflows
}

#[test]
fn identities() {
    // Ordering 0 < i1e < i0e, 0 < d, and the recurrence I0 − I2 = 2 I1 / x, i.e.
    // Q = 4 d − 2 i1e / x, where that formula does not cancel much (x ≤ 8).
    for &x in grid().iter().filter(|&&x| x > 0.0 && x.is_finite()) {
        let (i0, i1, d) = i01e(x);
        if x < 1e300 {
            assert!(0.0 < i1 && i1 < i0 && d > 0.0, "ordering at {x}");
        }
        assert!(
            ((i1 + d) - i0).abs() <= 2.0 * ulp(i0),
            "i0e = i1e + d at {x}"
        );
        if x <= 8.0 {
            let q = 4.0 * d - 2.0 * i1 / x;
            let scale = 4.0 * d + 2.0 * i1 / x;
            assert!(
                (bessel_q(x) - q).abs() <= 1e-15 * scale,
                "recurrence at {x}: {} vs {q}",
                bessel_q(x)
            );
        }
    }
}
