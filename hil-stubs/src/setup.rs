//! [`Setup`] (the `CONFIG` message) ↔ [`TrackerConfig`]: one conversion, used by the firmware
//! and by the host, so both build bit-identical trackers from the same numbers.
//!
//! Both directions copy every number unchanged (no renormalisation, no unit conversion):
//! `Setup::from_tracker_config(&c, ..)?.tracker_config()? == c` exactly. The arm is always
//! the PA-10 and the rig two identical parallel cameras ([`StereoRig::parallel`]); other
//! configurations cannot be sent and are refused by [`Setup::from_tracker_config`]. The
//! whole tuning ([`TrackerConfig::tuning`]) travels as the core's field table.

use evorec_core::camera::{CameraError, Pinhole, StereoRig};
use evorec_core::ga::{GaError, SearchSpace};
use evorec_core::kinematics::PA10;
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::tracker::{ConfigError, StepError, Tracker, TrackerConfig};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

use crate::protocol::{DOF, Setup};

/// How far `|q|²` of the flange-to-camera quaternion may be from 1.
pub const UNIT_QUATERNION_TOLERANCE: f32 = 1e-4;

/// Why a [`Setup`] does not give a tracker. [`SetupError::code`] is the status the firmware
/// returns in its `ACK`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum SetupError {
    /// Camera intrinsics or baseline (code 1).
    Camera(CameraError),
    /// Search space (code 2).
    Search(GaError),
    /// The flange-to-camera quaternion is not finite or not of unit length (code 3).
    NotUnitQuaternion,
    /// The tracker refused the configuration (code 4).
    Tracker(ConfigError),
    /// The initial pose or spread (code 5).
    InitialPose(StepError),
    /// The rig is not two identical parallel cameras (code 6, host side only).
    UnsupportedRig,
    /// The arm is not the PA-10 (code 7, host side only).
    UnsupportedArm,
}

impl SetupError {
    /// The error's numeric code (never 0, which means success in an `ACK`).
    pub fn code(&self) -> u32 {
        match self {
            Self::Camera(_) => 1,
            Self::Search(_) => 2,
            Self::NotUnitQuaternion => 3,
            Self::Tracker(_) => 4,
            Self::InitialPose(_) => 5,
            Self::UnsupportedRig => 6,
            Self::UnsupportedArm => 7,
        }
    }

    /// What an `ACK` status means.
    pub fn describe_code(code: u32) -> &'static str {
        match code {
            0 => "ok",
            1 => "camera intrinsics or baseline rejected",
            2 => "search space rejected",
            3 => "flange-to-camera quaternion is not a finite unit quaternion",
            4 => "tracker configuration rejected",
            5 => "initial pose or spread rejected",
            6 => "rig is not two identical parallel cameras",
            7 => "arm is not the PA-10",
            _ => "unknown setup error",
        }
    }
}

impl core::fmt::Display for SetupError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Camera(e) => write!(f, "camera: {e}"),
            Self::Search(e) => write!(f, "search space: {e}"),
            Self::Tracker(e) => write!(f, "tracker: {e}"),
            Self::InitialPose(e) => write!(f, "initial pose: {e}"),
            other => f.write_str(Self::describe_code(other.code())),
        }
    }
}

impl core::error::Error for SetupError {}

impl Setup {
    /// The tracker configuration these numbers describe.
    ///
    /// # Errors
    /// [`SetupError::Camera`], [`SetupError::Search`] or [`SetupError::NotUnitQuaternion`];
    /// the remaining checks happen in [`Tracker::new`].
    pub fn tracker_config(&self) -> Result<TrackerConfig<DOF>, SetupError> {
        let cam = Pinhole::new_checked(self.fx, self.fy, self.cx, self.cy, self.width, self.height)
            .map_err(SetupError::Camera)?;
        let rig = StereoRig::parallel(cam, self.baseline_m).map_err(SetupError::Camera)?;
        let search = SearchSpace::new_checked(self.search_min, self.search_max).map_err(SetupError::Search)?;
        let [w, i, j, k] = self.flange_to_camera_q;
        let n2 = w * w + i * i + j * j + k * k;
        if !n2.is_finite() || (n2 - 1.0).abs() > UNIT_QUATERNION_TOLERANCE {
            return Err(SetupError::NotUnitQuaternion);
        }
        let [tx, ty, tz] = self.flange_to_camera_t;
        // Kept bit for bit (no renormalisation), so a round trip through `Setup` is exact.
        let flange_to_camera = Isometry3::from_parts(
            Translation3::new(tx, ty, tz),
            UnitQuaternion::new_unchecked(Quaternion::new(w, i, j, k)),
        );
        let block = Block { size_m: self.block_size_m, face_hues_deg: self.face_hues_deg };
        Ok(TrackerConfig::pa10(rig, block, flange_to_camera, search).with_seed(self.seed).with_tuning(self.tuning))
    }

