//! ROS 2 bags (MCAP storage, CDR messages) as recorded sequences: `evorec import BAG` writes
//! one as an `evorec-seq/1` directory, `evorec track BAG` tracks it directly.
//!
//! A bag is read in two passes over its messages. The first ([`load`]) reads everything but
//! the pixels: camera_info, joint states, transforms, the URDF and each image's header (its
//! stamp and encoding). From these it builds the very [`Sequence`] `evorec track` would load
//! from the imported directory: the files' text is generated and parsed by the sequence
//! reader's own parsers, numbers in shortest round-trip form, so importing then tracking gives
//! the estimates of tracking the bag bit for bit. Every bad input is found here, before
//! anything is written, except undecodable image data, found in the second pass
//! ([`source::BagFrames`]), which streams the paired images in frame order.
//!
//! ## Crates
//! - **`mcap`** (Foxglove's reader and writer, the format's reference implementation): plain,
//!   zstd and lz4 chunks.
//! - **CDR by hand** ([`cdr`], [`msgs`]): the handful of fixed layouts evorec reads (Image,
//!   CompressedImage, CameraInfo, JointState, TFMessage, String) and writes
//!   ([`write_mcap`]: PoseWithCovarianceStamped, DiagnosticArray, TFMessage, Marker,
//!   TwistStamped) take ~500 lines; the serde CDR crates either stopped being maintained
//!   (`cdr`, last release 2021) or belong to a DDS stack (`cdr-encoding`), and going through
//!   serde would copy each image byte by byte where the reader borrows the pixels.
//!
//! ## Times
//! `header.stamp` is the capture time (the bag's receive time is ignored). A sequence's times
//! are seconds from an origin: the first frame's stamp rounded down to a whole second
//! (`stamp_origin_s` in the report), so they stay exact in `f64`.

pub mod cdr;
pub mod images;
pub mod import;
pub mod joints;
pub mod metadata;
pub mod msgs;
pub mod out_msgs;
pub mod pairing;
pub mod results;
pub mod rig;
pub mod rigfile;
pub mod scan;
pub mod source;
pub mod testbag;
pub mod tf;
pub mod track;
pub mod window;
pub mod write_mcap;

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use serde::Serialize;

use crate::recording::sequence::camera_info::{self, YamlMatrix};
use crate::recording::sequence::write::{ManifestFields, image_path, manifest_text};
use crate::recording::sequence::{FrameRow, Robot, Sequence, Texts};
use pairing::Pairing;
pub use rig::Rig;
use scan::{ImageRef, Scan};

/// What `evorec import` / `evorec track BAG` take besides the bag and the rig file.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BagOptions {
    /// Largest stamp difference of a stereo pair (ms); default a quarter of the frame period.
    pub pair_tolerance_ms: Option<f64>,
    /// The first frame to use (`--start`).
    pub start: Option<window::TimeArg>,
    /// The last frame to use (`--end`).
    pub end: Option<window::TimeArg>,
}

/// What was found in a bag (printed, logged and written into `summary.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BagReport {
    /// The bag.
    pub bag: String,
    /// Stereo pairs (frames).
    pub frames: usize,
    /// Left images without a right partner.
    pub unpaired_left: usize,
    /// Right images without a left partner.
    pub unpaired_right: usize,
    /// Estimated frame period (ms).
    pub frame_period_ms: f64,
    /// Pairing tolerance used (ms).
    pub pair_tolerance_ms: f64,
    /// Joint samples used.
    pub joint_samples: usize,
    /// Joint messages dropped for repeating an earlier stamp.
    pub duplicate_joint_stamps: usize,
    /// `recorded` or `derived` (central differences, see [`joints`]).
    pub joint_velocities: joints::Velocities,
    /// The sequence's time 0 as a stamp (s since the epoch).
    pub stamp_origin_s: i64,
    /// Where the bag stops being readable (truncated or corrupt), when it does: only the
    /// frames before it are used.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cut: Option<String>,
}

/// The files of a bag: its `.mcap` files in order, and its name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BagFiles {
    /// The MCAP files.
    pub files: Vec<PathBuf>,
    /// The bag's name (directory or file stem).
    pub name: String,
}

