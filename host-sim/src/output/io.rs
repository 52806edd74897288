//! File output: the trace CSV, JSON documents, PNG images, text. The only module that writes
//! output files, and it writes every one atomically ([`write_atomic`]).
//!
//! An output file appears complete or not at all: its bytes go to a temporary file in the same
//! directory (`.NAME.XXXXXX.tmp`), which is flushed, synced to disk and then renamed over
//! `NAME` in one step. A run that fails or is killed midway leaves any earlier `NAME` as it was,
//! never a truncated file that looks complete. The temporary file comes from
//! [`tempfile::NamedTempFile`] (the `tempfile` crate: widely used, already in the dependency
//! graph; it deletes the temporary file when the write fails and renames with
//! [`NamedTempFile::persist`](tempfile::NamedTempFile::persist)); the `atomic-write-file` crate
//! does the same with fewer users and would be one more dependency.
//!
//! Not output files, and not written here: QEMU's log (`firmware/timing/qemu.rs` hands QEMU the open
//! file, which QEMU fills as it runs) and the link's FIFOs of `evorec hil`.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow};
use evorec_core::pose::Psi;
use nalgebra::Isometry3;
use serde::Serialize;

use crate::sim::board::TraceRow;

/// Creates the output directory `dir` (and its parents) and checks that a file can be created
/// in it, so a command fails before its work rather than after it.
///
/// # Errors
/// `cannot create output directory DIR: …` or `cannot write into output directory DIR: …`.
pub fn create_out_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create output directory {}", dir.display()))?;
    tempfile::Builder::new()
        .prefix(".evorec-probe")
        .tempfile_in(dir)
        .with_context(|| format!("cannot write into output directory {}", dir.display()))?;
    Ok(())
}

/// Writes the file `path` atomically (see the [module docs](self)): `write` fills a buffered
/// temporary file in the same directory, which replaces `path` only if `write` and the flush
/// succeed. On any error `path` is untouched and the temporary file is removed.
///
/// # Errors
/// `path` has no file name, the temporary file cannot be created, `write` fails, or the
/// flush, sync or rename fails; the message names `path`.
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    let name = path.file_name().ok_or_else(|| anyhow!("cannot write {}: not a file name", path.display()))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    let prefix = format!(".{}.", name.to_string_lossy());
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o644));
    let mut tmp = builder.tempfile_in(dir).with_context(|| format!("cannot create a file in {}", dir.display()))?;
    {
        let mut w = BufWriter::new(tmp.as_file_mut());
        write(&mut w).with_context(|| format!("cannot write {}", path.display()))?;
        w.flush().with_context(|| format!("cannot write {}", path.display()))?;
    }
    tmp.as_file().sync_all().with_context(|| format!("cannot write {}", path.display()))?;
    tmp.persist(path).map_err(|e| e.error).with_context(|| format!("cannot replace {}", path.display()))?;
    Ok(())
}

/// Writes `bytes` as the file `path`, atomically ([`write_atomic`]).
///
/// # Errors
/// As [`write_atomic`].
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| Ok(w.write_all(bytes)?))
}

/// Writes `img` as a PNG file, atomically ([`write_atomic`]).
///
/// # Errors
/// As [`write_atomic`], or PNG encoding errors.
pub fn write_png(path: &Path, img: &image::RgbImage) -> Result<()> {
    write_atomic(path, |w| Ok(img.write_with_encoder(image::codecs::png::PngEncoder::new(w))?))
}

/// Writes `img` as a PNG file with fast compression (a few times faster to write, a little
/// larger), atomically ([`write_atomic`]).
///
/// # Errors
/// As [`write_png`].
pub fn write_png_fast(path: &Path, img: &image::RgbImage) -> Result<()> {
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    write_atomic(path, |w| {
        Ok(img.write_with_encoder(PngEncoder::new_with_quality(w, CompressionType::Fast, FilterType::Adaptive))?)
    })
}

/// Writes the file `rel` under `dir` (creating its parent directories), atomically.
///
/// # Errors
/// As [`write_atomic`].
pub fn write_file_in(dir: &Path, rel: &str, bytes: &[u8]) -> Result<()> {
    let path = dir.join(rel);
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    }
    write_bytes(&path, bytes)
}

