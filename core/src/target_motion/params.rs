//! The target motion model's parameters ([`TargetFilterParams`]) and their validation.
//!
//! Each parameter is a physical quantity with a unit: what the block may do (accelerations,
//! speeds at the first sight) and how well one estimate sees it (in image pixels, turned into
//! metres and radians per camera axis by [`super::Optics`]).

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

    /// Checks that every field is finite and positive.
    ///
    /// # Errors
    /// [`FilterParamsError`] naming the first bad field.
    pub fn validate(&self) -> Result<(), FilterParamsError> {
        match Self::REAL_FIELDS.iter().find(|f| !((f.get)(self).is_finite() && (f.get)(self) > 0.0)) {
            Some(f) => Err(FilterParamsError(f.name)),
            None => Ok(()),
        }
    }
}

/// A [`TargetFilterParams`] field is out of range (its name).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FilterParamsError(pub &'static str);

impl FilterParamsError {
    /// The rule the field broke (see [`TargetFilterParams::validate`]).
    pub fn rule(&self) -> &'static str {
        "finite and positive"
    }
}

impl core::fmt::Display for FilterParamsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "target motion parameter {} must be {}", self.0, self.rule())
    }
}

impl core::error::Error for FilterParamsError {}

/// One field of [`TargetFilterParams`] of type `T`, by name: for tools that read or send the
/// parameters field by field (a scenario file's keys, a link message), so that the list of
/// fields is kept once, here.
#[derive(Clone, Copy, Debug)]
pub struct Field<T> {
    /// The field's name in [`TargetFilterParams`].
    pub name: &'static str,
    /// The field's unit.
    pub unit: &'static str,
    /// Reads the field.
    pub get: fn(&TargetFilterParams) -> T,
    /// Writes the field.
    pub set: fn(&mut TargetFilterParams, T),
}

/// The [`Field`]s of the listed `(field, unit)` pairs of type `$ty`.
macro_rules! fields {
    ($ty:ty, [$(($f:ident, $unit:literal)),* $(,)?]) => {
        [$(Field::<$ty> { name: stringify!($f), unit: $unit, get: |p| p.$f, set: |p, v| p.$f = v }),*]
    };
}

impl TargetFilterParams {
    /// Every field, in the order a link message carries them.
    pub const REAL_FIELDS: [Field<f32>; 6] = fields!(
        f32,
        [
            (acceleration_m_s2, "m/s²"),
            (angular_acceleration_rad_s2, "rad/s²"),
            (max_speed_m_s, "m/s"),
            (max_rate_rad_s, "rad/s"),
            (image_noise_px, "px"),
            (max_gap_s, "s"),
        ]
    );
}