impl BagFiles {
    /// The bag at `path`: a ROS 2 bag directory (metadata.yaml and `.mcap` files) or one
    /// `.mcap` file.
    ///
    /// # Errors
    /// Neither, or a directory without `.mcap` files.
    pub fn open(path: &Path) -> Result<Self> {
        let stem = |p: &Path| p.file_stem().map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        if path.is_file() {
            return Ok(Self { files: vec![path.to_path_buf()], name: stem(path) });
        }
        if !path.is_dir() {
            bail!("{}: no such bag (a ROS 2 bag directory or an .mcap file)", path.display());
        }
        let mut files = Vec::new();
        let mut sqlite = false;
        for entry in std::fs::read_dir(path).with_context(|| format!("{}: cannot list", path.display()))? {
            let p = entry.with_context(|| format!("{}: cannot list", path.display()))?.path();
            match p.extension().and_then(|e| e.to_str()) {
                Some("mcap") => files.push(p),
                Some("db3") => sqlite = true,
                _ => {}
            }
        }
        if files.is_empty() {
            let hint = if sqlite { " (SQLite storage: convert it with `ros2 bag convert` to MCAP)" } else { "" };
            bail!("{}: no .mcap file in the bag directory{hint}", path.display());
        }
        files.sort();
        let name = path.file_name().map_or_else(|| stem(path), |s| s.to_string_lossy().into_owned());
        Ok(Self { files, name })
    }

    /// The bag's path as given to users (its first file when it has one).
    pub fn display(&self) -> String {
        match self.files.as_slice() {
            [one] => one.display().to_string(),
            _ => self.files.first().and_then(|f| f.parent()).map_or_else(String::new, |d| d.display().to_string()),
        }
    }
}

/// A bag read as a sequence.
#[derive(Debug, Clone)]
pub struct BagSequence {
    /// The sequence (no ground truth).
    pub seq: Sequence,
    /// The text of `sequence.toml`.
    pub manifest: String,
    /// The left camera_info YAML.
    pub left_yaml: String,
    /// The right camera_info YAML.
    pub right_yaml: String,
    /// The URDF.
    pub urdf: String,
    /// Per frame: the left and right image messages.
    pub pairs: Vec<(ImageRef, ImageRef)>,
    /// Per frame: the capture stamp (ns; the left image's).
    pub stamps_ns: Vec<i64>,
    /// The bag.
    pub files: BagFiles,
    /// The rig file.
    pub rig: Rig,
    /// What was found.
    pub report: BagReport,
    /// Where the bag stops being readable, when it does (see [`scan::Cut`]).
    pub cut: Option<scan::Cut>,
}

/// Reads `bag` with `rig` into a sequence whose files would be in `dir`. A bag that stops
/// being readable part-way (a truncated recording) gives the frames before that point, with
/// [`BagSequence::cut`] saying where.
///
/// # Errors
/// The first bad input, as one message naming the topic and message index or the key.
pub fn load(bag: &Path, rig: &Rig, opts: &BagOptions, dir: &Path) -> Result<BagSequence> {
    let files = BagFiles::open(bag)?;
    let scan = Scan::read(&files, rig)?;
    let cut = scan.cut.clone();
    let read_any = scan.topics.values().any(|t| t.count > 0);
    let loaded = from_scan(files, scan, rig, opts, dir);
    match (loaded, &cut) {
        (Err(_), Some(cut)) if !read_any => bail!("{cut}"),
        (Err(e), Some(cut)) => bail!("{cut}; the messages before it do not make a sequence: {e:#}"),
        (loaded, _) => loaded,
    }
}

