//! The tuning of a [`TargetFilter`](super::TargetFilter) and its validation.

/// Tuning of a [`TargetFilter`](super::TargetFilter).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetFilterParams {
    /// Standard deviation of a position measurement across the line of sight (m); the whole
    /// measurement's when no line of sight is known
    /// ([`TargetFilter::update`](super::TargetFilter::update)).
    pub position_noise_m: f32,
    /// Standard deviation of a position measurement along the camera's line of sight to the
    /// block (m, [`TargetFilter::update_from_estimate`](super::TargetFilter::update_from_estimate)):
    /// stereo depth is far noisier than the position across the view.
    pub depth_noise_m: f32,
    /// Standard deviation of an orientation measurement (rad, per axis).
    pub rotation_noise_rad: f32,
    /// Spectral density of the white acceleration noise of the position axes (m²/s³).
    pub acceleration_psd: f32,
    /// Spectral density of the white angular acceleration noise (rad²/s³).
    pub angular_acceleration_psd: f32,
    /// Spectral density of the white angular acceleration noise of the second, slow angular
    /// model (rad²/s³) run beside the fast one for a steady turn; 0 feeds forward none of it
    /// (see [`TargetFilter::feedforward_velocity`](super::TargetFilter::feedforward_velocity)).
    pub slow_angular_acceleration_psd: f32,
    /// Feedforward dead band of the slow model's angular speed (rad/s).
    pub slow_deadband_rad_s: f32,
    /// The slow model learns only from estimates of at least this fitness; a lower one
    /// restarts it (its long memory would keep the errors of a poorly seen block).
    pub slow_min_fitness: f32,
    /// Spectral density of the white jerk noise of the position axes' acceleration state
    /// (m²/s⁵): each position axis is `[x, ẋ, ẍ]`, so a block that speeds up, stops and
    /// reverses is followed without the lag of a constant-velocity model. 0 together with
    /// [`TargetFilterParams::initial_accel_sd_m_s2`] 0 keeps the acceleration at 0 (a
    /// constant-velocity filter).
    pub jerk_psd: f32,
    /// Prior standard deviation of the acceleration after a reset (m/s²).
    pub initial_accel_sd_m_s2: f32,
    /// The linear velocity fed forward is the filter's velocity moved on by its acceleration
    /// over this time (s): `v + a·lead`; half a frame period is the mean velocity over the
    /// next frame. The acceleration state is noisy, so the lead pays only when the filter is fed
    /// a quiet position ([`TargetFilterParams::measurement_fitness_margin`]); 0 feeds the
    /// velocity alone.
    pub acceleration_lead_s: f32,
    /// Prior standard deviation of the velocity after a reset (m/s).
    pub initial_speed_sd_m_s: f32,
    /// Prior standard deviation of the angular velocity after a reset (rad/s).
    pub initial_rate_sd_rad_s: f32,
    /// Innovation gate in standard deviations; a larger innovation on any axis is an outlier.
    pub gate_sigma: f32,
    /// Consecutive rejected measurements after which the filter restarts at the newest one.
    pub max_outliers: u16,
    /// Consecutive accepted updates needed before the velocity is trusted.
    pub converge_updates: u16,
    /// The velocity is trusted only while its standard deviation is below this (m/s).
    pub trusted_speed_sd_m_s: f32,
    /// The angular velocity is trusted only while its standard deviation is below this (rad/s).
    pub trusted_rate_sd_rad_s: f32,
    /// A fitness below this means the tracker lost the target: the filter resets.
    pub lost_fitness: f32,
    /// A time step above this (s) restarts the filter.
    pub max_gap_s: f32,
    /// Feedforward dead band: a speed below this (m/s) is fed forward as 0.
    pub deadband_m_s: f32,
    /// Feedforward dead band: an angular speed below this (rad/s) is fed forward as 0.
    pub deadband_rad_s: f32,
    /// Feedforward significance: the linear (angular) velocity is fed forward only when its
    /// length in standard deviations of its own estimate, `√(Σ vᵢ² / σᵢ²)`, reaches this — a
    /// velocity inside the filter's `significance_sigma`-σ ellipsoid around zero cannot be told
    /// from a target at rest, and feeding its noise forward drags the population along it.
    pub significance_sigma: f32,
    /// Once the linear velocity has been fed forward, keep feeding it forward (without the
    /// significance test and the dead band) until the filter restarts: a block that moved
    /// keeps moving, and its speed passes zero at every reversal.
    pub hold_motion: bool,
    /// While the linear motion is held ([`TargetFilterParams::hold_motion`]: the block is known
    /// to move), the fast angular model's velocity is not fed forward (the slow angular
    /// model's still is). On a moving block the fast model mostly measures the estimate's own
    /// drift (the x/turn ambiguity of a box seen from the front) and, fed forward, sustains it.
    pub linear_motion_mutes_angular: bool,
    /// The position the filter is fed is the mean position of the GA's individuals whose
    /// fitness is within this margin of the best's (with the best's orientation,
    /// [`Ga::mean_translation_near`](crate::ga::Ga::mean_translation_near)), not the best
    /// individual's: the best jumps between the individuals at the top of a flat fitness peak
    /// from frame to frame, the crowd's centre much less. 0 feeds the best alone.
    pub measurement_fitness_margin: f32,
    /// Share (0..=1) of the linear velocity along the line of sight, beyond what the world axes
    /// seen across the sight carry, that
    /// [`TargetFilter::feedforward_velocity_seen_along`](super::TargetFilter::feedforward_velocity_seen_along)
    /// feeds forward: that rest is mostly the difference of noisy stereo depths, and fed
    /// forward it drags the population along the viewing ray.
    pub depth_feedforward: f32,
}

