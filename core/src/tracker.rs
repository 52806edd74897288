//! The tracker: GA state, configuration, and the generations run on each frame pair
//! (`generations_per_frame`, default 2).
//!
//! [`Tracker::step`] validates its input first and only then touches its state, so an
//! invalid frame, joint sample or time step returns a [`StepError`] and leaves the population,
//! the random generator and the generation counter exactly as they were.

use nalgebra::{Isometry3, Vector3};
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro128PlusPlus;

use crate::acquire::{self, Acquisition, HueBlobs};
use crate::camera::{Pinhole, StereoRig};
use crate::colour::{ColourModel, Colours, LEARN_CAMERA_RATIO, Tally};
use crate::edge::{self, EdgeShift};
use crate::feedforward;
use crate::fitness::{Evaluator, Fitness};
use crate::ga::{Best, Ga, GaParams, SearchSpace};
use crate::image::{Hue, Image, PixelFormat};
pub use crate::kinematics::JointSample;
use crate::kinematics::{Chain, PA10};
use crate::limits::{
    CONFIRM_FULL_FACES, DEFAULT_GRID, EDGE_PROBE_IDLE, MIN_DEPTH_M, PA10_DOF, POPULATION_CAPACITY, TRACKING_IDLE,
};
use crate::model::{Block, FACES, ModelError, SurfaceStrips};
use crate::pose::{PoseError, Psi};
use crate::quat;
use crate::status::{DOUBT_FRAMES, Status, StatusMonitor};
use crate::target_motion::{Optics, PredictError, Prediction, TargetFilter, TargetVelocity};
use crate::tuning::{POPULATION_ERROR, Tuning};

/// The estimate is the mean pose of the individuals whose fitness is within this of the best's
/// ([`Ga::crowd`](crate::ga::Ga::crowd)), and the target filter is fed their mean
/// position and orientation: the best jumps between the individuals at the top of a
/// flat fitness peak from frame to frame, and on a peak that moves it trails (ties go to the
/// elite, which is not moved by the block's own motion); the centre of those individuals does
/// both much less. Fed the best's orientation, the filter would read those jumps as turns and
/// feed them forward to the population. 0.01 is one sample point in a hundred.
pub const MEASUREMENT_FITNESS_MARGIN: f32 = 0.01;

/// Depth probes per generation in [`Feedforward::OnWithTarget`] while tracking: the last
/// children bred before the immigrants are replaced by the best pose moved along its viewing
/// ray, two per entry of [`DEPTH_PROBE_DISPARITY_PX`] (one nearer, one farther).
pub const DEPTH_PROBES: usize = 2 * DEPTH_PROBE_DISPARITY_PX.len();

/// The disparity changes (px) at which the depth probes sit on either side of the best pose:
/// from a quarter of a pixel, below which the fitness's whole-pixel samples cannot tell two
/// depths apart, to two pixels, beyond which the coarse mutation takes over.
pub const DEPTH_PROBE_DISPARITY_PX: [f32; 4] = [0.25, 0.5, 1.0, 2.0];

/// Turn probes per generation in [`Feedforward::OnWithTarget`] while the block is held but
/// `uncertain`: the children bred before the depth probes are replaced by the best pose
/// tilted, about its visible surface ([`Psi::turned_about_surface`]), so that each of the two
/// faces nearest edge-on turns towards and away from the camera, by `k` times the coarse
/// mutation's largest turn, `k` in [`TURN_PROBE_MULTIPLES`].
pub const TURN_PROBES: usize = 4 * TURN_PROBE_MULTIPLES.len();

/// The turn probes' sizes in coarse mutation turns (the largest of
/// `ga.mutation_scale.coarse.turn_*`, a quaternion vector part): beyond the largest turn one
/// coarse mutation makes. A face seen edge-on by the estimate but at a grazing angle in the
/// image (or the reverse) enters the fitness only after a tilt of several degrees, which no
/// smaller turn rewards.
pub const TURN_PROBE_MULTIPLES: [f32; 2] = [2.0, 4.0];

pub use crate::tuning::Feedforward;

/// A synchronised stereo pair of images in pixel format `F` (hue bytes by default).
#[derive(Debug, Clone, Copy)]
pub struct StereoFrame<'a, F: PixelFormat = Hue> {
    /// Left image.
    pub left: Image<&'a [u8], F>,
    /// Right image.
    pub right: Image<&'a [u8], F>,
}

