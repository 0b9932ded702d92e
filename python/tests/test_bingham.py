"""Tests of the ctypes binding (run by `make python-test` against the pip-installed package).

References are computed here with NumPy, independently of the library: quadrature over the
circle / the 2-sphere, the d = 2 closed form with numpy.i0, eigendecompositions with eigh, and
complex / quaternion products written out by hand.
"""

import math
import os
import re
import threading
import unittest

import numpy as np

import bingham as bh

HEADER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "include", "bingham.h")


def rot2(a):
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


def random_orthogonal(d, seed):
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(d, d)))
    return q * np.sign(np.diag(r))


def circle_nodes(n=2000):
    t = 2 * np.pi * np.arange(n) / n
    return np.stack([np.cos(t), np.sin(t)], axis=1), 2 * np.pi / n


def sphere_nodes(n=200):
    g, w = np.polynomial.legendre.leggauss(n)
    th = (g + 1) * np.pi / 2
    wth = w * np.pi / 2 * np.sin(th)
    ph = 2 * np.pi * np.arange(2 * n) / (2 * n)
    T, P = np.meshgrid(th, ph, indexing="ij")
    x = np.stack([np.cos(T), np.sin(T) * np.cos(P), np.sin(T) * np.sin(P)], axis=-1).reshape(-1, 3)
    w = (wth[:, None] * np.full(2 * n, 2 * np.pi / (2 * n))[None, :]).reshape(-1)
    return x, w


def quad_moments(m, z):
    """(F, S) of Bingham(m, z) by quadrature, d = 2 or 3."""
    d = len(z)
    a = m @ np.diag(z) @ m.T
    x, w = circle_nodes() if d == 2 else sphere_nodes()
    e = w * np.exp(np.einsum("ki,ij,kj->k", x, a, x))
    f = e.sum()
    return f, (x * e[:, None]).T @ x / f


def qmul(p, q):
    w1, x1, y1, z1 = p
    w2, x2, y2, z2 = q
    return np.array([
        w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
        w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
    ])


def cmul(p, q):
    c = complex(*p) * complex(*q)
    return np.array([c.real, c.imag])


class Binding(unittest.TestCase):
    def test_every_exported_function_is_bound(self):
        with open(HEADER, encoding="utf-8") as f:
            header = f.read()
        declared = set(re.findall(r"^[a-z][^\n]*?\b(bingham_\w+)\(", header, re.M))
        self.assertIn("bingham_mle", declared)
        self.assertEqual(declared, set(bh._SIGNATURES), "bind new functions in python/bingham/_library.py")
        # the number of parameters agrees with the header
        for name, params in re.findall(r"^[a-z][^\n]*?\b(bingham_\w+)\(([^)]*)\)", header, re.M):
            n = 0 if params.strip() in ("", "void") else params.count(",") + 1
            self.assertEqual(len(bh._SIGNATURES[name][1]), n, name)
        for name in declared:
            fn = getattr(bh.lib(), name)
            restype, argtypes = bh._SIGNATURES[name]
            self.assertEqual(fn.argtypes, argtypes, name)
            self.assertIs(fn.restype, restype, name)

    def test_version_matches_header(self):
        with open(HEADER, encoding="utf-8") as f:
            header = f.read()
        parts = [re.search(rf"#define BINGHAM_VERSION_{k} (\d+)", header).group(1) for k in ("MAJOR", "MINOR", "PATCH")]
        self.assertEqual(bh.version(), ".".join(parts))

    def test_status_strings(self):
        names = {
            0: "ok",
            1: "null argument",
            2: "invalid dimension",
            3: "invalid argument",
            4: "not converged",
            5: "numerical failure",
            6: "internal error (panic)",
            7: "callback failed",
        }
        for code, text in names.items():
            self.assertEqual(bh.status_str(code), text)
            self.assertEqual(int(bh.Status(code)), code)
        for code in (8, -1, 10**6):
            self.assertEqual(bh.status_str(code), "unknown status")


