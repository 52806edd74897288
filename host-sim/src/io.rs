//! File output: the trace CSV and JSON documents. The only module that writes files.

use std::path::Path;

use anyhow::{Context, Result};
use serde::Serialize;

use crate::sim::TraceRow;

/// Header of `trace.csv`.
pub fn trace_header() -> Vec<String> {
    let mut h = vec!["t".to_owned()];
    h.extend((1..=7).map(|i| format!("q{i}")));
    h.extend((1..=7).map(|i| format!("qd{i}")));
    for prefix in ["", "est_"] {
        for c in ["x_mm", "y_mm", "z_mm", "e1", "e2", "e3"] {
            h.push(format!("{prefix}{c}"));
        }
    }
    h.push("F".to_owned());
    h.push("status".to_owned());
    h.push("hidden".to_owned());
    h
}

/// Writes `rows` as `trace.csv` (one row per frame; see [`trace_header`]).
///
/// # Errors
/// I/O errors.
pub fn write_trace(path: &Path, rows: &[TraceRow]) -> Result<()> {
    let mut w = csv::Writer::from_path(path).with_context(|| format!("creating {}", path.display()))?;
    w.write_record(trace_header())?;
    for r in rows {
        let mut rec: Vec<String> = Vec::with_capacity(36);
        rec.push(format!("{:.3}", r.t));
        rec.extend(r.q.iter().chain(r.qd.iter()).map(|v| format!("{v:.6}")));
        for psi in [&r.truth, &r.estimate] {
            rec.extend(psi.0[..3].iter().map(|v| format!("{:.4}", v * 1e3)));
            rec.extend(psi.0[3..].iter().map(|v| format!("{v:.6}")));
        }
        rec.push(format!("{:.5}", r.fitness));
        rec.push(r.status.as_str().to_owned());
        rec.push(u8::from(r.hidden).to_string());
        w.write_record(&rec)?;
    }
    w.flush()?;
    Ok(())
}

/// Writes `value` as pretty JSON.
///
/// # Errors
/// I/O or serialisation errors.
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    std::fs::write(path, text + "\n").with_context(|| format!("writing {}", path.display()))
}
