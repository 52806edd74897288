//! Scenario files: one TOML file describes one simulated experiment.
//!
//! Every key is checked: unknown keys, wrong types and out-of-range values are errors, and a
//! bad file yields **one** message naming the offending field, e.g.
//! `camera.width: must be in 16..=4096, got 0`.
//!
//! ```toml
//! # Motion A with feedforward.
//! seed = 1                 # required, 0 ..= 2^63−1; seeds the GA and the image noise
//! duration_s = 72.0        # required, (0, 3600]
//! frame_period_s = 0.033   # [0.001, 1], ≤ duration_s
//!
//! [camera]                 # both cameras share these intrinsics
//! width = 640              # 16 ..= 4096 pixels
//! height = 480             # 16 ..= 4096 pixels
//! fx = 800.0               # (0, 100000] pixels
//! fy = 800.0               # (0, 100000] pixels
//! cx = 320.0               # [0, width]
//! cy = 240.0               # [0, height]
//! baseline_m = 0.1         # (0, 1]; right camera at +baseline/2 on the flange x axis
//! noise_std = 2.0          # [0, 100]: RGB noise σ in 8-bit levels
//! supersample = 4          # 1 ..= 8 samples per pixel side (anti-aliasing)
//!
//! [target]
//! size_m = [0.1, 0.15, 0.2]                  # block edge lengths, each (0, 2]
//! face_hues_deg = [0, 120, 240, 0, 120, 240] # hue of each face, each [0, 360)
//! distance_m = 0.7         # (0, 5], beyond the block's half diagonal + 0.05 m
//! amplitude_deg = 15.0     # [0, 180]: yaw oscillation amplitude
//! omega_rad_s = 0.125      # [0, 10]: yaw oscillation angular frequency; 0 = still
//! yaw0_deg = 25.0          # [-180, 180]: initial yaw about world z
//! conveyor_speed_m_s = 0.0 # 0 (off) or [0.05, 0.3]: the centre shuttles along conveyor_direction
//! conveyor_travel_m = 0.2  # (0, 0.5]: length of the shuttle
//! conveyor_accel_m_s2 = 0.5 # (0, 10], ≥ 2·speed²/travel: peak acceleration of the reversals
//! conveyor_direction = [0, 1, 0] # direction of travel, finite and non-zero (normalised on load)
//! conveyor_direction_frame = "world" # "world" | "camera": the right camera's frame at t = 0
//!                          #   ([0, 0, -1]: along its optical axis towards the cameras)
//! conveyor_start = "rest"  # "rest": at rest at the −direction end | "moving": at full speed
//!                          #   along +direction in the middle of its travel at t = 0
//! random_amplitude_m = 0.0 # [0, 0.1]: 0 = off; seeded smooth random motion, per-axis scale
//! random_amplitude_deg = 10.0 # [0, 30]: its rotation scale per axis
//! random_omega_rad_s = 1.0 # (0, 2]: its highest angular frequency
//!
//! [robot]
//! motion = "A"             # "static" | "A" | "B"
//! omega_rad_s = 0.125      # [0, 2]; 0 = static
//! amplitude_m = 0.1        # [0, 0.3]: motion A amplitude along world y
//! amplitude_deg = 15.0     # [0, 45]: motion B orbit amplitude
//!
//! [servo]                  # optional: closes the loop (position-based visual servoing)
//! desired_t_m = [-0.05, 0.0, 0.6]  # required in [servo]: block centre in Σ_CR (m)
//! desired_q_xyzw = [0, 0, 0, 1]    # optional ^CR Q_M* (unit); default: the one at t = 0
//! gain = 2.0               # (0, 50] 1/s
//! max_speed_m_s = 0.3      # (0, 2]
//! max_rot_speed_rad_s = 1.0    # (0, 5]
//! max_accel_m_s2 = 1.0     # (0, 20]
//! max_rot_accel_rad_s2 = 3.0   # (0, 50]
//! delay_frames = 1         # 0 ..= 10: processing delay between capture and estimate
//!
//! [start]
//! delay_s = 0.033          # [0, 1]: capture → output delay of the hand-over; default frame_period_s
//!
//! [render]                 # optional camera-like light: the keys, their ranges and defaults
//! specular = 0.0           #   are in crate::sim::render::light (the defaults render flat faces)
//!
//! [tracker]                # the tracker's tuning: every key of `evorec config`, e.g.
//! method = "ff"            # "ga" (plain 1-step GA) | "ff" (GA + motion feedforward)
//!                          #   | "ff+target" (GA + feedforward of the arm's and the target's motion)
//! ga.population = 40       # 2..=HOST_POPULATION_CAPACITY (the host's compiled capacity, 64)
//! ```
//! The target's paths (conveyor, random) are described in [`crate::sim::target_path`]; the light's
//! keys and effects in [`crate::sim::render::light`].
//! Acquisition keys (`[start] initial`, `[target] placement`, `[[occlusion]]`) are
//! described in [`crate::sim::occlusion`]. `[tracker]` is the core's field table
//! ([`evorec_core::tuning::FIELDS`], [`TrackerTable`]); `evorec config` prints it with every
//! default, unit and meaning.
//! All tables and all keys except `seed` and `duration_s` are optional; the values shown are
//! the defaults (`robot.motion` defaults to `"static"`, no `[servo]` runs the scripted motion
//! open loop).
//!
//! A file is read by the `toml` crate into one serde struct per table (every key optional, no
//! other key accepted: `deny_unknown_fields`), whose errors are given the key's dotted path;
//! each value is then checked against its range, in the order of the tables above.

