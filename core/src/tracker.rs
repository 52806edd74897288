//! The tracker: GA state, configuration, and one generation per frame pair.
//!
//! [`Tracker::step`] validates its input first and only then touches its state, so an
//! invalid frame, joint sample or time step returns a [`StepError`] and leaves the population,
//! the random generator and the generation counter exactly as they were.

use nalgebra::Isometry3;
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro128PlusPlus;

use crate::acquire::{self, AcquireConfig, AcquireError, HueBlobs};
use crate::camera::{Pinhole, StereoRig};
use crate::config::{DEFAULT_GRID, DEFAULT_HUE_TOLERANCE, DEFAULT_POPULATION, HUE_UNITS, PA10_DOF};
use crate::feedforward;
use crate::fitness::{Evaluator, Fitness};
use crate::ga::{Best, Ga, GaError, GaParams, SearchSpace};
use crate::hue::{HueImage, HueLut};
use crate::kinematics::{Chain, PA10};
use crate::model::{Block, FACES, ModelError, SurfaceStrips};
use crate::pose::{PoseError, Psi};
use crate::status::{Status, StatusConfig, StatusError, StatusMonitor};

/// Whether the arm's motion is fed forward to the population (eq. 36).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feedforward {
    /// Plain 1-step GA.
    Off,
    /// 1-step GA + motion feedforward.
    On,
}

/// Joint positions (rad) and velocities (rad/s) sampled at `time_us`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointSample<const DOF: usize> {
    /// Joint positions.
    pub q: [f32; DOF],
    /// Joint velocities.
    pub qd: [f32; DOF],
    /// Sample time (µs, the board's clock).
    pub time_us: u64,
}

/// A synchronised stereo pair of hue images.
#[derive(Debug, Clone, Copy)]
pub struct StereoFrame<'a> {
    /// Left image.
    pub left: HueImage<&'a [u8]>,
    /// Right image.
    pub right: HueImage<&'a [u8]>,
}

/// The tracker's output for one frame pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Best pose `^CR ψ_M` of this generation.
    pub psi: Psi,
    /// Its fitness `F` (0..=1).
    pub fitness: f32,
    /// Generation number (1 after the first frame).
    pub generation: u32,
    /// Whether the tracker has the block (decided after this generation's evaluation).
    pub status: Status,
}

/// Why a tracker configuration was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ConfigError {
    /// The block model.
    Model(ModelError),
    /// GA parameters or search space.
    Ga(GaError),
    /// Hue tolerance of half a turn or more.
    HueTolerance,
    /// `max_dt_s` not finite and positive.
    MaxDt,
    /// The flange-to-camera transform is not finite.
    NonFiniteTransform,
    /// Acquisition settings.
    Acquire(AcquireError),
    /// Status thresholds.
    Status(StatusError),
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Model(e) => write!(f, "block model: {e}"),
            Self::Ga(e) => write!(f, "GA: {e}"),
            Self::HueTolerance => f.write_str("hue tolerance must be below 90 units"),
            Self::MaxDt => f.write_str("max_dt_s must be finite and positive"),
            Self::NonFiniteTransform => f.write_str("flange-to-camera transform is not finite"),
            Self::Acquire(e) => write!(f, "acquisition: {e}"),
            Self::Status(e) => write!(f, "status: {e}"),
        }
    }
}

impl core::error::Error for ConfigError {}

impl From<ModelError> for ConfigError {
    fn from(e: ModelError) -> Self {
        Self::Model(e)
    }
}

impl From<GaError> for ConfigError {
    fn from(e: GaError) -> Self {
        Self::Ga(e)
    }
}

/// Which camera an image error is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// Left camera.
    Left,
    /// Right camera.
    Right,
}

/// Why a step was refused (the tracker's state is unchanged).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum StepError {
    /// An image's size differs from its camera's.
    ImageSize {
        /// Which image.
        side: Side,
        /// Its width × height.
        got: (u16, u16),
        /// The camera's.
        expected: (u16, u16),
    },
    /// A joint position or velocity is NaN or infinite.
    NonFiniteJoint,
    /// `dt` is negative, NaN, or above the configured maximum.
    BadDt(f32),
    /// A pose given to a reset is invalid.
    Pose(PoseError),
}

