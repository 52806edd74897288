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
//! method = "ff"            # required: "ga" (plain 1-step GA) | "ff" (GA + motion feedforward)
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
//!
//! [robot]
//! motion = "A"             # "static" | "A" | "B"
//! omega_rad_s = 0.125      # [0, 2]; 0 = static
//! amplitude_m = 0.1        # [0, 0.3]: motion A amplitude along world y
//! amplitude_deg = 15.0     # [0, 45]: motion B orbit amplitude
//!
//! [ga]
//! population = 40          # min_population()..=HOST_POPULATION_CAPACITY (the host's compiled capacity, 64)
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
//! ```
//! Acquisition keys (`[tracker] initial`, `[target] placement`, `[[occlusion]]`) are
//! described in [`crate::occlusion`].
//! All tables and all keys except `seed`, `duration_s` and `method` are optional; the values
//! shown are the defaults (`robot.motion` defaults to `"static"`, no `[servo]` runs the
//! scripted motion open loop).

use std::path::{Path, PathBuf};

use serde::Serialize;
use toml::{Table, Value};

use crate::motion::MotionKind;
use crate::occlusion::{self, Initial, Occlusions, Placement};

/// Population capacity of the host's trackers (simulator and `evorec track`): any population
/// from 3 up to this is accepted at run time. Larger than the firmware's
/// [`evorec_core::config::POPULATION_CAPACITY`], whose worst case sets the M4 budget; the same
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

/// How the pose is recognised.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Method {
    /// The plain 1-step GA (`Feedforward::Off`).
    #[serde(rename = "ga")]
    Ga,
    /// The 1-step GA with quaternion motion feedforward (`Feedforward::On`).
    #[serde(rename = "ff")]
    Ff,
}

impl Method {
    /// The spelling used in scenario files.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Ga => "ga",
            Self::Ff => "ff",
        }
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
        }
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

/// `[ga]`: genetic algorithm settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GaConfig {
    /// Population size, chosen at run time up to the core's compiled capacity
    /// ([`HOST_POPULATION_CAPACITY`]); checked against the GA's other settings.
    pub population: usize,
}

impl Default for GaConfig {
    fn default() -> Self {
        Self { population: evorec_core::config::DEFAULT_POPULATION }
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

/// `[tracker]`: how the tracker starts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct TrackerStart {
    /// Around the true pose, or unknown.
    pub initial: Initial,
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
    /// Recognition method.
    pub method: Method,
    /// Camera settings.
    pub camera: CameraConfig,
    /// Target settings.
    pub target: TargetConfig,
    /// Robot motion.
    pub robot: RobotConfig,
    /// GA settings.
    pub ga: GaConfig,
    /// The closed loop, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub servo: Option<ServoSection>,
    /// How the tracker starts.
    pub tracker: TrackerStart,
    /// Times when the block is hidden.
    #[serde(skip_serializing_if = "Occlusions::is_empty")]
    pub occlusion: Occlusions,
}

impl Scenario {
    /// A scenario with the required values given and every other value at its default.
    pub fn new(seed: u64, duration_s: f64, method: Method) -> Self {
        Self {
            seed,
            duration_s,
            frame_period_s: 0.033,
            method,
            camera: CameraConfig::default(),
            target: TargetConfig::default(),
            robot: RobotConfig::default(),
            ga: GaConfig::default(),
            servo: None,
            tracker: TrackerStart::default(),
            occlusion: Occlusions::default(),
        }
    }

