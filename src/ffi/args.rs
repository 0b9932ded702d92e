//! Reading an export's pointer arguments: each export lists them once, with [`args!`], and the
//! list is checked and read in two phases that keep the C API's error model:
//!
//! 1. [`Arg::check`]: every pointer, in the order of the list — NULL (unless optional) and
//!    alignment — without touching the caller's memory;
//! 2. [`Arg::take`]: the inputs are read and validated in the same order (finite entries, then
//!    a valid distribution where one is built); outputs become checked places ([`Output`],
//!    [`Place`], [`BinghamOutput`]) that the export writes only after its computation succeeded.
//!
//! So a NULL pointer is reported before a bad value, nothing is read before every pointer (and,
//! before the list, `d`) is checked, and nothing is written on error. The messages are those of
//! [`guard`](super::guard) (`` `x` is NULL ``, `` `x[2]` = NaN is not finite ``,
//! `` (`m`, `z`): … ``). Arithmetic with `d` belongs after the dimension check: the lengths in the
//! list are evaluated when the list is built.

use std::marker::PhantomData;

use super::guard::{len2, need, output, read, read_raw, write, write_handle, Failure, FfiResult};
use crate::distribution::Bingham;

/// The arguments of an export, in the order of its C signature, as one [`Arg`] (a tuple of the
/// items' descriptors; `.read()` checks and reads them all, see the module doc).
///
/// | item | phase 1 checks | phase 2 reads | value |
/// |---|---|---|---|
/// | `x: [len]` | `x` | `len` finite doubles | `&[f64]` |
/// | `x: raw [len]` | `x` | `len` doubles, unchecked (NaN/Inf allowed) | `&[f64]` |
/// | `(m, z): bingham [d]` | `m`, `z` | d*d and d finite doubles, a valid `Bingham` | `Bingham` |
/// | `x: rows [n; K]` | `x` | n rows of K doubles, unchecked; n*K overflow refused | `&[[f64;K]]` |
/// | `x: out [len]` | `x` | – | [`Output`] (`len` doubles) |
/// | `x: out` | `x` (any `*mut T`) | – | [`Place<T>`] |
/// | `(m, z): out bingham` | `m`, `z` | – | [`BinghamOutput`] |
/// | `x: mut [len]` | `x` | – | `&mut [f64]` (written progressively) |
/// | `x: mut rows [n; K]` | `x` | n*K overflow refused | `&mut [[f64; K]]` |
///
/// `opt` in front of a kind (`w: opt [n]`, `df: opt out [d]`) makes the pointer optional: NULL
/// gives `None`, anything else is checked and read as above (`Some`). `if cond` after a kind
/// (`x: [nd] if n > 0`) requires the pointer only when `cond` holds (`None` otherwise, the
/// pointer is then neither checked nor read).
///
/// Building the list reads nothing; `.read()` is `unsafe`: the caller vouches for the C
/// contract (every pointer aims at the stated number of elements).
macro_rules! args {
    // the list, item by item, into a tuple of descriptors
    (@list [$($done:expr,)*]) => { ($($done,)*) };
    (@list [$($done:expr,)*]
        $n:tt : $($kw:ident)* [$($len:tt)*] if $c:expr $(, $($rest:tt)*)?) => {
        args!(@list [
            $($done,)*
            $crate::ffi::args::Opt::when($c, args!(@one $n, $($kw)* [$($len)*])),
        ] $($($rest)*)?)
    };
    (@list [$($done:expr,)*] $n:tt : $($kw:ident)* [$($len:tt)*] $(, $($rest:tt)*)?) => {
        args!(@list [$($done,)* args!(@one $n, $($kw)* [$($len)*]),] $($($rest)*)?)
    };
    (@list [$($done:expr,)*] $n:tt : $($kw:ident)+ $(, $($rest:tt)*)?) => {
        args!(@list [$($done,)* args!(@one $n, $($kw)+),] $($($rest)*)?)
    };
    // one item
    (@one $n:ident, opt $($kind:tt)+) => {
        $crate::ffi::args::Opt::when(!$n.is_null(), args!(@one $n, $($kind)+))
    };
    (@one $n:ident, [$len:expr]) => {
        $crate::ffi::args::ArrayIn::new(stringify!($n), $n, $len)
    };
    (@one $n:ident, raw [$len:expr]) => {
        $crate::ffi::args::ArrayIn::raw(stringify!($n), $n, $len)
    };
    (@one ($m:ident, $z:ident), bingham [$d:expr]) => {
        $crate::ffi::args::BinghamIn::new($d, stringify!($m), $m, stringify!($z), $z)
    };
    (@one $n:ident, rows [$rows:expr; $k:expr]) => {
        $crate::ffi::args::RowsIn::<{ $k }>::new(stringify!($n), $n, $rows)
    };
    (@one $n:ident, out [$len:expr]) => {
        $crate::ffi::args::ArrayOut::new(stringify!($n), $n, $len)
    };
    (@one $n:ident, out) => {
        $crate::ffi::args::ValueOut::new(stringify!($n), $n)
    };
    (@one ($m:ident, $z:ident), out bingham) => {
        $crate::ffi::args::BinghamOut::new(stringify!($m), $m, stringify!($z), $z)
    };
    (@one $n:ident, mut [$len:expr]) => {
        $crate::ffi::args::SliceOut::new(stringify!($n), $n, $len)
    };
    (@one $n:ident, mut rows [$rows:expr; $k:expr]) => {
        $crate::ffi::args::RowsOut::<{ $k }>::new(stringify!($n), $n, $rows)
    };
    ($($items:tt)*) => { args!(@list [] $($items)*) };
}
pub(crate) use args;

