//! The `q4` quaternion helpers (`bingham::quaternion::q4`) against independent references:
//! `compose`, the rotation matrix from the textbook quaternion formula, and Rodrigues' formula.

use bingham::quaternion::{compose, q4};
use std::f64::consts::PI;
use testkit::{dist3, dot3, matvec, rot, Rng64};

/// Rodrigues' formula: `v` rotated about the axis of `w` by the angle `|w|`.
fn rodrigues(w: &[f64; 3], v: &[f64; 3]) -> [f64; 3] {
    let th = dot3(w, w).sqrt();
    if th == 0.0 {
        return *v;
    }
    let k = [w[0] / th, w[1] / th, w[2] / th];
    let kxv = [
        k[1] * v[2] - k[2] * v[1],
        k[2] * v[0] - k[0] * v[2],
        k[0] * v[1] - k[1] * v[0],
    ];
    let kv = dot3(&k, v);
    let (s, c) = th.sin_cos();
    [
        v[0] * c + kxv[0] * s + k[0] * kv * (1.0 - c),
        v[1] * c + kxv[1] * s + k[1] * kv * (1.0 - c),
        v[2] * c + kxv[2] * s + k[2] * kv * (1.0 - c),
    ]
}

#[test]
fn q4_mul_and_rotate() {
    let mut rng = Rng64(71);
    for _ in 0..200 {
        let (a, b) = (rng.unit_array::<4>(), rng.unit_array::<4>());
        let m = q4::mul(&a, &b);
        let c = compose(&a, &b).unwrap();
        for i in 0..4 {
            assert!((m[i] - c[i]).abs() < 1e-15, "{m:?} vs {c:?}");
        }
        // R(a ⊗ b) = R(a) R(b), conj inverts.
        let v = rng.unit_array::<3>();
        let r1 = matvec(&rot(&m), &v);
        let r2 = matvec(&rot(&a), &matvec(&rot(&b), &v));
        assert!(dist3(&r1, &r2) < 1e-14);
        let rv = q4::rotate(&a, &v);
        assert!(dist3(&rv, &matvec(&rot(&a), &v)) < 1e-14, "rotate");
        let back = q4::rotate_inverse(&a, &rv);
        assert!(dist3(&back, &v) < 1e-14, "rotate_inverse");
        let id = q4::mul(&a, &q4::conj(&a));
        assert!((id[0] - 1.0).abs() < 1e-15 && id[1..].iter().all(|x| x.abs() < 1e-15));
        // Non-unit vectors scale linearly.
        let v5 = [5.0 * v[0], 5.0 * v[1], 5.0 * v[2]];
        let r5 = q4::rotate(&a, &v5);
        assert!(dist3(&r5, &matvec(&rot(&a), &v5)) < 1e-13);
    }
}

