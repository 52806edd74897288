//! The checks after deserialisation: ranges with one-line messages naming the key, and the
//! translation of the toml deserializer's errors into the same messages (the key's dotted path,
//! `expected …, got …`, `unknown key (expected one of: …)`).

use serde::de::DeserializeOwned;
use toml::de::{DeTable, DeValue};
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

/// `x` (or `default` when the key is absent), checked against `lo` and `hi`.
pub(super) fn float_in(field: &str, x: Option<f64>, default: f64, lo: Bound, hi: f64) -> Result<f64> {
    let x = x.unwrap_or(default);
    check_range(field, x, lo, hi)?;
    Ok(x)
}

/// `x` (or `default` when the key is absent), checked to lie in `lo..=hi`.
pub(super) fn int_in(field: &str, x: Option<i64>, default: i64, lo: i64, hi: i64) -> Result<i64> {
    let x = x.unwrap_or(default);
    if (lo..=hi).contains(&x) { Ok(x) } else { Err(invalid(field, format!("must be in {lo}..={hi}, got {x}"))) }
}

/// The error for a required key that is absent.
pub(super) fn missing(field: &str) -> ScenarioError {
    invalid(field, "missing (this key is required)")
}

/// `a string ("x")`, `an array`, … for error messages.
pub(super) fn describe(v: &Value) -> String {
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

/// `text` (already parsed into `table`) deserialised into `T`; the deserializer's error as a
/// [`ScenarioError::Invalid`] naming the key.
pub(super) fn deserialize<T: DeserializeOwned>(text: &str, table: &Table) -> Result<T> {
    toml::from_str(text).map_err(|e| translate(text, table, &e))
}

/// One step of a key's path: a table's key or an array's index.
enum Step {
    Key(String),
    Index(usize),
}

/// The dotted name of `path`: `camera.width`, `target.size_m[1]`.
fn dotted(path: &[Step]) -> String {
    let mut out = String::new();
    for step in path {
        match step {
            Step::Key(k) if out.is_empty() => out += k,
            Step::Key(k) => out += &format!(".{k}"),
            Step::Index(i) => out += &format!("[{i}]"),
        }
    }
    out
}

/// The deserializer's error `e` in the words of a scenario error: its span gives the key (an
/// unknown key's name or a value's), the parsed `table` the value it is about.
fn translate(text: &str, table: &Table, e: &toml::de::Error) -> ScenarioError {
    let message = e.message().trim_end();
    let found = e.span().and_then(|span| {
        let doc = DeTable::parse(text).ok()?;
        find_in_table(doc.get_ref(), &span, &mut Vec::new())
    });
    let Some((path, at)) = found else { return ScenarioError::Syntax(message.to_owned()) };
    let field = dotted(&path);
    let value = lookup(table, &path);
    if let Some(rest) = message.strip_prefix("unknown field `") {
        // A datetime reaches a table's fields as a one-key table of toml's own.
        if at == At::Value && matches!(value, Some(Value::Datetime(_))) {
            return invalid(field, "expected a table, got a datetime");
        }
        let known = rest.split_once(", expected ").map_or("", |(_, list)| list);
        let known = known.trim_start_matches("one of ").replace(" or ", ", ").replace('`', "");
        return invalid(field, format!("unknown key (expected one of: {known})"));
    }
    match (message.strip_prefix("invalid type: ").and_then(|m| m.rsplit_once(", expected ")), value) {
        (Some((_, want)), Some(v)) => invalid(field, format!("expected {}, got {}", expected(want), describe(v))),
        _ => invalid(field, message),
    }
}

/// serde's name of an expected type as the messages word it.
fn expected(want: &str) -> &str {
    match want {
        "i64" => "an integer",
        "f64" => "a number",
        w => w,
    }
}

/// Whether an error's span is a key's or a value's.
#[derive(Clone, Copy, PartialEq, Eq)]
enum At {
    Key,
    Value,
}

type Found = Option<(Vec<Step>, At)>;

/// The path of the key or value at `span` in `t`, under `path`.
fn find_in_table(t: &DeTable<'_>, span: &std::ops::Range<usize>, path: &mut Vec<Step>) -> Found {
    for (k, v) in t {
        path.push(Step::Key(k.get_ref().to_string()));
        if k.span() == *span {
            return Some((std::mem::take(path), At::Key));
        }
        if v.span() == *span {
            return Some((std::mem::take(path), At::Value));
        }
        if let Some(found) = find_in_value(v.get_ref(), span, path) {
            return Some(found);
        }
        path.pop();
    }
    None
}

fn find_in_value(v: &DeValue<'_>, span: &std::ops::Range<usize>, path: &mut Vec<Step>) -> Found {
    match v {
        DeValue::Table(t) => find_in_table(t, span, path),
        DeValue::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                path.push(Step::Index(i));
                if item.span() == *span {
                    return Some((std::mem::take(path), At::Value));
                }
                if let Some(found) = find_in_value(item.get_ref(), span, path) {
                    return Some(found);
                }
                path.pop();
            }
            None
        }
        _ => None,
    }
}

/// The value at `path` in `table`, if there is one (an unknown key's value too).
fn lookup<'a>(table: &'a Table, path: &[Step]) -> Option<&'a Value> {
    let (Step::Key(first), rest) = path.split_first()? else { return None };
    let mut v = table.get(first)?;
    for step in rest {
        v = match (step, v) {
            (Step::Key(k), Value::Table(t)) => t.get(k)?,
            (Step::Index(i), Value::Array(a)) => a.get(*i)?,
            _ => return None,
        };
    }
    Some(v)
}