/// One argument (or a list of them) of an export, checked and read in two phases.
pub(crate) trait Arg: Sized {
    /// What the export works with: a slice, a distribution, a checked output place.
    type Value;

    /// Phase 1: the pointers (NULL, alignment); reads nothing.
    fn check(&self) -> FfiResult<()>;

    /// Phase 2: reads and validates the inputs, hands out the checked outputs.
    ///
    /// # Safety
    /// [`check`](Arg::check) has succeeded on `self`, and every pointer aims at the stated
    /// number of readable (inputs) or writable (outputs) elements (the export's C contract),
    /// valid and not written by anyone else while the values are in use.
    unsafe fn take(self) -> FfiResult<Self::Value>;

    /// Both phases: every check before any read.
    ///
    /// # Safety
    /// As for [`take`](Arg::take), without the precondition on `check`.
    #[inline(always)]
    unsafe fn read(self) -> FfiResult<Self::Value> {
        self.check()?;
        // SAFETY: checked just now; the pointer contract is the caller's.
        unsafe { self.take() }
    }
}

/// A list of arguments: checked in order, then read in order.
macro_rules! arg_tuple {
    ($($a:ident),*) => {
        #[allow(non_snake_case)]
        impl<$($a: Arg),*> Arg for ($($a,)*) {
            type Value = ($($a::Value,)*);

            #[inline(always)]
            fn check(&self) -> FfiResult<()> {
                let ($($a,)*) = self;
                $($a.check()?;)*
                Ok(())
            }

            #[inline(always)]
            unsafe fn take(self) -> FfiResult<Self::Value> {
                let ($($a,)*) = self;
                // SAFETY: forwarded contract (each item checked as part of the list).
                Ok(($(unsafe { $a.take()? },)*))
            }
        }
    };
}
arg_tuple!();
arg_tuple!(A);
arg_tuple!(A, B);
arg_tuple!(A, B, C);
arg_tuple!(A, B, C, D);
arg_tuple!(A, B, C, D, E);
arg_tuple!(A, B, C, D, E, F);
arg_tuple!(A, B, C, D, E, F, G);
arg_tuple!(A, B, C, D, E, F, G, H);

/// An optional argument (`opt`, `if cond`): `None` is neither checked nor read.
pub(crate) struct Opt<A>(Option<A>);

impl<A> Opt<A> {
    #[inline]
    pub(crate) fn when(present: bool, arg: A) -> Opt<A> {
        Opt(present.then_some(arg))
    }
}