impl TargetFilterParams {
    /// Defaults for the simulator's set-up (33 ms frames, estimates good to a few mm and a few
    /// mrad). The dead bands are about one frame's shift at the estimates' own noise floor
    /// (0.01 m/s · 33 ms = 0.33 mm; 0.05 rad/s · 33 ms = 1.7 mrad ≈ 0.0008 in ε).
    ///
    /// The linear part is tuned for a block that starts, stops and reverses on a conveyor
    /// (0.2 m/s, reversals at 0.54 m/s², `scenarios/conveyor_ff_target.toml`): a fast filter
    /// (white acceleration 0.2 m²/s³ and white jerk 30 m²/s⁵ on an acceleration state, 1 mm
    /// across the line of sight, 8 mm along it) that follows a reversal within a few frames,
    /// trusted once its velocity is known to 0.1 m/s, reset only when the fitness falls below
    /// 0.3 (or the tracker's status leaves *tracking*). It is fed the centre of the GA's
    /// individuals within 0.01 of the best fitness
    /// ([`TargetFilterParams::measurement_fitness_margin`]), which jumps less than the best
    /// individual, and the velocity it feeds forward is moved on by its acceleration over half a
    /// frame ([`TargetFilterParams::acceleration_lead_s`] 0.0165 s). Once fed forward, its
    /// velocity is held through the reversals ([`TargetFilterParams::hold_motion`]), and along
    /// the line of sight only what the axes seen across it say is fed forward
    /// ([`TargetFilterParams::depth_feedforward`] 0). The significance test still decides
    /// whether a block moves at all, so a block at rest is tracked as with FF alone.
    /// While the block moves, the fast angular model is not fed forward
    /// ([`TargetFilterParams::linear_motion_mutes_angular`]): on the conveyor it lost the block
    /// in 5 of 20 runs by feeding forward the estimate's own turn.
    pub const DEFAULT: TargetFilterParams = TargetFilterParams {
        position_noise_m: 0.001,
        depth_noise_m: 0.008,
        rotation_noise_rad: 0.02,
        acceleration_psd: 0.2,
        angular_acceleration_psd: 0.01,
        slow_angular_acceleration_psd: 1e-4,
        slow_deadband_rad_s: 0.02,
        slow_min_fitness: 0.96,
        jerk_psd: 30.0,
        initial_accel_sd_m_s2: 1.0,
        acceleration_lead_s: 0.0165,
        initial_speed_sd_m_s: 0.5,
        initial_rate_sd_rad_s: 2.0,
        gate_sigma: 6.0,
        max_outliers: 3,
        converge_updates: 10,
        trusted_speed_sd_m_s: 0.1,
        trusted_rate_sd_rad_s: 0.15,
        lost_fitness: 0.3,
        max_gap_s: 0.5,
        deadband_m_s: 0.01,
        deadband_rad_s: 0.05,
        significance_sigma: 2.0,
        hold_motion: true,
        linear_motion_mutes_angular: true,
        depth_feedforward: 0.0,
        measurement_fitness_margin: 0.01,
    };

