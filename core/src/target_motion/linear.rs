//! The second, slow linear model of [`super::TargetFilter`]: the position axes `[x, ẋ, ẍ]` run
//! again with low process noise ([`super::TargetFilterParams::slow_acceleration_psd`],
//! [`super::TargetFilterParams::slow_jerk_psd`]) on the same accepted positions. The fast
//! model must be fast to follow a reversal within a few frames, so its velocity is noisy frame
//! to frame; between manoeuvres the slow model knows the velocity better and is fed forward
//! instead. When the two disagree (the slow model lags a manoeuvre: their velocities differ by
//! more than [`super::TargetFilterParams::slow_linear_gate_sigma`] of the fast model's own
//! uncertainty), the slow model restarts as a copy of the fast one, and the fast model's
//! velocity is fed forward until the copy has followed
//! [`super::TargetFilterParams::slow_linear_updates`] updates on its own.

use nalgebra::Vector3;

use super::axis::PosAxis;

/// The slow linear model: three position axes and the updates since its last restart.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct SlowLinear {
    axes: [PosAxis; 3],
    /// Accepted updates since the (re)start (saturating).
    updates: u16,
}

impl SlowLinear {
    /// A model that starts as a copy of `fast`.
    pub(super) fn from_fast(fast: &[PosAxis; 3]) -> Self {
        Self { axes: *fast, updates: 0 }
    }

    /// Moves the model on by `dt` (s) with white acceleration `qa` and white jerk `qj`.
    pub(super) fn predict(&mut self, dt: f32, qa: f32, qj: f32) {
        self.axes.iter_mut().for_each(|a| a.predict(dt, qa, qj));
    }

    /// Measurement update with the accepted position `measured` of variances `r` (per axis).
    pub(super) fn update(&mut self, measured: &Vector3<f32>, r: &[f32; 3]) {
        for ((a, m), r) in self.axes.iter_mut().zip(measured.iter()).zip(r.iter()) {
            let y = m - a.x;
            a.update(y, *r);
        }
        self.updates = self.updates.saturating_add(1);
    }

    /// Whether the model's velocity lies within `gate` standard deviations of the fast model's
    /// velocity, `Σᵢ (v_slow,i − v_fast,i)² / σ²_fast,i ≤ gate²`.
    pub(super) fn agrees(&self, fast: &[PosAxis; 3], gate: f32) -> bool {
        let d2: f32 = self
            .axes
            .iter()
            .zip(fast.iter())
            .map(|(s, f)| {
                let d = s.v - f.v;
                d * d / f.var_v().max(f32::MIN_POSITIVE)
            })
            .sum();
        d2 <= gate * gate // false for NaN
    }

    /// The velocity.
    pub(super) fn velocity(&self) -> Vector3<f32> {
        Vector3::new(self.axes[0].v, self.axes[1].v, self.axes[2].v)
    }

    /// Accepted updates since the (re)start.
    pub(super) fn updates(&self) -> u16 {
        self.updates
    }
}
