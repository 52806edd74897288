//! A constant-velocity Kalman filter on three coupled axes: state `[x, ẋ]` with `x, ẋ ∈ ℝ³` and
//! the covariance kept as three 3 × 3 blocks, `P = [[A, B], [Bᵀ, C]]`.
//!
//! The process noise is the discrete white-noise acceleration of Bar-Shalom et al.
//! ("Estimation with Applications to Tracking and Navigation", §6.3.3): the acceleration is
//! constant over a step and of standard deviation `σ_a` per axis, so over a step `dt`
//! `Q = σ_a² [[dt⁴/4, dt³/2], [dt³/2, dt²]] ⊗ I₃`. The measurement is the position `x` with a
//! full 3 × 3 covariance `R`, so an axis poorly seen (depth along the line of sight) weighs
//! less in every world axis it projects on.
//!
//! [`SingerFilter`] is the same on `[x, ẋ, ẍ]`: the acceleration is a state too, which
//! decays towards zero over a manoeuvre time (Singer's model).
//!
//! Work per call is a fixed number of 3 × 3 products and one 3 × 3 inverse: no loops over data.

use nalgebra::{Matrix3, Vector3};

use crate::math;

/// One constant-velocity filter (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct CvFilter {
    pub(super) x: Vector3<f32>,
    pub(super) v: Vector3<f32>,
    a: Matrix3<f32>,
    b: Matrix3<f32>,
    c: Matrix3<f32>,
}

/// The innovation of a measurement and its covariance's inverse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Innovation {
    pub(super) y: Vector3<f32>,
    s_inv: Matrix3<f32>,
}

impl Innovation {
    /// The innovation of measurement `z` (covariance `r`) of a position estimate `x` of
    /// covariance `p`: `y = z − x`, `S⁻¹ = (p + r)⁻¹`; `None` when `S` is singular.
    fn of(x: &Vector3<f32>, p: &Matrix3<f32>, z: &Vector3<f32>, r: &Matrix3<f32>) -> Option<Self> {
        let s_inv = (p + r).try_inverse()?;
        Some(Self { y: z - x, s_inv })
    }
}

impl CvFilter {
    /// A filter at `x` (covariance `r`) with an unknown velocity of standard deviation `sd_v`
    /// per axis.
    pub(super) fn start(x: Vector3<f32>, r: &Matrix3<f32>, sd_v: f32) -> Self {
        let c = Matrix3::identity() * (sd_v * sd_v);
        Self { x, v: Vector3::zeros(), a: *r, b: Matrix3::zeros(), c }
    }

    /// Moves the state on by `dt` (s) with acceleration standard deviation `sd_a`.
    pub(super) fn predict(&mut self, dt: f32, sd_a: f32) {
        let q = sd_a * sd_a;
        let dt2 = dt * dt;
        let i = Matrix3::<f32>::identity();
        self.x += self.v * dt;
        let bt = self.b.transpose();
        self.a += (self.b + bt) * dt + self.c * dt2 + i * (q * dt2 * dt2 * 0.25);
        self.b += self.c * dt + i * (q * dt2 * dt * 0.5);
        self.c += i * (q * dt2);
    }

    /// The innovation of measurement `z` of covariance `r`; `None` when `S` is singular
    /// (never for a positive definite `r`).
    pub(super) fn innovation(&self, z: &Vector3<f32>, r: &Matrix3<f32>) -> Option<Innovation> {
        Innovation::of(&self.x, &self.a, z, r)
    }

    /// The measurement update with innovation `inn`; returns the correction of `x`.
    pub(super) fn update(&mut self, inn: &Innovation) -> Vector3<f32> {
        let kx = self.a * inn.s_inv;
        let kv = self.b.transpose() * inn.s_inv;
        let dx = kx * inn.y;
        self.x += dx;
        self.v += kv * inn.y;
        let (a, b) = (self.a, self.b);
        self.a = symmetric(&(a - kx * a));
        self.b = b - kx * b;
        self.c = symmetric(&(self.c - kv * b));
        dx
    }

    /// Sets the position to `x` (after its correction was applied elsewhere).
    pub(super) fn set_position(&mut self, x: Vector3<f32>) {
        self.x = x;
    }
}

/// `(m + mᵀ) / 2`: keeps a covariance symmetric against rounding.
fn symmetric(m: &Matrix3<f32>) -> Matrix3<f32> {
    (m + m.transpose()) * 0.5
}