impl<A: Arg> Arg for Opt<A> {
    type Value = Option<A::Value>;

    #[inline]
    fn check(&self) -> FfiResult<()> {
        self.0.as_ref().map_or(Ok(()), Arg::check)
    }

    #[inline]
    unsafe fn take(self) -> FfiResult<Self::Value> {
        // SAFETY: forwarded contract.
        self.0.map(|a| unsafe { a.take() }).transpose()
    }
}

/// `name: [len]`: an input array of finite doubles; `name: raw [len]`: of any doubles (a
/// sensor sample whose NaN means "no sample").
pub(crate) struct ArrayIn<'a> {
    name: &'static str,
    p: *const f64,
    len: usize,
    finite: bool,
    _data: PhantomData<&'a [f64]>,
}

impl ArrayIn<'_> {
    #[inline]
    pub(crate) fn new(name: &'static str, p: *const f64, len: usize) -> Self {
        ArrayIn {
            name,
            p,
            len,
            finite: true,
            _data: PhantomData,
        }
    }

    #[inline]
    pub(crate) fn raw(name: &'static str, p: *const f64, len: usize) -> Self {
        ArrayIn {
            finite: false,
            ..ArrayIn::new(name, p, len)
        }
    }
}

impl<'a> Arg for ArrayIn<'a> {
    type Value = &'a [f64];

    #[inline]
    fn check(&self) -> FfiResult<()> {
        need(self.name, self.p)
    }

    #[inline(always)]
    unsafe fn take(self) -> FfiResult<&'a [f64]> {
        // SAFETY: forwarded contract (`len` readable doubles).
        unsafe {
            if self.finite {
                read(self.name, self.p, self.len)
            } else {
                read_raw(self.name, self.p, self.len)
            }
        }
    }
}

/// `(m, z): bingham [d]`: a distribution, `m` d×d row-major and `z` length d.
pub(crate) struct BinghamIn {
    d: usize,
    m: (&'static str, *const f64),
    z: (&'static str, *const f64),
}

impl BinghamIn {
    #[inline]
    pub(crate) fn new(
        d: usize,
        m_name: &'static str,
        m: *const f64,
        z_name: &'static str,
        z: *const f64,
    ) -> Self {
        BinghamIn {
            d,
            m: (m_name, m),
            z: (z_name, z),
        }
    }
}

impl Arg for BinghamIn {
    type Value = Bingham;

    #[inline]
    fn check(&self) -> FfiResult<()> {
        need(self.m.0, self.m.1)?;
        need(self.z.0, self.z.1)
    }

    #[inline]
    unsafe fn take(self) -> FfiResult<Bingham> {
        let (d, (m_name, m), (z_name, z)) = (self.d, self.m, self.z);
        // SAFETY: forwarded contract (d*d and d readable doubles); d <= 64 (checked by the
        // export before the list was built), so d*d cannot overflow.
        let (ms, zs) = unsafe { (read(m_name, m, d * d)?, read(z_name, z, d)?) };
        Bingham::from_row_major(d, ms, zs)
            .map_err(|e| Failure::from(e).context(format_args!("(`{m_name}`, `{z_name}`)")))
    }
}

/// `name: rows [n; K]`: `n` rows of `K` doubles whose values are not checked (streams whose bad
/// entries are refused one sample at a time).
pub(crate) struct RowsIn<'a, const K: usize> {
    name: &'static str,
    p: *const f64,
    rows: usize,
    _data: PhantomData<&'a [[f64; K]]>,
}

impl<const K: usize> RowsIn<'_, K> {
    #[inline]
    pub(crate) fn new(name: &'static str, p: *const f64, rows: usize) -> Self {
        RowsIn {
            name,
            p,
            rows,
            _data: PhantomData,
        }
    }
}

impl<'a, const K: usize> Arg for RowsIn<'a, K> {
    type Value = &'a [[f64; K]];

    #[inline]
    fn check(&self) -> FfiResult<()> {
        need(self.name, self.p)
    }

