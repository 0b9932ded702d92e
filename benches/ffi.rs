//! The C ABI's cost per call (criterion, group `c_call`; issue 35): each exported function timed
//! against the Rust function it wraps, in one run, on the same inputs and the same state.
//!
//! - `log_f_d2`: `bingham_log_normalization_constant(2, …)` (with the gradient) against
//!   `normalization::log_normalization_into`; `rust+catch_unwind` is the Rust call inside
//!   `std::panic::catch_unwind`, as the export's panic guard runs it (the price of the guard).
//! - `filter_step_d2`: `bingham_filter_predict` + `bingham_filter_update` against
//!   `BinghamFilter::predict` + `update`, from the same state every iteration (a clone made
//!   outside the timing, on the heap on both sides as the C handle is, so both do the same work:
//!   the JAIF Sec. 7 d = 2 scenario after 50 steps).
//! - `ahrs_sample`: `bingham_ahrs_update` (gyroscope, accelerometer, magnetometer) against
//!   `Ahrs::update`, from the same state every iteration (a clone outside the timing, the 100 Hz
//!   stream of `benches/ahrs.rs` after 1000 samples): `ahrs_sample_one` the next sample,
//!   `ahrs_sample_two` the next two (one of them with a correction: every 2nd sample at
//!   100 Hz).
//!
//! The exports are called from Rust through the crate's rlib (`bingham::ffi`); they are not
//! inlined into this crate (no LTO), so each is a real call of the exported symbol, as from C.
//! Figures: `docs/speed.md`, row `c-call`.

use bingham::ahrs::{Ahrs, AhrsParams};
use bingham::ffi::{
    bingham_ahrs, bingham_ahrs_clone, bingham_ahrs_free, bingham_ahrs_new, bingham_ahrs_update,
    bingham_filter, bingham_filter_clone, bingham_filter_free, bingham_filter_new,
    bingham_filter_predict, bingham_filter_update, bingham_log_normalization_constant,
    bingham_status,
};
use bingham::filter::BinghamFilter;
use bingham::normalization::{log_normalization_into, Method};
use bingham::quaternion::compose;
use bingham::Bingham;
use criterion::{black_box, criterion_group, criterion_main, BatchSize, Criterion};
use rand::rngs::StdRng;
use rand::SeedableRng;
use testkit::scenarios::{scenario_2d, simulate_with};

mod imu_stream;

/// A filter handle of the C ABI, freed on drop (outside the timing).
struct CFilter(*mut bingham_filter);

impl Drop for CFilter {
    fn drop(&mut self) {
        // SAFETY: a live handle from `bingham_filter_new` / `_clone`, freed once.
        unsafe { bingham_filter_free(self.0) }
    }
}

/// An AHRS handle of the C ABI, freed on drop (outside the timing).
struct CAhrs(*mut bingham_ahrs);

impl Drop for CAhrs {
    fn drop(&mut self) {
        // SAFETY: a live handle from `bingham_ahrs_new` / `_clone`, freed once.
        unsafe { bingham_ahrs_free(self.0) }
    }
}

fn ok(status: bingham_status) {
    assert_eq!(status, bingham_status::BINGHAM_OK);
}

fn bench_log_f(c: &mut Criterion) {
    let mut g = c.benchmark_group("c_call");
    let z = [-100.0, 0.0];
    g.bench_function("log_f_d2/rust", |b| {
        let mut grad = [0.0; 2];
        b.iter(|| {
            log_normalization_into(black_box(&z), Method::Exact, Some(&mut grad), None).unwrap()
        })
    });
    g.bench_function("log_f_d2/rust+catch_unwind", |b| {
        let mut grad = [0.0; 2];
        b.iter(|| {
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                log_normalization_into(black_box(&z), Method::Exact, Some(&mut grad), None)
            }))
            .unwrap()
            .unwrap()
        })
    });
    g.bench_function("log_f_d2/c", |b| {
        let mut grad = [0.0; 2];
        let mut lf = 0.0;
        b.iter(|| {
            // SAFETY: z has 2 readable doubles, lf one and grad 2 writable ones.
            let st = unsafe {
                bingham_log_normalization_constant(
                    2,
                    black_box(z.as_ptr()),
                    &mut lf,
                    grad.as_mut_ptr(),
                )
            };
            ok(st);
            lf
        })
    });
    g.finish();
}