/// A manoeuvring-target filter on three coupled axes (Singer, "Estimating optimal tracking
/// filter performance for manned maneuvering targets", IEEE Trans. AES-6, 1970): state
/// `[x, ẋ, ẍ]`, covariance kept as six 3 × 3 blocks `P = [[A, B, D], [Bᵀ, C, E], [Dᵀ, Eᵀ, G]]`.
///
/// The acceleration is a first-order Markov process: over a step `dt` it decays by
/// `ρ = e^(−dt/τ)` (`τ` the manoeuvre time) and gains a white increment of variance
/// `σ_a² (1 − ρ²)` per axis, so its standard deviation stays `σ_a`. The increment enters position and velocity as a constant acceleration over the
/// step would, `γ = [dt²/2, dt, 1]` (the discrete form of Bar-Shalom et al., §6.3.3, for
/// `dt ≪ τ`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct SingerFilter {
    pub(super) x: Vector3<f32>,
    pub(super) v: Vector3<f32>,
    pub(super) acc: Vector3<f32>,
    a: Matrix3<f32>,
    b: Matrix3<f32>,
    d: Matrix3<f32>,
    c: Matrix3<f32>,
    e: Matrix3<f32>,
    g: Matrix3<f32>,
}

impl SingerFilter {
    /// A filter at `x` (covariance `r`) with an unknown velocity and acceleration of standard
    /// deviations `sd_v` and `sd_a` per axis.
    pub(super) fn start(x: Vector3<f32>, r: &Matrix3<f32>, sd_v: f32, sd_a: f32) -> Self {
        let (i, z, zero) = (Matrix3::identity(), Matrix3::zeros(), Vector3::zeros());
        Self { x, v: zero, acc: zero, a: *r, b: z, d: z, c: i * (sd_v * sd_v), e: z, g: i * (sd_a * sd_a) }
    }

    /// Moves the state on by `dt` (s): the acceleration decays by `rho = e^(−dt/τ)` and gains
    /// the white increment of variance `sd_a² (1 − rho²)`.
    pub(super) fn predict(&mut self, dt: f32, rho: f32, sd_a: f32) {
        let (h, h2) = (dt, 0.5 * dt * dt);
        self.x += self.v * h + self.acc * h2;
        self.v += self.acc * h;
        self.acc *= rho;
        let (a, b, d, c, e, g) = (self.a, self.b, self.d, self.c, self.e, self.g);
        // F·P by block rows (F = [[I, h, h2], [0, I, h], [0, 0, ρ]]), then ·Fᵀ by block columns.
        let r1 = [a + b.transpose() * h + d.transpose() * h2, b + c * h + e.transpose() * h2, d + e * h + g * h2];
        let r2 = [c + e.transpose() * h, e + g * h];
        let q = sd_a * sd_a * (1.0 - rho * rho);
        let i = Matrix3::<f32>::identity();
        self.a = symmetric(&(r1[0] + r1[1] * h + r1[2] * h2)) + i * (q * h2 * h2);
        self.b = r1[1] + r1[2] * h + i * (q * h2 * h);
        self.d = r1[2] * rho + i * (q * h2);
        self.c = symmetric(&(r2[0] + r2[1] * h)) + i * (q * h * h);
        self.e = r2[1] * rho + i * (q * h);
        self.g = g * (rho * rho) + i * q;
    }

    /// The innovation of measurement `z` of covariance `r`; `None` when `S` is singular.
    pub(super) fn innovation(&self, z: &Vector3<f32>, r: &Matrix3<f32>) -> Option<Innovation> {
        Innovation::of(&self.x, &self.a, z, r)
    }

    /// The measurement update with innovation `inn`.
    pub(super) fn update(&mut self, inn: &Innovation) {
        let kx = self.a * inn.s_inv;
        let kv = self.b.transpose() * inn.s_inv;
        let ka = self.d.transpose() * inn.s_inv;
        self.x += kx * inn.y;
        self.v += kv * inn.y;
        self.acc += ka * inn.y;
        let (a, b, d) = (self.a, self.b, self.d);
        self.a = symmetric(&(a - kx * a));
        self.b = b - kx * b;
        self.d = d - kx * d;
        self.c = symmetric(&(self.c - kv * b));
        self.e -= kv * d;
        self.g = symmetric(&(self.g - ka * d));
    }

