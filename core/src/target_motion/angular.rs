//! The second, slow angular model of [`super::TargetFilter`]: a constant-velocity turn with
//! low process noise ([`super::TargetFilterParams::slow_angular_acceleration_psd`]), run beside
//! the fast one on the same accepted orientations. A steady turn slower than the fast model's
//! noise (0.03 rad/s against its σ of 0.05 rad/s) is known to a few mrad/s by it; it is fed
//! forward instead of the fast model's velocity. A turn that the fast model sees (its angular
//! velocity significant: a yaw that oscillates or accelerates) restarts it, and so does a poorly
//! seen block ([`super::TargetFilterParams::slow_min_fitness`]): its long memory would carry a
//! lagging or wrong velocity forward.

use nalgebra::{UnitQuaternion, Vector3};

use super::axis::Axis;
use super::{exp_rotation, log_rotation};

/// The slow angular model: its own orientation and three error-state axes `[φ, ω]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct SlowTurn {
    orientation: UnitQuaternion<f32>,
    axes: [Axis; 3],
    /// Accepted updates since the (re)start (saturating).
    updates: u16,
}

impl SlowTurn {
    /// A model at rest at `orientation`, with prior variances `var_x` (rad²) and `var_w`
    /// ((rad/s)²).
    pub(super) fn start(orientation: UnitQuaternion<f32>, var_x: f32, var_w: f32) -> Self {
        Self { orientation, axes: [Axis::start(0.0, var_x, var_w); 3], updates: 0 }
    }

    /// Moves the model on by `dt` (s) with white angular acceleration of density `q`.
    pub(super) fn predict(&mut self, dt: f32, q: f32) {
        self.axes.iter_mut().for_each(|a| a.predict(dt, q));
        self.fold_into_orientation();
    }

    /// Measurement update with an accepted orientation `measured` of variance `r` (rad²).
    pub(super) fn update(&mut self, measured: &UnitQuaternion<f32>, r: f32) {
        let y = log_rotation(&(measured * self.orientation.inverse()));
        for (a, y) in self.axes.iter_mut().zip(y.iter()) {
            a.update(*y, r);
        }
        self.fold_into_orientation();
        self.updates = self.updates.saturating_add(1);
    }

    /// Turns the orientation by the error state and zeroes it.
    fn fold_into_orientation(&mut self) {
        let turn = Vector3::new(self.axes[0].x, self.axes[1].x, self.axes[2].x);
        self.orientation = exp_rotation(&turn) * self.orientation;
        self.axes.iter_mut().for_each(|a| a.x = 0.0);
    }

    /// The angular velocity and its variances.
    pub(super) fn velocity(&self) -> (Vector3<f32>, Vector3<f32>) {
        let a = &self.axes;
        (Vector3::new(a[0].v, a[1].v, a[2].v), Vector3::new(a[0].p[2], a[1].p[2], a[2].p[2]))
    }

    /// Accepted updates since the (re)start.
    pub(super) fn updates(&self) -> u16 {
        self.updates
    }
}