#[test]
fn q4_rotation_vectors() {
    let mut rng = Rng64(72);
    let mut angles = vec![
        0.0, 1e-15, 1e-12, 1e-9, 1e-5, 0.99e-4, 1e-4, 1.01e-4, 0.1, 1.0, 2.0, 3.0,
    ];
    angles.extend([PI - 1e-3, PI - 1e-6, PI - 1e-9]);
    for &th in &angles {
        for _ in 0..10 {
            let k = rng.unit_array::<3>();
            let w = [th * k[0], th * k[1], th * k[2]];
            let q = q4::from_rotation_vector(&w);
            let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!((n - 1.0).abs() < 1e-15, "|q| = {n}");
            // Against Rodrigues' formula.
            let v = rng.unit_array::<3>();
            let e = dist3(&q4::rotate(&q, &v), &rodrigues(&w, &v));
            assert!(e < 1e-14, "θ = {th}: rotation differs by {e}");
            // Round trip, relative to the angle (tiny angles keep their digits).
            let back = q4::to_rotation_vector(&q);
            let e = dist3(&back, &w);
            assert!(e <= 1e-15 * th, "θ = {th}: {w:?} -> {back:?} ({e:e})");
            // −q is the same rotation.
            let neg = q4::to_rotation_vector(&[-q[0], -q[1], -q[2], -q[3]]);
            assert!(dist3(&neg, &back) <= 1e-15 * th, "−q: {neg:?}");
        }
    }
    // Beyond π the returned rotation vector is the equivalent one with angle 2π − θ.
    let k = [0.0, 0.6, 0.8];
    let th = PI + 0.1;
    let q = q4::from_rotation_vector(&[th * k[0], th * k[1], th * k[2]]);
    let back = q4::to_rotation_vector(&q);
    let want = [-(PI - 0.1) * k[0], -(PI - 0.1) * k[1], -(PI - 0.1) * k[2]];
    assert!(dist3(&back, &want) < 1e-13, "{back:?}");
    // Exactly π about x: w = cos(π/2) ≈ 6e-17.
    let back = q4::to_rotation_vector(&q4::from_rotation_vector(&[PI, 0.0, 0.0]));
    assert!(dist3(&back, &[PI, 0.0, 0.0]) < 1e-14, "{back:?}");
}

/// Below `SERIES_ANGLE` the quaternion comes from series: the scalar part within 2.5e-16 of the
/// library's `cos(θ/2)`, the vector part within 2.5e-16 of `sin(θ/2)` (relative to its norm)
/// of `sin(θ/2)·v/θ` (about an ulp), over angles from
/// 1e-300 to the switch (log-spaced, random axes), and both sides of the switch agree as well.
#[test]
fn q4_from_rotation_vector_series_matches_sin_cos() {
    let mut rng = Rng64(91);
    let top = q4::SERIES_ANGLE;
    let mut worst = 0.0f64;
    for i in 0..=4000 {
        // θ from 1e-300 up to just below the switch, then a few just above it
        let th = if i < 4000 {
            top * 10f64.powf(-300.0 * (1.0 - f64::from(i) / 4000.0)) * (1.0 - 1e-12)
        } else {
            top * (1.0 + 1e-12)
        };
        let k: [f64; 3] = rng.unit_array::<3>();
        let v = [th * k[0], th * k[1], th * k[2]];
        let q = q4::from_rotation_vector(&v);
        // from θ itself: |v|² underflows below 1e-154
        let h = 0.5 * th;
        let want = [h.cos(), h.sin() * k[0], h.sin() * k[1], h.sin() * k[2]];
        for j in 0..4 {
            let scale = if j == 0 { 1.0 } else { h.sin() };
            let rel = (q[j] - want[j]).abs() / scale.max(f64::MIN_POSITIVE);
            worst = worst.max(rel);
        }
    }
    assert!(worst <= 2.5e-16, "largest relative difference {worst:e}");
}

#[test]
fn q4_from_matrix() {
    let mut rng = Rng64(73);
    let mut qs: Vec<[f64; 4]> = (0..200).map(|_| rng.unit_array::<4>()).collect();
    // Each branch: the largest component first, second, third, fourth; rotations by π.
    for i in 0..4 {
        let mut q = [0.1, -0.2, 0.15, 0.05];
        q[i] = 0.95;
        let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        qs.push([q[0] / n, q[1] / n, q[2] / n, q[3] / n]);
        let mut e = [0.0; 4];
        e[i] = 1.0;
        qs.push(e);
    }
    qs.push([0.0, 0.6, 0.8, 0.0]);
    qs.push([0.0, 0.0, 0.6, -0.8]);
    for q in &qs {
        let got = q4::from_matrix(&rot(q));
        let s = if got.iter().zip(q).map(|(a, b)| a * b).sum::<f64>() < 0.0 {
            -1.0
        } else {
            1.0
        };
        for i in 0..4 {
            assert!((s * got[i] - q[i]).abs() < 1e-14, "{q:?} -> {got:?}");
        }
    }
}