impl core::fmt::Display for StepError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::ImageSize { side, got, expected } => {
                write!(f, "{side:?} image is {}x{}, camera is {}x{}", got.0, got.1, expected.0, expected.1)
            }
            Self::NonFiniteJoint => f.write_str("joint sample is not finite"),
            Self::BadDt(dt) => write!(f, "time step {dt} s is out of range"),
            Self::Pose(e) => write!(f, "pose: {e}"),
        }
    }
}

impl core::error::Error for StepError {}

/// The phases of one generation, reported to a [`PhaseProbe`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Input validated; feedforward shift starts.
    Feedforward,
    /// Projection + fitness of every individual starts.
    Evaluate,
    /// Selection, crossover, mutation start.
    Breed,
    /// The generation is complete.
    Done,
}

/// Observer of the phases of a generation (for timing on a board; no-op by default).
pub trait PhaseProbe {
    /// Called when `phase` begins.
    fn mark(&mut self, phase: Phase);
}

/// A probe that does nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProbe;

impl PhaseProbe for NoProbe {
    #[inline(always)]
    fn mark(&mut self, _phase: Phase) {}
}

/// Everything a tracker is built from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackerConfig<const DOF: usize> {
    /// The stereo rig (poses are estimated in its right camera frame `Σ_CR`).
    pub rig: StereoRig,
    /// The target block.
    pub block: Block,
    /// The arm carrying the cameras.
    pub arm: Chain<DOF>,
    /// `^H T_CR`: the right camera's pose on the flange.
    pub flange_to_camera: Isometry3<f32>,
    /// Searched positions.
    pub search: SearchSpace,
    /// GA settings.
    pub ga: GaParams,
    /// Hue match half-band in hue units (2° each).
    pub hue_tolerance: u8,
    /// Seed of the GA's random generator.
    pub seed: u64,
    /// Largest accepted time step between frames (s); larger steps are refused.
    pub max_dt_s: f32,
    /// Acquisition from the colour blobs ([`crate::acquire`]).
    pub acquire: AcquireConfig,
    /// Status thresholds ([`crate::status`]).
    pub status: StatusConfig,
}

impl TrackerConfig<PA10_DOF> {
    /// A PA-10 configuration with default GA settings, hue tolerance, acquisition and status
    /// thresholds, seed 0 and `max_dt_s = 0.5`.
    pub fn pa10(rig: StereoRig, block: Block, flange_to_camera: Isometry3<f32>, search: SearchSpace) -> Self {
        Self {
            rig,
            block,
            arm: PA10,
            flange_to_camera,
            search,
            ga: GaParams::DEFAULT,
            hue_tolerance: DEFAULT_HUE_TOLERANCE,
            seed: 0,
            max_dt_s: 0.5,
            acquire: AcquireConfig::DEFAULT,
            status: StatusConfig::DEFAULT,
        }
    }
}

impl<const DOF: usize> TrackerConfig<DOF> {
    /// Builder: seed.
    #[must_use]
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Builder: GA parameters.
    #[must_use]
    pub fn with_ga(mut self, ga: GaParams) -> Self {
        self.ga = ga;
        self
    }
}

/// The pose tracker: `DOF` arm joints, population `P`, `G × G` samples per face.
#[derive(Debug, Clone)]
pub struct Tracker<const DOF: usize = PA10_DOF, const P: usize = DEFAULT_POPULATION, const G: usize = DEFAULT_GRID> {
    config: TrackerConfig<DOF>,
    model: SurfaceStrips<G>,
    lut: HueLut,
    ga: Ga<P>,
    rng: Xoshiro128PlusPlus,
    generation: u32,
    monitor: StatusMonitor,
}