    /// Parses and validates a scenario.
    ///
    /// # Errors
    /// [`ScenarioError::Syntax`] for malformed TOML, [`ScenarioError::Invalid`] for the first
    /// unknown key, missing required key, wrongly typed or out-of-range value.
    pub fn from_toml_str(text: &str) -> Result<Self> {
        let table: Table =
            toml::from_str(text).map_err(|e| ScenarioError::Syntax(e.to_string().trim_end().to_owned()))?;
        let top = Section::new(
            "",
            &table,
            &[
                "seed",
                "duration_s",
                "frame_period_s",
                "method",
                "camera",
                "target",
                "robot",
                "ga",
                "tracker",
                "occlusion",
                "servo",
            ],
        )?;
        let camera = parse_camera(&top.subtable("camera")?)?;
        let target = parse_target(&top.subtable("target")?)?;
        let robot = parse_robot(&top.subtable("robot")?)?;
        let ga = parse_ga(&top.subtable("ga")?)?;
        let servo = parse_servo(&top.subtable("servo")?)?;
        let tracker_section = top.subtable("tracker")?;
        tracker_section.check_keys(&["initial"])?;
        let tracker = TrackerStart { initial: occlusion::parse_initial(tracker_section.get("initial"))? };

        let seed = top.int("seed", None)?;
        let seed = u64::try_from(seed).map_err(|_| invalid("seed", format!("must be ≥ 0, got {seed}")))?;
        let duration_s = top.float("duration_s", None)?;
        check_range("duration_s", duration_s, Bound::Open(0.0), 3600.0)?;
        let frame_period_s = top.float("frame_period_s", Some(0.033))?;
        check_range("frame_period_s", frame_period_s, Bound::Closed(0.001), 1.0)?;
        if frame_period_s > duration_s {
            return Err(invalid(
                "frame_period_s",
                format!("must not exceed duration_s ({duration_s}), got {frame_period_s}"),
            ));
        }
        let method = match top.string("method", None)?.as_str() {
            "ga" => Method::Ga,
            "ff" => Method::Ff,
            other => return Err(invalid("method", format!("expected \"ga\" or \"ff\", got \"{other}\""))),
        };
        let occlusion = occlusion::parse_occlusions(top.get("occlusion"), duration_s)?;
        Ok(Self { seed, duration_s, frame_period_s, method, camera, target, robot, ga, servo, tracker, occlusion })
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

fn parse_camera(s: &Section<'_>) -> Result<CameraConfig> {
    s.check_keys(&["width", "height", "fx", "fy", "cx", "cy", "baseline_m", "noise_std", "supersample"])?;
    let d = CameraConfig::default();
    let width = s.int_in("width", i64::from(d.width), 16, 4096)?;
    let height = s.int_in("height", i64::from(d.height), 16, 4096)?;
    let fx = s.float_in("fx", d.fx, Bound::Open(0.0), 1e5)?;
    let fy = s.float_in("fy", d.fy, Bound::Open(0.0), 1e5)?;
    let cx = s.float("cx", Some(d.cx))?;
    check_range_why(&s.path("cx"), cx, Bound::Closed(0.0), width as f64, " (inside the image width)")?;
    let cy = s.float("cy", Some(d.cy))?;
    check_range_why(&s.path("cy"), cy, Bound::Closed(0.0), height as f64, " (inside the image height)")?;
    let baseline_m = s.float_in("baseline_m", d.baseline_m, Bound::Open(0.0), 1.0)?;
    let noise_std = s.float_in("noise_std", d.noise_std, Bound::Closed(0.0), 100.0)?;
    let supersample = s.int_in("supersample", i64::from(d.supersample), 1, 8)?;
    let samples = (width * height * supersample * supersample) as u64;
    if samples > MAX_SAMPLES_PER_IMAGE {
        return Err(invalid(
            s.path("supersample"),
            format!("width·height·supersample² must be ≤ {MAX_SAMPLES_PER_IMAGE}, got {samples}"),
        ));
    }
    Ok(CameraConfig {
        // In range by the checks above.
        width: width as u16,
        height: height as u16,
        fx,
        fy,
        cx,
        cy,
        baseline_m,
        noise_std,
        supersample: supersample as u32,
    })
}

fn parse_target(s: &Section<'_>) -> Result<TargetConfig> {
    s.check_keys(&["size_m", "face_hues_deg", "distance_m", "amplitude_deg", "omega_rad_s", "yaw0_deg", "placement"])?;
    let d = TargetConfig::default();
    let size_m: [f64; 3] = s.floats("size_m", d.size_m)?;
    for (i, x) in size_m.iter().enumerate() {
        check_range(&format!("{}[{i}]", s.path("size_m")), *x, Bound::Open(0.0), 2.0)?;
    }
    let face_hues_deg: [f64; 6] = s.floats("face_hues_deg", d.face_hues_deg)?;
    for (i, h) in face_hues_deg.iter().enumerate() {
        let field = format!("{}[{i}]", s.path("face_hues_deg"));
        if !h.is_finite() || *h < 0.0 || *h >= 360.0 {
            return Err(invalid(field, format!("must be in [0, 360), got {h}")));
        }
    }
    let distance_m = s.float_in("distance_m", d.distance_m, Bound::Open(0.0), 5.0)?;
    let half_diagonal = 0.5 * size_m.iter().map(|x| x * x).sum::<f64>().sqrt();
    if distance_m <= half_diagonal + 0.05 {
        return Err(invalid(
            s.path("distance_m"),
            format!(
                "must exceed the block's half diagonal plus 0.05 m ({:.4} m), got {distance_m}",
                half_diagonal + 0.05
            ),
        ));
    }
    let amplitude_deg = s.float_in("amplitude_deg", d.amplitude_deg, Bound::Closed(0.0), 180.0)?;
    let omega_rad_s = s.float_in("omega_rad_s", d.omega_rad_s, Bound::Closed(0.0), 10.0)?;
    let yaw0_deg = s.float_in("yaw0_deg", d.yaw0_deg, Bound::Closed(-180.0), 180.0)?;
    let placement = occlusion::parse_placement(s.get("placement"))?;
    Ok(TargetConfig { size_m, face_hues_deg, distance_m, amplitude_deg, omega_rad_s, yaw0_deg, placement })
}

fn parse_robot(s: &Section<'_>) -> Result<RobotConfig> {
    s.check_keys(&["motion", "omega_rad_s", "amplitude_m", "amplitude_deg"])?;
    let d = RobotConfig::default();
    let motion = match s.string("motion", Some(d.motion.as_str()))?.as_str() {
        "static" => MotionKind::Static,
        "A" => MotionKind::A,
        "B" => MotionKind::B,
        other => {
            return Err(invalid(s.path("motion"), format!("expected \"static\", \"A\" or \"B\", got \"{other}\"")));
        }
    };
    let omega_rad_s = s.float_in("omega_rad_s", d.omega_rad_s, Bound::Closed(0.0), 2.0)?;
    let amplitude_m = s.float_in("amplitude_m", d.amplitude_m, Bound::Closed(0.0), 0.3)?;
    let amplitude_deg = s.float_in("amplitude_deg", d.amplitude_deg, Bound::Closed(0.0), 45.0)?;
    Ok(RobotConfig { motion, omega_rad_s, amplitude_m, amplitude_deg })
}

fn parse_ga(s: &Section<'_>) -> Result<GaConfig> {
    s.check_keys(&["population"])?;
    let population = s.int("population", Some(GaConfig::default().population as i64))?;
    let capacity = HOST_POPULATION_CAPACITY;
    let ga = evorec_core::ga::GaParams::DEFAULT;
    let acquire = evorec_core::acquire::AcquireConfig::DEFAULT;
    let fits = |p: usize| ga.with_population(p).validate(capacity).is_ok() && acquire.validate(p).is_ok();
    let checked = usize::try_from(population).ok().filter(|&p| fits(p));
    match checked {
        Some(p) => Ok(GaConfig { population: p }),
        None => Err(invalid(
            s.path("population"),
            format!(
                "must be in [{}, {capacity}] (room for the elite, one child, the immigrants and the \
                 acquisition's seeded and idle individuals; at most the host's compiled capacity), got {population}",
                min_population(),
            ),
        )),
    }
}

/// The smallest population the default GA and acquisition settings accept.
pub fn min_population() -> usize {
    let (ga, acquire) = (evorec_core::ga::GaParams::DEFAULT, evorec_core::acquire::AcquireConfig::DEFAULT);
    (ga.immigrants + 2).max(acquire.seed_immigrants + acquire.idle_individuals + 2)
}

fn parse_servo(s: &Section<'_>) -> Result<Option<ServoSection>> {
    if s.table.is_none() {
        return Ok(None);
    }
    s.check_keys(&[
        "desired_t_m",
        "desired_q_xyzw",
        "gain",
        "max_speed_m_s",
        "max_rot_speed_rad_s",
        "max_accel_m_s2",
        "max_rot_accel_rad_s2",
        "delay_frames",
    ])?;
    if s.get("desired_t_m").is_none() {
        return Err(s.missing("desired_t_m"));
    }
    let desired_t_m: [f64; 3] = s.floats("desired_t_m", [0.0; 3])?;
    let t_field = s.path("desired_t_m");
    check_range_why(&format!("{t_field}[0]"), desired_t_m[0].abs(), Bound::Closed(0.0), 1.0, " (|x|)")?;
    check_range_why(&format!("{t_field}[1]"), desired_t_m[1].abs(), Bound::Closed(0.0), 1.0, " (|y|)")?;
    check_range_why(&format!("{t_field}[2]"), desired_t_m[2], Bound::Open(0.2), 3.0, " (in front of the camera)")?;
    let desired_q_xyzw = match s.get("desired_q_xyzw") {
        None => None,
        Some(_) => {
            let q: [f64; 4] = s.floats("desired_q_xyzw", [0.0; 4])?;
            let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            if !n.is_finite() || (n - 1.0).abs() > 1e-3 {
                return Err(invalid(s.path("desired_q_xyzw"), format!("must be a unit quaternion, got norm {n}")));
            }
            Some(q.map(|x| x / n))
        }
    };
    let d = ServoSection::new(desired_t_m);
    let gain = s.float_in("gain", d.gain, Bound::Open(0.0), 50.0)?;
    let max_speed_m_s = s.float_in("max_speed_m_s", d.max_speed_m_s, Bound::Open(0.0), 2.0)?;
    let max_rot_speed_rad_s = s.float_in("max_rot_speed_rad_s", d.max_rot_speed_rad_s, Bound::Open(0.0), 5.0)?;
    let max_accel_m_s2 = s.float_in("max_accel_m_s2", d.max_accel_m_s2, Bound::Open(0.0), 20.0)?;
    let max_rot_accel_rad_s2 = s.float_in("max_rot_accel_rad_s2", d.max_rot_accel_rad_s2, Bound::Open(0.0), 50.0)?;
    let delay_frames = s.int_in("delay_frames", i64::from(d.delay_frames), 0, 10)? as u32;
    Ok(Some(ServoSection {
        desired_t_m,
        desired_q_xyzw,
        gain,
        max_speed_m_s,
        max_rot_speed_rad_s,
        max_accel_m_s2,
        max_rot_accel_rad_s2,
        delay_frames,
    }))
}

/// Lower end of a range check.
#[derive(Clone, Copy)]
enum Bound {
    Open(f64),
    Closed(f64),
}

fn check_range(field: &str, x: f64, lo: Bound, hi: f64) -> Result<()> {
    check_range_why(field, x, lo, hi, "")
}

fn check_range_why(field: &str, x: f64, lo: Bound, hi: f64, why: &str) -> Result<()> {
    let (ok_lo, text) = match lo {
        Bound::Open(l) => (x > l, format!("({l}, {hi}]")),
        Bound::Closed(l) => (x >= l, format!("[{l}, {hi}]")),
    };
    if x.is_finite() && ok_lo && x <= hi {
        Ok(())
    } else {
        Err(invalid(field, format!("must be in {text}{why}, got {x}")))
    }
}

/// One TOML table and its dotted name, for typed look-ups with field-naming errors.
struct Section<'a> {
    name: &'static str,
    table: Option<&'a Table>,
}

impl<'a> Section<'a> {
    fn new(name: &'static str, table: &'a Table, known: &[&str]) -> Result<Self> {
        let s = Self { name, table: Some(table) };
        s.check_keys(known)?;
        Ok(s)
    }

