//! After warm-up, filter steps perform no heap allocation at all: a counting global allocator
//! (this test binary only) sees zero allocations over many predict + update steps, through the
//! Rust API and through the C API, over vector-observation updates, over the world-frame steps
//! (`predict_world` with and without control, `update_world`, `log_likelihood_world`), over
//! spin-filter steps (with and without control and observation, and the spin filter's
//! log-likelihood, modes, spreads and state), and over AHRS samples.

mod filter_common;

use bingham::ffi::bingham_status;
use bingham::ffi::filter::*;
use bingham::ffi::spin::*;
use bingham::ffi::world::*;
use bingham::filter::{BinghamFilter, SpinFilter};
use filter_common::simulate;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use testkit::scenarios::{normalized, scenario_2d, scenario_4d, turn, Scenario};

/// Counts every allocation and reallocation of the thread that makes it. Per thread, not per
/// process: the library does all its work on the calling thread (it starts none), and the test
/// harness's own threads (which may allocate at any moment, e.g. the main thread bookkeeping
/// the running test while the machine is loaded) must not count against a step.
struct Counting;

thread_local! {
    // const-initialized: reading it never allocates (it may be read from inside `alloc`)
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    // during the thread's teardown the slot may be gone: nothing to count then
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: forwards to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: forwarded contract.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: forwarded contract.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: forwarded contract.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded contract.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The allocations this thread has made so far.
fn allocations() -> usize {
    ALLOCATIONS.with(|c| c.get())
}

/// Every scenario in one test function (the counter is per thread; one function keeps the
/// warm-ups and the windows in one place).
#[test]
fn filter_steps_do_not_allocate() {
    // the counter sees this thread's allocations
    let before = allocations();
    let v: Vec<u64> = std::hint::black_box(vec![1, 2, 3]);
    assert!(allocations() > before && v.len() == 3);
    for sc in [scenario_2d(), scenario_4d()] {
        rust_api(&sc);
        c_api(&sc);
        nonlinear_steps(&sc);
        world_steps(&sc);
    }
    spin_steps();
    vector_updates();
    ahrs_steps();
}

/// The world-frame steps through the Rust and the C API, after one warm-up step of each with the
/// same noises: `predict_world` with a control and without (NULL), `log_likelihood_world`,
/// `update_world`.
fn world_steps(sc: &Scenario) {
    let meas: Vec<Vec<f64>> = (0..3).flat_map(|r| simulate(sc, r).1).collect();
    let u = normalized(&vec![1.0; sc.d]);
    let ok = bingham_status::BINGHAM_OK;
    let mut f = BinghamFilter::new(sc.d, &sc.m0, &sc.z0).unwrap();
    f.predict_world(Some(&u), &sc.mw, &sc.zw).unwrap();
    f.update_world(&meas[0], &sc.mv, &sc.zv).unwrap();
    let mut mode = vec![0.0; sc.d];
    let before = allocations();
    let mut ll = 0.0;
    for (k, y) in meas.iter().enumerate() {
        let control = (k % 2 == 0).then_some(&u[..]);
        f.predict_world(control, &sc.mw, &sc.zw).unwrap();
        ll += f.log_likelihood_world(y, &sc.mv, &sc.zv).unwrap();
        f.update_world(y, &sc.mv, &sc.zv).unwrap();
        f.mode_into(&mut mode).unwrap();
    }
    let n = allocations() - before;
    assert!(ll.is_finite());
    assert_eq!(
        n,
        0,
        "d = {}: {n} allocations in {} world-frame steps (Rust API)",
        sc.d,
        meas.len()
    );
    let mut h: *mut bingham_filter = std::ptr::null_mut();
    // SAFETY: valid arrays of the documented lengths; the handle is freed below.
    unsafe {
        assert_eq!(
            bingham_filter_new(sc.d, sc.m0.as_ptr(), sc.z0.as_ptr(), &mut h),
            ok
        );
        assert_eq!(
            bingham_filter_predict_world(h, u.as_ptr(), sc.mw.as_ptr(), sc.zw.as_ptr()),
            ok
        );
        assert_eq!(
            bingham_filter_update_world(h, meas[0].as_ptr(), sc.mv.as_ptr(), sc.zv.as_ptr()),
            ok
        );
        let before = allocations();
        for (k, y) in meas.iter().enumerate() {
            let control = if k % 2 == 0 {
                u.as_ptr()
            } else {
                std::ptr::null()
            };
            let s1 = bingham_filter_predict_world(h, control, sc.mw.as_ptr(), sc.zw.as_ptr());
            let s2 = bingham_filter_log_likelihood_world(
                h,
                y.as_ptr(),
                sc.mv.as_ptr(),
                sc.zv.as_ptr(),
                &mut ll,
            );
            let s3 = bingham_filter_update_world(h, y.as_ptr(), sc.mv.as_ptr(), sc.zv.as_ptr());
            assert!([s1, s2, s3].iter().all(|&s| s == ok));
        }
        let n = allocations() - before;
        bingham_filter_free(h);
        assert_eq!(
            n,
            0,
            "d = {}: {n} allocations in {} world-frame steps (C API)",
            sc.d,
            meas.len()
        );
    }
    println!(
        "d = {}: {} world-frame steps (Rust and C API): 0 allocations",
        sc.d,
        meas.len()
    );
}

/// A spinning object observed most steps: the spin filter's steps (with and without control,
/// with and without observation), log-likelihood, modes, spreads and state, through the Rust and
/// the C API, after one warm-up step with the same noises.
fn spin_steps() {
    let identity: [f64; 16] = std::array::from_fn(|i| if i % 5 == 0 { 1.0 } else { 0.0 });
    let (z_x, z_v) = ([0.0; 4], [0.0, -3.0, -3.0, -3.0]);
    let (z_w, z_o) = ([0.0, -400.0, -400.0, -10.0], [0.0, -40.0, -40.0, -10.0]);
    let u = normalized(&[1.0, 0.02, -0.01, 0.03]);
    let spin = normalized(&[0.9, 0.3, -0.2, 0.1]);
    let mut x = vec![1.0, 0.0, 0.0, 0.0];
    let ys: Vec<Vec<f64>> = (0..300)
        .map(|_| {
            x = bingham::quaternion::compose(&spin, &x).unwrap();
            x.clone()
        })
        .collect();
    let ok = bingham_status::BINGHAM_OK;
    let (mut m, mut z, mut m2, mut z2) = ([0.0; 16], [0.0; 4], [0.0; 16], [0.0; 4]);
    let (mut xs, mut vs) = ([0.0; 4], [0.0; 4]);
    let mut f = SpinFilter::new(&identity, &z_x, &identity, &z_v).unwrap();
    f.step(Some(&u), &identity, &z_w, Some(&ys[0]), &identity, &z_o)
        .unwrap();
    let before = allocations();
    let mut sum = 0.0;
    for (k, y) in ys.iter().enumerate() {
        let control = (k % 2 == 0).then_some(&u[..]);
        let observed = (k % 4 != 3).then_some(&y[..]);
        sum += f.log_likelihood(y, &identity, &z_o).unwrap();
        f.step(control, &identity, &z_w, observed, &identity, &z_o)
            .unwrap();
        sum += f.orientation_mode()[0] + f.spin_mode()[0];
        f.angular_spread_into(&mut xs, &mut vs).unwrap();
        f.state_into(&mut m, &mut z, &mut m2, &mut z2).unwrap();
    }
    let n = allocations() - before;
    assert!(sum.is_finite());
    assert_eq!(
        n,
        0,
        "{n} allocations in {} spin steps (Rust API)",
        ys.len()
    );
    let mut h: *mut bingham_spin_filter = std::ptr::null_mut();
    // SAFETY: valid arrays of the documented lengths; the handle is freed below.
    unsafe {
        let id = identity.as_ptr();
        assert_eq!(
            bingham_spin_filter_new(id, z_x.as_ptr(), id, z_v.as_ptr(), &mut h),
            ok
        );
        assert_eq!(
            bingham_spin_filter_step(
                h,
                u.as_ptr(),
                id,
                z_w.as_ptr(),
                ys[0].as_ptr(),
                id,
                z_o.as_ptr()
            ),
            ok
        );
        let mut ll = 0.0;
        let mut q = [0.0; 4];
        let before = allocations();
        for (k, y) in ys.iter().enumerate() {
            let control = if k % 2 == 0 {
                u.as_ptr()
            } else {
                std::ptr::null()
            };
            let s1 = bingham_spin_filter_log_likelihood(h, y.as_ptr(), id, z_o.as_ptr(), &mut ll);
            // without observation, the observation noise is not passed
            let s2 = if k % 4 == 3 {
                bingham_spin_filter_step(
                    h,
                    control,
                    id,
                    z_w.as_ptr(),
                    std::ptr::null(),
                    std::ptr::null(),
                    std::ptr::null(),
                )
            } else {
                bingham_spin_filter_step(h, control, id, z_w.as_ptr(), y.as_ptr(), id, z_o.as_ptr())
            };
            let s3 = bingham_spin_filter_spin_mode(h, q.as_mut_ptr());
            let s4 = bingham_spin_filter_angular_spread(h, xs.as_mut_ptr(), vs.as_mut_ptr());
            let s5 = bingham_spin_filter_get_state(
                h,
                m.as_mut_ptr(),
                z.as_mut_ptr(),
                m2.as_mut_ptr(),
                z2.as_mut_ptr(),
            );
            assert!([s1, s2, s3, s4, s5].iter().all(|&s| s == ok));
        }
        let n = allocations() - before;
        bingham_spin_filter_free(h);
        assert_eq!(n, 0, "{n} allocations in {} spin steps (C API)", ys.len());
    }
    println!(
        "{} spin-filter steps (Rust and C API): 0 allocations",
        ys.len()
    );
}

/// `update_vector`, `log_likelihood_vector` and `angular_spread_into` after a predict.
fn vector_updates() {
    let sc = scenario_4d();
    let mut f = BinghamFilter::new(4, &sc.m0, &sc.z0).unwrap();
    let dirs: Vec<[f64; 3]> = (0..200)
        .map(|k| {
            let t = k as f64 * 0.1;
            let v = [t.cos(), t.sin(), 0.3 * (0.7 * t).cos()];
            let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            [v[0] / n, v[1] / n, v[2] / n]
        })
        .collect();
    let refs = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0]];
    f.predict(&sc.mw, &sc.zw).unwrap();
    f.update_vector(&dirs[0], &refs[0], 5.0).unwrap();
    let mut spread = [0.0; 4];
    let before = allocations();
    let mut ll = 0.0;
    for (k, b) in dirs.iter().enumerate() {
        let r = &refs[k % 2];
        f.predict(&sc.mw, &sc.zw).unwrap();
        ll += f.log_likelihood_vector(b, r, 5.0).unwrap();
        f.update_vector(b, r, 5.0).unwrap();
        f.angular_spread_into(&mut spread).unwrap();
    }
    let n = allocations() - before;
    assert!(ll.is_finite());
    assert_eq!(n, 0, "{n} allocations in {} vector updates", dirs.len());
    println!("{} vector updates: 0 allocations", dirs.len());
}