    /// The mean position and velocity `tau` seconds on, the acceleration decaying with
    /// `manoeuvre_s`: `ẋ + ẍ·τ_m(1 − e^(−τ/τ_m))` and its integral. Backwards in time (`tau < 0`)
    /// only the velocity is extrapolated.
    pub(super) fn ahead(&self, tau: f32, manoeuvre_s: f32) -> (Vector3<f32>, Vector3<f32>) {
        let on = tau.max(0.0);
        let decayed = manoeuvre_s * (1.0 - math::exp(-on / manoeuvre_s));
        let x = self.x + self.v * tau + self.acc * (manoeuvre_s * (on - decayed));
        (x, self.v + self.acc * decayed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{SMatrix, SVector};

    type M9 = SMatrix<f32, 9, 9>;

    /// The filter's covariance as one 9 × 9 matrix.
    fn dense(f: &SingerFilter) -> M9 {
        let blocks = [[f.a, f.b, f.d], [f.b.transpose(), f.c, f.e], [f.d.transpose(), f.e.transpose(), f.g]];
        let mut p = M9::zeros();
        for (r, row) in blocks.iter().enumerate() {
            for (c, m) in row.iter().enumerate() {
                p.fixed_view_mut::<3, 3>(3 * r, 3 * c).copy_from(m);
            }
        }
        p
    }

    /// The filter's state `[x, ẋ, ẍ]` as one vector.
    fn state(f: &SingerFilter) -> SVector<f32, 9> {
        SVector::from_iterator(f.x.iter().chain(f.v.iter()).chain(f.acc.iter()).copied())
    }

    /// A filter with a full, positive definite covariance (an update after a few steps).
    fn filter() -> SingerFilter {
        let r = Matrix3::new(4e-6, 1e-6, 0.0, 1e-6, 9e-6, 2e-6, 0.0, 2e-6, 1e-5);
        let mut f = SingerFilter::start(Vector3::new(0.7, 0.1, -0.05), &r, 0.5, 0.6);
        for k in 0..5 {
            f.predict(0.033, 0.94, 0.6);
            let z = Vector3::new(0.7, 0.1 + 0.003 * k as f32, -0.05);
            let inn = f.innovation(&z, &r).unwrap();
            f.update(&inn);
        }
        f
    }

    #[test]
    fn the_singer_blocks_are_the_dense_kalman_filter() {
        let (dt, rho, sd) = (0.033f32, 0.936f32, 0.58f32);
        let mut f = filter();
        let p = dense(&f);
        // F = [[I, dt, dt²/2], [0, I, dt], [0, 0, ρ]] ⊗ blocks, Q = σ²(1 − ρ²) γγᵀ, γ = [dt²/2, dt, 1].
        let mut big_f = M9::identity();
        let i3 = Matrix3::<f32>::identity();
        big_f.fixed_view_mut::<3, 3>(0, 3).copy_from(&(i3 * dt));
        big_f.fixed_view_mut::<3, 3>(0, 6).copy_from(&(i3 * (0.5 * dt * dt)));
        big_f.fixed_view_mut::<3, 3>(3, 6).copy_from(&(i3 * dt));
        big_f.fixed_view_mut::<3, 3>(6, 6).copy_from(&(i3 * rho));
        let gamma = [0.5 * dt * dt, dt, 1.0];
        let q = sd * sd * (1.0 - rho * rho);
        let mut big_q = M9::zeros();
        for r in 0..3 {
            for c in 0..3 {
                big_q.fixed_view_mut::<3, 3>(3 * r, 3 * c).copy_from(&(i3 * (q * gamma[r] * gamma[c])));
            }
        }
        let want_state = big_f * state(&f);
        let want = big_f * p * big_f.transpose() + big_q;
        f.predict(dt, rho, sd);
        let got = dense(&f);
        let scale = want.amax();
        assert!((got - want).amax() < 1e-5 * scale, "predict: {}", (got - want).amax() / scale);
        assert!((state(&f) - want_state).amax() < 1e-6);

        // The update with H = [I 0 0]: K = P Hᵀ S⁻¹, P' = (I − K H) P.
        let r = Matrix3::new(5e-6, 0.0, 0.0, 0.0, 5e-6, 0.0, 0.0, 0.0, 3e-5);
        let z = Vector3::new(0.705, 0.12, -0.049);
        let p = dense(&f);
        let mut h = SMatrix::<f32, 3, 9>::zeros();
        h.fixed_view_mut::<3, 3>(0, 0).copy_from(&i3);
        let s_inv = (h * p * h.transpose() + r).try_inverse().unwrap();
        let k = p * h.transpose() * s_inv;
        let before = state(&f);
        let want_state = before + k * (z - h * before);
        let want = (M9::identity() - k * h) * p;
        let inn = f.innovation(&z, &r).unwrap();
        f.update(&inn);
        let got = dense(&f);
        let scale = p.amax();
        assert!((got - want).amax() < 1e-4 * scale, "update: {}", (got - want).amax() / scale);
        let got_state = state(&f);
        assert!((got_state - want_state).amax() < 1e-4 * want_state.amax(), "{got_state} vs {want_state}");
    }
}
