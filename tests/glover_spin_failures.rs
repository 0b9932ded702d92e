//! What sets QBF-2's spin error on the simulated ping-pong balls of `tests/glover_spin.rs`
//! (Glover & Kaelbling 2013, Sec. 6; issue 22): the noise levels, and what its gross failures
//! are. Figures and discussion: docs/accuracy/filter.md, "Spin tracking on simulated ping-pong balls".

#[path = "glover_common/ball.rs"]
mod ball;
mod glover_common;

use ball::*;
use bingham::quaternion::q4;
use glover_common::{angle, Q};

/// QBF-2 alone on the same trajectories with other noise levels: what sets its spin error.
/// Returns the mean spin error and classification rate at frame 30.
fn qbf2_only(z_detect_truth: &[f64; 4], z_process: [f64; 4], z_detect: [f64; 4]) -> (f64, f64) {
    let noises = noises(z_detect_truth);
    let means: Vec<Q> = (0..TYPES).map(type_mean).collect();
    let (mut e, mut h, mut n) = (0.0, 0.0, 0.0);
    for kind in 0..TYPES {
        for index in 0..PER_TYPE {
            let t = simulate(kind, index, &noises);
            let mut f = Qbf2::with_noises(&IDENTITY, &Z_SPIN_PRIOR, z_process, z_detect);
            for obs in &t.obs[..30] {
                f.frame(obs, "sensitivity");
            }
            e += angle(&f.f.spin_mode(), &t.spin);
            h += f64::from(u8::from(classify(&f.f.spin(), &means) == t.kind));
            n += 1.0;
        }
    }
    (e / n, h / n)
}

/// What sets QBF-2's spin error: the filter's assumed process noise (the paper's `(−400)³` lets
/// the spin wander 7° per frame; the simulated spin is constant) and the detection noise (drawn
/// here from the paper's Λo itself, 26° RMS about the line of sight; the paper's final logo
/// errors of 6–7° suggest its detections were better than its Λo). Detections drawn from
/// `(−400, −400, −100)` (λ × 10, angles / √10), with the filter told or still assuming the
/// paper's Λo; the filter's process noise `(−4000)³`; both.
#[test]
fn spin_error_depends_on_the_noise_levels() {
    let tight = [0.0, -400.0, -400.0, -100.0];
    let slow = [0.0, -4000.0, -4000.0, -4000.0];
    let cases = [
        ("as in the main test", Z_DETECT, Z_PROCESS, Z_DETECT),
        ("filter process noise (-4000)^3", Z_DETECT, slow, Z_DETECT),
        (
            "detections (-400,-400,-100), filter told",
            tight,
            Z_PROCESS,
            tight,
        ),
        (
            "detections (-400,-400,-100), filter not told",
            tight,
            Z_PROCESS,
            Z_DETECT,
        ),
        ("both, filter told", tight, slow, tight),
    ];
    println!("QBF-2 at frame 30 (spin error rad / classification %):");
    let mut out = Vec::new();
    for (name, truth, process, detect) in cases {
        let (e, h) = qbf2_only(&truth, process, detect);
        println!("  {name:<46} {e:.3} / {:.1}", 100.0 * h);
        out.push((e, h));
    }
    // measured: 0.379, 0.342, 0.179, 0.201, 0.134 rad
    assert!(
        out[2].0 < 0.6 * out[0].0 && out[3].0 < 0.6 * out[0].0,
        "{out:?}"
    );
    assert!(out[4].0 < out[2].0, "{out:?}");
}

