//! `[tracker]`: the tracker's whole tuning, keyed by the core's field table
//! ([`evorec_core::tuning::FIELDS`]): `method = "ff"`, `ga.mutation_prob = 0.9`,
//! `target.acceleration_m_s2 = 1.0`, … Dotted keys and sub-tables (`[tracker.ga]`) are the
//! same to TOML; the table is walked by the core's names, so every field the core has is
//! accepted here and nothing else. An absent key keeps its value of the base the table is
//! read over (a scenario's: [`Tuning::DEFAULT`]). The same table is a scenario's, a
//! `--config` file's and a run's `config.toml`.

use std::path::Path;

use evorec_core::tuning::{FIELDS, Kind, Tuning, Value as FieldValue};
use serde::ser::{Serialize, SerializeMap, Serializer};
use toml::{Table, Value};

use super::{HOST_POPULATION_CAPACITY, Result, ScenarioError, invalid};

/// A scenario's or a configuration file's `[tracker]` table, as the core's [`Tuning`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TrackerTable(pub Tuning);

/// Reads the `[tracker]` table `t` (its path in messages: `path`) over `base`, then checks the
/// result for the host's population capacity ([`Tuning::validate`]).
///
/// # Errors
/// [`ScenarioError::Invalid`] naming the key: unknown, of the wrong type, or breaking its rule.
pub fn parse_tracker(t: Option<&Table>, base: Tuning, path: &str) -> Result<Tuning> {
    let mut tuning = base;
    if let Some(t) = t {
        set_keys(&mut tuning, t, "", path)?;
    }
    tuning.validate(HOST_POPULATION_CAPACITY).map_err(|e| invalid(format!("{path}.{}", e.field), e.rule.to_owned()))?;
    Ok(tuning)
}

/// Old names of fields, still accepted (old name, the field's name): the status counts were
/// named in generations, but count frames (one status decision per frame).
pub const OLD_NAMES: [(&str, &str); 3] = [
    ("status.confirm_generations", "status.confirm_frames"),
    ("status.lose_generations", "status.lose_frames"),
    ("status.lost_generations_to_search", "status.lost_frames_to_search"),
];

/// Sets every key of `t` (dotted names under `prefix`; an [`OLD_NAMES`] name as its field's) in
/// `tuning`.
fn set_keys(tuning: &mut Tuning, t: &Table, prefix: &str, path: &str) -> Result<()> {
    for (key, value) in t {
        let name = format!("{prefix}{key}");
        if let Value::Table(sub) = value {
            set_keys(tuning, sub, &format!("{name}."), path)?;
            continue;
        }
        let field = format!("{path}.{name}");
        let name = match OLD_NAMES.iter().find(|(old, _)| *old == name) {
            Some((_, new)) if t.contains_key(new.rsplit('.').next().unwrap_or(new)) => {
                return Err(invalid(field, format!("is the old name of {path}.{new}: give one of them")));
            }
            Some((_, new)) => (*new).to_owned(),
            None => name,
        };
        let Some(f) = FIELDS.iter().find(|f| f.name == name) else {
            return Err(invalid(field, "unknown key (`evorec config` lists every key)"));
        };
        let v = field_value(f.kind, value).ok_or_else(|| invalid(&field, expected(f.kind, value)))?;
        (f.set)(tuning, v).map_err(|rule| invalid(&field, rule.to_owned()))?;
    }
    Ok(())
}

/// `value` as a value of `kind`, if it is one.
fn field_value(kind: Kind, value: &Value) -> Option<FieldValue> {
    match (kind, value) {
        (Kind::Real, Value::Float(x)) => real(*x),
        (Kind::Real, Value::Integer(i)) => real(*i as f64),
        (Kind::Int, Value::Integer(i)) => u32::try_from(*i).ok().map(FieldValue::Int),
        (Kind::Name(names), Value::String(s)) => names.iter().find(|n| **n == s).map(|n| FieldValue::Name(n)),
        _ => None,
    }
}