/// The tracker's output for one frame pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The pose `^CR ψ_M` of this frame: while the block is held ([`Status::holds`]), the mean pose of the
    /// individuals within [`MEASUREMENT_FITNESS_MARGIN`] of the best fitness of its last
    /// generation and within one coarse mutation step of the best
    /// ([`Ga::crowd`](crate::ga::Ga::crowd)); otherwise the best individual's.
    pub psi: Psi,
    /// The best individual's fitness `F` (0..=1).
    pub fitness: f32,
    /// The best individual's fitness in the left and in the right camera, `[F_L, F_R]`
    /// (`fitness` is their mean): a pair whose images do not show the same instant fits one
    /// camera and not the other ([`crate::status`]).
    pub camera_fitness: [f32; 2],
    /// Generation number (1 after the first frame).
    pub generation: u32,
    /// Whether the tracker has the block (decided after this generation's evaluation).
    pub status: Status,
    /// Capture time of the frame pair (µs, the board's clock): the time of the joint sample
    /// the estimate was computed with, which the board takes with the frame.
    pub capture_time_us: u64,
    /// The pose the target filter was fed with this estimate
    /// ([`Feedforward::OnWithTarget`]): the mean position of the individuals within
    /// [`MEASUREMENT_FITNESS_MARGIN`] of the best fitness, with the mean orientation of those
    /// of them within one coarse mutation step of the best (the estimate's); the best
    /// individual's pose in the other modes. A
    /// consumer running its own copy of the filter
    /// ([`TargetFilter::update_from_estimate`](crate::target_motion::TargetFilter::update_from_estimate))
    /// feeds it this to get the tracker's numbers.
    pub target_measurement: Psi,
}

pub use crate::tuning::ConfigError;

/// What one generation of [`Tracker::step_probed`] gives (see `generation_on`).
struct Outcome {
    best: Best,
    /// The best individual's fitness per camera, `[F_L, F_R]`.
    cameras: [f32; 2],
    estimate: Psi,
    target_measurement: Psi,
}

impl From<ModelError> for ConfigError {
    fn from(e: ModelError) -> Self {
        let rule = match e {
            ModelError::NonFinite => "sizes and hues must be finite",
            ModelError::TooSmall => "every edge must be longer than twice the deepest inner inset plus 2 mm",
        };
        ConfigError { field: "block", rule }
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
    /// Seed of the GA's random generator.
    pub seed: u64,
    /// Every tuning parameter ([`Tuning`], one field table: [`crate::tuning::FIELDS`]).
    pub tuning: Tuning,
}

impl TrackerConfig<PA10_DOF> {
    /// A PA-10 configuration with seed 0 and the default tuning ([`Tuning::DEFAULT`]).
    pub fn pa10(rig: StereoRig, block: Block, flange_to_camera: Isometry3<f32>, search: SearchSpace) -> Self {
        Self { rig, block, arm: PA10, flange_to_camera, search, seed: 0, tuning: Tuning::DEFAULT }
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
        self.tuning.ga = ga;
        self
    }

    /// Builder: the whole tuning.
    #[must_use]
    pub fn with_tuning(mut self, tuning: Tuning) -> Self {
        self.tuning = tuning;
        self
    }

    /// Builder: the feedforward mode (the table's `method`).
    #[must_use]
    pub fn with_feedforward(mut self, feedforward: Feedforward) -> Self {
        self.tuning.feedforward = feedforward;
        self
    }

    /// Checks everything [`Tracker::new`] can refuse for a population capacity `capacity`:
    /// the block, the flange-to-camera transform, and the tuning ([`Tuning::validate`]).
    ///
    /// # Errors
    /// The first [`ConfigError`], naming its field.
    pub fn validate(&self, capacity: usize) -> Result<(), ConfigError> {
        // The block's check does not depend on the points per row.
        SurfaceStrips::<DEFAULT_GRID>::check(&self.block)?;
        let ft = &self.flange_to_camera;
        if !ft.translation.vector.iter().chain(ft.rotation.coords.iter()).all(|v| v.is_finite()) {
            return Err(ConfigError { field: "flange_to_camera", rule: "must be finite" });
        }
        self.tuning.validate(capacity)
    }
}

/// The pose tracker: `DOF` arm joints, population capacity `P` (the population in use is
/// [`GaParams::population`] of the configuration, up to `P`), `G × G` samples per face.
#[derive(Debug, Clone)]
pub struct Tracker<const DOF: usize = PA10_DOF, const P: usize = POPULATION_CAPACITY, const G: usize = DEFAULT_GRID> {
    config: TrackerConfig<DOF>,
    model: SurfaceStrips<G>,
    colours: Colours,
    ga: Ga<P>,
    rng: Xoshiro128PlusPlus,
    generation: u32,
    monitor: StatusMonitor,
    acquisition: Acquisition,
    target: TargetFilter,
    edge: EdgeShift,
}

impl<const DOF: usize, const P: usize, const G: usize> Tracker<DOF, P, G> {
    /// A tracker whose population is spread uniformly over the search space.
    ///
    /// # Errors
    /// [`ConfigError`] for an invalid block, GA parameters, tolerance or `max_dt_s`.
    pub fn new(config: TrackerConfig<DOF>) -> Result<Self, ConfigError> {
        let (model, colours) = Self::checked_parts(&config)?;
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(config.seed);
        let mut ga = Ga::new(Psi::IDENTITY);
        ga.set_population(&config.tuning.ga).map_err(|_| POPULATION_ERROR)?;
        ga.reset_uniform(&config.search, &mut rng);
        Ok(Self {
            config,
            model,
            colours,
            ga,
            rng,
            generation: 0,
            monitor: StatusMonitor::new(Status::Searching),
            acquisition: Acquisition::new(),
            target: TargetFilter::tuned(config.tuning.target, Optics::of(&config.rig, &config.block)),
            edge: EdgeShift::NONE,
        })
    }

