//! The target motion model's parameters ([`TargetFilterParams`]) and their validation.
//!
//! Each parameter is a physical quantity with a unit: what the block may do (accelerations,
//! speeds at the first sight) and how well one estimate sees it (in image pixels, turned into
//! metres and radians per camera axis by [`super::Optics`]).

use crate::tuning::{ConfigError, Tuning};

/// The target motion model's parameters (see the [module docs](super)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetFilterParams {
    /// The largest linear acceleration of the block expected (m/s²): the standard deviation of
    /// the constant-velocity model's white acceleration per world axis. Larger follows starts,
    /// stops and reversals sooner; smaller smooths the velocity of a steady block more.
    pub acceleration_m_s2: f32,
    /// The largest angular acceleration of the block expected (rad/s²), likewise for turns.
    pub angular_acceleration_rad_s2: f32,
    /// The largest speed of the block expected when it is first seen (m/s): the standard
    /// deviation of the unknown velocity at a (re)start, so a block already moving when it
    /// is acquired is followed from its first estimates.
    pub max_speed_m_s: f32,
    /// The largest angular speed of the block expected when it is first seen (rad/s).
    pub max_rate_rad_s: f32,
    /// Standard deviation of one estimate's image position in each camera (px). Through the
    /// camera model ([`super::Optics`]) it gives the measurement noise per camera axis: at
    /// range `Z`, `Z·σ/f` across the line of sight, `Z²·σ/(f·b)` along it (stereo depth), and
    /// the orientation's noise as those over the block's radius.
    pub image_noise_px: f32,
    /// A time step longer than this (s) between two estimates restarts the model: the
    /// velocity is not extrapolated across a longer gap.
    pub max_gap_s: f32,
}

impl TargetFilterParams {
    /// Defaults from physics and the camera model, not from any test scene:
    /// - 1 m/s² (about 0.1 g): a part on a conveyor started, stopped or reversed, or handed
    ///   over at a walking pace;
    /// - 2 rad/s²: a part turned to 1 rad/s within half a second;
    /// - 0.5 m/s and 1 rad/s at the first sight: a fast conveyor, a part turned by hand;
    /// - 0.5 px: an estimate's projection is good to half a pixel (the fitness counts whole
    ///   pixels, and one generation does not reach the optimum exactly);
    /// - 0.5 s: fifteen frames at 30 frames/s.
    pub const DEFAULT: TargetFilterParams = TargetFilterParams {
        acceleration_m_s2: 1.0,
        angular_acceleration_rad_s2: 2.0,
        max_speed_m_s: 0.5,
        max_rate_rad_s: 1.0,
        image_noise_px: 0.5,
        max_gap_s: 0.5,
    };

    /// Checks that every field is finite and positive ([`Tuning::validate_target`]).
    ///
    /// # Errors
    /// [`ConfigError`] naming the first bad field (`target.…`).
    pub fn validate(&self) -> Result<(), ConfigError> {
        Tuning::validate_target(self)
    }
}