use std::path::{Path, PathBuf};

use evorec_core::tracker::Feedforward;
use evorec_core::tuning::Tuning;
use serde::Serialize;
use toml::Table;

use crate::sim::motion::MotionKind;
use crate::sim::occlusion::{Initial, Occlusions, Placement};
use crate::sim::render::Light;

/// Population capacity of the host's trackers (simulator and `evorec track`): any population
/// from 3 up to this is accepted at run time. Larger than the firmware's
/// [`evorec_core::limits::POPULATION_CAPACITY`], whose worst case sets the M4 budget; the same
/// population gives bit-identical estimates in either capacity (`core/tests/population.rs`).
pub const HOST_POPULATION_CAPACITY: usize = 64;

/// Largest `width·height·supersample²` accepted (samples per rendered image).
pub const MAX_SAMPLES_PER_IMAGE: u64 = 1 << 26;

/// Why a scenario could not be loaded.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The text is not valid TOML.
    #[error("TOML syntax error: {0}")]
    Syntax(String),
    /// A field is missing, unknown, of the wrong type or out of range.
    #[error("{field}: {message}")]
    Invalid {
        /// Dotted key path, e.g. `camera.width`.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// An error in a named file.
    #[error("{}: {source}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// The error.
        source: Box<ScenarioError>,
    },
}

impl ScenarioError {
    /// The dotted path of the offending field, if the error is about one field.
    pub fn field(&self) -> Option<&str> {
        match self {
            Self::Invalid { field, .. } => Some(field),
            Self::InFile { source, .. } => source.field(),
            _ => None,
        }
    }
}

type Result<T> = std::result::Result<T, ScenarioError>;

fn invalid(field: impl Into<String>, message: impl Into<String>) -> ScenarioError {
    ScenarioError::Invalid { field: field.into(), message: message.into() }
}

/// serde of core's [`Feedforward`] by its name ([`Feedforward::NAMES`]), for a field
/// `#[serde(with = "crate::sim::scenario::feedforward_name")]`.
pub mod feedforward_name {
    use evorec_core::tuning::Feedforward;
    use serde::{Deserialize, Deserializer, Serializer, de::Error as _};

    /// Writes the mode's name.
    ///
    /// # Errors
    /// The serializer's.
    pub fn serialize<S: Serializer>(mode: &Feedforward, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(mode.name())
    }

    /// Reads a name of [`Feedforward::NAMES`].
    ///
    /// # Errors
    /// Not a string, or not one of the names ([`evorec_core::tuning::UnknownFeedforward`]).
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Feedforward, D::Error> {
        String::deserialize(d)?.parse().map_err(D::Error::custom)
    }
}

/// `[camera]`: intrinsics shared by both cameras, stereo baseline, rendering options.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CameraConfig {
    /// Image width (pixels).
    pub width: u16,
    /// Image height (pixels).
    pub height: u16,
    /// Focal length along x (pixels).
    pub fx: f64,
    /// Focal length along y (pixels).
    pub fy: f64,
    /// Principal point x (pixels).
    pub cx: f64,
    /// Principal point y (pixels).
    pub cy: f64,
    /// Stereo baseline (m).
    pub baseline_m: f64,
    /// RGB noise standard deviation (8-bit levels).
    pub noise_std: f64,
    /// Samples per pixel side when rendering.
    pub supersample: u32,
}

impl Default for CameraConfig {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            fx: 800.0,
            fy: 800.0,
            cx: 320.0,
            cy: 240.0,
            baseline_m: 0.1,
            noise_std: 2.0,
            supersample: 4,
        }
    }
}