impl<const DOF: usize, const P: usize, const G: usize> Tracker<DOF, P, G> {
    /// A tracker whose population is spread uniformly over the search space.
    ///
    /// # Errors
    /// [`ConfigError`] for an invalid block, GA parameters, tolerance or `max_dt_s`.
    pub fn new(config: TrackerConfig<DOF>) -> Result<Self, ConfigError> {
        let model = SurfaceStrips::<G>::new(&config.block)?;
        config.ga.validate(P)?;
        if config.hue_tolerance >= HUE_UNITS / 2 {
            return Err(ConfigError::HueTolerance);
        }
        if !config.max_dt_s.is_finite() || config.max_dt_s <= 0.0 {
            return Err(ConfigError::MaxDt);
        }
        config.acquire.validate(P).map_err(ConfigError::Acquire)?;
        config.status.validate().map_err(ConfigError::Status)?;
        let ft = &config.flange_to_camera;
        if !ft.translation.vector.iter().chain(ft.rotation.coords.iter()).all(|v| v.is_finite()) {
            return Err(ConfigError::NonFiniteTransform);
        }
        let hues: [u8; FACES] = model.faces().map(|f| f.hue);
        let lut = HueLut::new(&hues, config.hue_tolerance);
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(config.seed);
        let mut ga = Ga::new(Psi::IDENTITY);
        ga.reset_uniform(&config.search, &mut rng);
        Ok(Self { config, model, lut, ga, rng, generation: 0, monitor: StatusMonitor::new(Status::Searching) })
    }

    /// The configuration.
    pub fn config(&self) -> &TrackerConfig<DOF> {
        &self.config
    }

    /// The surface-strips model.
    pub fn model(&self) -> &SurfaceStrips<G> {
        &self.model
    }

    /// The population (index 0 holds the elite after a step).
    pub fn population(&self) -> &[Psi; P] {
        self.ga.individuals()
    }

    /// Generations run so far.
    pub fn generation(&self) -> u32 {
        self.generation
    }

    /// The status after the last generation ([`Status::Searching`] after [`Tracker::new`]).
    pub fn status(&self) -> Status {
        self.monitor.status()
    }

    /// Puts the tracker in `status` with cleared status counters, leaving the population as it
    /// is. Meant for tests and for measuring the worst-case work of each status on a board
    /// (`evorec timing`); the tracker decides its status itself otherwise.
    pub fn set_status(&mut self, status: Status) {
        self.monitor = StatusMonitor::new(status);
    }

    /// Re-seeds the population around a known pose (the paper starts with the true pose
    /// known): the elite at `psi`, the others within `±spread` per gene. The status becomes
    /// [`Status::Tracking`]: the pose is known.
    ///
    /// # Errors
    /// [`StepError::Pose`] if `psi` is invalid or `spread` not finite (state unchanged).
    pub fn reset_around(&mut self, psi: &Psi, spread: &[f32; 6]) -> Result<(), StepError> {
        psi.validate().map_err(StepError::Pose)?;
        if !spread.iter().all(|s| s.is_finite()) {
            return Err(StepError::Pose(PoseError::NonFinite));
        }
        self.ga.reset_around(psi, spread, &self.config.search, &mut self.rng);
        self.monitor = StatusMonitor::new(Status::Tracking);
        Ok(())
    }

    /// Re-seeds the population uniformly over the search space; the status becomes
    /// [`Status::Searching`].
    pub fn reset_uniform(&mut self) {
        self.ga.reset_uniform(&self.config.search, &mut self.rng);
        self.monitor = StatusMonitor::new(Status::Searching);
    }

    /// The colour blobs of a frame pair as the acquisition scan sees them (left, right).
    ///
    /// # Errors
    /// [`StepError::ImageSize`].
    pub fn blobs_of(&self, frame: &StereoFrame<'_>) -> Result<(HueBlobs, HueBlobs), StepError> {
        self.check_frame(frame)?;
        let stride = self.config.acquire.scan_stride;
        Ok((acquire::scan(&frame.left, &self.lut, stride), acquire::scan(&frame.right, &self.lut, stride)))
    }

    /// `F(ψ)` of any pose on a frame pair (diagnostics; no state change).
    ///
    /// # Errors
    /// [`StepError::ImageSize`] or [`StepError::Pose`].
    pub fn fitness_of(&self, psi: &Psi, frame: &StereoFrame<'_>) -> Result<Fitness, StepError> {
        self.check_frame(frame)?;
        psi.validate().map_err(StepError::Pose)?;
        let eval = Evaluator::new(&self.model, &self.lut, &self.config.rig);
        Ok(eval.evaluate_psi(psi, &frame.left, &frame.right))
    }

    fn check_frame(&self, frame: &StereoFrame<'_>) -> Result<(), StepError> {
        let check = |side: Side, img: &HueImage<&[u8]>, cam: &Pinhole| {
            let (got, expected) = ((img.width(), img.height()), (cam.width(), cam.height()));
            if got == expected { Ok(()) } else { Err(StepError::ImageSize { side, got, expected }) }
        };
        check(Side::Left, &frame.left, &self.config.rig.left)?;
        check(Side::Right, &frame.right, &self.config.rig.right)
    }

