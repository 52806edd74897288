//! The tracker's tuning: every parameter a rig may set at run time, in one struct ([`Tuning`],
//! the `tuning` of a [`TrackerConfig`](crate::tracker::TrackerConfig)) and one table of its
//! fields ([`FIELDS`]).
//!
//! The table is the one serialization of the tuning: each [`Field`] has a dotted name
//! (`ga.mutation_prob`, `target.acceleration_m_s2`, `method`, …), a unit, a one-line meaning,
//! a validity [`Rule`], and reads and writes its value as a [`Value`]. A scenario's or a
//! configuration file's `[tracker]` table, `evorec config`, and the link's `CONFIG` message
//! all walk this table, in its order. An array (the GA's level CDFs and mutation scales, the
//! acquisition's spreads) has one entry per element, named after the element.
//!
//! The types of two of its parts are defined here and re-exported where they are used: the
//! feedforward mode ([`Feedforward`], `crate::tracker::Feedforward`) and the target motion
//! model's parameters ([`TargetFilterParams`], `crate::target_motion::TargetFilterParams`).
//!
//! What stays compiled: the population capacity `P` and the points per sample row `G` of a
//! [`Tracker`](crate::tracker::Tracker) (const generics: storage and the model's point arrays
//! are sized by them), and the model constants of [`crate::limits`].

use crate::acquire::AcquireConfig;
use crate::ga::GaParams;
use crate::limits::{DEFAULT_HUE_TOLERANCE, HUE_UNITS, MAX_GENERATIONS_PER_FRAME};
use crate::status::StatusConfig;

/// `1/√3`: the standard deviation of a uniform distribution over ±1.
const FRAC_1_SQRT_3: f32 = 0.577_350_26;

/// Whether the arm's motion, and the target's own, is fed forward to the population (eq. 36).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feedforward {
    /// Plain 1-step GA.
    Off,
    /// 1-step GA + motion feedforward of the arm (`J_m q̇`, eq. 24).
    On,
    /// 1-step GA + feedforward of the arm's and the target's motion
    /// (`J_m q̇ + J_n ^W ψ̇_M`, eq. 23), the target's velocity from the tracker's
    /// [`TargetFilter`](crate::target_motion::TargetFilter) once it has observed the velocity (until then as [`Feedforward::On`]).
    OnWithTarget,
}

impl Feedforward {
    /// Every mode, in the order of [`Feedforward::NAMES`].
    pub const ALL: [Feedforward; 3] = [Feedforward::Off, Feedforward::On, Feedforward::OnWithTarget];

    /// The modes' names, in [`Feedforward::ALL`]'s order: the spellings of a scenario's or
    /// configuration file's `[tracker] method`, of `--method`, of the `CONFIG` message and of
    /// the firmware's timing lines.
    pub const NAMES: [&'static str; 3] = ["ga", "ff", "ff+target"];

    /// The mode's name ([`Feedforward::NAMES`]): `ga`, `ff` or `ff+target`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Off => Self::NAMES[0],
            Self::On => Self::NAMES[1],
            Self::OnWithTarget => Self::NAMES[2],
        }
    }
}

/// The mode's name ([`Feedforward::name`]).
impl core::fmt::Display for Feedforward {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.pad(self.name())
    }
}

/// Parses a name of [`Feedforward::NAMES`] (exactly, case included).
impl core::str::FromStr for Feedforward {
    type Err = UnknownFeedforward;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let found = Self::ALL.into_iter().find(|f| f.name() == text);
        found.ok_or_else(|| UnknownFeedforward::new(text))
    }
}

/// A text that names no [`Feedforward`] mode. It keeps the text (its first
/// [`UnknownFeedforward::KEPT`] bytes, cut at a character boundary, without allocating) and
/// displays as `expected "ga", "ff" or "ff+target", got "<text>"`.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct UnknownFeedforward {
    bytes: [u8; Self::KEPT],
    len: u8,
    cut: bool,
}

impl UnknownFeedforward {
    /// The most bytes of the bad text kept (a longer text is shown cut, ending in `…`).
    pub const KEPT: usize = 32;

    fn new(text: &str) -> Self {
        let mut len = text.len().min(Self::KEPT);
        while !text.is_char_boundary(len) {
            len -= 1;
        }
        let mut bytes = [0; Self::KEPT];
        bytes[..len].copy_from_slice(&text.as_bytes()[..len]);
        // `len` ≤ KEPT = 32 fits a u8.
        Self { bytes, len: len as u8, cut: len < text.len() }
    }