/// Creates the directory `out` complete or not at all: `fill` writes its contents into
/// `OUT.partial`, which is renamed to `out` when `fill` succeeds and removed when it fails.
/// `out` must not exist or be empty.
///
/// # Errors
/// A non-empty `out`, `fill`'s error, I/O errors.
pub fn write_dir<T>(out: &Path, fill: impl FnOnce(&Path) -> Result<T>) -> Result<T> {
    if out.exists() && std::fs::read_dir(out).map(|mut d| d.next().is_some()).unwrap_or(true) {
        anyhow::bail!("{}: exists and is not empty; a new directory is written there", out.display());
    }
    let mut name = out.file_name().map(std::ffi::OsStr::to_os_string).unwrap_or_default();
    name.push(".partial");
    let partial = out.with_file_name(name);
    if partial.exists() {
        std::fs::remove_dir_all(&partial).with_context(|| format!("removing {}", partial.display()))?;
    }
    std::fs::create_dir_all(&partial).with_context(|| format!("cannot create {}", partial.display()))?;
    let value = match fill(&partial) {
        Ok(v) => v,
        Err(e) => {
            let _ = std::fs::remove_dir_all(&partial);
            return Err(e);
        }
    };
    if out.exists() {
        std::fs::remove_dir(out).with_context(|| format!("replacing {}", out.display()))?;
    }
    std::fs::rename(&partial, out).with_context(|| format!("renaming {} to {}", partial.display(), out.display()))?;
    Ok(value)
}

/// Writes a table as `STEM.csv` in `out` (header `columns`, then `records`) and as `STEM.md`
/// (`markdown`), both atomically ([`write_atomic`]), creating `out` first.
///
/// # Errors
/// I/O and CSV errors.
pub fn write_table(out: &Path, stem: &str, columns: &[&str], records: &[Vec<String>], markdown: &str) -> Result<()> {
    std::fs::create_dir_all(out)?;
    write_csv(&out.join(format!("{stem}.csv")), columns, records)?;
    write_bytes(&out.join(format!("{stem}.md")), markdown.as_bytes())
}

/// Writes a CSV file (header `columns`, then `records`), atomically ([`write_atomic`]).
///
/// # Errors
/// I/O and CSV errors.
pub fn write_csv(path: &Path, columns: &[&str], records: &[Vec<String>]) -> Result<()> {
    write_atomic(path, |file| {
        let mut w = csv::Writer::from_writer(file);
        w.write_record(columns)?;
        for rec in records {
            w.write_record(rec)?;
        }
        Ok(w.flush()?)
    })
}

/// Writes `estimate.tum` into `dir` (the TUM format: one `t tx ty tz qx qy qz qw` line per
/// estimate), atomically; returns its path. `evorec track`, `run` and `hil` write it.
///
/// # Errors
/// As [`write_atomic`].
pub fn write_estimate_tum(dir: &Path, poses: &[(f64, Isometry3<f64>)], times: TumTimes) -> Result<PathBuf> {
    let path = dir.join("estimate.tum");
    let mut comment =
        "t tx ty tz qx qy qz qw: evorec's estimate of the block in the right camera frame (^CR T_M), metres".to_owned();
    let text = match times {
        TumTimes::Plain => crate::recording::sequence::tum::format(&comment, poses),
        TumTimes::Sequence => {
            comment.push_str("\nt: the sequence's time (frames.csv t_s), s");
            crate::recording::sequence::tum::format(&comment, poses)
        }
        TumTimes::SinceStamp(origin) => {
            comment.push_str(&format!(
                "\nt: s since the ROS stamp {origin} s (header.stamp = {origin} + t; --absolute-stamps writes the stamps)"
            ));
            crate::recording::sequence::tum::format(&comment, poses)
        }
        TumTimes::Absolute(origin) => {
            comment.push_str("\nt: the image's header.stamp (ROS time, s since the epoch)");
            let stamp = |t: f64| {
                let ns = i128::from(origin) * 1_000_000_000 + (t * 1e9).round() as i128;
                format!("{}.{:09}", ns.div_euclid(1_000_000_000), ns.rem_euclid(1_000_000_000))
            };
            crate::recording::sequence::tum::format_with(&comment, poses, stamp)
        }
    };
    write_bytes(&path, text.as_bytes())?;
    Ok(path)
}

/// How `estimate.tum` gives each pose's time (its second comment line says which).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum TumTimes {
    /// A simulator run's time (s), no second comment line.
    #[default]
    Plain,
    /// A recorded sequence's `frames.csv` `t_s`.
    Sequence,
    /// Seconds since the ROS stamp `origin` (s): a bag's, or a sequence's `stamp_origin_s`.
    SinceStamp(i64),
    /// The stamps themselves (`origin` + t, to the nanosecond): `--absolute-stamps`.
    Absolute(i64),
}

