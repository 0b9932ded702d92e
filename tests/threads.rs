//! Threads and the C ABI: 8 threads, each driving its own filter handles (and the stateless
//! distribution functions) through the `extern "C"` functions, produce results bit-identical to a
//! single-threaded run of the same call sequences; read-only calls on one shared handle agree
//! across threads; handles may move between threads; and the last error message is per thread
//! (one thread's failures are never visible in another).

use std::sync::{Arc, Barrier};

use bingham::ffi::bingham_status::*;
use bingham::ffi::*;
use testkit::fuzz::{env_count, identity, orthogonal, read_message, z_moderate};
use testkit::{mix, norm, Rng64};

const THREADS: usize = 8;

/// A filter handle that may be moved to (or shared with) another thread. The header allows a
/// handle to be used by one thread at a time, and read-only (`const bingham_filter *`) calls to
/// run concurrently on the same handle.
#[derive(Clone, Copy)]
struct Handle(*mut bingham_filter);
// SAFETY: see above; the tests below respect those rules.
unsafe impl Send for Handle {}
// SAFETY: only read-only functions are called concurrently on a shared handle.
unsafe impl Sync for Handle {}

impl Handle {
    /// The raw pointer (a method, so that closures capture the whole `Send` wrapper).
    fn get(self) -> *mut bingham_filter {
        self.0
    }
}

/// This thread's last error message.
fn last_error() -> String {
    // SAFETY: the length query (NULL buffer, len 0), then a buffer of the length it gave.
    read_message(|buf, len, n| unsafe {
        bingham_last_error_message(buf, len, n);
    })
}

fn new_filter(d: usize, m: &[f64], z: &[f64]) -> Handle {
    let mut f = std::ptr::null_mut();
    // SAFETY: valid arrays of lengths d*d and d; out-pointer valid.
    let st = unsafe { bingham_filter_new(d, m.as_ptr(), z.as_ptr(), &mut f) };
    assert_eq!(st, BINGHAM_OK, "{}", last_error());
    Handle(f)
}

fn push_bits(out: &mut Vec<u64>, v: &[f64]) {
    out.extend(v.iter().map(|x| x.to_bits()));
}

fn get_state(h: Handle, d: usize) -> Vec<f64> {
    let mut m = vec![0.0; d * d + d];
    let (mp, zp) = m.split_at_mut(d * d);
    // SAFETY: live handle; buffers of lengths d*d and d.
    let st = unsafe { bingham_filter_get_state(h.0, mp.as_mut_ptr(), zp.as_mut_ptr()) };
    assert_eq!(st, BINGHAM_OK);
    m
}

/// One deterministic call sequence (a function of `seed` only): two filters (d = 2 and d = 4)
/// stepped with predicts, rotations and updates, plus stateless calls (log F, MLE, sampling,
/// products), everything recorded bit for bit, including the statuses.
fn transcript(seed: u64, steps: usize) -> Vec<u64> {
    let mut rng = Rng64::new(mix(seed));
    let mut out = Vec::new();
    for d in [2usize, 4] {
        let h = new_filter(d, &orthogonal(&mut rng, d), &z_moderate(&mut rng, d));
        let noises: Vec<(Vec<f64>, Vec<f64>)> = (0..3)
            .map(|_| {
                let mut z = vec![0.0; d];
                for v in z.iter_mut().skip(1) {
                    *v = -rng.log_uniform(-1.0, 7.0);
                }
                (identity(d), z)
            })
            .collect();
        for k in 0..steps {
            let (mw, zw) = &noises[rng.below(3)];
            let (mv, zv) = &noises[rng.below(3)];
            let y = rng.unit_vector(d);
            // SAFETY: live handle (this thread only); arrays of lengths d, d*d, d.
            let st = unsafe {
                if k % 4 == 3 {
                    let mut u = vec![0.0; d];
                    u[0] = 1.0;
                    u[1] = 0.01 * rng.normal();
                    let n = norm(&u);
                    u.iter_mut().for_each(|x| *x /= n);
                    bingham_filter_predict_rotation(h.0, u.as_ptr(), mw.as_ptr(), zw.as_ptr())
                } else {
                    bingham_filter_predict(h.0, mw.as_ptr(), zw.as_ptr())
                }
            };
            out.push(st as u64);
            let mut ll = 0.0;
            // SAFETY: as above.
            let st = unsafe {
                bingham_filter_log_likelihood(h.0, y.as_ptr(), mv.as_ptr(), zv.as_ptr(), &mut ll)
            };
            out.push(st as u64);
            out.push(ll.to_bits());
            // SAFETY: as above.
            let st = unsafe { bingham_filter_update(h.0, y.as_ptr(), mv.as_ptr(), zv.as_ptr()) };
            out.push(st as u64);
            push_bits(&mut out, &get_state(h, d));
        }
        // SAFETY: freed once.
        unsafe { bingham_filter_free(h.0) };
    }
    // stateless functions
    for _ in 0..steps / 4 + 1 {
        let d = 2 + rng.below(7);
        let z = z_moderate(&mut rng, d);
        let m = orthogonal(&mut rng, d);
        let mut lf = 0.0;
        let mut w = vec![0.0; d];
        let mut s = vec![0.0; d * d];
        let mut mm = vec![0.0; d * d];
        let mut zz = vec![0.0; d];
        let mut x = vec![0.0; 5 * d];
        // SAFETY: buffers of the documented lengths.
        unsafe {
            out.push(
                bingham_log_normalization_constant(d, z.as_ptr(), &mut lf, w.as_mut_ptr()) as u64,
            );
            out.push(bingham_second_moment(d, m.as_ptr(), z.as_ptr(), s.as_mut_ptr()) as u64);
            out.push(bingham_mle(d, s.as_ptr(), mm.as_mut_ptr(), zz.as_mut_ptr()) as u64);
            out.push(bingham_sample(d, m.as_ptr(), z.as_ptr(), seed, 5, x.as_mut_ptr()) as u64);
        }
        out.push(lf.to_bits());
        push_bits(&mut out, &w);
        push_bits(&mut out, &s);
        push_bits(&mut out, &mm);
        push_bits(&mut out, &zz);
        push_bits(&mut out, &x);
    }
    out
}

