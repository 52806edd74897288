//! `[target_filter]`: the tuning of the target-velocity filter that `method = "ff+target"`
//! feeds forward (the core's [`TargetFilterParams`]). Every key is optional and named as the
//! core's field; an absent key keeps [`TargetFilterParams::DEFAULT`]. A rig whose blocks move
//! differently from the simulator's (a faster belt, a hand) tunes it here instead of in a
//! rebuilt core.

use evorec_core::target_motion::TargetFilterParams;
use serde::ser::{Serialize, SerializeMap, Serializer};
use toml::Value;

use super::section::Section;
use super::{Result, ScenarioError, invalid};

/// Generates the name lists and the by-name accessors of the parameters' fields of one type.
macro_rules! fields {
    ($names:ident, $get:ident, $set:ident, $ty:ty, [$($f:ident),* $(,)?]) => {
        const $names: &[&str] = &[$(stringify!($f)),*];

        fn $get(p: &TargetFilterParams, name: &str) -> Option<$ty> {
            match name {
                $(stringify!($f) => Some(p.$f),)*
                _ => None,
            }
        }

        fn $set(p: &mut TargetFilterParams, name: &str, v: $ty) {
            match name {
                $(stringify!($f) => p.$f = v,)*
                _ => {}
            }
        }
    };
}

fields!(
    REAL_KEYS,
    get_real,
    set_real,
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
fields!(COUNT_KEYS, get_count, set_count, u16, [max_outliers, converge_updates]);
fields!(FLAG_KEYS, get_flag, set_flag, bool, [hold_motion, linear_motion_mutes_angular]);

/// The `[target_filter]` section: the filter's parameters (the defaults when the section is
/// absent). Written back to TOML and into `summary.json` only when it differs from the
/// defaults, in full then, so a run's record names the tuning it ran with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetFilterSection(pub TargetFilterParams);

impl Default for TargetFilterSection {
    fn default() -> Self {
        Self(TargetFilterParams::DEFAULT)
    }
}

impl TargetFilterSection {
    /// Whether every parameter is the core's default.
    pub fn is_default(&self) -> bool {
        self.0 == TargetFilterParams::DEFAULT
    }
}

impl Serialize for TargetFilterSection {
    fn serialize<S: Serializer>(&self, ser: S) -> std::result::Result<S::Ok, S::Error> {
        let p = &self.0;
        let mut map = ser.serialize_map(Some(REAL_KEYS.len() + COUNT_KEYS.len() + FLAG_KEYS.len()))?;
        for k in REAL_KEYS {
            // Through the shortest decimal of the f32, so that 0.001 is written as 0.001.
            let v: f64 = get_real(p, k).map_or(f64::NAN, |v| v.to_string().parse().unwrap_or(f64::NAN));
            map.serialize_entry(k, &v)?;
        }
        for k in COUNT_KEYS {
            map.serialize_entry(k, &get_count(p, k))?;
        }
        for k in FLAG_KEYS {
            map.serialize_entry(k, &get_flag(p, k))?;
        }
        map.end()
    }
}

/// Parses `[target_filter]`: known keys, each of its type, then the core's own validation
/// ([`TargetFilterParams::validate`]), whose rule is reported with the key's path.
pub(super) fn parse_target_filter(s: &Section<'_>) -> Result<TargetFilterSection> {
    let known: Vec<&str> = REAL_KEYS.iter().chain(COUNT_KEYS).chain(FLAG_KEYS).copied().collect();
    s.check_keys(&known)?;
    let mut p = TargetFilterParams::DEFAULT;
    for k in REAL_KEYS {
        if s.get(k).is_some() {
            let v = s.float(k, None)?;
            // Outside f32's range the value would become infinite: say so in f64 terms.
            if v.is_finite() && v.abs() > f64::from(f32::MAX) {
                return Err(invalid(s.path(k), format!("must fit a 32-bit float, got {v}")));
            }
            set_real(&mut p, k, v as f32);
        }
    }
    for k in COUNT_KEYS {
        if s.get(k).is_some() {
            let v = s.int_in(k, 0, 0, i64::from(u16::MAX))?;
            set_count(&mut p, k, u16::try_from(v).unwrap_or(u16::MAX));
        }
    }
    for k in FLAG_KEYS {
        match s.get(k) {
            None => {}
            Some(Value::Boolean(b)) => set_flag(&mut p, k, *b),
            Some(v) => return Err(invalid(s.path(k), format!("expected true or false, got {v}"))),
        }
    }
    p.validate().map_err(|e| invalid(s.path(e.0), format!("{}, got {}", e.rule(), value_of(&p, e.0))))?;
    Ok(TargetFilterSection(p))
}

/// The value of the field `name` as text (for an error message).
fn value_of(p: &TargetFilterParams, name: &str) -> String {
    get_real(p, name)
        .map(|v| v.to_string())
        .or_else(|| get_count(p, name).map(|v| v.to_string()))
        .or_else(|| get_flag(p, name).map(|v| v.to_string()))
        .unwrap_or_default()
}

impl TargetFilterSection {
    /// Reads a `[target_filter]` table on its own (the same text as in a scenario file, and
    /// nothing else), e.g. for `evorec servo --target-filter FILE`.
    ///
    /// # Errors
    /// As [`Scenario::from_toml_str`](super::Scenario::from_toml_str) for that section, and a
    /// top-level key other than `target_filter`.
    pub fn from_toml_str(text: &str) -> Result<Self> {
        let table: toml::Table =
            toml::from_str(text).map_err(|e| ScenarioError::Syntax(e.to_string().trim_end().to_owned()))?;
        let top = Section::new("", &table, &["target_filter"])?;
        parse_target_filter(&top.subtable("target_filter")?)
    }

    /// [`TargetFilterSection::from_toml_str`] of a file.
    ///
    /// # Errors
    /// [`ScenarioError::Io`] if the file cannot be read, otherwise [`ScenarioError::InFile`]
    /// naming it.
    pub fn load(path: impl AsRef<std::path::Path>) -> Result<Self> {
        let path = path.as_ref();
        let text =
            std::fs::read_to_string(path).map_err(|source| ScenarioError::Io { path: path.to_path_buf(), source })?;
        Self::from_toml_str(&text).map_err(|e| ScenarioError::InFile { path: path.to_path_buf(), source: Box::new(e) })
    }
}
