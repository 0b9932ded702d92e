//! The complex arithmetic the contour needs: a minimal complex number, `log(1 + u)` accurate for
//! small `u`, and a product whose argument is tracked beyond the principal branch.

use std::f64::consts::{LN_2, PI};
use std::ops::{Add, Mul, Sub};

/// A minimal complex number (only what the contour needs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Cx {
    pub(super) re: f64,
    pub(super) im: f64,
}

impl Cx {
    pub(super) const fn new(re: f64, im: f64) -> Self {
        Cx { re, im }
    }

    pub(super) fn abs(self) -> f64 {
        self.re.hypot(self.im)
    }

    /// `|re| + |im|`, within a factor √2 of `|self|` (cheap size for step control).
    pub(super) fn norm1(self) -> f64 {
        self.re.abs() + self.im.abs()
    }

    pub(super) fn scale(self, k: f64) -> Self {
        Cx::new(self.re * k, self.im * k)
    }

    /// `1/self` by Smith's algorithm (no overflow in the intermediate squares).
    pub(super) fn recip(self) -> Self {
        if self.re.abs() >= self.im.abs() {
            let t = self.im / self.re;
            let den = self.re + self.im * t;
            Cx::new(1.0 / den, -t / den)
        } else {
            let t = self.re / self.im;
            let den = self.re * t + self.im;
            Cx::new(t / den, -1.0 / den)
        }
    }

    pub(super) fn is_finite(self) -> bool {
        self.re.is_finite() && self.im.is_finite()
    }
}

impl Add for Cx {
    type Output = Cx;
    fn add(self, o: Cx) -> Cx {
        Cx::new(self.re + o.re, self.im + o.im)
    }
}

impl Sub for Cx {
    type Output = Cx;
    fn sub(self, o: Cx) -> Cx {
        Cx::new(self.re - o.re, self.im - o.im)
    }
}

impl Mul for Cx {
    type Output = Cx;
    fn mul(self, o: Cx) -> Cx {
        Cx::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}

/// Principal `log(1 + u)`, accurate for small `|u|` and away from `u = −1`.
pub(super) fn clog1p(u: Cx) -> Cx {
    let xp1 = 1.0 + u.re;
    // |1 + u|² − 1, without forming 1 + u first.
    let t = u.re * (2.0 + u.re) + u.im * u.im;
    let re = if t.abs() < 0.5 {
        0.5 * t.ln_1p()
    } else {
        xp1.hypot(u.im).ln()
    };
    Cx::new(re, u.im.atan2(xp1))
}

/// A product of factors with arguments in `(0, π)`, scaled by powers of two to stay in range,
/// with its argument tracked beyond the principal branch: multiplying by such a factor rotates
/// counterclockwise by less than π, so the product crosses the negative real axis exactly when
/// its imaginary part turns from `≥ 0` to `< 0`.
#[derive(Clone, Copy, Debug)]
pub(super) struct ArgProduct {
    /// The product times `2^(−exp2)`.
    pub(super) p: Cx,
    /// Crossings of the negative real axis: `arg = atan2(p) + 2π·wraps`.
    pub(super) wraps: i32,
    pub(super) exp2: i32,
}

impl ArgProduct {
    pub(super) const ONE: ArgProduct = ArgProduct {
        p: Cx::new(1.0, 0.0),
        wraps: 0,
        exp2: 0,
    };

    pub(super) fn rescale(&mut self) {
        const BIG: f64 = 1.157_920_892_373_162e77; // 2^256
        const SMALL: f64 = 8.636_168_555_094_445e-78; // 2^-256
        let size = self.p.norm1();
        if !(SMALL..=BIG).contains(&size) {
            let (k, e) = if size > BIG {
                (SMALL, 256)
            } else {
                (BIG, -256)
            };
            self.p = self.p.scale(k);
            self.exp2 += e;
        }
    }

    /// Multiplies by `f` with `Im f > 0`.
    pub(super) fn mul(&mut self, f: Cx) {
        let q = self.p * f;
        self.wraps += i32::from(self.p.im >= 0.0 && q.im < 0.0);
        self.p = q;
        self.rescale();
    }

    /// The product of two: the principal arguments `a`, `b` add to `a + b − 2πk`, `k = 1` when
    /// both lie in `[0, π]` and the product's imaginary part is negative, `k = −1` when both are
    /// negative and the product's is not.
    pub(super) fn merge(self, o: ArgProduct) -> ArgProduct {
        let p = self.p * o.p;
        let k = match (self.p.im >= 0.0, o.p.im >= 0.0) {
            (true, true) => i32::from(p.im < 0.0),
            (false, false) => -i32::from(p.im >= 0.0),
            _ => 0,
        };
        let mut out = ArgProduct {
            p,
            wraps: self.wraps + o.wraps + k,
            exp2: self.exp2 + o.exp2,
        };
        out.rescale();
        out
    }

    /// `log` of the product, argument beyond the principal branch.
    pub(super) fn log(self) -> Cx {
        Cx::new(
            0.5 * (self.p.re * self.p.re + self.p.im * self.p.im).ln()
                + f64::from(self.exp2) * LN_2,
            self.p.im.atan2(self.p.re) + 2.0 * PI * f64::from(self.wraps),
        )
    }
}