/// 1000 AHRS samples (gyroscope, accelerometer, magnetometer; some with a disturbed field, some
/// without magnetometer, a short free fall) after a few samples of warm-up, with the default
/// parameters and with both latencies compensated; the getters (latency estimate included) too.
fn ahrs_steps() {
    use bingham::ahrs::AhrsParams;
    use bingham::quaternion::q4;
    let dt = 0.01;
    let n = 1010;
    let mut q = [1.0, 0.0, 0.0, 0.0];
    let mut samples = Vec::with_capacity(n);
    for k in 0..n {
        let t = k as f64 * dt;
        let w = [0.5 * t.sin(), 0.4 * (0.7 * t).cos(), 0.3];
        q = q4::mul(
            &q,
            &q4::from_rotation_vector(&[w[0] * dt, w[1] * dt, w[2] * dt]),
        );
        let mut acc = q4::rotate_inverse(&q, &[0.0, 0.0, 9.81]);
        if (600..620).contains(&k) {
            acc = [0.0; 3]; // free fall
        }
        let scale = if (400..450).contains(&k) { 1.6 } else { 1.0 };
        let mag = q4::rotate_inverse(&q, &[0.0, 20.0 * scale, -40.0 * scale]);
        let gyr = [w[0] + 0.01, w[1] - 0.01, w[2] + 0.005];
        samples.push((gyr, acc, mag));
    }
    // the defaults, and the latency compensation of both sensors
    let latencies = AhrsParams {
        mag_latency: 0.011,
        acc_latency: 0.005,
        ..AhrsParams::new(dt)
    };
    for params in [AhrsParams::new(dt), latencies] {
        ahrs_run(&params, &samples);
    }
}