fn bench_filter_step(c: &mut Criterion) {
    let sc = scenario_2d();
    let draw = |m: &[f64], z: &[f64], seed: u64, n: usize| -> Vec<Vec<f64>> {
        let b = Bingham::from_row_major(sc.d, m, z).unwrap();
        let x = b.sample(&mut StdRng::seed_from_u64(seed), n);
        x.iter().map(|v| v.as_slice().to_vec()).collect()
    };
    let meas = simulate_with(&sc, 0, draw, |x, y| compose(x, y).unwrap()).1;
    let mut f = BinghamFilter::new(sc.d, &sc.m0, &sc.z0).unwrap();
    let mut cf = std::ptr::null_mut();
    // SAFETY: m0 (d*d), z0 (d) readable, `cf` a writable handle pointer.
    ok(unsafe { bingham_filter_new(sc.d, sc.m0.as_ptr(), sc.z0.as_ptr(), &mut cf) });
    let cf = CFilter(cf);
    for y in &meas[..50] {
        f.predict(&sc.mw, &sc.zw).unwrap();
        f.update(y, &sc.mv, &sc.zv).unwrap();
        // SAFETY: a live handle; noise d*d and d, the measurement d readable doubles.
        unsafe {
            ok(bingham_filter_predict(cf.0, sc.mw.as_ptr(), sc.zw.as_ptr()));
            ok(bingham_filter_update(
                cf.0,
                y.as_ptr(),
                sc.mv.as_ptr(),
                sc.zv.as_ptr(),
            ));
        }
    }
    let y = meas[50].clone();
    let mut g = c.benchmark_group("c_call");
    g.bench_function("filter_step_d2/rust", |b| {
        b.iter_batched_ref(
            || Box::new(f.clone()),
            |h| {
                h.predict(black_box(&sc.mw), black_box(&sc.zw)).unwrap();
                h.update(black_box(&y), black_box(&sc.mv), black_box(&sc.zv))
                    .unwrap();
            },
            BatchSize::SmallInput,
        )
    });
    g.bench_function("filter_step_d2/c", |b| {
        b.iter_batched_ref(
            || {
                let mut h = std::ptr::null_mut();
                // SAFETY: a live handle; `h` a writable handle pointer.
                ok(unsafe { bingham_filter_clone(cf.0, &mut h) });
                CFilter(h)
            },
            |h| {
                // SAFETY: a live handle; noise d*d and d, the measurement d readable doubles.
                unsafe {
                    ok(bingham_filter_predict(
                        h.0,
                        black_box(sc.mw.as_ptr()),
                        black_box(sc.zw.as_ptr()),
                    ));
                    ok(bingham_filter_update(
                        h.0,
                        black_box(y.as_ptr()),
                        black_box(sc.mv.as_ptr()),
                        black_box(sc.zv.as_ptr()),
                    ));
                }
            },
            BatchSize::SmallInput,
        )
    });
    g.finish();
}

/// Samples of the 100 Hz stream of `benches/ahrs.rs` (gyroscope, accelerometer, magnetometer).
fn stream(n: usize) -> Vec<[[f64; 3]; 3]> {
    imu_stream::stream(0.01, n)
}

fn bench_ahrs(c: &mut Criterion) {
    let data = stream(1002);
    let params = AhrsParams::new(0.01);
    let mut a = Ahrs::new(&params).unwrap();
    let mut ca = std::ptr::null_mut();
    // SAFETY: `params` readable, `ca` a writable handle pointer.
    ok(unsafe { bingham_ahrs_new(&params, &mut ca) });
    let ca = CAhrs(ca);
    for [gyr, acc, mag] in &data[..1000] {
        a.update(gyr, acc, Some(mag)).unwrap();
        // SAFETY: a live handle; 3 readable doubles each.
        ok(unsafe { bingham_ahrs_update(ca.0, gyr.as_ptr(), acc.as_ptr(), mag.as_ptr()) });
    }
    let mut g = c.benchmark_group("c_call");
    // Which of two samples corrects is the AHRS's business: one sample, and two (one of them
    // corrects), from the state after 1000 samples.
    for (name, samples) in [("one", &data[1000..1001]), ("two", &data[1000..1002])] {
        g.bench_function(format!("ahrs_sample_{name}/rust"), |b| {
            b.iter_batched_ref(
                || Box::new(a.clone()),
                |h| {
                    for [gyr, acc, mag] in samples {
                        h.update(black_box(gyr), black_box(acc), black_box(Some(mag)))
                            .unwrap();
                    }
                },
                BatchSize::SmallInput,
            )
        });
        g.bench_function(format!("ahrs_sample_{name}/c"), |b| {
            b.iter_batched_ref(
                || {
                    let mut h = std::ptr::null_mut();
                    // SAFETY: a live handle; `h` a writable handle pointer.
                    ok(unsafe { bingham_ahrs_clone(ca.0, &mut h) });
                    CAhrs(h)
                },
                |h| {
                    for [gyr, acc, mag] in samples {
                        // SAFETY: a live handle; 3 readable doubles each.
                        ok(unsafe {
                            bingham_ahrs_update(
                                h.0,
                                black_box(gyr.as_ptr()),
                                black_box(acc.as_ptr()),
                                black_box(mag.as_ptr()),
                            )
                        });
                    }
                },
                BatchSize::SmallInput,
            )
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(std::time::Duration::from_millis(500)).measurement_time(std::time::Duration::from_secs(2));
    targets = bench_log_f, bench_filter_step, bench_ahrs
}
criterion_main!(benches);