    /// The bad text as kept (cut to [`UnknownFeedforward::KEPT`] bytes).
    pub fn text(&self) -> &str {
        // Cut at a character boundary of a `str`, so always valid UTF-8.
        core::str::from_utf8(&self.bytes[..usize::from(self.len)]).unwrap_or("")
    }
}

impl core::fmt::Debug for UnknownFeedforward {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("UnknownFeedforward").field("text", &self.text()).field("cut", &self.cut).finish()
    }
}

impl core::fmt::Display for UnknownFeedforward {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let [ga, ff, ff_target] = Feedforward::NAMES;
        let more = if self.cut { "…" } else { "" };
        write!(f, "expected \"{ga}\", \"{ff}\" or \"{ff_target}\", got \"{}{more}\"", self.text())
    }
}

impl core::error::Error for UnknownFeedforward {}

/// The target motion model's parameters (see [`crate::target_motion`]).
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
    /// camera model ([`crate::target_motion::Optics`]) it gives the measurement noise per camera axis: at
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

    /// The manoeuvre time (s) of the hand-over's model ([`crate::target_motion`]): how long the
    /// largest acceleration expected takes to bring the block to the largest speed expected,
    /// `max_speed_m_s / acceleration_m_s2` (0.5 s by default). An acceleration is expected to
    /// last about that long: a conveyor's start, stop or reversal.
    pub fn manoeuvre_s(&self) -> f32 {
        self.max_speed_m_s / self.acceleration_m_s2
    }

    /// The standard deviation of the hand-over model's acceleration (m/s²): an acceleration
    /// anywhere between ± `acceleration_m_s2` alike (Singer's uniform case), `acceleration_m_s2 / √3`.
    pub fn acceleration_sd(&self) -> f32 {
        self.acceleration_m_s2 * FRAC_1_SQRT_3
    }

    /// Checks that every field is finite and positive (the `target.` rows of [`FIELDS`]).
    ///
    /// # Errors
    /// [`ConfigError`] naming the first bad field (`target.…`).
    pub fn validate(&self) -> Result<(), ConfigError> {
        let t = Tuning { target: *self, ..Tuning::DEFAULT };
        let bad = FIELDS.iter().filter(|f| f.name.starts_with("target.")).find(|f| !f.rule.holds((f.get)(&t)));
        bad.map_or(Ok(()), |f| Err(ConfigError { field: f.name, rule: f.rule.text() }))
    }
}

/// Every tuning parameter of a tracker (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tuning {
    /// What is fed forward to the population: nothing, the arm's motion, or the arm's and the
    /// target's (table name `method`: `ga`, `ff`, `ff+target`).
    pub feedforward: Feedforward,
    /// Hue match half-band in hue units (2° each).
    pub hue_tolerance: u8,
    /// Largest accepted time step between frames (s); larger steps are refused.
    pub max_dt_s: f32,
    /// GA generations run on each frame pair, 1 to [`MAX_GENERATIONS_PER_FRAME`]: 1 is the
    /// paper's 1-step GA; each further generation refines on the same frame (no feedforward
    /// shift) and costs one more generation's work. The status and the target motion model
    /// are updated once per frame, from the last generation.
    pub generations_per_frame: u8,
    /// GA settings.
    pub ga: GaParams,
    /// Acquisition from the colour blobs ([`crate::acquire`]).
    pub acquire: AcquireConfig,
    /// Status thresholds ([`crate::status`]).
    pub status: StatusConfig,
    /// The target motion model ([`crate::target_motion`]).
    pub target: TargetFilterParams,
}

impl Tuning {
    /// Every default: the arm's and the block's motion fed forward (`ff+target`: a block that
    /// stands still is held as with `ff`, a moving one is followed), [`DEFAULT_HUE_TOLERANCE`],
    /// `max_dt_s` 0.5 s, two generations per frame (the most whose worst case with flash wait
    /// states fits a 33 ms frame on the Cortex-M4, `docs/results.md`), [`GaParams::DEFAULT`],
    /// [`AcquireConfig::DEFAULT`], [`StatusConfig::DEFAULT`], [`TargetFilterParams::DEFAULT`].
    /// Every command starts from it; the paper's experiment names its method per cell.
    pub const DEFAULT: Tuning = Tuning {
        feedforward: Feedforward::OnWithTarget,
        hue_tolerance: DEFAULT_HUE_TOLERANCE,
        max_dt_s: 0.5,
        generations_per_frame: 2,
        ga: GaParams::DEFAULT,
        acquire: AcquireConfig::DEFAULT,
        status: StatusConfig::DEFAULT,
        target: TargetFilterParams::DEFAULT,
    };
}