    /// One generation on the newest frame pair (see [`Tracker::step_probed`]).
    ///
    /// # Errors
    /// As [`Tracker::step_probed`].
    pub fn step(
        &mut self,
        frame: &StereoFrame<'_>,
        joints: &JointSample<DOF>,
        dt_s: f32,
        feedforward: Feedforward,
    ) -> Result<Estimate, StepError> {
        self.step_probed(frame, joints, dt_s, feedforward, &mut NoProbe)
    }

    /// One generation: with [`Feedforward::On`] every individual is first moved by
    /// `J_m(q) q̇ · dt` (eq. 36), then the population is evaluated on `frame`, the best is the
    /// estimate, its fitness updates the [`Status`], and the next population is bred. While
    /// the status is not [`Status::Tracking`], the last
    /// [`AcquireConfig::seed_immigrants`] children are replaced by poses seeded from the
    /// colour blobs of the frame ([`crate::acquire`]; the scan runs in every status, inside
    /// the evaluation phase, so the work per generation is bounded the same way in all of
    /// them). `dt_s` is the time since the previous frame (0 for the first). `probe` is told
    /// when each [`Phase`] begins.
    ///
    /// # Errors
    /// [`StepError::ImageSize`], [`StepError::NonFiniteJoint`] or [`StepError::BadDt`]; the
    /// tracker is then unchanged.
    pub fn step_probed(
        &mut self,
        frame: &StereoFrame<'_>,
        joints: &JointSample<DOF>,
        dt_s: f32,
        feedforward: Feedforward,
        probe: &mut impl PhaseProbe,
    ) -> Result<Estimate, StepError> {
        self.check_frame(frame)?;
        if !joints.q.iter().chain(joints.qd.iter()).all(|v| v.is_finite()) {
            return Err(StepError::NonFiniteJoint);
        }
        if !(dt_s >= 0.0 && dt_s <= self.config.max_dt_s) {
            return Err(StepError::BadDt(dt_s));
        }

        probe.mark(Phase::Feedforward);
        if feedforward == Feedforward::On {
            let twist =
                feedforward::camera_twist(&self.config.arm, &joints.q, &joints.qd, &self.config.flange_to_camera);
            self.ga.shift_all(&self.config.search, |psi| {
                let rate = feedforward::psi_rate(&twist, psi);
                feedforward::shift(psi, &rate, dt_s);
            });
        }

        probe.mark(Phase::Evaluate);
        let stride = self.config.acquire.scan_stride;
        let (left, right) =
            (acquire::scan(&frame.left, &self.lut, stride), acquire::scan(&frame.right, &self.lut, stride));
        let eval = Evaluator::new(&self.model, &self.lut, &self.config.rig);
        let best: Best = self.ga.evaluate(|psi| eval.evaluate_psi(psi, &frame.left, &frame.right).total);
        let status = self.monitor.update(best.fitness, &self.config.status);

        probe.mark(Phase::Breed);
        self.ga.breed(&best, &self.config.ga, &self.config.search, &mut self.rng);
        if status != Status::Tracking {
            self.seed_from_blobs(&left, &right);
        }
        self.generation = self.generation.wrapping_add(1);
        probe.mark(Phase::Done);

        Ok(Estimate { psi: best.psi, fitness: best.fitness, generation: self.generation, status })
    }

    /// Replaces the last [`AcquireConfig::seed_immigrants`] individuals (never the elite) by
    /// poses seeded from the blobs; does nothing when the blobs give no pose.
    fn seed_from_blobs(&mut self, left: &HueBlobs, right: &HueBlobs) {
        let cfg = &self.config.acquire;
        let half = self.model.half_size();
        let half = [half.x, half.y, half.z];
        let Some(seed) = acquire::best_seed(&self.config.rig, &half, left, right, cfg.scan_stride, cfg.min_face_hits)
        else {
            return;
        };
        let n = cfg.seed_immigrants.min(P - 1);
        for k in 0..n {
            if let Some(psi) = acquire::seed_immigrant(&seed, k, cfg, &mut self.rng) {
                self.ga.set_individual(P - n + k, psi, &self.config.search);
            }
        }
    }
}
