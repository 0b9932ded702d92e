//! After warm-up, filter steps perform no heap allocation at all: a counting global allocator
//! (this test binary only) sees zero allocations over many predict + update steps, through the
//! Rust API and through the C API.

mod filter_common;

use bingham::ffi::bingham_status;
use bingham::ffi::filter::*;
use bingham::filter::BinghamFilter;
use filter_common::{scenario_2d, scenario_4d, simulate, Scenario};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Counts every allocation and reallocation of this process.
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: forwarded contract.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: forwarded contract.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
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

fn allocations() -> usize {
    ALLOCATIONS.load(Ordering::SeqCst)
}

/// The test harness runs tests on several threads; the counter is global, so everything runs in
/// one test function.
#[test]
fn filter_steps_do_not_allocate() {
    for sc in [scenario_2d(), scenario_4d()] {
        rust_api(&sc);
        c_api(&sc);
    }
}

fn rust_api(sc: &Scenario) {
    let meas: Vec<Vec<f64>> = (0..3).flat_map(|r| simulate(sc, r).1).collect();
    let u = filter_common::normalized(&vec![1.0; sc.d]);
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