/// `[target]`: the coloured block and its own motion.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TargetConfig {
    /// Edge lengths along the block's x, y, z (m).
    pub size_m: [f64; 3],
    /// Hue of each face (degrees), in the core's face order.
    pub face_hues_deg: [f64; 6],
    /// Distance of the block centre along the right camera's optical axis at `t = 0` (m).
    pub distance_m: f64,
    /// Yaw oscillation amplitude (degrees).
    pub amplitude_deg: f64,
    /// Yaw oscillation angular frequency (rad/s).
    pub omega_rad_s: f64,
    /// Initial yaw about world z (degrees).
    pub yaw0_deg: f64,
    /// Where the block stands: fixed (`distance_m`, `yaw0_deg`) or a random pose.
    pub placement: Placement,
    /// Conveyor speed along world y (m/s); 0 = no conveyor ([`crate::sim::target_path`]).
    pub conveyor_speed_m_s: f64,
    /// Length of the conveyor's shuttle (m).
    pub conveyor_travel_m: f64,
    /// Peak acceleration of the conveyor's reversals (m/s²).
    pub conveyor_accel_m_s2: f64,
    /// Rest of the conveyor at each end of its travel (s): a belt that stops and starts
    /// again; written only when not 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub conveyor_dwell_s: f64,
    /// The conveyor's direction of travel (unit, in [`conveyor_direction_frame`]); written
    /// only when not world `y`, so older scenarios' outputs stay as they were.
    ///
    /// [`conveyor_direction_frame`]: TargetConfig::conveyor_direction_frame
    #[serde(skip_serializing_if = "is_world_y")]
    pub conveyor_direction: [f64; 3],
    /// The frame [`conveyor_direction`](TargetConfig::conveyor_direction) is given in.
    #[serde(skip_serializing_if = "ConveyorFrame::is_default")]
    pub conveyor_direction_frame: ConveyorFrame,
    /// Where the conveyor is at `t = 0`.
    #[serde(skip_serializing_if = "ConveyorStart::is_default")]
    pub conveyor_start: ConveyorStart,
    /// Scale of the random smooth motion per axis (m); 0 = off.
    pub random_amplitude_m: f64,
    /// Scale of the random smooth rotation per axis (degrees).
    pub random_amplitude_deg: f64,
    /// Highest angular frequency of the random motion (rad/s).
    pub random_omega_rad_s: f64,
}

impl Default for TargetConfig {
    fn default() -> Self {
        Self {
            size_m: [0.1, 0.15, 0.2],
            face_hues_deg: [0.0, 120.0, 240.0, 0.0, 120.0, 240.0],
            distance_m: 0.7,
            amplitude_deg: 15.0,
            omega_rad_s: 0.125,
            yaw0_deg: 25.0,
            placement: Placement::Fixed,
            conveyor_speed_m_s: 0.0,
            conveyor_travel_m: 0.2,
            conveyor_accel_m_s2: 0.5,
            conveyor_dwell_s: 0.0,
            conveyor_direction: WORLD_Y,
            conveyor_direction_frame: ConveyorFrame::World,
            conveyor_start: ConveyorStart::Rest,
            random_amplitude_m: 0.0,
            random_amplitude_deg: 10.0,
            random_omega_rad_s: 1.0,
        }
    }
}

/// The default `[target] conveyor_direction`: world `y`.
pub const WORLD_Y: [f64; 3] = [0.0, 1.0, 0.0];

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

fn is_world_y(d: &[f64; 3]) -> bool {
    *d == WORLD_Y
}

/// `[target] conveyor_direction_frame`: the frame the conveyor's direction is given in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
pub enum ConveyorFrame {
    /// The world (the PA-10's base frame, `z` up).
    #[default]
    #[serde(rename = "world")]
    World,
    /// The right camera's frame at `t = 0` (`z` its optical axis, away from the camera),
    /// turned into the world once when the run is set up ([`crate::sim::target_path`]).
    #[serde(rename = "camera")]
    Camera,
}