    fn path(&self, key: &str) -> String {
        if self.name.is_empty() { key.to_owned() } else { format!("{}.{key}", self.name) }
    }

    fn check_keys(&self, known: &[&str]) -> Result<()> {
        let Some(t) = self.table else { return Ok(()) };
        match t.keys().find(|k| !known.contains(&k.as_str())) {
            Some(k) => Err(invalid(self.path(k), format!("unknown key (expected one of: {})", known.join(", ")))),
            None => Ok(()),
        }
    }

    /// The sub-table `key` (absent → an empty section that yields defaults).
    fn subtable(&self, key: &'static str) -> Result<Section<'a>> {
        match self.table.and_then(|t| t.get(key)) {
            None => Ok(Section { name: key, table: None }),
            Some(Value::Table(t)) => Ok(Section { name: key, table: Some(t) }),
            Some(v) => Err(invalid(self.path(key), format!("expected a table, got {}", describe(v)))),
        }
    }

    fn get(&self, key: &str) -> Option<&'a Value> {
        self.table.and_then(|t| t.get(key))
    }

    fn missing(&self, key: &str) -> ScenarioError {
        invalid(self.path(key), "missing (this key is required)")
    }

    fn float(&self, key: &str, default: Option<f64>) -> Result<f64> {
        match self.get(key) {
            None => default.ok_or_else(|| self.missing(key)),
            Some(v) => {
                as_float(v).ok_or_else(|| invalid(self.path(key), format!("expected a number, got {}", describe(v))))
            }
        }
    }