    #[inline]
    unsafe fn take(self) -> FfiResult<&'a [[f64; K]]> {
        let len = len2(self.name, self.rows, K)?;
        // SAFETY: forwarded contract (`rows * K` readable doubles, no overflow: checked).
        let flat = unsafe { read_raw(self.name, self.p, len)? };
        // SAFETY: `[f64; K]` has the size of K doubles and the alignment of one (checked by
        // `need`), no padding.
        Ok(unsafe { std::slice::from_raw_parts(flat.as_ptr().cast::<[f64; K]>(), self.rows) })
    }
}

/// `name: out [len]`: an output array, written once at the end ([`Output`]).
pub(crate) struct ArrayOut {
    name: &'static str,
    p: *mut f64,
    len: usize,
}

impl ArrayOut {
    #[inline]
    pub(crate) fn new(name: &'static str, p: *mut f64, len: usize) -> Self {
        ArrayOut { name, p, len }
    }
}

impl Arg for ArrayOut {
    type Value = Output;

    #[inline]
    fn check(&self) -> FfiResult<()> {
        need(self.name, self.p)
    }

    #[inline]
    unsafe fn take(self) -> FfiResult<Output> {
        Ok(Output {
            p: self.p,
            len: self.len,
        })
    }
}

/// A checked output array of `len()` doubles.
pub(crate) struct Output {
    p: *mut f64,
    len: usize,
}

impl Output {
    #[inline]
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Copies the result `src` (at most `len()` doubles) to the caller.
    ///
    /// # Safety
    /// Call only after every input has been read and the computation has succeeded (outputs may
    /// alias inputs): no reference into the caller's memory may be used afterwards.
    #[inline]
    pub(crate) unsafe fn write(self, src: &[f64]) {
        debug_assert!(src.len() <= self.len);
        // SAFETY: checked pointer, `len` writable doubles (contract of `take`); see above.
        unsafe { write(self.p, src) }
    }
}

/// `name: out`: one output value of the pointer's type ([`Place`]).
pub(crate) struct ValueOut<T> {
    name: &'static str,
    p: *mut T,
}

impl<T> ValueOut<T> {
    #[inline]
    pub(crate) fn new(name: &'static str, p: *mut T) -> Self {
        ValueOut { name, p }
    }
}

impl<T> Arg for ValueOut<T> {
    type Value = Place<T>;

    #[inline]
    fn check(&self) -> FfiResult<()> {
        need(self.name, self.p)
    }

    #[inline]
    unsafe fn take(self) -> FfiResult<Place<T>> {
        Ok(Place(self.p))
    }
}

/// A checked place for one output value.
pub(crate) struct Place<T>(*mut T);

impl<T> Place<T> {
    /// Stores the result (without dropping what the place held: C data).
    ///
    /// # Safety
    /// As for [`Output::write`].
    #[inline]
    pub(crate) unsafe fn set(self, value: T) {
        // SAFETY: non-NULL, aligned and writable (checked; contract of `take`).
        unsafe { self.0.write(value) }
    }
}

impl<T> Place<*mut T> {
    /// Moves `value` to the heap and stores the new handle (see [`write_handle`]).
    ///
    /// # Safety
    /// As for [`Output::write`].
    #[inline]
    pub(crate) unsafe fn set_handle(self, value: T) {
        // SAFETY: checked, writable `T *` (contract of `take`).
        unsafe { write_handle(self.0, value) }
    }
}