impl ConveyorFrame {
    fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// `[target] conveyor_start`: where the conveyor is at `t = 0`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
pub enum ConveyorStart {
    /// At rest at the −direction end of its travel (the tracker starts on a still block).
    #[default]
    #[serde(rename = "rest")]
    Rest,
    /// In the middle of its travel at full speed along +direction
    /// ([`crate::sim::target_path::Conveyor::middle_time`]): the tracker starts on a moving block.
    #[serde(rename = "moving")]
    Moving,
}

impl ConveyorStart {
    fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// `[robot]`: the flange motion.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RobotConfig {
    /// Motion type.
    pub motion: MotionKind,
    /// Angular frequency of motion A/B (rad/s).
    pub omega_rad_s: f64,
    /// Motion A amplitude (m).
    pub amplitude_m: f64,
    /// Motion B amplitude (degrees).
    pub amplitude_deg: f64,
}

impl Default for RobotConfig {
    fn default() -> Self {
        Self { motion: MotionKind::Static, omega_rad_s: 0.125, amplitude_m: 0.1, amplitude_deg: 15.0 }
    }
}

/// `[servo]`: the closed loop (see `evorec_core::servo`). With it the flange follows the servo's
/// camera twist instead of `[robot]`'s scripted motion.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ServoSection {
    /// Desired block centre in `Σ_CR` (m).
    pub desired_t_m: [f64; 3],
    /// Desired `^CR Q_M` as `[x, y, z, w]` (unit); `None`: the relative orientation at `t = 0`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub desired_q_xyzw: Option<[f64; 4]>,
    /// Feedback gain `λ` (1/s).
    pub gain: f64,
    /// Linear speed limit of the camera (m/s).
    pub max_speed_m_s: f64,
    /// Angular speed limit (rad/s).
    pub max_rot_speed_rad_s: f64,
    /// Linear acceleration limit (m/s²).
    pub max_accel_m_s2: f64,
    /// Angular acceleration limit (rad/s²).
    pub max_rot_accel_rad_s2: f64,
    /// Frame periods between a frame's capture and its estimate reaching the servo.
    pub delay_frames: u32,
}

impl ServoSection {
    /// Defaults for every key but `desired_t_m`.
    pub fn new(desired_t_m: [f64; 3]) -> Self {
        Self {
            desired_t_m,
            desired_q_xyzw: None,
            gain: 2.0,
            max_speed_m_s: 0.3,
            max_rot_speed_rad_s: 1.0,
            max_accel_m_s2: 1.0,
            max_rot_accel_rad_s2: 3.0,
            delay_frames: 1,
        }
    }
}

/// `[start]`: how the tracker starts, and when its estimates are handed over.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TrackerStart {
    /// Around the true pose, or unknown.
    pub initial: Initial,
    /// Processing delay between a frame's capture and the output of its estimate (s); the
    /// hand-over at the output time is measured ([`crate::sim::board::Handover`]). Default: one
    /// frame period.
    pub delay_s: f64,
}

impl TrackerStart {
    /// Around the true pose, output one `frame_period_s` after capture.
    pub fn new(frame_period_s: f64) -> Self {
        Self { initial: Initial::default(), delay_s: frame_period_s }
    }
}

/// One validated experiment description. See the module documentation for the file format.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Scenario {
    /// Seed of every random generator of the run.
    pub seed: u64,
    /// Simulated duration (s).
    pub duration_s: f64,
    /// Time between stereo frames (s).
    pub frame_period_s: f64,
    /// Camera settings.
    pub camera: CameraConfig,
    /// Target settings.
    pub target: TargetConfig,
    /// Robot motion.
    pub robot: RobotConfig,
    /// The closed loop, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub servo: Option<ServoSection>,
    /// How the tracker starts.
    pub start: TrackerStart,
    /// Times when the block is hidden.
    #[serde(skip_serializing_if = "Occlusions::is_empty")]
    pub occlusion: Occlusions,
    /// The tracker's tuning (`[tracker]`).
    pub tracker: TrackerTable,
    /// The camera-like light (`[render]`); written only when not the default, so older
    /// scenarios' outputs stay as they were.
    #[serde(skip_serializing_if = "Light::is_default")]
    pub render: Light,
}

impl Scenario {
    /// A scenario with the required values given and every other value at its default.
    pub fn new(seed: u64, duration_s: f64, method: Feedforward) -> Self {
        Self {
            seed,
            duration_s,
            frame_period_s: 0.033,
            camera: CameraConfig::default(),
            target: TargetConfig::default(),
            robot: RobotConfig::default(),
            servo: None,
            start: TrackerStart::new(0.033),
            occlusion: Occlusions::default(),
            tracker: TrackerTable(Tuning { feedforward: method, ..Tuning::DEFAULT }),
            render: Light::default(),
        }
    }

    /// [`Scenario::new`] with 160×120 cameras of f = 200 px (the board's frame size): quick
    /// runs for tests.
    #[cfg(test)]
    pub(crate) fn small(seed: u64, duration_s: f64, method: Feedforward) -> Self {
        let mut s = Self::new(seed, duration_s, method);
        (s.camera.width, s.camera.height) = (160, 120);
        (s.camera.fx, s.camera.fy, s.camera.cx, s.camera.cy) = (200.0, 200.0, 80.0, 60.0);
        s
    }