fn steps() -> usize {
    env_count("BINGHAM_THREAD_STEPS", 300) as usize
}

#[test]
fn eight_threads_match_a_single_thread_bit_for_bit() {
    let seeds: Vec<u64> = (0..2 * THREADS as u64).collect();
    let n = steps();
    let reference: Vec<Vec<u64>> = seeds.iter().map(|&s| transcript(s, n)).collect();
    for round in 0..3 {
        let barrier = Arc::new(Barrier::new(THREADS));
        let results: Vec<Vec<(u64, Vec<u64>)>> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..THREADS)
                .map(|t| {
                    let barrier = Arc::clone(&barrier);
                    let seeds = &seeds;
                    scope.spawn(move || {
                        barrier.wait();
                        // each thread runs two sequences, in a round-dependent order
                        let mine: Vec<u64> = seeds
                            .iter()
                            .copied()
                            .filter(|s| (*s as usize + round) % THREADS == t)
                            .collect();
                        mine.iter().map(|&s| (s, transcript(s, n))).collect()
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        let mut seen = 0;
        for (s, got) in results.into_iter().flatten() {
            assert!(
                got == reference[s as usize],
                "round {round}: sequence {s} differs between the threaded and the single-threaded run"
            );
            seen += 1;
        }
        assert_eq!(seen, seeds.len());
    }
}

#[test]
fn read_only_calls_share_a_handle() {
    let d = 4;
    let mut rng = Rng64::new(7);
    let h = new_filter(d, &orthogonal(&mut rng, d), &[-50.0, -20.0, -5.0, 0.0]);
    let (mv, zv) = (identity(d), vec![0.0, -100.0, -100.0, -100.0]);
    let ys: Vec<Vec<f64>> = (0..64).map(|_| rng.unit_vector(d)).collect();
    let single: Vec<u64> = ys
        .iter()
        .map(|y| {
            let mut ll = 0.0;
            // SAFETY: live handle, valid arrays.
            let st = unsafe {
                bingham_filter_log_likelihood(h.0, y.as_ptr(), mv.as_ptr(), zv.as_ptr(), &mut ll)
            };
            assert_eq!(st, BINGHAM_OK);
            ll.to_bits()
        })
        .collect();
    let state = get_state(h, d);
    let barrier = Barrier::new(THREADS);
    std::thread::scope(|scope| {
        for _ in 0..THREADS {
            scope.spawn(|| {
                barrier.wait();
                for _ in 0..50 {
                    for (y, want) in ys.iter().zip(&single) {
                        let mut ll = 0.0;
                        let mut mode = [0.0; 4];
                        let mut dd = 0usize;
                        // SAFETY: read-only functions on a shared live handle (allowed
                        // concurrently by the header).
                        unsafe {
                            let st = bingham_filter_log_likelihood(
                                h.0,
                                y.as_ptr(),
                                mv.as_ptr(),
                                zv.as_ptr(),
                                &mut ll,
                            );
                            assert_eq!(st, BINGHAM_OK);
                            assert_eq!(bingham_filter_mode(h.0, mode.as_mut_ptr()), BINGHAM_OK);
                            assert_eq!(bingham_filter_dim(h.0, &mut dd), BINGHAM_OK);
                        }
                        assert_eq!(ll.to_bits(), *want);
                        assert_eq!(dd, d);
                        assert_eq!(get_state(h, d), state);
                    }
                }
            });
        }
    });
    // SAFETY: freed once, no other user left.
    unsafe { bingham_filter_free(h.0) };
}

#[test]
fn handles_move_between_threads() {
    let d = 2;
    let (mw, zw) = (identity(d), vec![0.0, -100.0]);
    let y = [0.6, 0.8];
    let h = new_filter(d, &identity(d), &[-1.0, 0.0]);
    // reference: the same steps on one thread
    let r = new_filter(d, &identity(d), &[-1.0, 0.0]);
    for _ in 0..THREADS {
        // SAFETY: live handle, valid arrays.
        unsafe {
            assert_eq!(
                bingham_filter_predict(r.0, mw.as_ptr(), zw.as_ptr()),
                BINGHAM_OK
            );
            assert_eq!(
                bingham_filter_update(r.0, y.as_ptr(), mw.as_ptr(), zw.as_ptr()),
                BINGHAM_OK
            );
        }
    }
    // the handle is passed from thread to thread; each makes one step
    let mut cur = h;
    for _ in 0..THREADS {
        let (mw, zw) = (mw.clone(), zw.clone());
        cur = std::thread::spawn(move || {
            // SAFETY: this thread is the only user of the handle now.
            unsafe {
                assert_eq!(
                    bingham_filter_predict(cur.get(), mw.as_ptr(), zw.as_ptr()),
                    BINGHAM_OK
                );
                assert_eq!(
                    bingham_filter_update(cur.get(), y.as_ptr(), mw.as_ptr(), zw.as_ptr()),
                    BINGHAM_OK
                );
            }
            cur
        })
        .join()
        .unwrap();
    }
    assert_eq!(get_state(cur, d), get_state(r, d));
    // freed on yet another thread
    std::thread::spawn(move || {
        // SAFETY: freed once.
        unsafe { bingham_filter_free(cur.get()) }
    })
    .join()
    .unwrap();
    // SAFETY: freed once.
    unsafe { bingham_filter_free(r.0) };
}

/// A failing `bingham_log_pdf` whose message names the row `row`.
fn fail_with_row(row: usize) {
    let d = 2;
    let n = row + 1;
    let mut x = vec![0.0; n * d];
    for r in 0..n {
        x[r * d] = 1.0;
    }
    x[row * d] = 2.0;
    let (m, z) = (identity(d), [-1.0, 0.0]);
    let mut p = vec![0.0; n];
    // SAFETY: valid buffers.
    let st = unsafe { bingham_log_pdf(d, m.as_ptr(), z.as_ptr(), n, x.as_ptr(), p.as_mut_ptr()) };
    assert_eq!(st, BINGHAM_ERR_INVALID_ARGUMENT);
}

#[test]
fn last_error_is_per_thread() {
    let barrier = Barrier::new(THREADS + 1);
    std::thread::scope(|scope| {
        for t in 0..THREADS {
            let barrier = &barrier;
            scope.spawn(move || {
                // a new thread starts with no message
                assert_eq!(last_error(), "");
                barrier.wait();
                for i in 0..2000 {
                    let row = t + THREADS * (i % 64); // distinct per thread, short arrays
                    fail_with_row(row);
                    // other threads fail at the same time with other rows
                    std::thread::yield_now();
                    let msg = last_error();
                    assert!(
                        msg.starts_with("bingham_log_pdf: ")
                            && msg.contains(&format!("row {row}:")),
                        "thread {t} sees {msg:?}, expected its own row {row}"
                    );
                    // successful calls do not clear it
                    let mut lf = 0.0;
                    // SAFETY: valid buffers.
                    let st = unsafe {
                        bingham_log_normalization_constant(
                            2,
                            [-1.0, 0.0].as_ptr(),
                            &mut lf,
                            std::ptr::null_mut(),
                        )
                    };
                    assert_eq!(st, BINGHAM_OK);
                    assert_eq!(last_error(), msg);
                }
            });
        }
        // one thread that never fails sees no message while the others fail
        let barrier = &barrier;
        scope.spawn(move || {
            barrier.wait();
            for _ in 0..2000 {
                let mut lf = 0.0;
                // SAFETY: valid buffers.
                let st = unsafe {
                    bingham_log_normalization_constant(
                        3,
                        [-1.0, -2.0, 0.0].as_ptr(),
                        &mut lf,
                        std::ptr::null_mut(),
                    )
                };
                assert_eq!(st, BINGHAM_OK);
                assert_eq!(last_error(), "", "a failure of another thread is visible");
                std::thread::yield_now();
            }
        });
    });
}