/// `(m, z): out bingham`: a distribution's outputs, `m` d×d row-major and `z` length d (d: the
/// dimension of the distribution written).
pub(crate) struct BinghamOut {
    m: (&'static str, *mut f64),
    z: (&'static str, *mut f64),
}

impl BinghamOut {
    #[inline]
    pub(crate) fn new(
        m_name: &'static str,
        m: *mut f64,
        z_name: &'static str,
        z: *mut f64,
    ) -> Self {
        BinghamOut {
            m: (m_name, m),
            z: (z_name, z),
        }
    }
}

impl Arg for BinghamOut {
    type Value = BinghamOutput;

    #[inline]
    fn check(&self) -> FfiResult<()> {
        need(self.m.0, self.m.1)?;
        need(self.z.0, self.z.1)
    }

    #[inline]
    unsafe fn take(self) -> FfiResult<BinghamOutput> {
        Ok(BinghamOutput {
            m: self.m.1,
            z: self.z.1,
        })
    }
}

/// Checked outputs for a distribution of dimension d: `m` (d*d doubles) and `z` (d doubles).
pub(crate) struct BinghamOutput {
    m: *mut f64,
    z: *mut f64,
}

impl BinghamOutput {
    /// Copies `b` to the caller: M row-major, z.
    ///
    /// # Safety
    /// As for [`Output::write`]; the outputs hold d*d and d doubles for the dimension d of `b`.
    #[inline]
    pub(crate) unsafe fn write(self, b: &Bingham) {
        let mr = b.m_row_major();
        // SAFETY: checked pointers (contract of `take`), lengths d*d and d; see above.
        unsafe {
            write(self.m, &mr);
            write(self.z, b.z().as_slice());
        }
    }
}

/// `name: mut [len]`: an output array the core writes progressively (e.g. row by row).
pub(crate) struct SliceOut<'a> {
    name: &'static str,
    p: *mut f64,
    len: usize,
    _data: PhantomData<&'a mut [f64]>,
}

impl SliceOut<'_> {
    #[inline]
    pub(crate) fn new(name: &'static str, p: *mut f64, len: usize) -> Self {
        SliceOut {
            name,
            p,
            len,
            _data: PhantomData,
        }
    }
}

impl<'a> Arg for SliceOut<'a> {
    type Value = &'a mut [f64];

    #[inline]
    fn check(&self) -> FfiResult<()> {
        need(self.name, self.p)
    }

    #[inline]
    unsafe fn take(self) -> FfiResult<&'a mut [f64]> {
        // SAFETY: forwarded contract (`len` writable doubles, not aliased by any input in use).
        unsafe { output(self.name, self.p, self.len) }
    }
}

/// `name: mut rows [n; K]`: `n` writable rows of `K` doubles.
pub(crate) struct RowsOut<'a, const K: usize> {
    name: &'static str,
    p: *mut f64,
    rows: usize,
    _data: PhantomData<&'a mut [[f64; K]]>,
}

impl<const K: usize> RowsOut<'_, K> {
    #[inline]
    pub(crate) fn new(name: &'static str, p: *mut f64, rows: usize) -> Self {
        RowsOut {
            name,
            p,
            rows,
            _data: PhantomData,
        }
    }
}

impl<'a, const K: usize> Arg for RowsOut<'a, K> {
    type Value = &'a mut [[f64; K]];

    #[inline]
    fn check(&self) -> FfiResult<()> {
        need(self.name, self.p)
    }

    #[inline]
    unsafe fn take(self) -> FfiResult<&'a mut [[f64; K]]> {
        let len = len2(self.name, self.rows, K)?;
        // SAFETY: forwarded contract (`rows * K` writable doubles, no overflow: checked).
        let flat = unsafe { output(self.name, self.p, len)? };
        // SAFETY: as in `RowsIn::take`.
        Ok(unsafe {
            std::slice::from_raw_parts_mut(flat.as_mut_ptr().cast::<[f64; K]>(), self.rows)
        })
    }
}

/// Checked outputs that receive a result (see [`store`](Store::store)).
pub(crate) trait Store<V> {
    /// Writes `value` to the caller.
    ///
    /// # Safety
    /// As for [`Output::write`].
    unsafe fn store(self, value: V);
}

impl Store<()> for () {
    unsafe fn store(self, (): ()) {}
}

impl<T> Store<T> for Place<T> {
    unsafe fn store(self, value: T) {
        // SAFETY: forwarded contract.
        unsafe { self.set(value) }
    }
}

impl Store<Bingham> for BinghamOutput {
    unsafe fn store(self, value: Bingham) {
        // SAFETY: forwarded contract.
        unsafe { self.write(&value) }
    }
}

