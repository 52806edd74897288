//! The acquisition keys of a scenario file: `[start] initial`, `[target] placement` and the
//! `[[occlusion]]` array (the types and the occluder's rendering are in [`crate::sim::occlusion`]).

use toml::Value;

use super::{ScenarioError, invalid};
use crate::sim::occlusion::{Initial, MAX_OCCLUSIONS, Occlusion, OcclusionKind, Occlusions, Placement};

/// Parses `initial` of `[tracker]` (`None`: the default).
///
/// # Errors
/// One [`ScenarioError::Invalid`] naming `start.initial`.
pub fn parse_initial(v: Option<&Value>) -> Result<Initial, ScenarioError> {
    match v {
        None => Ok(Initial::Truth),
        Some(Value::String(s)) if s == "truth" => Ok(Initial::Truth),
        Some(Value::String(s)) if s == "unknown" => Ok(Initial::Unknown),
        Some(other) => Err(invalid("start.initial", format!("expected \"truth\" or \"unknown\", got {other}"))),
    }
}

/// Parses `placement` of `[target]` (`None`: the default).
///
/// # Errors
/// One [`ScenarioError::Invalid`] naming `target.placement`.
pub fn parse_placement(v: Option<&Value>) -> Result<Placement, ScenarioError> {
    match v {
        None => Ok(Placement::Fixed),
        Some(Value::String(s)) if s == "fixed" => Ok(Placement::Fixed),
        Some(Value::String(s)) if s == "random" => Ok(Placement::Random),
        Some(other) => Err(invalid("target.placement", format!("expected \"fixed\" or \"random\", got {other}"))),
    }
}

/// Parses the top-level `occlusion` array of tables against the run's `duration_s`.
///
/// # Errors
/// One [`ScenarioError::Invalid`] naming the entry and field, e.g. `occlusion[1].duration_s`.
pub fn parse_occlusions(v: Option<&Value>, duration_s: f64) -> Result<Occlusions, ScenarioError> {
    let Some(v) = v else { return Ok(Occlusions::default()) };
    let Value::Array(list) = v else {
        return Err(invalid("occlusion", "expected an array of tables ([[occlusion]])"));
    };
    if list.len() > MAX_OCCLUSIONS {
        return Err(invalid("occlusion", format!("at most {MAX_OCCLUSIONS} entries, got {}", list.len())));
    }
    let mut out = Vec::with_capacity(list.len());
    for (i, item) in list.iter().enumerate() {
        let name = |k: &str| format!("occlusion[{i}].{k}");
        let Value::Table(t) = item else {
            return Err(invalid(format!("occlusion[{i}]"), "expected a table"));
        };
        if let Some(k) = t.keys().find(|k| !["start_s", "duration_s", "kind"].contains(&k.as_str())) {
            return Err(invalid(name(k), "unknown key (expected one of: start_s, duration_s, kind)"));
        }
        let num = |k: &str| -> Result<f64, ScenarioError> {
            match t.get(k) {
                None => Err(invalid(name(k), "missing (this key is required)")),
                Some(Value::Float(x)) => Ok(*x),
                Some(Value::Integer(n)) => Ok(*n as f64),
                Some(other) => Err(invalid(name(k), format!("expected a number, got {other}"))),
            }
        };
        let start_s = num("start_s")?;
        if !(start_s.is_finite() && (0.0..=duration_s).contains(&start_s)) {
            return Err(invalid(name("start_s"), format!("must be in [0, {duration_s}] (the run), got {start_s}")));
        }
        let d = num("duration_s")?;
        if !(d.is_finite() && d > 0.0 && d <= 3600.0) {
            return Err(invalid(name("duration_s"), format!("must be in (0, 3600], got {d}")));
        }
        let kind = match t.get("kind") {
            None => OcclusionKind::Occluder,
            Some(Value::String(s)) if s == "occluder" => OcclusionKind::Occluder,
            Some(Value::String(s)) if s == "removed" => OcclusionKind::Removed,
            Some(other) => {
                return Err(invalid(name("kind"), format!("expected \"occluder\" or \"removed\", got {other}")));
            }
        };
        out.push(Occlusion { start_s, duration_s: d, kind });
    }
    Ok(Occlusions::from_slice(&out))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn occ(text: &str, duration: f64) -> Result<Occlusions, ScenarioError> {
        let t: toml::Table = toml::from_str(text).unwrap_or_else(|e| unreachable!("{e}"));
        parse_occlusions(t.get("occlusion"), duration)
    }

    #[test]
    fn occlusions_parse_and_errors_name_the_entry() {
        let o = occ("[[occlusion]]\nstart_s = 1\nduration_s = 0.5\n[[occlusion]]\nstart_s = 2.0\nduration_s = 1\nkind = \"removed\"\n", 5.0)
            .unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(o.iter().count(), 2);
        assert_eq!(o.at(1.2), Some(OcclusionKind::Occluder));
        assert_eq!(o.at(1.5), None);
        assert_eq!(o.at(2.9), Some(OcclusionKind::Removed));
        let e = |t: &str| occ(t, 5.0).err().map(|e| e.to_string()).unwrap_or_default();
        assert_eq!(
            e("[[occlusion]]\nstart_s = 9\nduration_s = 1\n"),
            "occlusion[0].start_s: must be in [0, 5] (the run), got 9"
        );
        assert_eq!(
            e("[[occlusion]]\nstart_s = 1\nduration_s = 1\n[[occlusion]]\nstart_s = 1\n"),
            "occlusion[1].duration_s: missing (this key is required)"
        );
        assert_eq!(
            e("[[occlusion]]\nstart_s = 1\nduration_s = 1\nkind = \"hand\"\n"),
            "occlusion[0].kind: expected \"occluder\" or \"removed\", got \"hand\""
        );
        assert!(
            e("[[occlusion]]\nstart_s = 1\nduration_s = 1\nwhen = 2\n").starts_with("occlusion[0].when: unknown key")
        );
        assert_eq!(e("occlusion = 3\n"), "occlusion: expected an array of tables ([[occlusion]])");
    }

    #[test]
    fn initial_and_placement_values() {
        assert_eq!(parse_initial(Some(&Value::String("unknown".into()))).ok(), Some(Initial::Unknown));
        assert_eq!(
            parse_initial(Some(&Value::Integer(1))).err().map(|e| e.to_string()),
            Some("start.initial: expected \"truth\" or \"unknown\", got 1".to_owned())
        );
        assert_eq!(parse_placement(None).ok(), Some(Placement::Fixed));
        assert!(parse_placement(Some(&Value::String("anywhere".into()))).is_err());
    }
}