fn from_scan(files: BagFiles, scan: Scan, rig: &Rig, opts: &BagOptions, dir: &Path) -> Result<BagSequence> {
    let name = files.display();
    scan.check_topics(&name, rig)?;
    let urdf = urdf_text(&scan, rig, &name)?;
    let urdf_name = PathBuf::from(format!("{name}: {}", urdf_label(rig)));
    let robot = Robot::from_urdf_str(&urdf, &rig.frames.base_link, &rig.frames.flange_link, &urdf_name)?;
    log_resolved(&scan, rig, &robot, &name);
    let (mut pairs, pairing) = pairs(&scan, rig, opts, &name)?;
    // Time 0 is the whole second before the bag's first frame (whatever --start says, so that
    // times agree with a run over the whole bag).
    let origin_ns = scan.left[pairing.pairs[0].0].stamp_ns.div_euclid(1_000_000_000) * 1_000_000_000;
    let (table, velocities, duplicates) =
        joints::table(&scan.joints, &robot.joint_names, origin_ns).map_err(|(index, e)| match index {
            Some(i) => anyhow!("{name}: {} message {i}: {e}", rig.topics.joint_states),
            None => anyhow!("{name}: {}: {e}", rig.topics.joint_states),
        })?;
    if scan.cut.is_some() {
        // The images of the last frames may have been read, their joint states not.
        let last_ns = origin_ns + (table.span().1 * 1e9).round() as i64;
        pairs.truncate(pairs.partition_point(|(l, _)| l.stamp_ns <= last_ns).max(1));
    }
    let stamps_ns: Vec<i64> = pairs.iter().map(|(l, _)| l.stamp_ns).collect();
    let frames = frame_rows(&pairs, origin_ns, dir);
    check_frame_times(&frames, &pairs, &table, (rig, origin_ns, &name))?;
    check_image_sizes(&pairs, &scan, rig, &name)?;
    let (left_yaml, right_yaml) = (camera_yaml(&scan, rig, true, &name)?, camera_yaml(&scan, rig, false, &name)?);
    let mut paired = format!(
        "{} stereo pairs within {:.3} ms; unpaired: {} left, {} right",
        pairs.len(),
        pairing.tolerance_ns as f64 / 1e6,
        pairing.unpaired_left.len(),
        pairing.unpaired_right.len()
    );
    if let Some(cut) = &scan.cut {
        paired.push_str(&format!("\nthe frames before where the bag ends: {cut}"));
    }
    let manifest = manifest(&scan, rig, (&files.name, &name, &paired), origin_ns)?;
    let texts = Texts { manifest: &manifest, left_yaml: &left_yaml, right_yaml: &right_yaml, urdf: &urdf };
    let report = BagReport {
        bag: name.clone(),
        frames: pairs.len(),
        unpaired_left: pairing.unpaired_left.len(),
        unpaired_right: pairing.unpaired_right.len(),
        frame_period_ms: pairing.period_ns as f64 / 1e6,
        pair_tolerance_ms: pairing.tolerance_ns as f64 / 1e6,
        joint_samples: table.times().len(),
        duplicate_joint_stamps: duplicates,
        joint_velocities: velocities,
        stamp_origin_s: origin_ns / 1_000_000_000,
        cut: scan.cut.as_ref().map(ToString::to_string),
    };
    let seq = Sequence::from_memory(dir, &texts, frames, table).map_err(|e| rig_error(e, rig))?;
    let cut = scan.cut;
    Ok(BagSequence {
        seq,
        manifest,
        left_yaml,
        right_yaml,
        urdf,
        pairs,
        stamps_ns,
        files,
        rig: rig.clone(),
        report,
        cut,
    })
}

/// Logs (`-v`) what the bag's messages resolved to: the chain, the image encodings and the
/// intrinsics (the transforms are logged by [`manifest`], the pairing by [`BagReport::log`]).
fn log_resolved(scan: &Scan, rig: &Rig, robot: &Robot, name: &str) {
    let f = &rig.frames;
    log::info!(
        "{name}: chain {} -> {}: {} joints ({})",
        f.base_link,
        f.flange_link,
        robot.joint_names.len(),
        robot.joint_names.join(", ")
    );
    let t = &rig.topics;
    for (topic, info) in [(&t.left_image, &scan.left_info), (&t.right_image, &scan.right_info)] {
        let encodings: Vec<&str> =
            scan.encodings.get(topic).map_or_else(Vec::new, |e| e.iter().map(String::as_str).collect());
        let Some(c) = info else { continue };
        log::info!(
            "{name}: {topic}: encoding {}; {}x{}, fx {} fy {} cx {} cy {}, distortion {} ({} coefficients)",
            encodings.join(", "),
            c.width,
            c.height,
            c.k[0],
            c.k[4],
            c.k[2],
            c.k[5],
            c.distortion_model,
            c.d.len()
        );
    }
}

/// The stereo pairs of the scanned images (at least one), and how they were paired.
fn pairs(scan: &Scan, rig: &Rig, opts: &BagOptions, name: &str) -> Result<(Vec<(ImageRef, ImageRef)>, Pairing)> {
    let tolerance_ns = tolerance_ns(opts.pair_tolerance_ms)?;
    let left_stamps: Vec<i64> = scan.left.iter().map(|r| r.stamp_ns).collect();
    let right_stamps: Vec<i64> = scan.right.iter().map(|r| r.stamp_ns).collect();
    let pairing = pairing::pair(&left_stamps, &right_stamps, tolerance_ns).map_err(|e| anyhow!("{name}: {e}"))?;
    if pairing.pairs.is_empty() {
        bail!(
            "{name}: no stereo pair: no image on {} is within {:.3} ms of one on {}",
            rig.topics.left_image,
            pairing.tolerance_ns as f64 / 1e6,
            rig.topics.right_image
        );
    }
    let stamps: Vec<i64> = pairing.pairs.iter().map(|&(l, _)| scan.left[l].stamp_ns).collect();
    let range = window::select(&stamps, opts.start, opts.end).map_err(|e| anyhow!("{name}: {e}"))?;
    let pairs = pairing.pairs[range].iter().map(|&(l, r)| (scan.left[l].clone(), scan.right[r].clone())).collect();
    Ok((pairs, pairing))
}