/// An `f32` field's value: NaN and infinities pass (the rules refuse them), a finite value
/// beyond `f32`'s range does not.
fn real(x: f64) -> Option<FieldValue> {
    (!x.is_finite() || x.abs() <= f64::from(f32::MAX)).then_some(FieldValue::Real(x as f32))
}

fn expected(kind: Kind, got: &Value) -> String {
    let want = match kind {
        Kind::Real => "a number".to_owned(),
        Kind::Int => "a non-negative integer".to_owned(),
        Kind::Name(names) => format!("one of \"{}\"", names.join("\", \"")),
    };
    format!("expected {want}, got {got}")
}

/// A field's value as TOML text: a real as the shortest decimal of its `f32` (so it reads back
/// bit for bit), always with a decimal point.
fn toml_text(v: FieldValue) -> String {
    match v {
        FieldValue::Real(x) if x.is_nan() => "nan".to_owned(),
        FieldValue::Real(x) if x.is_infinite() => if x > 0.0 { "inf" } else { "-inf" }.to_owned(),
        FieldValue::Real(x) => {
            let s = format!("{x:?}");
            if s.contains(['.', 'e']) { s } else { format!("{s}.0") }
        }
        FieldValue::Int(n) => n.to_string(),
        FieldValue::Name(s) => format!("\"{s}\""),
    }
}

impl TrackerTable {
    /// Whether every field is the core's default.
    pub fn is_default(&self) -> bool {
        self.0 == Tuning::DEFAULT
    }

    /// The `[tracker]` table as TOML, every field in table order with a comment giving its
    /// unit and meaning; [`TrackerTable::from_toml_str`] reads it back to the same tuning.
    pub fn to_toml(&self) -> String {
        let mut out = String::from("[tracker]\n");
        for f in &FIELDS {
            let unit = if f.unit.is_empty() { String::new() } else { format!("[{}] ", f.unit) };
            out += &format!("# {unit}{}\n{} = {}\n", f.meaning, f.name, toml_text((f.get)(&self.0)));
        }
        out
    }

    /// Reads a configuration file's text: a `[tracker]` table and nothing else, over `base`.
    ///
    /// # Errors
    /// [`ScenarioError::Syntax`], or [`ScenarioError::Invalid`] naming the key.
    pub fn from_toml_str(text: &str, base: Tuning) -> Result<Self> {
        let table: Table =
            toml::from_str(text).map_err(|e| ScenarioError::Syntax(e.to_string().trim_end().to_owned()))?;
        if let Some(k) = table.keys().find(|k| *k != "tracker") {
            return Err(invalid(k.as_str(), "unknown key (a configuration file holds a [tracker] table only)"));
        }
        let t = match table.get("tracker") {
            None => None,
            Some(Value::Table(t)) => Some(t),
            Some(_) => return Err(invalid("tracker", "expected a table")),
        };
        Ok(Self(parse_tracker(t, base, "tracker")?))
    }

    /// [`TrackerTable::from_toml_str`] of a file, over `base`.
    ///
    /// # Errors
    /// [`ScenarioError::Io`], or [`ScenarioError::InFile`] naming the file.
    pub fn load(path: impl AsRef<Path>, base: Tuning) -> Result<Self> {
        let path = path.as_ref();
        let text =
            std::fs::read_to_string(path).map_err(|source| ScenarioError::Io { path: path.to_path_buf(), source })?;
        Self::from_toml_str(&text, base)
            .map_err(|e| ScenarioError::InFile { path: path.to_path_buf(), source: Box::new(e) })
    }
}

/// `base` overridden by the configuration file at `path`, if one is given.
///
/// # Errors
/// As [`TrackerTable::load`].
pub fn with_config_file(base: Tuning, path: Option<&Path>) -> Result<Tuning> {
    match path {
        Some(p) => Ok(TrackerTable::load(p, base)?.0),
        None => Ok(base),
    }
}