/// The columns of `trace.csv` that every trace has, for an arm of `dof` joints: time, joints,
/// truth, estimate, fitness, status and whether the block was hidden (`evorec track` writes
/// only these; a recording does not say when the block was hidden, so the column stays empty).
pub fn trace_columns(dof: usize) -> Vec<String> {
    let mut h = vec!["t".to_owned()];
    h.extend((1..=dof).map(|i| format!("q{i}")));
    h.extend((1..=dof).map(|i| format!("qd{i}")));
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

/// Header of `trace.csv` of a simulated run: [`trace_columns`] of the PA-10's 7 joints, then the
/// hand-over's.
pub fn trace_header() -> Vec<String> {
    let mut h = trace_columns(7);
    // The hand-over at the output time (`sim::Handover`); empty where not simulated.
    h.push("t_out".to_owned());
    for prefix in ["out_", "pred_"] {
        for c in ["x_mm", "y_mm", "z_mm", "e1", "e2", "e3"] {
            h.push(format!("{prefix}{c}"));
        }
    }
    h.push("target_trusted".to_owned());
    for prefix in ["target_", "ff_target_", "true_target_"] {
        for c in ["vx", "vy", "vz", "wx", "wy", "wz"] {
            h.push(format!("{prefix}{c}"));
        }
    }
    // The estimate's fitness per camera.
    h.push("F_left".to_owned());
    h.push("F_right".to_owned());
    h
}

/// Columns of the hand-over in [`trace_header`].
const HANDOVER_COLUMNS: usize = 1 + 12 + 1 + 18;

/// Writes `rows` as `trace.csv` (one row per frame; see [`trace_header`]), atomically.
///
/// # Errors
/// I/O errors.
pub fn write_trace(path: &Path, rows: &[TraceRow]) -> Result<()> {
    write_atomic(path, |out| write_trace_to(out, rows))
}

fn write_trace_to(out: &mut dyn Write, rows: &[TraceRow]) -> Result<()> {
    let mut w = csv::Writer::from_writer(out);
    w.write_record(trace_header())?;
    for r in rows {
        w.write_record(trace_record(r))?;
    }
    w.flush()?;
    Ok(())
}

/// The 6 fields of a pose in `trace.csv`: the position in mm, then ε.
fn push_pose(rec: &mut Vec<String>, psi: &Psi) {
    rec.extend(psi.0[..3].iter().map(|v| format!("{:.4}", v * 1e3)));
    rec.extend(psi.0[3..].iter().map(|v| format!("{v:.6}")));
}

/// The fields of one row of `trace.csv` (see [`trace_header`]).
pub fn trace_record(r: &TraceRow) -> Vec<String> {
    let mut rec: Vec<String> = Vec::with_capacity(36 + HANDOVER_COLUMNS + 2);
    rec.push(format!("{:.3}", r.t));
    rec.extend(r.q.iter().chain(r.qd.iter()).map(|v| format!("{v:.6}")));
    push_pose(&mut rec, &r.truth);
    push_pose(&mut rec, &r.estimate);
    rec.push(format!("{:.5}", r.fitness));
    rec.push(r.status.as_str().to_owned());
    rec.push(u8::from(r.hidden).to_string());
    match &r.handover {
        Some(ho) => {
            rec.push(format!("{:.3}", ho.t_out));
            match &ho.poses {
                Some(p) => {
                    push_pose(&mut rec, &p.truth_out);
                    push_pose(&mut rec, &p.predicted);
                }
                None => rec.extend(std::iter::repeat_n(String::new(), 12)),
            }
            rec.push(u8::from(ho.trusted).to_string());
            for vel in [&ho.velocity, &ho.feedforward, &ho.true_velocity] {
                rec.extend(vel.v.iter().chain(vel.w.iter()).map(|v| format!("{v:.5}")));
            }
        }
        None => rec.extend(std::iter::repeat_n(String::new(), HANDOVER_COLUMNS)),
    }
    rec.extend(r.camera_fitness.iter().map(|f| format!("{f:.5}")));
    rec
}

/// Writes `trace.csv` of a closed-loop run: the columns of [`trace_header`] followed by
/// `extra_header`, one row of `rows` with its `extra` fields per frame, atomically.
///
/// # Errors
/// I/O errors, or `extra` shorter than `rows`.
pub fn write_trace_with(path: &Path, rows: &[TraceRow], extra_header: &[&str], extra: &[Vec<String>]) -> Result<()> {
    anyhow::ensure!(extra.len() >= rows.len(), "{} extra rows for {} trace rows", extra.len(), rows.len());
    write_atomic(path, |out| {
        let mut w = csv::Writer::from_writer(out);
        let mut header = trace_header();
        header.extend(extra_header.iter().map(|h| (*h).to_owned()));
        w.write_record(header)?;
        for (r, x) in rows.iter().zip(extra) {
            let mut rec = trace_record(r);
            rec.extend(x.iter().cloned());
            w.write_record(rec)?;
        }
        Ok(w.flush()?)
    })
}

/// Writes `tuning` as `dir/config.toml`: the full `[tracker]` table (`evorec config`'s
/// format), which `--config` reads back to the same tuning.
///
/// # Errors
/// I/O errors.
pub fn write_tracker_config(dir: &Path, tuning: &evorec_core::tuning::Tuning) -> Result<()> {
    write_bytes(&dir.join("config.toml"), crate::sim::scenario::TrackerTable(*tuning).to_toml().as_bytes())
}

/// Writes `value` as pretty JSON, atomically.
///
/// # Errors
/// I/O or serialisation errors.
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    write_bytes(path, (text + "\n").as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("evorec-io-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| unreachable!("{e}"));
        dir
    }

    #[test]
    fn a_table_is_written_as_csv_and_markdown() {
        let dir = scratch("table").join("sub");
        let records = vec![vec!["A".to_owned(), "0.5".to_owned()], vec!["B, C".to_owned(), "1".to_owned()]];
        write_table(&dir, "t", &["name", "x"], &records, "| name |\n").unwrap_or_else(|e| unreachable!("{e}"));
        let read = |f: &str| std::fs::read_to_string(dir.join(f)).unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(read("t.csv"), "name,x\nA,0.5\n\"B, C\",1\n");
        assert_eq!(read("t.md"), "| name |\n");
        assert_eq!(entries(&dir), ["t.csv", "t.md"]);
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap_or_else(|e| unreachable!("{e}"))
            .map(|e| e.unwrap_or_else(|e| unreachable!("{e}")).file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    /// A writer that fails after half of its output, as a full disk or a crash would.
    fn half_then_fail(w: &mut dyn Write) -> Result<()> {
        w.write_all(&[b'x'; 100_000])?;
        Err(anyhow!("disk full (simulated)"))
    }

    #[test]
    fn failed_write_leaves_no_file_with_the_final_name() {
        let dir = scratch("fresh");
        let path = dir.join("trace.csv");
        let err = write_atomic(&path, half_then_fail).err().map(|e| format!("{e:#}"));
        assert!(err.as_deref().is_some_and(|e| e.contains("trace.csv") && e.contains("disk full")), "{err:?}");
        assert!(!path.exists(), "a failed write created {}", path.display());
        assert!(entries(&dir).is_empty(), "temporary files left: {:?}", entries(&dir));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn failed_write_keeps_the_complete_file() {
        let dir = scratch("keep");
        let path = dir.join("summary.json");
        write_json(&path, &serde_json::json!({"frames": 90})).unwrap_or_else(|e| unreachable!("{e}"));
        let before = std::fs::read(&path).unwrap_or_else(|e| unreachable!("{e}"));
        assert!(write_atomic(&path, half_then_fail).is_err());
        assert_eq!(std::fs::read(&path).unwrap_or_else(|e| unreachable!("{e}")), before);
        assert_eq!(entries(&dir), vec!["summary.json".to_owned()]);
        // A successful write replaces it completely.
        write_bytes(&path, b"{}\n").unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(std::fs::read(&path).unwrap_or_else(|e| unreachable!("{e}")), b"{}\n");
        assert_eq!(entries(&dir), vec!["summary.json".to_owned()]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn writers_produce_readable_files() {
        let dir = scratch("formats");
        let png = dir.join("p.png");
        write_png(&png, &image::RgbImage::from_pixel(3, 2, image::Rgb([1, 2, 3])))
            .unwrap_or_else(|e| unreachable!("{e}"));
        let back = image::open(&png).unwrap_or_else(|e| unreachable!("{e}")).to_rgb8();
        assert_eq!((back.width(), back.height(), back.get_pixel(2, 1).0), (3, 2, [1, 2, 3]));
        write_trace(&dir.join("trace.csv"), &[]).unwrap_or_else(|e| unreachable!("{e}"));
        let text = std::fs::read_to_string(dir.join("trace.csv")).unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(text.trim_end(), trace_header().join(","));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn output_dir_that_cannot_exist_is_reported() {
        let dir = scratch("blocked");
        let file = dir.join("f");
        std::fs::write(&file, "x").unwrap_or_else(|e| unreachable!("{e}"));
        let err = create_out_dir(&file.join("out")).err().map(|e| format!("{e:#}"));
        assert!(err.as_deref().is_some_and(|e| e.contains("cannot create output directory")), "{err:?}");
        create_out_dir(&dir.join("new/deeper")).unwrap_or_else(|e| unreachable!("{e}"));
        assert!(entries(&dir.join("new/deeper")).is_empty(), "the write probe was not removed");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