class Normalization(unittest.TestCase):
    def test_uniform(self):
        for d, f0 in ((2, 2 * math.pi), (3, 4 * math.pi), (4, 2 * math.pi**2)):
            f, df = bh.normalization_constant(np.zeros(d))
            self.assertAlmostEqual(f / f0, 1.0, places=13)
            np.testing.assert_allclose(df, f0 / d, rtol=1e-12)

    def test_d2_closed_form_and_input_order(self):
        for z in ([-3.0, 0.0], [0.0, -3.0], [2.0, -5.0], [-40.0, -1.0]):
            f, df = bh.normalization_constant(z)
            ref = 2 * math.pi * math.exp((z[0] + z[1]) / 2) * np.i0((z[0] - z[1]) / 2)
            self.assertAlmostEqual(f / ref, 1.0, places=12)
            self.assertAlmostEqual(df.sum() / f, 1.0, places=12)
            lf, g = bh.log_normalization_constant(z)
            self.assertAlmostEqual(lf, math.log(ref), places=11)
            np.testing.assert_allclose(g, df / f, rtol=1e-12)
            self.assertEqual(g[0] < g[1], z[0] < z[1])

    def test_d3_quadrature(self):
        z = np.array([-4.0, 1.0, -10.0])
        f_ref, s_ref = quad_moments(np.eye(3), z)
        f, df = bh.normalization_constant(z)
        self.assertAlmostEqual(f / f_ref, 1.0, places=11)
        np.testing.assert_allclose(df / f, np.diag(s_ref), atol=1e-12)

    def test_overflow_is_an_error_not_inf(self):
        with self.assertRaises(bh.BinghamError) as cm:
            bh.normalization_constant([800.0, 0.0, 0.0])
        self.assertEqual(cm.exception.status, bh.Status.ERR_NUMERICAL)
        self.assertIn("bingham_log_normalization_constant", cm.exception.message)
        lf, _ = bh.log_normalization_constant([800.0, 0.0, 0.0])
        self.assertTrue(790 < lf < 800)

    def test_hessian(self):
        z = np.array([-2.0, -7.0, 0.5, -1.0])
        lf, g, h = bh.log_normalization_hessian(z)
        lf2, g2 = bh.log_normalization_constant(z)
        self.assertEqual(lf, lf2)
        np.testing.assert_allclose(g, g2, rtol=1e-14)
        np.testing.assert_allclose(h, h.T, atol=1e-14)
        np.testing.assert_allclose(h.sum(axis=1), 0, atol=1e-12)
        eps = 1e-5  # central differences of the gradient
        for j in range(4):
            e = np.zeros(4)
            e[j] = eps
            fd = (bh.log_normalization_constant(z + e)[1] - bh.log_normalization_constant(z - e)[1]) / (2 * eps)
            np.testing.assert_allclose(h[:, j], fd, atol=1e-8)

    def test_saddlepoint_is_close_but_approximate(self):
        z = [-3.0, -1.0, 0.0, -8.0]
        ls, gs = bh.log_normalization_constant_saddlepoint(z)
        le, ge = bh.log_normalization_constant(z)
        self.assertLess(abs(ls - le), 0.05)
        self.assertNotEqual(ls, le)
        self.assertEqual(gs.shape, (4,))

    def test_errors(self):
        cases = [
            ([1.0], bh.Status.ERR_INVALID_DIMENSION, "d = 1"),
            (np.zeros(65), bh.Status.ERR_INVALID_DIMENSION, "d = 65"),
            ([0.0, math.nan], bh.Status.ERR_INVALID_ARGUMENT, "`z[1]` = NaN"),
            ([math.inf, 0.0], bh.Status.ERR_INVALID_ARGUMENT, "`z[0]` = inf"),
        ]
        for fn in (
            bh.normalization_constant,
            bh.log_normalization_constant,
            bh.log_normalization_constant_saddlepoint,
            bh.log_normalization_hessian,
        ):
            for z, status, text in cases:
                with self.assertRaises(bh.BinghamError) as cm:
                    fn(z)
                self.assertEqual(cm.exception.status, status)
                self.assertIn(text, cm.exception.message)
                self.assertTrue(cm.exception.message.startswith("bingham_"))
                self.assertIn(text, bh.last_error_message())
            with self.assertRaises(ValueError):
                fn(np.zeros((2, 2)))