impl<V, S: Store<V>> Store<V> for (S,) {
    unsafe fn store(self, value: V) {
        // SAFETY: forwarded contract.
        unsafe { self.0.store(value) }
    }
}

impl<V, W, S: Store<V>, T: Store<W>> Store<(V, W)> for (S, T) {
    unsafe fn store(self, (v, w): (V, W)) {
        // SAFETY: forwarded contract.
        unsafe {
            self.0.store(v);
            self.1.store(w);
        }
    }
}

/// Checked output arrays filled from consecutive pieces of one library buffer (see
/// [`get_into`]).
pub(crate) trait Fill {
    /// The number of doubles of all the outputs together.
    fn total(&self) -> usize;

    /// Writes `values`: the first `len()` to the first output, the next to the second, ….
    ///
    /// # Safety
    /// As for [`Output::write`].
    unsafe fn fill(self, values: &[f64]);
}

impl Fill for (Output,) {
    fn total(&self) -> usize {
        self.0.len()
    }

    unsafe fn fill(self, values: &[f64]) {
        // SAFETY: forwarded contract.
        unsafe { self.0.write(values) }
    }
}

impl Fill for (Output, Output) {
    fn total(&self) -> usize {
        self.0.len() + self.1.len()
    }

    unsafe fn fill(self, values: &[f64]) {
        let (a, b) = values.split_at(self.0.len());
        // SAFETY: forwarded contract.
        unsafe {
            self.0.write(a);
            self.1.write(b);
        }
    }
}

impl Fill for (Output, Output, Output, Output) {
    fn total(&self) -> usize {
        self.0.len() + self.1.len() + self.2.len() + self.3.len()
    }

    unsafe fn fill(self, values: &[f64]) {
        let (a, rest) = values.split_at(self.0.len());
        let (b, rest) = rest.split_at(self.1.len());
        let (c, d) = rest.split_at(self.2.len());
        // SAFETY: forwarded contract.
        unsafe {
            self.0.write(a);
            self.1.write(b);
            self.2.write(c);
            self.3.write(d);
        }
    }
}

/// The most doubles a getter returns: two 4×4 M and their 4 concentrations (the spin filter's
/// state).
const GET_MAX: usize = 40;

