//! Quaternion helpers shared by the reproductions of Glover & Kaelbling (2013)
//! (`tests/glover_spin.rs`, `tests/glover_table1.rs`, `tests/glover_composition_kl.rs`):
//! the Hamilton product, normalization, the inner product and the angle between two
//! orientations, the product matrices `L(q)` and `R(q)`, `M` with a given mode, and one draw of a
//! unit quaternion from a Bingham. Quaternions are `[w, x, y, z]` arrays (scalar first), as in
//! `bingham::quaternion::q4`.
//!
//! `ekf2.rs` in this directory is not a submodule of this one: it is the second-order EKF of
//! `tests/glover_spin.rs`, which includes it with `#[path]` (it uses that test's observation
//! model).
#![allow(dead_code)]

use bingham::quaternion::q4;
use bingham::Bingham;
use nalgebra::{Matrix4, Vector4};
use rand::rngs::StdRng;

pub type Q = [f64; 4];

pub const I4: [f64; 16] = [
    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
];

pub fn mul(a: &Q, b: &Q) -> Q {
    q4::mul(a, b)
}

pub fn normalized(q: &Q) -> Q {
    let n = q.iter().map(|a| a * a).sum::<f64>().sqrt();
    [q[0] / n, q[1] / n, q[2] / n, q[3] / n]
}

pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The rotation angle between two unit quaternions (of `a⁻¹ ∘ b`), in `[0, π]`; slices, so
/// that `Vec` and `DVector` modes can be passed as they are.
pub fn angle(a: &[f64], b: &[f64]) -> f64 {
    2.0 * dot(a, b).abs().min(1.0).acos()
}

/// `L(q)`: `q ∘ r = L(q) r`.
pub fn lmat(q: &Q) -> Matrix4<f64> {
    let [w, x, y, z] = *q;
    Matrix4::new(w, -x, -y, -z, x, w, -z, y, y, z, w, -x, z, -y, x, w)
}

/// `R(q)`: `p ∘ q = R(q) p`.
pub fn rmat(q: &Q) -> Matrix4<f64> {
    let [w, x, y, z] = *q;
    Matrix4::new(w, -x, -y, -z, x, w, z, -y, y, -z, w, x, z, y, -x, w)
}

pub fn to_q(v: &Vector4<f64>) -> Q {
    [v[0], v[1], v[2], v[3]]
}

/// `M` with the mode `q` last: columns `q ∘ e_1, q ∘ e_2, q ∘ e_3, q` (as in `tests/spin.rs`).
pub fn m_with_mode(q: &Q) -> Vec<f64> {
    let l = lmat(q);
    let cols = [1usize, 2, 3, 0];
    let mut m = vec![0.0; 16];
    for (j, &c) in cols.iter().enumerate() {
        for i in 0..4 {
            m[i * 4 + j] = l[(i, c)];
        }
    }
    m
}

pub fn draw(b: &Bingham, rng: &mut StdRng) -> Q {
    let s = &b.sample(rng, 1)[0];
    normalized(&[s[0], s[1], s[2], s[3]])
}