fn ahrs_run(params: &bingham::ahrs::AhrsParams, samples: &[([f64; 3], [f64; 3], [f64; 3])]) {
    use bingham::ahrs::Ahrs;
    let mut a = Ahrs::new(params).unwrap();
    for (gyr, acc, mag) in &samples[..10] {
        a.update(gyr, acc, Some(mag)).unwrap();
    }
    let mut m = [0.0; 16];
    let mut z = [0.0; 4];
    let mut spread = [0.0; 4];
    let mut sum = 0.0;
    let before = allocations();
    for (k, (gyr, acc, mag)) in samples[10..].iter().enumerate() {
        let mag = if (700..720).contains(&k) {
            None
        } else {
            Some(mag)
        };
        a.update(gyr, acc, mag).unwrap();
        sum += a.quaternion()[0] + a.gyro_bias()[0] + a.mag_latency_estimate().unwrap_or(0.0);
        a.state_into(&mut m, &mut z).unwrap();
        a.angular_spread(&mut spread).unwrap();
    }
    let n = allocations() - before;
    assert!(sum.is_finite());
    assert_eq!(
        n,
        0,
        "{n} allocations in {} AHRS samples",
        samples.len() - 10
    );
    println!("{} AHRS samples: 0 allocations", samples.len() - 10);
}