/// Shared body of the getters of the handles: checks the output pointers `outs`, lets `get`
/// compute their values into a library buffer (the outputs' values one after another, in the
/// order of `outs`) and only then copies them out, so nothing is written on error.
///
/// # Safety
/// The caller's contract for `outs` (see [`Arg::read`]).
pub(crate) unsafe fn get_into<O>(
    outs: O,
    get: impl FnOnce(&mut [f64]) -> crate::error::Result<()>,
) -> FfiResult<()>
where
    O: Arg,
    O::Value: Fill,
{
    // SAFETY: forwarded contract.
    let outs = unsafe { outs.read()? };
    let mut buf = [0.0; GET_MAX];
    let values = &mut buf[..outs.total()];
    get(values)?;
    // SAFETY: forwarded contract; the values are library-owned.
    unsafe { outs.fill(values) };
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ffi::status::bingham_status::*;

    #[test]
    fn checks_every_pointer_before_reading_any() {
        let z = [0.0, f64::NAN];
        let mut out = 7.0;
        let (zp, nul) = (z.as_ptr(), std::ptr::null_mut::<f64>());
        // SAFETY: `zp` has 2 readable doubles; NULL is refused before any read or write.
        let e = unsafe { args!(zp: [2], nul: out).read() }.err().unwrap();
        assert_eq!(e.status, BINGHAM_ERR_NULL_ARGUMENT);
        assert_eq!(e.message, "`nul` is NULL");
        let op: *mut f64 = &mut out;
        // SAFETY: as above, `op` is one writable double.
        let e = unsafe { args!(zp: [2], op: out).read() }.err().unwrap();
        assert_eq!(e.status, BINGHAM_ERR_INVALID_ARGUMENT);
        assert_eq!(e.message, "`zp[1]` = NaN is not finite");
        assert_eq!(out, 7.0);
    }

    #[test]
    fn optional_and_conditional_items() {
        let w = [1.0, 2.0];
        let (wp, nul) = (w.as_ptr(), std::ptr::null::<f64>());
        // SAFETY: `wp` has 2 readable doubles; the NULL ones are not read.
        let (a, b, c, e) =
            unsafe { args!(wp: opt [2], nul: opt [2], nul: [9] if false, wp: [2] if true).read() }
                .unwrap();
        assert_eq!((a, b, c, e), (Some(&w[..]), None, None, Some(&w[..])));
        // SAFETY: as above.
        let e = unsafe { args!(nul: [0] if 1 > 0).read() }.err().unwrap();
        assert_eq!(e.message, "`nul` is NULL");
    }

    #[test]
    fn distributions_in_and_out() {
        let (m, z) = ([0.0, 1.0, 1.0, 0.0], [-2.0, 0.0]);
        let (mut mo, mut zo) = ([9.0; 4], [9.0; 2]);
        let (mp, zp, m_out, z_out) = (m.as_ptr(), z.as_ptr(), mo.as_mut_ptr(), zo.as_mut_ptr());
        // SAFETY: arrays of the stated lengths.
        unsafe {
            let (b, out) = args!((mp, zp): bingham [2], (m_out, z_out): out bingham)
                .read()
                .unwrap();
            out.write(&b);
        }
        assert_eq!((mo, zo), ([0.0, 1.0, 1.0, 0.0], [-2.0, 0.0]));
        let bad = [1.0, 1.0, 0.0, 1.0];
        let bp = bad.as_ptr();
        // SAFETY: as above.
        let e = unsafe { args!((bp, zp): bingham [2]).read() }
            .err()
            .unwrap();
        assert_eq!(e.status, BINGHAM_ERR_INVALID_ARGUMENT);
        assert!(e.message.starts_with("(`bp`, `zp`): "), "{}", e.message);
    }

    #[test]
    fn raw_arrays_take_any_values() {
        let v = [1.0, f64::NAN, f64::INFINITY];
        let (vp, nul) = (v.as_ptr(), std::ptr::null::<f64>());
        // SAFETY: `vp` has 3 readable doubles; NULL is refused before any read.
        let (r, o) = unsafe { args!(vp: raw [3], nul: opt raw [3]).read() }.unwrap();
        assert_eq!(r.len(), 3);
        assert!(r[1].is_nan() && r[2] == f64::INFINITY && o.is_none());
        // SAFETY: as above.
        let e = unsafe { args!(vp: raw [3], nul: raw [3]).read() }
            .err()
            .unwrap();
        assert_eq!(e.message, "`nul` is NULL");
    }

    #[test]
    fn rows_refuse_overflow() {
        let p = [0.0f64; 4];
        let pp = p.as_ptr();
        // SAFETY: the overflow is refused before any slice is formed.
        let e = unsafe { args!(pp: rows [usize::MAX; 3]).read() }
            .err()
            .unwrap();
        assert_eq!(e.status, BINGHAM_ERR_INVALID_DIMENSION);
        // SAFETY: 4 readable doubles.
        let (r,) = unsafe { args!(pp: rows [2; 2]).read() }.unwrap();
        assert_eq!(r, &[[0.0; 2]; 2]);
    }

    #[test]
    fn getters_write_only_on_success() {
        let (mut a, mut b) = ([7.0; 3], [7.0; 1]);
        let (ap, bp) = (a.as_mut_ptr(), b.as_mut_ptr());
        // SAFETY: 3 and 1 writable doubles.
        unsafe {
            let fail = get_into(args!(ap: out [3], bp: out [1]), |_| {
                Err(crate::error::Error::Numerical("no".into()))
            });
            assert_eq!(fail.unwrap_err().status, BINGHAM_ERR_NUMERICAL);
            get_into(args!(ap: out [3], bp: out [1]), |v| {
                v.copy_from_slice(&[1.0, 2.0, 3.0, 4.0]);
                Ok(())
            })
            .unwrap();
        }
        assert_eq!((a, b), ([1.0, 2.0, 3.0], [4.0]));
    }
}
