//! Running the two passes concurrently (the backward one on a second thread from the handoff
//! on) or in turn, and forming their product chunk by chunk.

use std::sync::atomic::{AtomicBool, Ordering};

use nalgebra::Matrix4;

use super::fusion::product;
use super::handoff::{coupling, handoff_index, Handoff};
use super::passes::{backward_pass, forward_pass, usable, Chunk};
use super::store::{Forward, ForwardBias, Pass};
use super::types::{Fusion, SmoothInput, SmoothOptions};
use crate::ahrs::{AhrsParams, StatedCoupling};
use crate::error::{Error, Result};

/// The number of samples from which the product runs on two threads when the passes ran one
/// after the other.
pub(super) const PARALLEL_PRODUCT: usize = 1 << 14;

/// A run of samples for the product: the forward states (and bias, exponents) in order, the
/// backward predictions of the same samples stored in reverse (`back[len − 1 − i]` for
/// `states[i]`).
struct Half<'a> {
    states: &'a mut [Forward],
    exponents: &'a [Matrix4<f64>],
    bias: Option<&'a mut [ForwardBias]>,
    back: &'a [Forward],
    back_exponents: &'a [Matrix4<f64>],
    back_bias: Option<&'a [ForwardBias]>,
}

impl Half<'_> {
    fn apply(mut self, options: &SmoothOptions) {
        let len = self.states.len();
        let exact = !self.exponents.is_empty();
        for i in 0..len {
            let j = len - 1 - i;
            let exps = exact.then(|| (&self.exponents[i], &self.back_exponents[j]));
            let bias = match (self.bias.as_deref_mut(), self.back_bias) {
                (Some(f), Some(b)) => Some((&mut f[i], &b[j])),
                _ => None,
            };
            product(options, &mut self.states[i], &self.back[j], exps, bias);
        }
    }
}

/// The forward pass's states (and exponents, bias) of the samples from `offset` on.
struct Span<'a> {
    offset: usize,
    states: &'a mut [Forward],
    exponents: &'a [Matrix4<f64>],
    bias: Option<&'a mut [ForwardBias]>,
}

impl Span<'_> {
    /// The product at the samples of `chunk` (within the span).
    fn apply(&mut self, options: &SmoothOptions, chunk: &Chunk) {
        let len = chunk.pass.states.len();
        let r = chunk.lo - self.offset..chunk.lo - self.offset + len;
        Half {
            states: &mut self.states[r.clone()],
            exponents: if self.exponents.is_empty() {
                &[]
            } else {
                &self.exponents[r.clone()]
            },
            bias: self.bias.as_deref_mut().map(|b| &mut b[r]),
            back: &chunk.pass.states,
            back_exponents: &chunk.pass.exponents,
            back_bias: chunk.pass.bias.as_deref(),
        }
        .apply(options);
    }
}

/// The span of `fwd`'s samples below `at` and that from `at` on.
fn split_at(fwd: &mut Pass, at: usize) -> (Span<'_>, Span<'_>) {
    let (s_lo, s_hi) = fwd.states.split_at_mut(at);
    let (e_lo, e_hi) = if fwd.exponents.is_empty() {
        (&[][..], &[][..])
    } else {
        fwd.exponents.split_at(at)
    };
    let (b_lo, b_hi) = match fwd.bias.as_mut() {
        Some(b) => {
            let (l, h) = b.split_at_mut(at);
            (Some(l), Some(h))
        }
        None => (None, None),
    };
    (
        Span {
            offset: 0,
            states: s_lo,
            exponents: e_lo,
            bias: b_lo,
        },
        Span {
            offset: at,
            states: s_hi,
            exponents: e_hi,
            bias: b_hi,
        },
    )
}