/// What QBF-2's gross failures (spin error above 0.5 rad at frame 30) are: for each, the total
/// predictive log-likelihood of the first 30 frames under a QBF-2 whose spin prior is tight
/// (`(−400)³`, the process noise's own scale) at the failed estimate, against one at the true
/// spin. Where the estimate's is the higher, the observations themselves prefer the wrong spin
/// (an alias: with the logo near the spin axis, its half-turn symmetry makes `v` and `v` turned
/// by a half turn about the logo's normal explain the detections almost equally well), and no
/// estimator could be expected to find the truth. Where the truth's is far higher, the single
/// unimodal spin belief committed to the wrong spin in the first frames and could not come back
/// (the bank of 12, whose priors start near the truth, recovers these). The same for the bank.
#[test]
fn gross_failures_are_aliases_or_early_commitment() {
    let noises = noises(&Z_DETECT);
    let means: Vec<Q> = (0..TYPES).map(type_mean).collect();
    let tight = [-400.0, -400.0, -400.0, 0.0];
    // (error, log-likelihood of the estimate minus the truth's, logo–spin-axis angle in degrees)
    let mut qbf2 = Vec::new();
    let mut bank_gross = Vec::new();
    let (mut n, mut e_all, mut e_bank) = (0.0, 0.0, 0.0);
    for kind in 0..TYPES {
        for index in 0..PER_TYPE {
            let t = simulate(kind, index, &noises);
            let frames = &t.obs[..30];
            let mut f = Qbf2::new(&IDENTITY, &Z_SPIN_PRIOR);
            let mut bank: Vec<Qbf2> = means.iter().map(|m| Qbf2::new(m, &Z_BANK_PRIOR)).collect();
            for obs in frames {
                f.frame(obs, "qbf2");
                bank.iter_mut().for_each(|b| b.frame(obs, "bank"));
            }
            let best = (0..TYPES)
                .max_by(|&a, &b| bank[a].total.total_cmp(&bank[b].total))
                .unwrap();
            let margin = |v: &Q| {
                let (mut at_v, mut at_truth) = (Qbf2::new(v, &tight), Qbf2::new(&t.spin, &tight));
                for obs in frames {
                    at_v.frame(obs, "estimate");
                    at_truth.frame(obs, "truth");
                }
                at_v.total - at_truth.total
            };
            let axis = q4::to_rotation_vector(&t.spin);
            let logo = q4::rotate(&t.x[0], &LOGO);
            let cos =
                glover_common::dot(&axis, &logo).abs() / glover_common::dot(&axis, &axis).sqrt();
            let alpha = cos.min(1.0).acos().to_degrees();
            let (v, vb) = (f.f.spin_mode(), bank[best].f.spin_mode());
            let (e, eb) = (angle(&v, &t.spin), angle(&vb, &t.spin));
            if e > 0.5 {
                qbf2.push((e, margin(&v), alpha));
            }
            if eb > 0.5 {
                bank_gross.push((eb, margin(&vb), alpha));
            }
            e_all += e;
            e_bank += eb;
            n += 1.0;
        }
    }
    let show = |name: &str, g: &[(f64, f64, f64)]| {
        println!("{name}: {} gross failures at frame 30 (error rad, log-likelihood of the estimate − the truth's, logo–axis angle °):", g.len());
        for (e, d, a) in g {
            println!("  {e:.2} {d:+7.2} {a:5.1}");
        }
    };
    show("QBF-2", &qbf2);
    show("bank", &bank_gross);
    let alias = |g: &[(f64, f64, f64)]| g.iter().filter(|r| r.1 >= 0.0).count();
    let committed: Vec<_> = qbf2.iter().filter(|r| r.1 < -5.0).collect();
    let e_committed: f64 = committed.iter().map(|r| r.0).sum();
    println!(
        "QBF-2: mean {:.3} rad; {} aliases the data prefers, {} early commitments (truth ≥ 5 nats likelier), \
         carrying {:.3} rad of the mean; bank: mean {:.3} rad, {} aliases",
        e_all / n,
        alias(&qbf2),
        committed.len(),
        e_committed / n,
        e_bank / n,
        alias(&bank_gross)
    );
    // measured (seeds fixed): QBF-2 26 gross failures, 8 aliases the data prefers, 13
    // commitments carrying 0.154 rad of the 0.379 mean; every wrong-sense failure (error
    // > 2.5 rad) is a commitment. The bank's 16: 11 aliases, the other 5 within 3 nats of the
    // truth — its 0.251 rad mean is about what choosing the likeliest spin can reach here.
    assert!((20..=32).contains(&qbf2.len()), "{}", qbf2.len());
    assert!(alias(&qbf2) >= 5, "{qbf2:?}");
    assert!(committed.len() >= 10, "{qbf2:?}");
    for r in qbf2.iter().filter(|r| r.0 > 2.5) {
        assert!(
            r.1 < -5.0,
            "a wrong-sense failure the data does not reject: {r:?}"
        );
    }
    assert!(alias(&bank_gross) >= 8, "{bank_gross:?}");
    for r in &bank_gross {
        assert!(r.1 > -3.5, "a bank failure the data rejects: {r:?}");
    }
}