class Distribution(unittest.TestCase):
    m3 = random_orthogonal(3, 1)
    z3 = np.array([-5.0, 0.0, -2.0])

    def test_second_moment_and_mle_round_trip(self):
        f_ref, s_ref = quad_moments(self.m3, self.z3)
        s = bh.second_moment(self.m3, self.z3)
        np.testing.assert_allclose(s, s_ref, atol=1e-12)
        m, z = bh.mle(s)
        np.testing.assert_allclose(z, [-5.0, -2.0, 0.0], atol=1e-8)
        self.assertEqual(z[-1], 0.0)
        w, v = np.linalg.eigh(s)  # ascending, like the library
        np.testing.assert_allclose(np.abs(np.sum(m * v, axis=0)), 1.0, atol=1e-10)
        np.testing.assert_allclose(m.T @ m, np.eye(3), atol=1e-13)

    def test_mle_samples(self):
        x = bh.sample(self.m3, self.z3, 2000, seed=3)
        w = np.linspace(0.5, 2.0, len(x))
        m, z = bh.mle_samples(x, w)
        scatter = (x * w[:, None]).T @ x / w.sum()
        m2, z2 = bh.mle(scatter)
        np.testing.assert_allclose(z, z2, atol=1e-8)
        m3, z3 = bh.mle_samples(x)
        m4, z4 = bh.mle(x.T @ x / len(x))
        np.testing.assert_allclose(z3, z4, atol=1e-8)
        np.testing.assert_allclose(z3, [-5.0, -2.0, 0.0], atol=0.6)  # statistical
        with self.assertRaises(bh.BinghamError) as cm:
            bh.mle_samples(x, -w)
        self.assertEqual(cm.exception.status, bh.Status.ERR_INVALID_ARGUMENT)
        with self.assertRaises(ValueError):
            bh.mle_samples(x, w[:-1])

    def test_multiply(self):
        m1, z1 = random_orthogonal(4, 2), np.array([-1.0, -3.0, 0.0, -8.0])
        m2, z2 = random_orthogonal(4, 3), np.array([-2.0, 0.0, -4.0, -1.0])
        m, z = bh.multiply(m1, z1, m2, z2)
        c = m1 @ np.diag(z1) @ m1.T + m2 @ np.diag(z2) @ m2.T
        lam, v = np.linalg.eigh(c)
        np.testing.assert_allclose(z, lam - lam[-1], atol=1e-12)
        np.testing.assert_allclose(np.abs(np.sum(m * v, axis=0)), 1.0, atol=1e-10)

    def test_compose_d2_exact_moment(self):
        m1, z1 = rot2(0.3), np.array([-10.0, 0.0])
        m2, z2 = rot2(-1.1), np.array([0.0, -30.0])
        a = quad_moments(m1, z1)[1]
        b = quad_moments(m2, z2)[1]
        e = np.eye(2)
        expected = sum(
            a[i, j] * b[k, l] * np.outer(cmul(e[i], e[k]), cmul(e[j], e[l]))
            for i in range(2)
            for j in range(2)
            for k in range(2)
            for l in range(2)
        )
        m, z = bh.compose(m1, z1, m2, z2)
        np.testing.assert_allclose(bh.second_moment(m, z), expected, atol=1e-10)
        with self.assertRaises(bh.BinghamError) as cm:
            bh.compose(self.m3, self.z3, self.m3, self.z3)
        self.assertEqual(cm.exception.status, bh.Status.ERR_INVALID_DIMENSION)

    def test_pdf_log_pdf_entropy(self):
        m, z = rot2(0.7), np.array([-6.0, 0.0])
        x, w = circle_nodes()
        p = bh.pdf(m, z, x)
        self.assertAlmostEqual((p * w).sum(), 1.0, places=12)
        lp = bh.log_pdf(m, z, x)
        np.testing.assert_allclose(np.exp(lp), p, rtol=1e-13)
        self.assertAlmostEqual(bh.entropy(m, z), -(p * lp * w).sum(), places=11)
        self.assertIsInstance(bh.pdf(m, z, [1.0, 0.0]), float)
        with self.assertRaises(bh.BinghamError) as cm:
            bh.pdf(m, z, [[1.0, 0.0], [1.0, 0.1]])
        self.assertEqual(cm.exception.status, bh.Status.ERR_INVALID_ARGUMENT)
        self.assertIn("x row 1", cm.exception.message)
        with self.assertRaises(ValueError):
            bh.pdf(m, z, np.ones((3, 3)))

    def test_kl_divergence(self):
        m1, z1 = self.m3, self.z3
        m2, z2 = random_orthogonal(3, 9), np.array([-1.0, -2.0, 0.0])
        x, w = sphere_nodes(120)
        p = bh.pdf(m1, z1, x)
        ref = (w * p * (bh.log_pdf(m1, z1, x) - bh.log_pdf(m2, z2, x))).sum()
        self.assertAlmostEqual(bh.kl_divergence(m1, z1, m2, z2), ref, places=9)
        self.assertAlmostEqual(bh.kl_divergence(m1, z1, m1, z1), 0.0, places=12)

    def test_sample(self):
        x = bh.sample(self.m3, self.z3, 5000, seed=11)
        self.assertEqual(x.shape, (5000, 3))
        np.testing.assert_allclose(np.linalg.norm(x, axis=1), 1.0, atol=1e-13)
        np.testing.assert_array_equal(x, bh.sample(self.m3, self.z3, 5000, seed=11))
        self.assertFalse(np.array_equal(x, bh.sample(self.m3, self.z3, 5000, seed=12)))
        s = x.T @ x / len(x)
        np.testing.assert_allclose(s, bh.second_moment(self.m3, self.z3), atol=0.04)
        self.assertEqual(bh.sample(self.m3, self.z3, 0).shape, (0, 3))

    def test_rotate_and_mode(self):
        m, z = random_orthogonal(4, 5), np.array([-3.0, -1.0, 0.0, -9.0])
        u = np.array([0.5, -0.5, 0.5, 0.5])
        ml, zl = bh.rotate_left(m, z, u)
        mr, zr = bh.rotate_right(m, z, u)
        for x in np.random.default_rng(0).normal(size=(5, 4)):
            x /= np.linalg.norm(x)
            self.assertAlmostEqual(bh.log_pdf(ml, zl, qmul(u, x)), bh.log_pdf(m, z, x), places=12)
            self.assertAlmostEqual(bh.log_pdf(mr, zr, qmul(x, u)), bh.log_pdf(m, z, x), places=12)
        mode = bh.mode(m, z)
        self.assertAlmostEqual(abs(mode @ m[:, 2]), 1.0, places=12)
        with self.assertRaises(bh.BinghamError) as cm:
            bh.rotate_left(m, z, 1.01 * u)
        self.assertIn("unit", cm.exception.message)

    def test_invalid_m(self):
        m = self.m3.copy()
        m[0, 0] += 1e-3
        for call in (
            lambda: bh.second_moment(m, self.z3),
            lambda: bh.mode(m, self.z3),
            lambda: bh.entropy(m, self.z3),
            lambda: bh.multiply(m, self.z3, self.m3, self.z3),
        ):
            with self.assertRaises(bh.BinghamError) as cm:
                call()
            self.assertEqual(cm.exception.status, bh.Status.ERR_INVALID_ARGUMENT)
            self.assertIn("orthogonal", cm.exception.message)
        with self.assertRaises(ValueError):
            bh.second_moment(np.eye(2), self.z3)