/// Into JSON and TOML as a map of the dotted names to their values (reals through their
/// shortest decimal, as in [`TrackerTable::to_toml`]).
impl Serialize for TrackerTable {
    fn serialize<S: Serializer>(&self, ser: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = ser.serialize_map(Some(FIELDS.len()))?;
        for f in &FIELDS {
            match (f.get)(&self.0) {
                FieldValue::Real(x) => {
                    map.serialize_entry(f.name, &x.to_string().parse::<f64>().unwrap_or(f64::NAN))?
                }
                FieldValue::Int(n) => map.serialize_entry(f.name, &n)?,
                FieldValue::Name(s) => map.serialize_entry(f.name, s)?,
            }
        }
        map.end()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_printed_table_reads_back_to_the_same_tuning() {
        let text = TrackerTable::default().to_toml();
        assert_eq!(TrackerTable::from_toml_str(&text, Tuning::DEFAULT).unwrap().0, Tuning::DEFAULT);
        let mut t = Tuning::DEFAULT;
        t.ga.mutation_prob = 0.123_456_79;
        t.target.max_gap_s = 1e-3;
        t.feedforward = evorec_core::Feedforward::OnWithTarget;
        t.acquire.scan_chunk = 77;
        let text = TrackerTable(t).to_toml();
        let mut zero = Tuning::DEFAULT;
        zero.ga.mutation_prob = 0.0;
        assert_eq!(TrackerTable::from_toml_str(&text, zero).unwrap().0, t);
    }

    #[test]
    fn dotted_keys_and_subtables_are_the_same() {
        let a = TrackerTable::from_toml_str("[tracker]\nga.mutation_prob = 0.5\n", Tuning::DEFAULT).unwrap();
        let b = TrackerTable::from_toml_str("[tracker.ga]\nmutation_prob = 0.5\n", Tuning::DEFAULT).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.0.ga.mutation_prob, 0.5);
    }

    #[test]
    fn the_old_names_of_the_status_counts_are_still_read() {
        let read = |text: &str| TrackerTable::from_toml_str(text, Tuning::DEFAULT).map(|t| t.0.status);
        let old = read(
            "[tracker]\nstatus.confirm_generations = 4\nstatus.lose_generations = 2\n\
                        status.lost_generations_to_search = 90\n",
        )
        .unwrap();
        let new = read("[tracker.status]\nconfirm_frames = 4\nlose_frames = 2\nlost_frames_to_search = 90\n").unwrap();
        assert_eq!(old, new);
        assert_eq!((new.confirm_frames, new.lose_frames, new.lost_frames_to_search), (4, 2, 90));
        let both = read("[tracker]\nstatus.lose_frames = 2\nstatus.lose_generations = 2\n").unwrap_err().to_string();
        assert_eq!(
            both,
            "tracker.status.lose_generations: is the old name of tracker.status.lose_frames: give one of them"
        );
        assert!(TrackerTable::default().to_toml().contains("status.lose_frames = 1"));
    }

    #[test]
    fn errors_name_the_key() {
        let err = |text: &str| TrackerTable::from_toml_str(text, Tuning::DEFAULT).unwrap_err().to_string();
        assert_eq!(err("[tracker]\nga.mutation_prob = 1.5"), "tracker.ga.mutation_prob: must be in [0, 1]");
        assert!(err("[tracker]\nga.mutaton_prob = 0.5").starts_with("tracker.ga.mutaton_prob: unknown key"));
        assert!(err("[tracker]\nmethod = \"fast\"").starts_with("tracker.method: expected one of \"ga\""));
        assert!(err("[tracker]\nga.population = 65").starts_with("tracker.ga.population: must be at least 2"));
        assert!(err("[tracker]\nacquire.scan_stride = -1").starts_with("tracker.acquire.scan_stride: expected"));
        assert!(err("seed = 1").starts_with("seed: unknown key"));
    }
}