    /// [`Tracker::new`] built in `slot` (e.g. a board's static), so that no whole tracker, and
    /// none of its large parts (the hue table, the population), is assembled on the stack and
    /// copied: the configuration is validated first, an empty slot gets a blank tracker written
    /// into it, and then every part is (re)built where it lives — the hue table through
    /// [`Colours::configure`], the population through [`Ga::reset_uniform`]. On error the slot is
    /// unchanged.
    ///
    /// # Errors
    /// As [`Tracker::new`].
    #[inline(never)]
    pub fn new_in(slot: &mut Option<Self>, config: TrackerConfig<DOF>) -> Result<&mut Self, ConfigError> {
        Self::check_config(&config)?;
        let t = match slot {
            Some(t) => t,
            None => Self::blank_in(slot, &config),
        };
        // Cannot fail: `check_config` checked the block (and `rebuild` checks before writing).
        t.model.rebuild(&config.block)?;
        t.config = config;
        let hues: [u8; FACES] = t.model.faces().map(|f| f.hue);
        t.colours.configure(hues, t.config.tuning.hue_tolerance);
        t.rng = Xoshiro128PlusPlus::seed_from_u64(t.config.seed);
        t.generation = 0;
        t.monitor = StatusMonitor::new(Status::Searching);
        t.acquisition = Acquisition::new();
        t.target = TargetFilter::tuned(t.config.tuning.target, Optics::of(&t.config.rig, &t.config.block));
        t.edge = EdgeShift::NONE;
        // Checked by `check_config` (2 ≤ population ≤ P), so this cannot fail.
        t.ga.set_population(&t.config.tuning.ga).map_err(|_| POPULATION_ERROR)?;
        t.ga.reset_uniform(&t.config.search, &mut t.rng);
        Ok(t)
    }