/// The forward and the backward pass and their product: the smoothed states (and bias).
/// With [`handoff_index`] before the last sample the backward pass runs on a second thread
/// from the handoff on (module documentation, "Threads"), and the forward pass's thread, once
/// its pass is done, forms the product at the backward pass's chunks as they come; one thread
/// if the second cannot be started, with the same result (the product at a sample is a
/// function of the two passes' states there alone). Passes run one after the other form the
/// product afterwards, on two threads from [`PARALLEL_PRODUCT`] samples on. Also returns the
/// heading's coupling to the tilt for the output ([`coupling`]).
pub(super) fn run(
    params: &AhrsParams,
    options: &SmoothOptions,
    input: &SmoothInput<'_>,
    want_bias: bool,
    threads: bool,
) -> Result<(Vec<Forward>, Option<Vec<ForwardBias>>, StatedCoupling)> {
    let n = input.gyr.len();
    let exact = options.fusion == Fusion::Bingham;
    let has_mag = input
        .mag
        .is_some_and(|m| m.iter().any(|r| usable(r) && r.iter().any(|x| *x != 0.0)));
    let at = handoff_index(n, params.sample_time, has_mag);
    let mut fwd = Pass::new(n, want_bias, exact)?;
    let abort = AtomicBool::new(false);
    let mut handoff = None;
    let mut back_result = None;
    std::thread::scope(|s| -> Result<()> {
        let (tx, rx) = std::sync::mpsc::channel::<Handoff>();
        let (chunk_tx, chunk_rx) = std::sync::mpsc::channel::<Chunk>();
        let abort_ref = &abort;
        let thread = if threads && at + 1 < n {
            std::thread::Builder::new()
                .name("bingham-smooth".into())
                .spawn_scoped(s, move || -> Option<Result<usize>> {
                    let h = rx.recv().ok()?;
                    // a closed channel: the forward pass failed, and nobody waits for these
                    let emit = |c: Chunk| {
                        let _ = chunk_tx.send(c);
                    };
                    Some(backward_pass(
                        params, options, input, &h, want_bias, abort_ref, emit,
                    ))
                })
                .ok()
        } else {
            drop(chunk_tx);
            None
        };
        let concurrent = thread.is_some();
        let fres = forward_pass(params, options, input, has_mag, at, &mut fwd, |h| {
            handoff = Some(h);
            if concurrent {
                // a closed channel: the thread has ended, the result says why
                let _ = tx.send(h);
            }
        });
        drop(tx);
        if fres.is_err() {
            abort.store(true, Ordering::Relaxed);
        } else if concurrent {
            // the product at each chunk as the backward pass hands it over, until it ends
            let (_, mut all) = split_at(&mut fwd, 0);
            for chunk in chunk_rx.iter() {
                all.apply(options, &chunk);
            }
        }
        if let Some(t) = thread {
            back_result = Some(
                t.join()
                    .unwrap_or_else(|_| {
                        Some(Err(Error::Numerical(
                            "the smoother's backward pass panicked".into(),
                        )))
                    })
                    .unwrap_or(Ok(0)),
            );
        }
        fres
    })?;
    if let Some(r) = back_result {
        r?;
        return Ok((fwd.states, fwd.bias, coupling(handoff.as_ref())));
    }
    // the passes one after the other: the backward pass's chunks kept, then the product
    let k = coupling(handoff.as_ref());
    let h = handoff
        .ok_or_else(|| Error::Numerical("the smoother's forward pass gave no handoff".into()))?;
    let mut chunks = Vec::new();
    backward_pass(params, options, input, &h, want_bias, &abort, |c| {
        chunks.push(c)
    })?;
    let total: usize = chunks.iter().map(|c| c.pass.states.len()).sum();
    // the chunks descend: the first half of them (the upper samples) on a second thread
    let half = chunks.len() / 2;
    if threads && total >= PARALLEL_PRODUCT && half > 0 {
        let mid = chunks[half - 1].lo;
        let (upper, lower) = chunks.split_at(half);
        let (mut lo, hi) = split_at(&mut fwd, mid);
        let hi = std::sync::Mutex::new(Some(hi));
        let run_hi = || {
            if let Some(mut h) = hi.lock().ok().and_then(|mut h| h.take()) {
                for c in upper {
                    h.apply(options, c);
                }
            }
        };
        std::thread::scope(|s| {
            // no thread: the half is left for this one
            let _ = std::thread::Builder::new()
                .name("bingham-smooth".into())
                .spawn_scoped(s, run_hi);
            for c in lower {
                lo.apply(options, c);
            }
        });
        run_hi();
    } else {
        let (_, mut all) = split_at(&mut fwd, 0);
        for c in &chunks {
            all.apply(options, c);
        }
    }
    Ok((fwd.states, fwd.bias, k))
}