    fn float_in(&self, key: &str, default: f64, lo: Bound, hi: f64) -> Result<f64> {
        let x = self.float(key, Some(default))?;
        check_range(&self.path(key), x, lo, hi)?;
        Ok(x)
    }

    fn int(&self, key: &str, default: Option<i64>) -> Result<i64> {
        match self.get(key) {
            None => default.ok_or_else(|| self.missing(key)),
            Some(Value::Integer(i)) => Ok(*i),
            Some(v) => Err(invalid(self.path(key), format!("expected an integer, got {}", describe(v)))),
        }
    }

    fn int_in(&self, key: &str, default: i64, lo: i64, hi: i64) -> Result<i64> {
        let x = self.int(key, Some(default))?;
        if (lo..=hi).contains(&x) {
            Ok(x)
        } else {
            Err(invalid(self.path(key), format!("must be in {lo}..={hi}, got {x}")))
        }
    }

    fn string(&self, key: &str, default: Option<&str>) -> Result<String> {
        match self.get(key) {
            None => default.map(str::to_owned).ok_or_else(|| self.missing(key)),
            Some(Value::String(s)) => Ok(s.clone()),
            Some(v) => Err(invalid(self.path(key), format!("expected a string, got {}", describe(v)))),
        }
    }

    fn floats<const N: usize>(&self, key: &str, default: [f64; N]) -> Result<[f64; N]> {
        let items = match self.get(key) {
            None => return Ok(default),
            Some(Value::Array(a)) => a,
            Some(v) => {
                return Err(invalid(self.path(key), format!("expected an array of {N} numbers, got {}", describe(v))));
            }
        };
        if items.len() != N {
            return Err(invalid(self.path(key), format!("expected {N} values, got {}", items.len())));
        }
        let mut out = default;
        for (i, (o, v)) in out.iter_mut().zip(items).enumerate() {
            *o = as_float(v).ok_or_else(|| {
                invalid(format!("{}[{i}]", self.path(key)), format!("expected a number, got {}", describe(v)))
            })?;
        }
        Ok(out)
    }
}

fn as_float(v: &Value) -> Option<f64> {
    match v {
        Value::Float(x) => Some(*x),
        Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// `a string ("x")`, `an array`, … for error messages.
fn describe(v: &Value) -> String {
    match v {
        Value::String(s) => format!("a string (\"{s}\")"),
        Value::Integer(i) => format!("an integer ({i})"),
        Value::Float(x) => format!("a float ({x})"),
        Value::Boolean(b) => format!("a boolean ({b})"),
        Value::Datetime(_) => "a datetime".to_owned(),
        Value::Array(_) => "an array".to_owned(),
        Value::Table(_) => "a table".to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = "seed = 1\nduration_s = 10.0\nmethod = \"ff\"\n";

    fn err(text: &str) -> String {
        match Scenario::from_toml_str(text) {
            Ok(s) => unreachable!("accepted: {s:?}"),
            Err(e) => e.to_string(),
        }
    }

    fn with(extra: &str) -> String {
        format!("{BASE}{extra}")
    }

    #[test]
    fn minimal_file_gets_defaults() {
        let s = Scenario::from_toml_str(BASE).unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(s, Scenario::new(1, 10.0, Method::Ff));
        assert_eq!(s.camera.width, 640);
        assert_eq!(s.target.face_hues_deg, [0.0, 120.0, 240.0, 0.0, 120.0, 240.0]);
        assert_eq!(s.robot.motion, MotionKind::Static);
        assert_eq!(s.frame_count(), 303);
    }

    #[test]
    fn validation_errors_name_the_field() {
        assert_eq!(err(&with("[camera]\nwidth = 0\n")), "camera.width: must be in 16..=4096, got 0");
        assert_eq!(
            err(&with("[robot]\nmotion = \"C\"\n")),
            "robot.motion: expected \"static\", \"A\" or \"B\", got \"C\""
        );
        assert_eq!(
            err(&with("[target]\nface_hues_deg = [0, 120, 240, 0, 120]\n")),
            "target.face_hues_deg: expected 6 values, got 5"
        );
        assert!(err(&with("[camera]\nwidht = 640\n")).starts_with("camera.widht: unknown key"));
        assert!(err(&with("colour = 3\n")).starts_with("colour: unknown key"));
        assert!(err(&with("[lens]\nk1 = 0.1\n")).starts_with("lens: unknown key"));
        assert_eq!(err("seed = 1\nmethod = \"ga\"\n"), "duration_s: missing (this key is required)");
        assert_eq!(
            err(&with("[camera]\ncx = 700.0\n")),
            "camera.cx: must be in [0, 640] (inside the image width), got 700"
        );
        assert_eq!(err("seed = 1\nduration_s = 0\nmethod = \"ga\"\n"), "duration_s: must be in (0, 3600], got 0");
        assert_eq!(err("seed = 1\nduration_s = 4000\nmethod = \"ga\"\n"), "duration_s: must be in (0, 3600], got 4000");
        assert_eq!(err("seed = -3\nduration_s = 1\nmethod = \"ga\"\n"), "seed: must be ≥ 0, got -3");
        assert_eq!(err("seed = 1\nduration_s = 1\nmethod = \"GA\"\n"), "method: expected \"ga\" or \"ff\", got \"GA\"");
        assert_eq!(
            err(&with("[camera]\nwidth = \"640\"\n")),
            "camera.width: expected an integer, got a string (\"640\")"
        );
        assert_eq!(err(&with("camera = 3\n")), "camera: expected a table, got an integer (3)");
        assert_eq!(
            err(&with("[target]\nsize_m = [0.1, -0.2, 0.3]\n")),
            "target.size_m[1]: must be in (0, 2], got -0.2"
        );
        assert_eq!(err(&with("[target]\ndistance_m = nan\n")), "target.distance_m: must be in (0, 5], got NaN");
        assert!(err(&with("[target]\ndistance_m = 0.1\n")).starts_with("target.distance_m: must exceed"));
        assert_eq!(
            err(&with("[target]\nface_hues_deg = [0, 120, 360, 0, 120, 240]\n")),
            "target.face_hues_deg[2]: must be in [0, 360), got 360"
        );
        assert_eq!(
            err(&with("[ga]\npopulation = 0\n")),
            "ga.population: must be in [16, 64] (room for the elite, one child, the immigrants and the \
             acquisition's seeded and idle individuals; at most the host's compiled capacity), got 0"
        );
        assert!(err(&with("[ga]\npopulation = 65\n")).ends_with("got 65"));
        assert!(err(&with("[ga]\npopulation = 15\n")).ends_with("got 15"));
        assert_eq!(Scenario::from_toml_str(&with("[ga]\npopulation = 16\n")).map(|s| s.ga.population).ok(), Some(16));
        assert!(err(&with("[ga]\npopulation = -1\n")).starts_with("ga.population: must be in [16, 64]"));
        assert_eq!(Scenario::from_toml_str(&with("[ga]\npopulation = 64\n")).map(|s| s.ga.population).ok(), Some(64));
        assert!(err("seed = 1\nduration_s = \n").starts_with("TOML syntax error"));
    }

    #[test]
    fn servo_section_is_validated_field_by_field() {
        let ok = Scenario::from_toml_str(&with("[servo]\ndesired_t_m = [0, 0, 0.6]\n"))
            .unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(ok.servo, Some(ServoSection::new([0.0, 0.0, 0.6])));
        assert_eq!(Scenario::from_toml_str(BASE).map(|s| s.servo).ok(), Some(None));
        assert_eq!(err(&with("[servo]\ngain = 2\n")), "servo.desired_t_m: missing (this key is required)");
        assert_eq!(
            err(&with("[servo]\ndesired_t_m = [0, 0, 0.1]\n")),
            "servo.desired_t_m[2]: must be in (0.2, 3] (in front of the camera), got 0.1"
        );
        assert_eq!(
            err(&with("[servo]\ndesired_t_m = [0, 0, 0.6]\ngain = 0\n")),
            "servo.gain: must be in (0, 50], got 0"
        );
        assert_eq!(
            err(&with("[servo]\ndesired_t_m = [0, 0, 0.6]\nmax_speed_m_s = -1\n")),
            "servo.max_speed_m_s: must be in (0, 2], got -1"
        );
        assert_eq!(
            err(&with("[servo]\ndesired_t_m = [0, 0, 0.6]\ndesired_q_xyzw = [0, 0, 0, 2]\n")),
            "servo.desired_q_xyzw: must be a unit quaternion, got norm 2"
        );
        assert_eq!(
            err(&with("[servo]\ndesired_t_m = [0, 0, 0.6]\ndelay_frames = 11\n")),
            "servo.delay_frames: must be in 0..=10, got 11"
        );
        assert!(err(&with("[servo]\ndesired_t_m = [0, 0, 0.6]\ngian = 1\n")).starts_with("servo.gian: unknown key"));
        let mut s = Scenario::new(3, 5.0, Method::Ff);
        s.servo = Some(ServoSection {
            desired_q_xyzw: Some([0.0, 0.0, 0.0, 1.0]),
            gain: 3.5,
            ..ServoSection::new([0.01, -0.02, 0.55])
        });
        let text = s.to_toml_string().unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(Scenario::from_toml_str(&text).unwrap_or_else(|e| unreachable!("{e}\n{text}")), s);
    }

    #[test]
    fn integers_are_accepted_for_floats_but_not_the_reverse() {
        let s = Scenario::from_toml_str(&with("[target]\ndistance_m = 1\n")).unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(s.target.distance_m, 1.0);
        assert_eq!(
            err(&with("[camera]\nsupersample = 2.0\n")),
            "camera.supersample: expected an integer, got a float (2)"
        );
    }

    #[test]
    fn round_trip_through_toml() {
        let mut s = Scenario::new(7, 12.5, Method::Ga);
        s.frame_period_s = 0.04;
        s.camera.width = 320;
        s.camera.cx = 161.5;
        s.camera.noise_std = 0.0;
        s.target.size_m = [0.08, 0.12, 0.3];
        s.target.face_hues_deg = [10.0, 50.0, 90.0, 130.0, 200.0, 300.5];
        s.robot = RobotConfig { motion: MotionKind::B, omega_rad_s: 0.3, amplitude_m: 0.05, amplitude_deg: 10.0 };
        let text = s.to_toml_string().unwrap_or_else(|e| unreachable!("{e}"));
        let back = Scenario::from_toml_str(&text).unwrap_or_else(|e| unreachable!("{e}\n{text}"));
        assert_eq!(back, s);
        let json = serde_json::to_value(s).unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(json["robot"]["motion"], "B");
        assert_eq!(json["method"], "ga");
    }

    #[test]
    fn load_names_the_file() {
        let dir = std::env::temp_dir().join(format!("evorec-scenario-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| unreachable!("{e}"));
        let path = dir.join("bad.toml");
        std::fs::write(&path, with("[camera]\nwidth = 0\n")).unwrap_or_else(|e| unreachable!("{e}"));
        let e = Scenario::load(&path).err().unwrap_or_else(|| unreachable!());
        assert_eq!(e.field(), Some("camera.width"));
        assert!(e.to_string().ends_with("bad.toml: camera.width: must be in 16..=4096, got 0"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
        assert!(matches!(Scenario::load(dir.join("missing.toml")), Err(ScenarioError::Io { .. })));
    }

    #[test]
    fn every_shipped_scenario_loads() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
        let mut names = Vec::new();
        for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| unreachable!("{e}")) {
            let path = entry.unwrap_or_else(|e| unreachable!("{e}")).path();
            if path.extension().is_some_and(|e| e == "toml") {
                let s = Scenario::load(&path).unwrap_or_else(|e| unreachable!("{e}"));
                assert!(s.duration_s > 0.0);
                names.push(path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default());
            }
        }
        names.sort();
        for want in [
            "motion_a_ff.toml",
            "motion_a_ga.toml",
            "motion_b_ff.toml",
            "motion_b_ga.toml",
            "smoke.toml",
            "static.toml",
        ] {
            assert!(names.iter().any(|n| n == want), "{want} missing from {names:?}");
        }
    }

    #[test]
    fn shipped_scenarios_have_the_specified_settings() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
        let load = |n: &str| Scenario::load(dir.join(n)).unwrap_or_else(|e| unreachable!("{e}"));
        for (file, motion, method) in [
            ("motion_a_ff.toml", MotionKind::A, Method::Ff),
            ("motion_a_ga.toml", MotionKind::A, Method::Ga),
            ("motion_b_ff.toml", MotionKind::B, Method::Ff),
            ("motion_b_ga.toml", MotionKind::B, Method::Ga),
        ] {
            let s = load(file);
            assert_eq!((s.robot.motion, s.method, s.seed, s.duration_s), (motion, method, 1, 72.0), "{file}");
            assert_eq!(s.robot.omega_rad_s, 0.125, "{file}");
        }
        let smoke = load("smoke.toml");
        assert_eq!(
            (smoke.robot.motion, smoke.robot.omega_rad_s, smoke.method, smoke.duration_s),
            (MotionKind::A, 0.5, Method::Ff, 3.0)
        );
        assert_eq!(load("static.toml").robot.motion, MotionKind::Static);
    }
}
