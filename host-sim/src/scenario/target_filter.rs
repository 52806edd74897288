//! `[target_filter]`: the parameters of the target motion model that `method = "ff+target"`
//! feeds forward (the core's [`TargetFilterParams`]). Every key is optional and named as the
//! core's field; an absent key keeps [`TargetFilterParams::DEFAULT`]. A rig whose blocks move
//! differently from the defaults' (a faster belt, a hand) says so here instead of in a rebuilt
//! core.

use evorec_core::target_motion::{Field, TargetFilterParams};
use serde::ser::{Serialize, SerializeMap, Serializer};

use super::section::Section;
use super::{Result, ScenarioError, invalid};

/// The core's by-name table of the parameters ([`TargetFilterParams::REAL_FIELDS`]): the keys,
/// their order in the written section, and the accessors.
const REALS: &[Field<f32>] = &TargetFilterParams::REAL_FIELDS;

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
        let mut map = ser.serialize_map(Some(REALS.len()))?;
        for f in REALS {
            // Through the shortest decimal of the f32, so that 0.001 is written as 0.001.
            let v: f64 = (f.get)(p).to_string().parse().unwrap_or(f64::NAN);
            map.serialize_entry(f.name, &v)?;
        }
        map.end()
    }
}

/// Parses `[target_filter]`: known keys, each of its type, then the core's own validation
/// ([`TargetFilterParams::validate`]), whose rule is reported with the key's path.
pub(super) fn parse_target_filter(s: &Section<'_>) -> Result<TargetFilterSection> {
    let known: Vec<&str> = REALS.iter().map(|f| f.name).collect();
    s.check_keys(&known)?;
    let mut p = TargetFilterParams::DEFAULT;
    for f in REALS {
        let k = f.name;
        if s.get(k).is_some() {
            let v = s.float(k, None)?;
            // Outside f32's range the value would become infinite: say so in f64 terms.
            if v.is_finite() && v.abs() > f64::from(f32::MAX) {
                return Err(invalid(s.path(k), format!("must fit a 32-bit float, got {v}")));
            }
            (f.set)(&mut p, v as f32);
        }
    }
    p.validate().map_err(|e| invalid(s.path(e.0), format!("{}, got {}", e.rule(), value_of(&p, e.0))))?;
    Ok(TargetFilterSection(p))
}

/// The value of the field `name` as text (for an error message).
fn value_of(p: &TargetFilterParams, name: &str) -> String {
    REALS.iter().find(|f| f.name == name).map(|f| (f.get)(p).to_string()).unwrap_or_default()
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