/// `predict_nonlinear` (a rotation as the transition) and `update_nonlinear` (the
/// measurement's Bingham log-likelihood written out, and a non-quadratic one) through the Rust
/// API: the callbacks allocate nothing, so neither may the steps.
fn nonlinear_steps(sc: &Scenario) {
    let meas: Vec<Vec<f64>> = (0..2).flat_map(|r| simulate(sc, r).1).collect();
    let d = sc.d;
    let mut f = BinghamFilter::new(d, &sc.m0, &sc.z0).unwrap();
    let transition = turn;
    f.predict_nonlinear(transition, &sc.mw, &sc.zw).unwrap(); // warm-up: the noise cache
    let before = allocations();
    let mut calls = 0usize;
    for (k, y) in meas.iter().enumerate() {
        f.predict_nonlinear(transition, &sc.mw, &sc.zw).unwrap();
        // log L(x) = -kappa (1 - <x, y>^2): sharp, Bingham-form; every third step its square
        // (not log-quadratic: several tempering rounds).
        let quartic = k % 3 == 0;
        f.update_nonlinear(|x| {
            calls += 1;
            let dot: f64 = x.iter().zip(y).map(|(a, b)| a * b).sum();
            let e = 1.0 - dot * dot;
            Ok(if quartic {
                -50.0 * e - 500.0 * e * e
            } else {
                -50.0 * e
            })
        })
        .unwrap();
    }
    let n = allocations() - before;
    assert_eq!(
        n,
        0,
        "d = {d}: {n} allocations in {} nonlinear steps",
        meas.len()
    );
    println!(
        "d = {d}: {} nonlinear predict + update steps ({calls} likelihood calls): 0 allocations",
        meas.len()
    );
}