    /// Checks every field against its rule: the noises, the fast densities, the prior speed and
    /// rate deviations, the gate, the trust bounds and `max_gap_s` finite and positive;
    /// `lost_fitness`, the dead bands, `significance_sigma`, `jerk_psd`,
    /// `initial_accel_sd_m_s2`, `acceleration_lead_s` and the slow angular model's
    /// `slow_angular_acceleration_psd`, `slow_deadband_rad_s` and `slow_min_fitness`, and
    /// `measurement_fitness_margin` finite and non-negative; `depth_feedforward` in `[0, 1]`;
    /// the counts `max_outliers` and `converge_updates` at least 1. The flags (`hold_motion`,
    /// `linear_motion_mutes_angular`) have no rule.
    ///
    /// # Errors
    /// [`FilterParamsError`] naming the first bad field.
    pub fn validate(&self) -> Result<(), FilterParamsError> {
        let positive = [
            (self.position_noise_m, "position_noise_m"),
            (self.depth_noise_m, "depth_noise_m"),
            (self.rotation_noise_rad, "rotation_noise_rad"),
            (self.acceleration_psd, "acceleration_psd"),
            (self.angular_acceleration_psd, "angular_acceleration_psd"),
            (self.initial_speed_sd_m_s, "initial_speed_sd_m_s"),
            (self.initial_rate_sd_rad_s, "initial_rate_sd_rad_s"),
            (self.gate_sigma, "gate_sigma"),
            (self.trusted_speed_sd_m_s, "trusted_speed_sd_m_s"),
            (self.trusted_rate_sd_rad_s, "trusted_rate_sd_rad_s"),
            (self.max_gap_s, "max_gap_s"),
        ];
        if let Some((_, name)) = positive.iter().find(|(v, _)| !(v.is_finite() && *v > 0.0)) {
            return Err(FilterParamsError(name));
        }
        let non_negative = [
            (self.lost_fitness, "lost_fitness"),
            (self.deadband_m_s, "deadband_m_s"),
            (self.deadband_rad_s, "deadband_rad_s"),
            (self.significance_sigma, "significance_sigma"),
            (self.jerk_psd, "jerk_psd"),
            (self.initial_accel_sd_m_s2, "initial_accel_sd_m_s2"),
            (self.acceleration_lead_s, "acceleration_lead_s"),
            (self.slow_angular_acceleration_psd, "slow_angular_acceleration_psd"),
            (self.slow_deadband_rad_s, "slow_deadband_rad_s"),
            (self.slow_min_fitness, "slow_min_fitness"),
            (self.measurement_fitness_margin, "measurement_fitness_margin"),
        ];
        if let Some((_, name)) = non_negative.iter().find(|(v, _)| !(v.is_finite() && *v >= 0.0)) {
            return Err(FilterParamsError(name));
        }
        if !(self.depth_feedforward >= 0.0 && self.depth_feedforward <= 1.0) {
            return Err(FilterParamsError("depth_feedforward"));
        }
        if self.max_outliers == 0 {
            return Err(FilterParamsError("max_outliers"));
        }
        if self.converge_updates == 0 {
            return Err(FilterParamsError("converge_updates"));
        }
        Ok(())
    }
}

/// A [`TargetFilterParams`] field is out of range (its name).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FilterParamsError(pub &'static str);

/// One field of [`TargetFilterParams`] of type `T`, by name: for tools that read or send the
/// parameters field by field (a scenario file's keys, a link message), so that the list of
/// fields is kept once, here.
#[derive(Clone, Copy, Debug)]
pub struct Field<T> {
    /// The field's name in [`TargetFilterParams`].
    pub name: &'static str,
    /// Reads the field.
    pub get: fn(&TargetFilterParams) -> T,
    /// Writes the field.
    pub set: fn(&mut TargetFilterParams, T),
}

/// The [`Field`]s of the listed fields of type `$ty`.
macro_rules! fields {
    ($ty:ty, [$($f:ident),* $(,)?]) => {
        [$(Field::<$ty> { name: stringify!($f), get: |p| p.$f, set: |p, v| p.$f = v }),*]
    };
}

impl TargetFilterParams {
    /// Every `f32` field, in the order a link message carries them.
    pub const REAL_FIELDS: [Field<f32>; 23] = fields!(
        f32,
        [
            position_noise_m,
            depth_noise_m,
            rotation_noise_rad,
            acceleration_psd,
            angular_acceleration_psd,
            slow_angular_acceleration_psd,
            slow_deadband_rad_s,
            slow_min_fitness,
            jerk_psd,
            initial_accel_sd_m_s2,
            acceleration_lead_s,
            initial_speed_sd_m_s,
            initial_rate_sd_rad_s,
            gate_sigma,
            trusted_speed_sd_m_s,
            trusted_rate_sd_rad_s,
            lost_fitness,
            max_gap_s,
            deadband_m_s,
            deadband_rad_s,
            significance_sigma,
            measurement_fitness_margin,
            depth_feedforward,
        ]
    );
    /// The two counts.
    pub const COUNT_FIELDS: [Field<u16>; 2] = fields!(u16, [max_outliers, converge_updates]);
    /// The two flags.
    pub const FLAG_FIELDS: [Field<bool>; 2] = fields!(bool, [hold_motion, linear_motion_mutes_angular]);
}

impl FilterParamsError {
    /// The rule the field broke (see [`TargetFilterParams::validate`]).
    pub fn rule(&self) -> &'static str {
        match self.0 {
            "lost_fitness"
            | "deadband_m_s"
            | "deadband_rad_s"
            | "significance_sigma"
            | "jerk_psd"
            | "initial_accel_sd_m_s2"
            | "acceleration_lead_s"
            | "slow_angular_acceleration_psd"
            | "slow_deadband_rad_s"
            | "slow_min_fitness"
            | "measurement_fitness_margin" => "finite and non-negative",
            "depth_feedforward" => "between 0 and 1",
            "max_outliers" | "converge_updates" => "at least 1",
            _ => "finite and positive",
        }
    }
}

impl core::fmt::Display for FilterParamsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "target filter parameter {} must be {}", self.0, self.rule())
    }
}

impl core::error::Error for FilterParamsError {}
