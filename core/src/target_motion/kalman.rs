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
//! Work per call is a fixed number of 3 × 3 products and one 3 × 3 inverse: no loops over data.

use nalgebra::{Matrix3, Vector3};

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
        let s_inv = (self.a + r).try_inverse()?;
        Some(Innovation { y: z - self.x, s_inv })
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
