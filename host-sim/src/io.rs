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
        w.write_record(trace_record(r))?;
    }
    w.flush()?;
    Ok(())
}

/// The fields of one row of `trace.csv` (see [`trace_header`]).
pub fn trace_record(r: &TraceRow) -> Vec<String> {
    let mut rec: Vec<String> = Vec::with_capacity(34);
    rec.push(format!("{:.3}", r.t));
    rec.extend(r.q.iter().chain(r.qd.iter()).map(|v| format!("{v:.6}")));
    for psi in [&r.truth, &r.estimate] {
        rec.extend(psi.0[..3].iter().map(|v| format!("{:.4}", v * 1e3)));
        rec.extend(psi.0[3..].iter().map(|v| format!("{v:.6}")));
    }
    rec.push(format!("{:.5}", r.fitness));
    rec
}

/// Writes `trace.csv` of a closed-loop run: the columns of [`trace_header`] followed by
/// `extra_header`, one row of `rows` with its `extra` fields per frame.
///
/// # Errors
/// I/O errors, or `extra` shorter than `rows`.
pub fn write_trace_with(path: &Path, rows: &[TraceRow], extra_header: &[&str], extra: &[Vec<String>]) -> Result<()> {
    anyhow::ensure!(extra.len() >= rows.len(), "{} extra rows for {} trace rows", extra.len(), rows.len());
    let mut w = csv::Writer::from_path(path).with_context(|| format!("creating {}", path.display()))?;
    let mut header = trace_header();
    header.extend(extra_header.iter().map(|h| (*h).to_owned()));
    w.write_record(header)?;
    for (r, x) in rows.iter().zip(extra) {
        let mut rec = trace_record(r);
        rec.extend(x.iter().cloned());
        w.write_record(rec)?;
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