impl BagReport {
    /// One line for the terminal and the log.
    pub fn describe(&self) -> String {
        format!(
            "{} stereo pairs (frame period {:.3} ms, pairing tolerance {:.3} ms); unpaired: {} left, {} right; \
             {} joint samples, velocities {}",
            self.frames,
            self.frame_period_ms,
            self.pair_tolerance_ms,
            self.unpaired_left,
            self.unpaired_right,
            self.joint_samples,
            match self.joint_velocities {
                joints::Velocities::Recorded => "as recorded",
                joints::Velocities::Derived => "derived from positions (central differences)",
            }
        )
    }

    /// Logs what deserves a warning: unpaired images, duplicate joint stamps.
    pub fn log(&self) {
        log::info!("{}: {}", self.bag, self.describe());
        if self.unpaired_left + self.unpaired_right > 0 {
            log::warn!(
                "{}: {} left and {} right images have no partner within {:.3} ms and are not used",
                self.bag,
                self.unpaired_left,
                self.unpaired_right,
                self.pair_tolerance_ms
            );
        }
        if self.duplicate_joint_stamps > 0 {
            log::warn!(
                "{}: {} joint messages repeat an earlier stamp and are ignored",
                self.bag,
                self.duplicate_joint_stamps
            );
        }
    }
}

/// An error in the generated `sequence.toml` is one in the rig file's `[target]` (the rest
/// comes from the bag and was checked before): named as the rig file's key.
fn rig_error(e: crate::recording::sequence::SequenceError, rig: &Rig) -> anyhow::Error {
    match &e.field {
        Some(field) if e.file.ends_with("sequence.toml") => {
            let key = if field == "search" { "target.search" } else { field.as_str() };
            anyhow!("{}: {key}: {}", rig.path.display(), e.message)
        }
        _ => e.into(),
    }
}

fn tolerance_ns(ms: Option<f64>) -> Result<Option<i64>> {
    match ms {
        Some(v) if !(0.0..=10_000.0).contains(&v) => {
            bail!("--pair-tolerance-ms {v}: must be in [0, 10000]")
        }
        Some(v) => Ok(Some((v * 1e6).round() as i64)),
        None => Ok(None),
    }
}

fn urdf_label(rig: &Rig) -> String {
    match rig.urdf_source() {
        rig::UrdfSource::Topic(t) => format!("URDF on {t}"),
        rig::UrdfSource::File(f) => f.display().to_string(),
    }
}

fn urdf_text(scan: &Scan, rig: &Rig, name: &str) -> Result<String> {
    match rig.urdf_source() {
        rig::UrdfSource::File(f) => std::fs::read_to_string(&f)
            .map_err(|e| anyhow!("{}: cannot read (topics.urdf of the rig file): {e}", f.display())),
        rig::UrdfSource::Topic(t) => scan.urdf.clone().ok_or_else(|| anyhow!("{name}: no messages on topic {t}")),
    }
}

fn frame_rows(pairs: &[(ImageRef, ImageRef)], origin_ns: i64, dir: &Path) -> Vec<FrameRow> {
    pairs
        .iter()
        .enumerate()
        .map(|(k, (l, _))| FrameRow {
            index: k as u64,
            t_s: (l.stamp_ns - origin_ns) as f64 / 1e9,
            left: dir.join(image_path("left", k as u64)),
            right: dir.join(image_path("right", k as u64)),
            line: k as u64 + 2,
        })
        .collect()
}