    /// Puts a blank tracker (empty model and hue table, identity population) into the empty
    /// `slot`; [`Tracker::new_in`] then builds its parts in place. Out of line, so that only
    /// this frame holds the blank's small parts.
    #[inline(never)]
    fn blank_in<'s>(slot: &'s mut Option<Self>, config: &TrackerConfig<DOF>) -> &'s mut Self {
        slot.insert(Self {
            config: *config,
            model: SurfaceStrips::EMPTY,
            colours: Colours::EMPTY,
            ga: Ga::new(Psi::IDENTITY),
            rng: Xoshiro128PlusPlus::seed_from_u64(config.seed),
            generation: 0,
            monitor: StatusMonitor::new(Status::Searching),
            acquisition: Acquisition::new(),
            target: TargetFilter::with_defaults(),
            edge: EdgeShift::NONE,
        })
    }

    /// Validates `config` and builds its model and hue table.
    fn checked_parts(config: &TrackerConfig<DOF>) -> Result<(SurfaceStrips<G>, Colours), ConfigError> {
        Self::check_config(config)?;
        let model = SurfaceStrips::<G>::new(&config.block)?;
        let hues: [u8; FACES] = model.faces().map(|f| f.hue);
        Ok((model, Colours::new(hues, config.tuning.hue_tolerance)))
    }

    /// Validates `config` (everything [`Tracker::new`] can refuse).
    fn check_config(config: &TrackerConfig<DOF>) -> Result<(), ConfigError> {
        config.validate(P)
    }

    /// The configuration.
    pub fn config(&self) -> &TrackerConfig<DOF> {
        &self.config
    }

    /// The surface-strips model.
    pub fn model(&self) -> &SurfaceStrips<G> {
        &self.model
    }

    /// The population in use (index 0 holds the elite after a step).
    pub fn population(&self) -> &[Psi] {
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

    /// Puts the tracker in `status` with cleared status counters ([`StatusMonitor::forced`]: a
    /// forced `Uncertain` counts as unconfirmed long enough for the turn probes), leaving the
    /// population as it is. Meant for tests and for measuring the worst-case work of each
    /// status on a board (`evorec timing`); the tracker decides its status itself otherwise.
    pub fn set_status(&mut self, status: Status) {
        self.monitor = StatusMonitor::forced(status);
    }

    /// The learnt shift of the nearest silhouette rows, pixel widths outwards ([`crate::edge`]).
    pub fn edge_shift_px(&self) -> f32 {
        self.edge.px()
    }

    /// The evaluator of the current hue table and silhouette shift.
    fn evaluator(&self) -> Evaluator<'_, G> {
        Evaluator::new(&self.model, self.colours.lut(), &self.config.rig).with_edge_shift(self.edge.px())
    }

    /// The filter of the target's own motion, updated with every estimate.
    pub fn target_filter(&self) -> &TargetFilter {
        &self.target
    }

    /// Hands the latest estimate over to time `t_us` (e.g. when a controller acts on it):
    /// see [`TargetFilter::predict`]. `joints` is the newest joint sample.
    ///
    /// # Errors
    /// [`PredictError::NoTrack`] before the first estimate or after the target was lost;
    /// [`PredictError::NonFiniteJoint`].
    pub fn predict(&self, joints: &JointSample<DOF>, t_us: u64) -> Result<Prediction, PredictError> {
        self.target.predict(&self.config.arm, &self.config.flange_to_camera, joints, t_us)
    }

    /// The target velocity (world frame) by which a [`Tracker::step`] with
    /// [`Feedforward::OnWithTarget`] would shift every individual, next to the camera's motion:
    /// the target filter's [`TargetFilter::feedforward_velocity`]. [`TargetVelocity::ZERO`]
    /// means such a step shifts by the camera's motion alone (as [`Feedforward::On`] does).
    pub fn target_feedforward_velocity(&self) -> TargetVelocity {
        self.target.feedforward_velocity()
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
        self.acquisition.reset();
        self.target.reset();
        Ok(())
    }

    /// Re-seeds the population uniformly over the search space; the status becomes
    /// [`Status::Searching`].
    pub fn reset_uniform(&mut self) {
        self.ga.reset_uniform(&self.config.search, &mut self.rng);
        self.monitor = StatusMonitor::new(Status::Searching);
        self.acquisition.reset();
        self.target.reset();
    }

    /// The colour blobs of a frame pair as the acquisition scan sees them (left, right),
    /// through the current hue table (the search table unless the last frame was tracked).
    ///
    /// # Errors
    /// [`StepError::ImageSize`].
    pub fn blobs_of<F: PixelFormat>(&self, frame: &StereoFrame<'_, F>) -> Result<(HueBlobs, HueBlobs), StepError> {
        self.check_frame(frame)?;
        let stride = self.config.tuning.acquire.scan_stride;
        let lut = self.colours.lut();
        Ok((acquire::scan(&frame.left, lut, stride), acquire::scan(&frame.right, lut, stride)))
    }

    /// `F(ψ)` of any pose on a frame pair through the current hue table (diagnostics; no state
    /// change).
    ///
    /// # Errors
    /// [`StepError::ImageSize`] or [`StepError::Pose`].
    pub fn fitness_of<F: PixelFormat>(&self, psi: &Psi, frame: &StereoFrame<'_, F>) -> Result<Fitness, StepError> {
        self.check_frame(frame)?;
        psi.validate().map_err(StepError::Pose)?;
        Ok(self.evaluator().evaluate_psi(psi, &frame.left, &frame.right))
    }

    fn check_frame<F: PixelFormat>(&self, frame: &StereoFrame<'_, F>) -> Result<(), StepError> {
        let check = |side: Side, img: &Image<&[u8], F>, cam: &Pinhole| {
            let (got, expected) = ((img.width(), img.height()), (cam.width(), cam.height()));
            if got == expected { Ok(()) } else { Err(StepError::ImageSize { side, got, expected }) }
        };
        check(Side::Left, &frame.left, &self.config.rig.left)?;
        check(Side::Right, &frame.right, &self.config.rig.right)
    }

    /// The frame's generations on the newest frame pair (see [`Tracker::step_probed`]).
    ///
    /// # Errors
    /// As [`Tracker::step_probed`].
    pub fn step<F: PixelFormat>(
        &mut self,
        frame: &StereoFrame<'_, F>,
        joints: &JointSample<DOF>,
        dt_s: f32,
    ) -> Result<Estimate, StepError> {
        self.step_probed(frame, joints, dt_s, &mut NoProbe)
    }

    /// The generations of one frame in the configured feedforward mode
    /// ([`Tuning::feedforward`]): with [`Feedforward::On`] every individual is first moved by
    /// `J_m(q) q̇ · dt` (eq. 36), with [`Feedforward::OnWithTarget`] by
    /// `(J_m q̇ + J_n ^W ψ̇_M) · dt` (eq. 23, 25); then, [`Tuning::generations_per_frame`] times,
    /// the population is evaluated on `frame` and the next one bred. The best of the last
    /// generation updates the [`Status`]; the estimate is, while tracking, the mean pose of the
    /// last generation's individuals within [`MEASUREMENT_FITNESS_MARGIN`] of it (else the
    /// best itself); the filter's measurement
    /// ([`Estimate::target_measurement`]), taken into the world at `joints.q`, updates the
    /// target filter.
    /// While the block is not held ([`Status::holds`]), the last
    /// [`AcquireConfig::seed_immigrants`](crate::acquire::AcquireConfig::seed_immigrants) children are replaced by poses seeded from the
    /// colour blobs of the frame ([`crate::acquire`]). `dt_s` is the time since the previous
    /// frame (0 for the first). `probe` is told when each [`Phase`] begins.
    ///
    /// # Errors
    /// [`StepError::ImageSize`], [`StepError::NonFiniteJoint`] or [`StepError::BadDt`]; the
    /// tracker is then unchanged.
    pub fn step_probed<F: PixelFormat>(
        &mut self,
        frame: &StereoFrame<'_, F>,
        joints: &JointSample<DOF>,
        dt_s: f32,
        probe: &mut impl PhaseProbe,
    ) -> Result<Estimate, StepError> {
        let feedforward = self.config.tuning.feedforward;
        self.check_frame(frame)?;
        if !joints.q.iter().chain(joints.qd.iter()).all(|v| v.is_finite()) {
            return Err(StepError::NonFiniteJoint);
        }
        if !(dt_s >= 0.0 && dt_s <= self.config.tuning.max_dt_s) {
            return Err(StepError::BadDt(dt_s));
        }

        // The work of this generation is decided by the status it starts in, and so is the
        // hue table: the learnt one while the block is held, the search one otherwise.
        let acquiring = !self.monitor.status().holds();
        self.colours.select(!acquiring);
        // Turn probes in this frame's generations ([`Tracker::probe_turns`]): a hold the fitness
        // has left unconfirmed for `DOUBT_FRAMES` frames while the block stands still.
        let turns = feedforward == Feedforward::OnWithTarget
            && !acquiring
            && self.monitor.unsure_frames() >= DOUBT_FRAMES
            && self.moves_less_than_a_fine_step(dt_s);
        // A tracked frame in every few tests where the silhouettes are (`crate::edge`).
        let edge_test = !acquiring && self.edge.is_due();
        probe.mark(Phase::Feedforward);
        match feedforward {
            Feedforward::Off => {}
            Feedforward::On => {
                let twist =
                    feedforward::camera_twist(&self.config.arm, &joints.q, &joints.qd, &self.config.flange_to_camera);
                let shift = |psi: &mut Psi| {
                    let rate = feedforward::psi_rate(&twist, psi);
                    feedforward::shift(psi, &rate, dt_s);
                };
                self.ga.shift_all(&self.config.search, shift);
                if acquiring {
                    self.acquisition.shift(shift);
                }
            }
            Feedforward::OnWithTarget => self.shift_with_target(joints, dt_s, acquiring),
        }

        for _ in 1..self.config.tuning.generations_per_frame {
            self.generation_on(frame, feedforward, acquiring, turns, None, probe);
        }
        let Outcome { best, cameras, estimate, target_measurement } =
            self.generation_on(frame, feedforward, acquiring, turns, Some(edge_test), probe);
        // The status is decided on the fitness relative to what the true pose can score under
        // the current light (`crate::colour`), so that its thresholds mean the same in every light.
        let expected = self.colours.model().expected_fitness();
        let worse = cameras[0].min(cameras[1]);
        // The confirmation's scale leans towards the best the light has let a held pose cover.
        let confirming = self.colours.model().confirming_fitness();
        // A pose is not confirmed while the seed from the colour blobs puts the block elsewhere
        // (see `agrees_with_seed`): the frame then counts as one without a find.
        let confirmable = !acquiring || self.agrees_with_seed(&best.psi);
        let (relative, lower) = if confirmable { (best.fitness / expected, worse / confirming) } else { (0.0, 0.0) };
        // Nor is a pose reported tracking where the view leaves its orientation open (fewer than
        // `CONFIRM_FULL_FACES` faces whole in a camera): it is then held and uncertain.
        let seen = self.evaluator().full_faces(&best.psi.rotation_unchecked(), &best.psi.translation());
        let settles = seen.iter().all(|&n| n >= CONFIRM_FULL_FACES);
        let status = self.monitor.update_view(relative, lower, settles, &self.config.tuning.status);
        let holds = status.holds();
        if holds && acquiring {
            self.acquisition.reset();
        }
        let alike = worse >= LEARN_CAMERA_RATIO * cameras[0].max(cameras[1]);
        if edge_test {
            // The test runs on every due frame (the board's work is the same whether it teaches
            // or not); it teaches as the colours do, from a held pose both cameras see alike.
            let pull = edge::disparity_pull(&self.evaluator(), &best.psi, &frame.left, &frame.right);
            if alike && holds {
                self.edge.learn(pull);
            }
        }
        if !acquiring {
            self.edge.tick();
        }
        if alike && holds {
            self.learn_colours(frame, &best);
        }
        // The target filter (one forward kinematics and a data-dependent update) runs only in the
        // mode that uses it, so the other modes keep the paper's constant work per generation.
        if feedforward == Feedforward::OnWithTarget {
            let (arm, mount) = (&self.config.arm, &self.config.flange_to_camera);
            self.target.update_from_estimate(arm, mount, joints, &target_measurement, status);
        }
        probe.mark(Phase::Done);

        // The centre of the near-best crowd is one peak's only while the block is held: a searching
        // population's near-best individuals may sit on different peaks (the colour symmetry's
        // twins among them), whose mean is neither.
        let psi = if holds { estimate } else { best.psi };
        Ok(Estimate {
            psi,
            fitness: best.fitness,
            camera_fitness: cameras,
            generation: self.generation,
            status,
            capture_time_us: joints.time_us,
            target_measurement,
        })
    }

    /// Whether `psi` lies where the acquisition's latest seed puts the block: its centre within
    /// the block's half diagonal of the seed's. The seed is computed from every coloured pixel
    /// of both images, independently of the GA, so a candidate further away than the block's
    /// own extent is another hypothesis (most often a lock at a wrong depth, which scores
    /// between the status thresholds). Without a seed yet, or with one from blobs cut by an
    /// image border ([`crate::acquire::Seed::cut`]), every candidate agrees.
    fn agrees_with_seed(&self, psi: &Psi) -> bool {
        let Some(seed) = self.acquisition.seed().filter(|s| !s.cut) else { return true };
        let reach = self.model.half_size();
        let d = psi.translation() - seed.centre;
        d.dot(&d) <= reach.dot(&reach)
    }

    /// Learns the face colours from the census of the frame's best pose (see
    /// [`crate::colour`]): called while the block is held, so that a candidate not yet held
    /// teaches the model nothing.
    fn learn_colours<F: PixelFormat>(&mut self, frame: &StereoFrame<'_, F>, best: &Best) {
        let eval = self.evaluator();
        let mut tally = Tally::EMPTY;
        let (r, t) = (best.psi.rotation_unchecked(), best.psi.translation());
        eval.census(&r, &t, &frame.left, &frame.right, &mut |k, row| tally.add(k, row));
        self.colours.learn(&tally);
    }

    /// The colour model of the block's faces, as learnt so far.
    pub fn colours(&self) -> &ColourModel {
        self.colours.model()
    }

    /// The feedforward of [`Feedforward::OnWithTarget`]: every individual is moved by the
    /// camera's motion and the target model's velocity, except three that let the fitness
    /// weigh the model. The elite (index 0) is moved by the camera's motion alone, the
    /// hypothesis that the block stands still. While tracking, children 1 and 2 are copies of
    /// the elite, moved by the model's translation alone and by its whole motion: a paired test
    /// of the turn. The GA trades a small turn for a small shift across the view, and a model
    /// that reads that as a turn would feed it to every child; with the copies the turn is kept
    /// only where it fits better, as ties go to the lower index.
    fn shift_with_target(&mut self, joints: &JointSample<DOF>, dt_s: f32, acquiring: bool) {
        let motion = feedforward::camera_motion(&self.config.arm, &joints.q, &joints.qd, &self.config.flange_to_camera);
        let velocity = self.target.feedforward_velocity();
        let r_cw = motion.r_wc.transpose();
        let whole = feedforward::TargetTwist::from_world(&r_cw, &velocity);
        let sliding = TargetVelocity { w: nalgebra::Vector3::zeros(), ..velocity };
        let sliding = feedforward::TargetTwist::from_world(&r_cw, &sliding);
        let moved = |psi: &mut Psi, target: Option<&feedforward::TargetTwist>| {
            let rate = match target {
                Some(t) => feedforward::psi_rate_moving(&motion.twist, t, psi),
                None => feedforward::psi_rate(&motion.twist, psi),
            };
            feedforward::shift(psi, &rate, dt_s);
        };
        let elite = self.ga.individuals().first().copied().filter(|_| !acquiring);
        let mut index = 0usize;
        self.ga.shift_all(&self.config.search, |psi| {
            match (index, elite) {
                (0, _) => moved(psi, None),
                (1, Some(e)) => {
                    *psi = e;
                    moved(psi, Some(&sliding));
                }
                (2, Some(e)) => {
                    *psi = e;
                    moved(psi, Some(&whole));
                }
                _ => moved(psi, Some(&whole)),
            }
            index += 1;
        });
        if acquiring {
            self.acquisition.shift(|psi| moved(psi, Some(&whole)));
        }
    }

    /// One generation on `frame` (the population already moved by the feedforward): evaluate,
    /// breed (with the depth probes in [`Feedforward::OnWithTarget`] while tracking, the turn
    /// probes too if `turns`, immigrants seeded from the colour blobs while `acquiring`).
    /// Returns the best of the evaluated population and, on the frame's last generation (`last`
    /// is `Some(edge_test)`, whether the frame runs the disparity test), the estimate and, in
    /// [`Feedforward::OnWithTarget`], the target filter's measurement (else the best).
    fn generation_on<F: PixelFormat>(
        &mut self,
        frame: &StereoFrame<'_, F>,
        feedforward: Feedforward,
        acquiring: bool,
        turns: bool,
        last: Option<bool>,
        probe: &mut impl PhaseProbe,
    ) -> Outcome {
        probe.mark(Phase::Evaluate);
        // The individuals left unevaluated pay for the frame's other work: the acquisition's
        // scan, the disparity test, the tracked frames' margin (see `crate::edge`).
        let idle = match (acquiring, last) {
            (true, _) => self.config.tuning.acquire.idle_individuals,
            (false, Some(true)) => EDGE_PROBE_IDLE,
            (false, Some(false)) => TRACKING_IDLE,
            (false, None) => 0,
        };
        let idle = idle.min(self.ga.len().saturating_sub(1));
        let last = last.is_some();
        // Field by field (the population is borrowed mutably beside it).
        let eval = Evaluator::new(&self.model, self.colours.lut(), &self.config.rig).with_edge_shift(self.edge.px());
        // The per-camera scores of the best are kept as the population is evaluated, by
        // `Ga::evaluate_first`'s own rule (the first strictly larger fitness, NaN as 0), so
        // that no pose is evaluated twice.
        let (mut top, mut cameras) = (f32::NEG_INFINITY, [0.0f32; 2]);
        let best: Best = self.ga.evaluate_first(self.ga.len().saturating_sub(idle), |psi| {
            let f = eval.evaluate_psi(psi, &frame.left, &frame.right);
            let v = if f.total.is_nan() { 0.0 } else { f.total };
            if v > top {
                (top, cameras) = (v, [f.left.score(), f.right.score()]);
            }
            f.total
        });
        // The estimate and the filter's measurement are taken from the evaluated population,
        // before breeding.
        let reach = self.config.tuning.ga.mutation_scale.first().copied().unwrap_or([0.0; 6]);
        let (estimate, target_measurement) = if last {
            let crowd = self.ga.crowd(&best, MEASUREMENT_FITNESS_MARGIN, &reach);
            let measured = if feedforward == Feedforward::OnWithTarget {
                Psi::new(crowd.translation, crowd.centre.eps().into())
            } else {
                best.psi
            };
            (crowd.centre, measured)
        } else {
            (best.psi, best.psi)
        };
        probe.mark(Phase::Breed);
        self.ga.breed(&best, &self.config.tuning.ga, &self.config.search, &mut self.rng);
        if feedforward == Feedforward::OnWithTarget && !acquiring {
            self.probe_depth(&best.psi);
            if turns {
                self.probe_turns(&best.psi);
            }
        }
        if acquiring {
            self.acquire_step(frame);
        }
        self.generation = self.generation.wrapping_add(1);
        Outcome { best, cameras, estimate, target_measurement }
    }

    /// Replaces the last [`DEPTH_PROBES`] bred children before the immigrants by the best
    /// pose moved along its viewing ray by `±k·Z²/(f·b)`, `k` in [`DEPTH_PROBE_DISPARITY_PX`]:
    /// the depths at which the disparity differs from the best's by those fractions of a
    /// pixel. Depth is the axis the fitness resolves least and that a random mutation, which
    /// moves several genes at once, corrects slowest; the probes give the next generation a
    /// line search along it, symmetric about the best, whatever the block's own motion.
    fn probe_depth(&mut self, best: &Psi) {
        let optics = self.target.optics();
        let z = best.0[2];
        if z.is_nan() || z <= MIN_DEPTH_M {
            return;
        }
        let unit = z * z / (optics.focal_px * optics.baseline_m);
        let end = self.ga.first_immigrant(&self.config.tuning.ga);
        let Some(first) = end.checked_sub(DEPTH_PROBES).filter(|&f| f >= 1) else { return };
        for (j, k) in DEPTH_PROBE_DISPARITY_PX.iter().enumerate() {
            for (s, sign) in [1.0f32, -1.0].iter().enumerate() {
                let probe = best.scaled_along_ray(1.0 + sign * k * unit / z);
                self.ga.set_individual(first + 2 * j + s, probe, &self.config.search);
            }
        }
    }

    /// Whether the target model has the block moving by itself, over `dt_s`, by less than the
    /// fine mutation's step: its centre by less than the fine lateral step and its orientation
    /// by less than the fine turn. A hold that stays unconfirmed while the block moves is most
    /// often the search lagging the block, which every bred child is needed to follow; one that
    /// stays unconfirmed while the block stands still is a local optimum.
    fn moves_less_than_a_fine_step(&self, dt_s: f32) -> bool {
        let fine = self.config.tuning.ga.mutation_scale.last().copied().unwrap_or([0.0; 6]);
        let v = self.target.feedforward_velocity();
        let step = v.v.norm() * dt_s;
        let turn = 0.5 * v.w.norm() * dt_s;
        step <= fine[0].min(fine[1]) && turn <= fine[3..].iter().fold(f32::INFINITY, |m, &x| m.min(x))
    }

    /// Replaces the [`TURN_PROBES`] bred children before the depth probes by the best pose
    /// tilted so that each of its two faces nearest edge-on turns towards and away from the
    /// camera (about the axis across the viewing ray and the face's normal), by `k` coarse
    /// mutation turns, `k` in [`TURN_PROBE_MULTIPLES`], about its visible surface: a lock that
    /// misses a face seen at a grazing angle climbs back only by a larger turn than the
    /// mutations make.
    fn probe_turns(&mut self, best: &Psi) {
        let coarse = self.config.tuning.ga.mutation_scale.first().copied().unwrap_or([0.0; 6]);
        let step = coarse[3..].iter().fold(0.0f32, |m, &v| m.max(v));
        let half = self.config.block.size_m.map(|s| 0.5 * s);
        let end = self.ga.first_immigrant(&self.config.tuning.ga).saturating_sub(DEPTH_PROBES);
        let Some(first) = end.checked_sub(TURN_PROBES).filter(|&f| f >= 1) else { return };
        let t = best.translation();
        let range = t.norm();
        if !(range > MIN_DEPTH_M && range.is_finite()) {
            return;
        }
        let ray = t / range;
        let r = best.rotation_unchecked();
        // The box axes ordered by how nearly edge-on their faces are (|cos| to the ray).
        let cos = (r.transpose() * ray).map(f32::abs);
        let mut axes = [0usize, 1, 2];
        axes.sort_unstable_by(|&a, &b| cos.get(a).unwrap_or(&0.0).total_cmp(cos.get(b).unwrap_or(&0.0)));
        let mut slot = first;
        for &k in &axes[..2] {
            let across = ray.cross(&r.column(k));
            let n = across.norm();
            let axis = if n > 1e-3 { across / n } else { Vector3::x() };
            for multiple in TURN_PROBE_MULTIPLES {
                for sign in [1.0f32, -1.0] {
                    let turn = quat::normalized(1.0, axis * (sign * multiple * step));
                    self.ga.set_individual(slot, best.turned_about_surface(&turn, &half), &self.config.search);
                    slot += 1;
                }
            }
        }
    }

    /// One stage of the acquisition ([`Acquisition::step`]), then the
    /// [`AcquireConfig::seed_immigrants`](crate::acquire::AcquireConfig::seed_immigrants) children before the idle ones replaced by poses
    /// seeded from the latest seed (none before the first seed).
    fn acquire_step<F: PixelFormat>(&mut self, frame: &StereoFrame<'_, F>) {
        let cfg = &self.config.tuning.acquire;
        let half = self.model.half_size();
        let half = [half.x, half.y, half.z];
        let solving = self.acquisition.stage() == acquire::Stage::Solve;
        self.acquisition.step(&frame.left, &frame.right, self.colours.lut(), &self.config.rig, &half, cfg);
        // The search table leaves out the scene's hues the solve stage took from its scan (a
        // stage of little work, so the table's rebuild is paid there).
        if solving {
            self.colours.set_scene(self.acquisition.scene());
        }
        let Some(seed) = self.acquisition.seed().copied() else { return };
        let used = self.ga.len();
        let end = used - cfg.idle_individuals.min(used - 1);
        let n = cfg.seed_immigrants.min(end - 1);
        for k in 0..n {
            if let Some(psi) = acquire::seed_immigrant(&seed, k, cfg, &mut self.rng) {
                self.ga.set_individual(end - n + k, psi, &self.config.search);
            }
        }
    }
}

#[cfg(test)]
mod tests;