    /// The recognition method (`[tracker] method`).
    pub fn method(&self) -> Feedforward {
        self.tracker.0.feedforward
    }

    /// Sets the recognition method (`[tracker] method`).
    pub fn set_method(&mut self, method: Feedforward) {
        self.tracker.0.feedforward = method;
    }

    /// The tuning the scenario's tracker runs with.
    pub fn tuning(&self) -> &Tuning {
        &self.tracker.0
    }

    /// Parses and validates a scenario.
    ///
    /// # Errors
    /// [`ScenarioError::Syntax`] for malformed TOML, [`ScenarioError::Invalid`] for the first
    /// unknown key, missing required key, wrongly typed or out-of-range value.
    pub fn from_toml_str(text: &str) -> Result<Self> {
        let table: Table =
            toml::from_str(text).map_err(|e| ScenarioError::Syntax(e.to_string().trim_end().to_owned()))?;
        let raw: RawScenario = check::deserialize(text, &table)?;
        refuse_old_keys(&raw)?;
        let camera = parse_camera(raw.camera.unwrap_or_default())?;
        let target = parse_target(raw.target.unwrap_or_default())?;
        let robot = parse_robot(raw.robot.unwrap_or_default())?;
        let servo = parse_servo(raw.servo)?;
        let tracker_table = match &raw.tracker {
            None => None,
            Some(toml::Value::Table(t)) => Some(t),
            Some(v) => return Err(invalid("tracker", format!("expected a table, got {}", check::describe(v)))),
        };
        let tracker = TrackerTable(tracker_table::parse_tracker(tracker_table, Tuning::DEFAULT, "tracker")?);
        let raw_start = raw.start.unwrap_or_default();
        let initial = acquisition::parse_initial(raw_start.initial.as_ref())?;

        let seed = raw.seed.ok_or_else(|| check::missing("seed"))?;
        let seed = u64::try_from(seed).map_err(|_| invalid("seed", format!("must be ≥ 0, got {seed}")))?;
        let duration_s = raw.duration_s.ok_or_else(|| check::missing("duration_s"))?;
        check_range("duration_s", duration_s, Bound::Open(0.0), 3600.0)?;
        let frame_period_s = raw.frame_period_s.unwrap_or(0.033);
        check_range("frame_period_s", frame_period_s, Bound::Closed(0.001), 1.0)?;
        if frame_period_s > duration_s {
            return Err(invalid(
                "frame_period_s",
                format!("must not exceed duration_s ({duration_s}), got {frame_period_s}"),
            ));
        }
        let delay_s = check::float_in("start.delay_s", raw_start.delay_s, frame_period_s, Bound::Closed(0.0), 1.0)?;
        let start = TrackerStart { initial, delay_s };
        let occlusion = acquisition::parse_occlusions(raw.occlusion.as_ref(), duration_s)?;
        let render = render_table::parse_render(raw.render.unwrap_or_default(), frame_period_s)?;
        Ok(Self { seed, duration_s, frame_period_s, camera, target, robot, servo, start, occlusion, tracker, render })
    }

    /// Reads, parses and validates a scenario file.
    ///
    /// # Errors
    /// [`ScenarioError::Io`] if the file cannot be read, otherwise [`ScenarioError::InFile`]
    /// wrapping the error of [`from_toml_str`](Self::from_toml_str).
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text =
            std::fs::read_to_string(path).map_err(|source| ScenarioError::Io { path: path.to_path_buf(), source })?;
        Self::from_toml_str(&text).map_err(|e| ScenarioError::InFile { path: path.to_path_buf(), source: Box::new(e) })
    }

    /// The scenario as TOML, in the format [`from_toml_str`](Self::from_toml_str) reads back.
    ///
    /// # Errors
    /// Only if serialisation fails (it does not for validated scenarios).
    pub fn to_toml_string(&self) -> std::result::Result<String, toml::ser::Error> {
        toml::to_string(self)
    }

    /// Number of stereo frames in the run: `⌊duration_s / frame_period_s⌋`, at least 1.
    pub fn frame_count(&self) -> u64 {
        ((self.duration_s / self.frame_period_s + 1e-9).floor() as u64).max(1)
    }
}

mod acquisition;
mod check;
pub mod fixture;
mod parse;
mod raw;
mod render_table;
mod tracker_table;
pub use render_table::{light_from_toml_str, load_light};
pub use tracker_table::{TrackerTable, parse_tracker, with_config_file};
#[cfg(test)]
mod tests;

use check::{Bound, check_range};
use parse::{parse_camera, parse_robot, parse_servo, parse_target, refuse_old_keys};
use raw::RawScenario;