impl Default for Tuning {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A configuration field broke its rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConfigError {
    /// The field: a [`Field::name`] of the table, or `block`, `flange_to_camera`.
    pub field: &'static str,
    /// What the value must be, e.g. `must be in [0, 1]`.
    pub rule: &'static str,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "tracker.{}: {}", self.field, self.rule)
    }
}

impl core::error::Error for ConfigError {}

/// The error of a population the GA's storage cannot take: below 2 or above the tracker's
/// compiled capacity (checked by [`Tuning::validate`]).
pub(crate) const POPULATION_ERROR: ConfigError =
    ConfigError { field: "ga.population", rule: "must be at least 2 and at most the compiled capacity" };

/// A field's value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// A real number.
    Real(f32),
    /// A count or an integer setting.
    Int(u32),
    /// One of the field's [`Kind::Name`] choices.
    Name(&'static str),
}

/// The type of a field's value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// [`Value::Real`].
    Real,
    /// [`Value::Int`].
    Int,
    /// [`Value::Name`], one of these.
    Name(&'static [&'static str]),
}

/// What a field's value must be on its own (relations between fields are checked by
/// [`Tuning::validate`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rule {
    /// A probability or fitness: in `[0, 1]`.
    Unit,
    /// Finite and positive.
    Positive,
    /// Finite and not negative.
    NonNegative,
    /// Finite.
    Finite,
    /// An integer of at least 1.
    AtLeastOne,
    /// Any value of its kind.
    Any,
}

impl Rule {
    /// The rule as the end of an error message.
    pub const fn text(self) -> &'static str {
        match self {
            Self::Unit => "must be in [0, 1]",
            Self::Positive => "must be finite and positive",
            Self::NonNegative => "must be finite and non-negative",
            Self::Finite => "must be finite",
            Self::AtLeastOne => "must be at least 1",
            Self::Any => "",
        }
    }

    /// Whether `value` keeps the rule.
    pub fn holds(self, value: Value) -> bool {
        match (self, value) {
            (Self::Unit, Value::Real(x)) => (0.0..=1.0).contains(&x),
            (Self::Positive, Value::Real(x)) => x.is_finite() && x > 0.0,
            (Self::NonNegative, Value::Real(x)) => x.is_finite() && x >= 0.0,
            (Self::Finite, Value::Real(x)) => x.is_finite(),
            (Self::AtLeastOne, Value::Int(n)) => n >= 1,
            _ => true,
        }
    }
}

/// One tuning field: its name, unit, meaning, rule, and accessors.
#[derive(Clone, Copy)]
pub struct Field {
    /// Dotted name, e.g. `ga.mutation_prob` (the key in a `[tracker]` table).
    pub name: &'static str,
    /// Unit (empty for a name).
    pub unit: &'static str,
    /// What the field does, in one line.
    pub meaning: &'static str,
    /// The type of its value.
    pub kind: Kind,
    /// What its value must be on its own.
    pub rule: Rule,
    /// Reads the field.
    pub get: fn(&Tuning) -> Value,
    /// Writes the field; `Err` holds the rule a value of the wrong kind or range broke.
    pub set: fn(&mut Tuning, Value) -> Result<(), &'static str>,
}

impl core::fmt::Debug for Field {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Field").field("name", &self.name).field("unit", &self.unit).finish()
    }
}

const WRONG_KIND: &str = "has the wrong type";

fn real(v: Value) -> Result<f32, &'static str> {
    match v {
        Value::Real(x) => Ok(x),
        _ => Err("must be a number"),
    }
}

fn int<T: TryFrom<u32>>(v: Value) -> Result<T, &'static str> {
    match v {
        Value::Int(n) => T::try_from(n).map_err(|_| "is too large for its integer type"),
        _ => Err("must be an integer"),
    }
}

/// An integer field's value (saturating: a stored value is always small).
fn count<T: TryInto<u32>>(n: T) -> Value {
    Value::Int(n.try_into().unwrap_or(u32::MAX))
}

fn method_name(f: Feedforward) -> Value {
    Value::Name(f.name())
}

fn set_method(t: &mut Tuning, v: Value) -> Result<(), &'static str> {
    t.feedforward = match v {
        Value::Name(name) => name.parse().map_err(|_| "must be \"ga\", \"ff\" or \"ff+target\"")?,
        _ => return Err(WRONG_KIND),
    };
    Ok(())
}

/// A real field at `$($p)+` of a [`Tuning`].
macro_rules! real {
    ($name:literal, $unit:literal, $rule:ident, $meaning:literal, $($p:tt)+) => {
        Field {
            name: $name,
            unit: $unit,
            meaning: $meaning,
            kind: Kind::Real,
            rule: Rule::$rule,
            get: |t| Value::Real(t.$($p)+),
            set: |t, v| {
                t.$($p)+ = real(v)?;
                Ok(())
            },
        }
    };
}