SWAP2 = np.array([[0.0, 1.0], [1.0, 0.0]])  # last column (1, 0): noise centred at the identity
ANTI4 = np.fliplr(np.eye(4))  # last column (1, 0, 0, 0)


def axis_error(a, b):
    """Angle between two axes (a and -a are the same), d = 2."""
    c = abs(float(np.dot(a, b)) / (np.linalg.norm(a) * np.linalg.norm(b)))
    return math.acos(min(1.0, c))


class FilterTests(unittest.TestCase):
    def test_jaif_d2_scenario_tracks_the_truth(self):
        # JAIF Sec. 7: M0 = I, Z0 = diag(-1, 0), Mw = Mv = [[0, 1], [1, 0]], Zw = diag(-200, 0),
        # Zv = diag(-2, 0), truth starting at (1, 0); the noises are drawn with bh.sample.
        zw, zv = np.array([-200.0, 0.0]), np.array([-2.0, 0.0])
        w = bh.sample(SWAP2, zw, 100, seed=1)
        v = bh.sample(SWAP2, zv, 100, seed=2)
        truth = np.array([1.0, 0.0])
        errors = []
        with bh.Filter(np.eye(2), [-1.0, 0.0]) as f:
            self.assertEqual(f.dim(), 2)
            for k in range(100):
                f.predict(SWAP2, zw)
                truth = cmul(truth, w[k])
                f.update(cmul(truth, v[k]), SWAP2, zv)
                errors.append(axis_error(f.mode(), truth))
        rmse = math.sqrt(np.mean(np.square(errors[20:])))
        self.assertLess(rmse, 0.25)

    def test_update_at_the_mode_adds_concentrations(self):
        with bh.Filter(np.eye(2), [-5.0, 0.0]) as f:
            f.update([0.0, 1.0], SWAP2, [-3.0, 0.0])
            m, z = f.state()
            np.testing.assert_allclose(z, [-8.0, 0.0], atol=1e-9)
            self.assertAlmostEqual(abs(f.mode()[1]), 1.0, places=12)

    def test_predict_keeps_the_mode_and_spreads(self):
        with bh.Filter(np.eye(2), [-50.0, 0.0]) as f:
            f.predict(SWAP2, [-200.0, 0.0])
            m, z = f.state()
            self.assertTrue(-50.0 < z[0] < -30.0)
            self.assertAlmostEqual(abs(f.mode()[1]), 1.0, places=12)

    def test_predict_rotation_d4(self):
        q0 = np.array([0.5, 0.5, 0.5, 0.5])
        m0 = np.linalg.qr(np.column_stack([np.eye(4)[:, :3], q0]))[0]
        m0[:, 3] = q0
        m0 = np.linalg.qr(m0)[0]
        u = np.array([math.cos(0.2), math.sin(0.2), 0.0, 0.0])
        with bh.Filter(m0, [-100.0, -100.0, -100.0, 0.0]) as f:
            start = f.mode()
            f.predict_rotation(u, ANTI4, [-1e6, -1e6, -1e6, 0.0])
            expected = qmul(start, u)
            self.assertAlmostEqual(abs(float(np.dot(f.mode(), expected))), 1.0, places=6)

    def test_log_likelihood_is_a_density_of_the_measurement(self):
        with bh.Filter(rot2(0.4), [-6.0, 0.0]) as f:
            before = f.state()
            x, w = circle_nodes(720)
            total = sum(math.exp(f.log_likelihood(p, SWAP2, [-3.0, 0.0])) for p in x) * w
            self.assertAlmostEqual(total, 1.0, places=8)
            after = f.state()
            np.testing.assert_array_equal(before[0], after[0])
            np.testing.assert_array_equal(before[1], after[1])

    def test_errors_leave_the_filter_unchanged(self):
        with bh.Filter(np.eye(2), [-5.0, 0.0]) as f:
            before = f.state()
            for call, status, text in (
                (lambda: f.predict(SWAP2, [math.nan, 0.0]), bh.Status.ERR_INVALID_ARGUMENT, "NaN"),
                (lambda: f.update([1.0, 0.1], SWAP2, [-2.0, 0.0]), bh.Status.ERR_INVALID_ARGUMENT, "unit"),
                (lambda: f.update([1.0, 0.0], 1.1 * SWAP2, [-2.0, 0.0]), bh.Status.ERR_INVALID_ARGUMENT, "orthogonal"),
                (lambda: f.set_state(np.eye(2), [math.inf, 0.0]), bh.Status.ERR_INVALID_ARGUMENT, "inf"),
            ):
                with self.assertRaises(bh.BinghamError) as cm:
                    call()
                self.assertEqual(cm.exception.status, status)
                self.assertIn(text, cm.exception.message)
                self.assertTrue(cm.exception.message.startswith("bingham_filter_"))
                after = f.state()
                np.testing.assert_array_equal(before[0], after[0])
                np.testing.assert_array_equal(before[1], after[1])
            with self.assertRaises(ValueError):
                f.predict(np.eye(4), np.zeros(4))
        with self.assertRaises(bh.BinghamError) as cm:
            bh.Filter(np.eye(3), [-1.0, -1.0, 0.0])
        self.assertEqual(cm.exception.status, bh.Status.ERR_INVALID_DIMENSION)

    def test_clone_and_close(self):
        f = bh.Filter(np.eye(2), [-5.0, 0.0])
        g = f.clone()
        g.update([0.0, 1.0], SWAP2, [-3.0, 0.0])
        self.assertEqual(f.state()[1][0], -5.0)
        self.assertAlmostEqual(g.state()[1][0], -8.0, places=9)
        f.close()
        f.close()
        with self.assertRaises(ValueError):
            f.mode()
        g.set_state(np.eye(2), [0.0, -2.0])
        self.assertEqual(list(g.state()[1]), [-2.0, 0.0])
        del g


class Threads(unittest.TestCase):
    def test_error_messages_are_per_thread(self):
        bad = {}

        def work(d):
            for _ in range(100):
                try:
                    bh.log_normalization_constant(np.zeros(d))
                except bh.BinghamError as e:
                    if f"d = {d}" not in e.message:
                        bad[d] = e.message

        threads = [threading.Thread(target=work, args=(d,)) for d in (1, 65, 70, 0)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        self.assertEqual(bad, {})


if __name__ == "__main__":
    unittest.main()
