//! The lane-wise evaluations against the scalar functions of `special`.

use super::*;
use crate::special::{bessel_q_times, i01e_times};

/// Deterministic arguments covering every branch: 0, tiny, piece boundaries, the switch to
/// the asymptotic series at 128, and magnitudes up to the largest doubles.
fn arguments() -> Vec<f64> {
    let mut xs = vec![
        0.0,
        5e-324,
        1e-300,
        1e-8,
        0.25,
        7.999999999999999,
        8.0,
        127.99999999999999,
    ];
    xs.extend([128.0, 1e6, 1e300, f64::MAX]);
    // batches whose lanes share a piece
    xs.extend([
        0.0, 0.01, 0.1, 0.2, 3.1, 3.11, 3.12, 3.13, 50.0, 50.1, 50.2, 50.3,
    ]);
    let mut lcg = testkit::Lcg(12345);
    for k in 0..4000 {
        let u = lcg.uniform();
        xs.push(match k % 3 {
            0 => 8.0 * u,
            1 => 128.0 * u,
            _ => 10f64.powf(-3.0 + 12.0 * u),
        });
    }
    xs
}

#[test]
fn plain_bessel_lanes_equal_the_scalar_functions() {
    let xs = arguments();
    for (n, chunk) in xs.chunks_exact(4).enumerate() {
        let x = F([chunk[0], chunk[1], chunk[2], chunk[3]]);
        // an exact power-of-two scale per lane
        let k = F([
            1.0,
            0.5,
            2f64.powi(n as i32 % 40),
            2f64.powi(-(n as i32 % 30)),
        ]);
        let b = bessel::<Plain, 4, 8, 16, true>(x, k, Span::Mixed);
        let g = bessel::<Plain, 4, 8, 16, false>(x, k, Span::Mixed);
        for l in 0..4 {
            let (i0, i1, dm, xdm) = i01e_times(x.0[l], k.0[l]);
            let (q, x2q) = bessel_q_times(x.0[l], k.0[l]);
            for (got, want) in [
                (b.i0.0[l], i0),
                (b.i1.0[l], i1),
                (b.dm.0[l], dm),
                (b.xdm.0[l], xdm),
                (g.i0.0[l], i0),
                (g.i1.0[l], i1),
                (g.dm.0[l], dm),
                (g.xdm.0[l], xdm),
                (b.q.0[l], q),
                (b.x2q.0[l], x2q),
            ] {
                assert_eq!(got.to_bits(), want.to_bits(), "x = {:e}", x.0[l]);
            }
            // k·i1e/x: the first piece's own fit, else one rounding more than i1/x
            let want = if x.0[l] < 1e-8 {
                0.5 * k.0[l] * (1.0 - x.0[l])
            } else {
                i1 / x.0[l]
            };
            let err = (b.i1x.0[l] - want).abs() / want.abs().max(f64::MIN_POSITIVE);
            assert!(
                err <= 4.5e-16,
                "x = {:e}: i1/x {} vs {want}",
                x.0[l],
                b.i1x.0[l]
            );
        }
    }
}

#[test]
fn fused_bessel_lanes_match_the_scalar_functions() {
    let xs = arguments();
    for chunk in xs.chunks_exact(4) {
        let x = F([chunk[0], chunk[1], chunk[2], chunk[3]]);
        let k = F::splat(1.0);
        let b = bessel::<Fused, 4, 8, 16, true>(x, k, Span::Mixed);
        for l in 0..4 {
            let (i0, i1, dm, _) = i01e_times(x.0[l], 1.0);
            let (q, _) = bessel_q_times(x.0[l], 1.0);
            for (got, want) in [
                (b.i0.0[l], i0),
                (b.i1.0[l], i1),
                (b.dm.0[l], dm),
                (b.q.0[l], q),
            ] {
                let err = (got - want).abs() / want.abs().max(f64::MIN_POSITIVE);
                assert!(err <= 4.5e-16, "x = {:e}: {got} vs {want}", x.0[l]);
            }
        }
    }
}

/// A span hint never changes a lane's value: batches of sorted arguments (one piece, the
/// asymptotic range, or both) give the same bits with the hint `Span::of` finds as with
/// `Span::Mixed`, with and without the fourth-moment outputs, plain and fused.
#[test]
fn span_hints_give_the_same_bits() {
    let mut xs = arguments();
    xs.retain(|x| x.is_finite());
    let mut hinted = [0usize; 3];
    for (n, chunk) in xs.chunks_exact(4).enumerate() {
        let mut v = [chunk[0], chunk[1], chunk[2], chunk[3]];
        // also batches narrow enough to share a piece
        if n % 2 == 1 {
            let base = v[0];
            for (l, x) in v.iter_mut().enumerate() {
                *x = base * (1.0 + 1e-3 * l as f64);
            }
        }
        v.sort_by(f64::total_cmp);
        let x = F(v);
        let k = F([1.0, 0.5, 2.0, 0.25]);
        let span = Span::of(v[0], v[3]);
        hinted[match span {
            Span::Piece(_) => 0,
            Span::Asymptotic => 1,
            Span::Mixed => 2,
        }] += 1;
        macro_rules! same {
            ($a:ty, $fourth:literal) => {{
                let h = bessel::<$a, 4, 8, 16, $fourth>(x, k, span);
                let m = bessel::<$a, 4, 8, 16, $fourth>(x, k, Span::Mixed);
                for (a, b) in [
                    (h.i0, m.i0),
                    (h.i1, m.i1),
                    (h.dm, m.dm),
                    (h.xdm, m.xdm),
                    (h.i1x, m.i1x),
                    (h.q, m.q),
                    (h.x2q, m.x2q),
                ] {
                    for l in 0..4 {
                        assert_eq!(a.0[l].to_bits(), b.0[l].to_bits(), "x = {v:?}, {span:?}");
                    }
                }
            }};
        }
        same!(Plain, true);
        same!(Plain, false);
        same!(Fused, true);
        same!(Fused, false);
    }
    assert!(hinted.iter().all(|&c| c > 50), "{hinted:?}");
}

/// Distance in units in the last place (both finite and of the same sign, or zero).
fn ulps(a: f64, b: f64) -> u64 {
    (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs()
}

#[test]
fn exp_is_within_one_ulp() {
    let mut xs: Vec<f64> = (0..=200_000)
        .map(|i| -746.0 * i as f64 / 200_000.0)
        .collect();
    xs.extend([
        -0.0,
        -1e-300,
        -5e-324,
        -708.3964185322641,
        -708.396_418_532_264_2,
        -709.0,
        -744.440_071_921_381_2,
        -745.1332191019411,
        -745.1332191019412,
        -746.0,
        -1e10,
        f64::MIN,
        f64::NEG_INFINITY,
        0.5,
        1.0,
        700.0,
    ]);
    let mut worst = 0;
    for chunk in xs.chunks(4) {
        let mut v = [0.0; 4];
        v[..chunk.len()].copy_from_slice(chunk);
        let plain = exp::<Plain, 4>(F(v));
        let fused = exp::<Fused, 4>(F(v));
        for (l, &x) in chunk.iter().enumerate() {
            let want = x.exp();
            for got in [plain.0[l], fused.0[l]] {
                let u = ulps(got, want);
                worst = worst.max(u);
                assert!(u <= 1, "exp({x:e}) = {got:e}, want {want:e}");
            }
        }
    }
    assert!(worst <= 1);
}