    /// Builds the tracker and seeds its population around [`Setup::initial_psi`]
    /// ([`Tracker::new`] then [`Tracker::reset_around`]).
    ///
    /// # Errors
    /// As [`Setup::tracker_config`], plus [`SetupError::Tracker`] and
    /// [`SetupError::InitialPose`].
    pub fn build_tracker<const P: usize, const G: usize>(&self) -> Result<Tracker<DOF, P, G>, SetupError> {
        let mut tracker = Tracker::new(self.tracker_config()?).map_err(SetupError::Tracker)?;
        self.prepare(&mut tracker)?;
        Ok(tracker)
    }

    /// [`Setup::build_tracker`] into `slot` (the firmware's static) through
    /// [`Tracker::new_in`], which builds it in place and keeps whole-tracker copies off the
    /// stack. After an initial-pose error `slot` holds a tracker that was not prepared; do not
    /// use it.
    ///
    /// # Errors
    /// As [`Setup::build_tracker`].
    pub fn build_tracker_in<'s, const P: usize, const G: usize>(
        &self,
        slot: &'s mut Option<Tracker<DOF, P, G>>,
    ) -> Result<&'s mut Tracker<DOF, P, G>, SetupError> {
        let config = self.tracker_config()?;
        let tracker = Tracker::new_in(slot, config).map_err(SetupError::Tracker)?;
        self.prepare(tracker)?;
        Ok(tracker)
    }

    /// What the setup holds beyond the tracker's configuration: the population seeded around
    /// [`Setup::initial_psi`].
    fn prepare<const P: usize, const G: usize>(&self, tracker: &mut Tracker<DOF, P, G>) -> Result<(), SetupError> {
        tracker.reset_around(&self.initial_psi, &self.initial_spread).map_err(SetupError::InitialPose)
    }

    /// The `Setup` of a tracker configuration (its whole tuning included) and the initial
    /// population.
    ///
    /// # Errors
    /// [`SetupError::UnsupportedRig`] unless the rig is [`StereoRig::parallel`] (identical
    /// cameras, identity rotation, translation `(b, 0, 0)`); [`SetupError::UnsupportedArm`]
    /// unless the arm is [`PA10`].
    pub fn from_tracker_config(
        config: &TrackerConfig<DOF>,
        initial_psi: &Psi,
        initial_spread: &[f32; 6],
    ) -> Result<Self, SetupError> {
        // Destructured so that a new configuration field in the core fails to compile here.
        let TrackerConfig { rig, block, arm, flange_to_camera, search, seed, tuning } = *config;
        let lfr = &rig.left_from_right;
        let t = lfr.translation.vector;
        let identity = lfr.rotation.coords == UnitQuaternion::<f32>::identity().coords;
        if rig.left != rig.right || !identity || t.y != 0.0 || t.z != 0.0 {
            return Err(SetupError::UnsupportedRig);
        }
        if arm != PA10 {
            return Err(SetupError::UnsupportedArm);
        }
        let cam = &rig.right;
        let ft = &flange_to_camera;
        let q = ft.rotation.quaternion();
        Ok(Self {
            fx: cam.fx(),
            fy: cam.fy(),
            cx: cam.cx(),
            cy: cam.cy(),
            width: cam.width(),
            height: cam.height(),
            baseline_m: t.x,
            block_size_m: block.size_m,
            face_hues_deg: block.face_hues_deg,
            flange_to_camera_t: [ft.translation.x, ft.translation.y, ft.translation.z],
            flange_to_camera_q: [q.w, q.i, q.j, q.k],
            search_min: search.t_min(),
            search_max: search.t_max(),
            seed,
            tuning,
            initial_psi: *initial_psi,
            initial_spread: *initial_spread,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::tests::sample_setup;
    use evorec_core::quat;
    use evorec_core::tracker::Feedforward;
    use nalgebra::Vector3;

    #[test]
    fn round_trip_is_exact() {
        let cam = Pinhole::new_checked(210.0, 209.5, 79.5, 60.5, 160, 120).unwrap();
        let rig = StereoRig::parallel(cam, 0.12).unwrap();
        let space = SearchSpace::new_checked([-0.3, -0.2, 0.35], [0.3, 0.25, 1.1]).unwrap();
        let rot = quat::from_angle_axis(0.3, &Vector3::new(0.2, -1.0, 0.4)).unwrap();
        let ft = Isometry3::from_parts(Translation3::new(0.01, 0.07, 0.12), rot);
        let mut config = TrackerConfig::pa10(rig, Block::PAPER, ft, space).with_seed(99);
        config.tuning.hue_tolerance = 7;
        config.tuning.max_dt_s = 0.25;
        config.tuning.feedforward = Feedforward::OnWithTarget;
        config.tuning.acquire.scan_stride = 4;
        config.tuning.status.lose_frames = 3;
        config.tuning.target.max_gap_s = 0.3;
        let psi = Psi::new([0.0, 0.01, 0.7], [0.1, 0.0, -0.2]);
        let setup = Setup::from_tracker_config(&config, &psi, &[0.01; 6]).unwrap();
        assert_eq!(setup.tracker_config().unwrap(), config);
    }

    #[test]
    fn same_setup_same_tracker() {
        let setup = sample_setup();
        let a: Tracker = setup.build_tracker().unwrap();
        let b: Tracker = setup.build_tracker().unwrap();
        assert_eq!(a.population(), b.population());
        assert_eq!(a.population()[0], setup.initial_psi);
        let mut slot = None;
        let c: &mut Tracker = setup.build_tracker_in(&mut slot).unwrap();
        assert_eq!(c.population(), a.population());
    }

    #[test]
    fn the_population_is_chosen_at_run_time_by_the_config() {
        let mut setup = sample_setup();
        setup.tuning.ga.population = 23;
        let t: Tracker = setup.build_tracker().unwrap();
        assert_eq!(t.population().len(), 23);
        assert_eq!(setup.tracker_config().unwrap().tuning.ga.population, 23);
    }

    #[test]
    fn the_setups_tuning_reaches_the_tracker_and_a_bad_value_names_its_field() {
        let mut setup = sample_setup();
        setup.tuning.target.acceleration_m_s2 = 0.4;
        setup.tuning.status.lose_fitness = 0.3;
        let t: Tracker = setup.build_tracker().unwrap();
        assert_eq!(t.config().tuning, setup.tuning);
        assert_eq!(t.target_filter().params().acceleration_m_s2, 0.4);
        let mut slot = None;
        let t: &mut Tracker = setup.build_tracker_in(&mut slot).unwrap();
        assert_eq!(t.config().tuning, setup.tuning);
        setup.tuning.target.image_noise_px = -0.5;
        let e = setup.build_tracker::<40, 8>().unwrap_err();
        assert_eq!(e.code(), 4);
        assert_eq!(std::format!("{e}"), "tracker: tracker.target.image_noise_px: must be finite and positive");
    }

    #[test]
    fn bad_setups_are_refused_with_codes() {
        let mut s = sample_setup();
        s.fx = 0.0;
        assert_eq!(s.tracker_config().unwrap_err().code(), 1);
        let mut s = sample_setup();
        s.search_max[2] = s.search_min[2];
        assert_eq!(s.tracker_config().unwrap_err().code(), 2);
        let mut s = sample_setup();
        s.flange_to_camera_q = [1.0, 0.1, 0.0, 0.0];
        assert_eq!(s.tracker_config().unwrap_err(), SetupError::NotUnitQuaternion);
        let mut s = sample_setup();
        s.tuning.hue_tolerance = 90;
        let r: Result<Tracker, _> = s.build_tracker();
        assert_eq!(r.unwrap_err().code(), 4);
        for bad in [0, evorec_core::limits::POPULATION_CAPACITY + 1] {
            let mut s = sample_setup();
            s.tuning.ga.population = bad;
            let r: Result<Tracker, _> = s.build_tracker();
            let rule = "must be at least 2 and at most the compiled capacity";
            assert_eq!(r.unwrap_err(), SetupError::Tracker(ConfigError { field: "ga.population", rule }));
        }
        let mut s = sample_setup();
        s.initial_psi = Psi::new([0.0; 3], [1.0, 1.0, 0.0]);
        let r: Result<Tracker, _> = s.build_tracker();
        assert_eq!(r.unwrap_err().code(), 5);
    }

    #[test]
    fn non_parallel_rig_is_refused() {
        let cam = Pinhole::new_checked(200.0, 200.0, 80.0, 60.0, 160, 120).unwrap();
        let mut rig = StereoRig::parallel(cam, 0.1).unwrap();
        rig.left_from_right.translation.y = 0.01;
        let space = SearchSpace::new_checked([-0.2; 3], [0.2, 0.2, 1.0]).unwrap();
        let config = TrackerConfig::pa10(rig, Block::PAPER, Isometry3::identity(), space);
        assert_eq!(Setup::from_tracker_config(&config, &Psi::IDENTITY, &[0.0; 6]), Err(SetupError::UnsupportedRig));
    }
}