fn rust_api(sc: &Scenario) {
    let meas: Vec<Vec<f64>> = (0..3).flat_map(|r| simulate(sc, r).1).collect();
    let u = normalized(&vec![1.0; sc.d]);
    let mut f = BinghamFilter::new(sc.d, &sc.m0, &sc.z0).unwrap();
    // warm-up: fills the noise caches
    f.predict(&sc.mw, &sc.zw).unwrap();
    f.update(&meas[0], &sc.mv, &sc.zv).unwrap();
    let mut mode = vec![0.0; sc.d];
    let mut m = vec![0.0; sc.d * sc.d];
    let mut z = vec![0.0; sc.d];
    let before = allocations();
    let mut ll = 0.0;
    for (k, y) in meas.iter().enumerate() {
        if k % 2 == 0 {
            f.predict(&sc.mw, &sc.zw).unwrap();
        } else {
            f.predict_rotation(&u, &sc.mw, &sc.zw).unwrap();
        }
        ll += f.log_likelihood(y, &sc.mv, &sc.zv).unwrap();
        f.update(y, &sc.mv, &sc.zv).unwrap();
        f.mode_into(&mut mode).unwrap();
        f.state_into(&mut m, &mut z).unwrap();
    }
    let n = allocations() - before;
    assert!(ll.is_finite());
    assert_eq!(
        n,
        0,
        "d = {}: {n} allocations in {} steps",
        sc.d,
        meas.len()
    );
    println!(
        "d = {}: {} steps (Rust API), 0 allocations",
        sc.d,
        meas.len()
    );
}

fn c_api(sc: &Scenario) {
    let meas: Vec<Vec<f64>> = (0..3).flat_map(|r| simulate(sc, r).1).collect();
    let mut f: *mut bingham_filter = std::ptr::null_mut();
    // SAFETY: valid arrays of the documented lengths; the handle is freed below.
    unsafe {
        let st = bingham_filter_new(sc.d, sc.m0.as_ptr(), sc.z0.as_ptr(), &mut f);
        assert_eq!(st, bingham_status::BINGHAM_OK);
        assert_eq!(
            bingham_filter_predict(f, sc.mw.as_ptr(), sc.zw.as_ptr()),
            bingham_status::BINGHAM_OK
        );
        assert_eq!(
            bingham_filter_update(f, meas[0].as_ptr(), sc.mv.as_ptr(), sc.zv.as_ptr()),
            bingham_status::BINGHAM_OK
        );
        let mut mode = vec![0.0; sc.d];
        let mut ll = 0.0;
        let before = allocations();
        for y in &meas {
            let s1 = bingham_filter_predict(f, sc.mw.as_ptr(), sc.zw.as_ptr());
            let s2 = bingham_filter_log_likelihood(
                f,
                y.as_ptr(),
                sc.mv.as_ptr(),
                sc.zv.as_ptr(),
                &mut ll,
            );
            let s3 = bingham_filter_update(f, y.as_ptr(), sc.mv.as_ptr(), sc.zv.as_ptr());
            let s4 = bingham_filter_mode(f, mode.as_mut_ptr());
            assert!([s1, s2, s3, s4]
                .iter()
                .all(|&s| s == bingham_status::BINGHAM_OK));
        }
        let n = allocations() - before;
        bingham_filter_free(f);
        assert_eq!(
            n,
            0,
            "d = {}: {n} allocations in {} C-API steps",
            sc.d,
            meas.len()
        );
        println!("d = {}: {} steps (C API), 0 allocations", sc.d, meas.len());
    }
}