fn check_frame_times(
    frames: &[FrameRow],
    pairs: &[(ImageRef, ImageRef)],
    table: &crate::recording::sequence::JointTable,
    (rig, origin_ns, name): (&Rig, i64, &str),
) -> Result<()> {
    let (first, last) = table.span();
    let origin_s = origin_ns as f64 / 1e9;
    for (f, (l, _)) in frames.iter().zip(pairs) {
        if !(f.t_s >= first && f.t_s <= last) {
            bail!(
                "{name}: {} message {}: stamp {:.9} s is outside the joint samples of {} ({:.9} to {:.9} s): \
                 no joint state at this frame's capture time",
                rig.topics.left_image,
                l.index,
                l.stamp_ns as f64 / 1e9,
                rig.topics.joint_states,
                origin_s + first,
                origin_s + last
            );
        }
    }
    Ok(())
}

/// Raw images have the size of their camera_info.
fn check_image_sizes(pairs: &[(ImageRef, ImageRef)], scan: &Scan, rig: &Rig, name: &str) -> Result<()> {
    let sides = [(&rig.topics.left_image, &scan.left_info, 0), (&rig.topics.right_image, &scan.right_info, 1)];
    for (topic, info, side) in sides {
        let Some(info) = info else { continue };
        for p in pairs {
            let r = if side == 0 { &p.0 } else { &p.1 };
            if let Some((w, h)) = r.size
                && (w, h) != (info.width, info.height)
            {
                bail!(
                    "{name}: {topic} message {}: image is {w}x{h}, its camera_info says {}x{}",
                    r.index,
                    info.width,
                    info.height
                );
            }
        }
    }
    Ok(())
}

/// The camera_info YAML of one camera, its values checked first (naming the topic).
fn camera_yaml(scan: &Scan, rig: &Rig, left: bool, name: &str) -> Result<String> {
    let (topic, info) =
        if left { (&rig.topics.left_info, &scan.left_info) } else { (&rig.topics.right_info, &scan.right_info) };
    let info = info.as_ref().ok_or_else(|| anyhow!("{name}: no messages on topic {topic}"))?;
    let m = |rows, cols, data: Vec<f64>| YamlMatrix { rows, cols, data };
    let yaml = camera_info::CameraInfo {
        image_width: info.width,
        image_height: info.height,
        camera_name: info.header.frame_id.clone(),
        camera_matrix: m(3, 3, info.k.to_vec()),
        distortion_model: info.distortion_model.clone(),
        distortion_coefficients: m(1, info.d.len(), info.d.clone()),
        rectification_matrix: m(3, 3, info.r.to_vec()),
        projection_matrix: m(3, 4, info.p.to_vec()),
    };
    camera_info::to_pinhole(&yaml).map_err(|(field, e)| anyhow!("{name}: {topic} message 0: {field}: {e}"))?;
    camera_info::to_yaml(&yaml).map_err(|e| anyhow!("{name}: {topic}: {e}"))
}

/// The text of `sequence.toml`: transforms from tf, the block from the rig file.
fn manifest(scan: &Scan, rig: &Rig, (seq_name, name, paired): (&str, &str, &str), origin_ns: i64) -> Result<String> {
    let f = &rig.frames;
    let tf_err = |e: String| anyhow!("{name}: {} (rig file frames): {e}", rig.topics.tf_static);
    let flange_to_right = scan.tf.pose_of(&f.right_camera, &f.flange_link).map_err(tf_err)?;
    let right_to_left = scan.tf.pose_of(&f.right_camera, &f.left_camera).map_err(tf_err)?;
    for (what, iso) in [
        (format!("flange_to_right ({} to {})", f.flange_link, f.right_camera), flange_to_right),
        (format!("right_to_left ({} to {})", f.right_camera, f.left_camera), right_to_left),
    ] {
        let (t, q) = (iso.translation.vector, iso.rotation.coords);
        log::info!(
            "{name}: transform {what}: t [{}, {}, {}] m, q_xyzw [{}, {}, {}, {}]",
            t.x,
            t.y,
            t.z,
            q.x,
            q.y,
            q.z,
            q.w
        );
    }
    let t = &rig.target;
    let comment = format!(
        "imported by evorec from the ROS 2 bag {name}\n{paired}\nt_s = header.stamp - {} s",
        origin_ns / 1_000_000_000
    );
    Ok(manifest_text(&ManifestFields {
        name: seq_name,
        comment: &comment,
        stamp_origin_s: Some(origin_ns / 1_000_000_000),
        base_link: &f.base_link,
        flange_link: &f.flange_link,
        right_to_left,
        flange_to_right,
        size_m: t.size_m,
        face_hues_deg: t.face_hues_deg,
        initial_pose: t.initial_pose.map(|p| (p.t_m, p.q_xyzw)),
        search: t.search.map(|s| (s.min_m, s.max_m)),
    }))
}
