//! Typed, field-naming look-ups in the TOML tables of a scenario file.

use toml::{Table, Value};

use super::{Result, ScenarioError, invalid};

/// Lower end of a range check.
#[derive(Clone, Copy)]
pub(super) enum Bound {
    Open(f64),
    Closed(f64),
}

pub(super) fn check_range(field: &str, x: f64, lo: Bound, hi: f64) -> Result<()> {
    check_range_why(field, x, lo, hi, "")
}

pub(super) fn check_range_why(field: &str, x: f64, lo: Bound, hi: f64, why: &str) -> Result<()> {
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
pub(super) struct Section<'a> {
    name: &'static str,
    pub(super) table: Option<&'a Table>,
}

impl<'a> Section<'a> {
    pub(super) fn new(name: &'static str, table: &'a Table, known: &[&str]) -> Result<Self> {
        let s = Self { name, table: Some(table) };
        s.check_keys(known)?;
        Ok(s)
    }

    /// The section of table `table` named `name`, its keys not yet checked.
    pub(super) fn named(name: &'static str, table: &'a Table) -> Self {
        Self { name, table: Some(table) }
    }

    pub(super) fn path(&self, key: &str) -> String {
        if self.name.is_empty() { key.to_owned() } else { format!("{}.{key}", self.name) }
    }

    pub(super) fn check_keys(&self, known: &[&str]) -> Result<()> {
        let Some(t) = self.table else { return Ok(()) };
        match t.keys().find(|k| !known.contains(&k.as_str())) {
            Some(k) => Err(invalid(self.path(k), format!("unknown key (expected one of: {})", known.join(", ")))),
            None => Ok(()),
        }
    }

    /// The sub-table `key` (absent → an empty section that yields defaults).
    pub(super) fn subtable(&self, key: &'static str) -> Result<Section<'a>> {
        match self.table.and_then(|t| t.get(key)) {
            None => Ok(Section { name: key, table: None }),
            Some(Value::Table(t)) => Ok(Section { name: key, table: Some(t) }),
            Some(v) => Err(invalid(self.path(key), format!("expected a table, got {}", describe(v)))),
        }
    }

    pub(super) fn get(&self, key: &str) -> Option<&'a Value> {
        self.table.and_then(|t| t.get(key))
    }

    pub(super) fn missing(&self, key: &str) -> ScenarioError {
        invalid(self.path(key), "missing (this key is required)")
    }

    pub(super) fn float(&self, key: &str, default: Option<f64>) -> Result<f64> {
        match self.get(key) {
            None => default.ok_or_else(|| self.missing(key)),
            Some(v) => {
                as_float(v).ok_or_else(|| invalid(self.path(key), format!("expected a number, got {}", describe(v))))
            }
        }
    }

    pub(super) fn float_in(&self, key: &str, default: f64, lo: Bound, hi: f64) -> Result<f64> {
        let x = self.float(key, Some(default))?;
        check_range(&self.path(key), x, lo, hi)?;
        Ok(x)
    }

    pub(super) fn int(&self, key: &str, default: Option<i64>) -> Result<i64> {
        match self.get(key) {
            None => default.ok_or_else(|| self.missing(key)),
            Some(Value::Integer(i)) => Ok(*i),
            Some(v) => Err(invalid(self.path(key), format!("expected an integer, got {}", describe(v)))),
        }
    }

    pub(super) fn int_in(&self, key: &str, default: i64, lo: i64, hi: i64) -> Result<i64> {
        let x = self.int(key, Some(default))?;
        if (lo..=hi).contains(&x) {
            Ok(x)
        } else {
            Err(invalid(self.path(key), format!("must be in {lo}..={hi}, got {x}")))
        }
    }

    pub(super) fn string(&self, key: &str, default: Option<&str>) -> Result<String> {
        match self.get(key) {
            None => default.map(str::to_owned).ok_or_else(|| self.missing(key)),
            Some(Value::String(s)) => Ok(s.clone()),
            Some(v) => Err(invalid(self.path(key), format!("expected a string, got {}", describe(v)))),
        }
    }

    pub(super) fn floats<const N: usize>(&self, key: &str, default: [f64; N]) -> Result<[f64; N]> {
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