/// An integer field at `$($p)+` of a [`Tuning`].
macro_rules! int {
    ($name:literal, $unit:literal, $rule:ident, $meaning:literal, $($p:tt)+) => {
        Field {
            name: $name,
            unit: $unit,
            meaning: $meaning,
            kind: Kind::Int,
            rule: Rule::$rule,
            get: |t| count(t.$($p)+),
            set: |t, v| {
                t.$($p)+ = int(v)?;
                Ok(())
            },
        }
    };
}

mod table;
pub use table::FIELDS;

/// The position of the field `name` in [`FIELDS`].
pub fn field_index(name: &str) -> Option<usize> {
    FIELDS.iter().position(|f| f.name == name)
}

/// A fingerprint of the table (FNV-1a over every name and kind, in order): a link peer built
/// from a different table refuses a `CONFIG` whose fingerprint differs.
pub const TABLE_ID: u32 = table_id();

const fn table_id() -> u32 {
    let mut h: u32 = 0x811c_9dc5;
    let mut i = 0;
    while i < FIELDS.len() {
        let name = FIELDS[i].name.as_bytes();
        let mut j = 0;
        while j < name.len() {
            h = (h ^ name[j] as u32).wrapping_mul(0x0100_0193);
            j += 1;
        }
        let kind = match FIELDS[i].kind {
            Kind::Real => 1,
            Kind::Int => 2,
            Kind::Name(_) => 3,
        };
        h = (h ^ kind).wrapping_mul(0x0100_0193);
        i += 1;
    }
    h
}

impl Tuning {
    /// The value of the field `name`, if there is one.
    pub fn get(&self, name: &str) -> Option<Value> {
        FIELDS.iter().find(|f| f.name == name).map(|f| (f.get)(self))
    }

    /// Sets the field `name` to `value` (checked only for its kind and integer range; the
    /// rules are [`Tuning::validate`]'s).
    ///
    /// # Errors
    /// [`ConfigError`] naming the field (`rule` "is not a tuning field" for an unknown name).
    pub fn set(&mut self, name: &str, value: Value) -> Result<(), ConfigError> {
        let Some(field) = FIELDS.iter().find(|f| f.name == name) else {
            return Err(ConfigError { field: "?", rule: "is not a tuning field" });
        };
        (field.set)(self, value).map_err(|rule| ConfigError { field: field.name, rule })
    }

    /// Checks every field's [`Rule`], then the relations between fields, for a tracker of
    /// population capacity `capacity`.
    ///
    /// # Errors
    /// The first [`ConfigError`], naming its field.
    pub fn validate(&self, capacity: usize) -> Result<(), ConfigError> {
        if let Some(f) = FIELDS.iter().find(|f| !f.rule.holds((f.get)(self))) {
            return Err(ConfigError { field: f.name, rule: f.rule.text() });
        }
        self.validate_relations(capacity)
    }

    fn validate_relations(&self, capacity: usize) -> Result<(), ConfigError> {
        let err = |field, rule| Err(ConfigError { field, rule });
        let (ga, acquire, status) = (&self.ga, &self.acquire, &self.status);
        if self.hue_tolerance >= HUE_UNITS / 2 {
            return err("hue_tolerance", "must be below 90 (half the hue circle)");
        }
        if !(1..=MAX_GENERATIONS_PER_FRAME).contains(&self.generations_per_frame) {
            // The rule's text and the table's meaning state the bound as a literal.
            const _: () = assert!(MAX_GENERATIONS_PER_FRAME == 4);
            return err("generations_per_frame", "must be 1 to 4 (MAX_GENERATIONS_PER_FRAME)");
        }
        if ga.population < 2 || ga.population > capacity {
            return Err(POPULATION_ERROR);
        }
        if ga.level_cdf[1] < ga.level_cdf[0] {
            return err("ga.level_cdf.medium", "must not be below ga.level_cdf.coarse");
        }
        if ga.settled_level_cdf[1] < ga.settled_level_cdf[0] {
            return err("ga.settled_level_cdf.medium", "must not be below ga.settled_level_cdf.coarse");
        }
        if ga.immigrants + 2 > ga.population {
            return err("ga.immigrants", "must leave the elite and one child: at most ga.population − 2");
        }
        if acquire.seed_immigrants + acquire.idle_individuals + 2 > ga.population {
            return err(
                "acquire.seed_immigrants",
                "plus acquire.idle_individuals must leave the elite and one child: at most ga.population − 2",
            );
        }
        if status.lose_fitness > status.acquire_fitness {
            return err("status.lose_fitness", "must not be above status.acquire_fitness");
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
