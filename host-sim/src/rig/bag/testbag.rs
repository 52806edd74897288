//! Writing a ROS 2 bag (one MCAP file) from an `evorec-seq/1` sequence, as recorders do: the
//! project's tests write their own small bags with it (from an exported simulator scenario),
//! in any image encoding and chunk compression, and spoil them on purpose.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::Path;

use anyhow::{Result, anyhow};
use image::RgbImage;

use super::msgs::{self, CameraInfo, Header, JointState, TransformStamped};
use crate::recording::sequence::{Sequence, camera_info};

/// Frame ids of the cameras in a test bag.
pub const LEFT_FRAME: &str = "left_camera_optical";
/// See [`LEFT_FRAME`].
pub const RIGHT_FRAME: &str = "right_camera_optical";

/// How to write the bag.
#[derive(Debug, Clone)]
pub struct TestBag {
    /// Encoding of the left images: an `Image` encoding, or `png` / `jpeg` for a
    /// `CompressedImage`.
    pub left_encoding: String,
    /// Same for the right images.
    pub right_encoding: String,
    /// Chunk compression.
    pub compression: Option<mcap::Compression>,
    /// The stamp of the sequence's time 0 (s since the epoch).
    pub origin_s: i64,
    /// The right image's stamp after the left one's (ns).
    pub right_delay_ns: i64,
    /// Write the joint velocities (else empty `velocity`, as most drivers do).
    pub joint_velocities: bool,
    /// Topics not to write.
    pub skip_topics: Vec<String>,
    /// Topics declared (their channel written) but given no message.
    pub silent_topics: Vec<String>,
    /// Joint samples only up to this sequence time (s).
    pub joints_until_s: Option<f64>,
    /// Which transforms `/tf_static` holds.
    pub transforms: Transforms,
    /// Leave out the right image of every frame whose index is a multiple of this.
    pub drop_right_every: Option<usize>,
    /// The left camera_info's `K[0]` from this frame on (a calibration that changes).
    pub change_left_info_at: Option<usize>,
}

/// The transforms of a test bag.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Transforms {
    /// flange → right camera and right → left camera.
    #[default]
    Good,
    /// The same with the first rotation quaternion doubled (not a rotation).
    NonRigid,
    /// flange → right camera only.
    NoLeft,
}

impl Default for TestBag {
    fn default() -> Self {
        Self {
            left_encoding: "bgr8".into(),
            right_encoding: "rgb8".into(),
            compression: Some(mcap::Compression::Zstd),
            origin_s: 1_700_000_000,
            right_delay_ns: 1_000_000,
            joint_velocities: false,
            skip_topics: Vec::new(),
            silent_topics: Vec::new(),
            joints_until_s: None,
            transforms: Transforms::Good,
            drop_right_every: None,
            change_left_info_at: None,
        }
    }
}

/// The rig file of a test bag of `seq`, with its initial pose and search box when it has them.
pub fn rig_toml(seq: &Sequence) -> String {
    let raw = &seq.manifest.raw;
    let f = |v: &[f64]| format!("{v:?}");
    let mut text = format!(
        "format = \"evorec-rig/1\"\n\n[topics]\nleft_image = \"/stereo/left/image\"\nright_image = \"/stereo/right/image\"\n\
         left_info = \"/stereo/left/camera_info\"\nright_info = \"/stereo/right/camera_info\"\njoint_states = \"/joint_states\"\n\
         robot_description = \"/robot_description\"\ntf_static = \"/tf_static\"\n\n[frames]\nbase_link = {:?}\n\
         flange_link = {:?}\nleft_camera = \"{LEFT_FRAME}\"\nright_camera = \"{RIGHT_FRAME}\"\n\n[target]\nsize_m = {}\n\
         face_hues_deg = {}\n",
        raw.robot.base_link,
        raw.robot.flange_link,
        f(&raw.target.size_m),
        f(&raw.target.face_hues_deg),
    );
    if let Some(p) = &raw.target.initial_pose {
        text.push_str(&format!("initial_pose = {{ t_m = {}, q_xyzw = {} }}\n", f(&p.t_m), f(&p.q_xyzw)));
    }
    if let Some(s) = &raw.search {
        text.push_str(&format!("search = {{ min_m = {}, max_m = {} }}\n", f(&s.min_m), f(&s.max_m)));
    }
    text
}

struct Out {
    messages: Vec<(u64, String, Vec<u8>)>,
}

impl Out {
    fn push(&mut self, stamp_ns: i64, topic: &str, data: Vec<u8>) {
        self.messages.push((u64::try_from(stamp_ns).unwrap_or(0), topic.to_owned(), data));
    }
}

/// Writes `seq` as the bag file `path` (`.mcap`).
///
/// # Errors
/// Unreadable sequence files, an unknown encoding, I/O errors.
pub fn write(seq: &Sequence, path: &Path, opts: &TestBag) -> Result<()> {
    let origin = opts.origin_s * 1_000_000_000;
    let stamp = |t: f64| origin + (t * 1e9).round() as i64;
    let mut out = Out { messages: Vec::new() };
    let urdf = std::fs::read_to_string(seq.dir.join(&seq.manifest.raw.robot.urdf))?;
    out.push(origin, "/robot_description", msgs::write_string(&urdf));
    let mut tf = transforms(seq, origin);
    match opts.transforms {
        Transforms::Good => {}
        Transforms::NonRigid => tf[0].rotation = tf[0].rotation.map(|v| 2.0 * v),
        Transforms::NoLeft => tf.truncate(1),
    }
    out.push(origin, "/tf_static", msgs::write_tf_message(&tf));
    joint_messages(seq, opts, &stamp, &mut out);
    let raw = &seq.manifest.raw;
    let infos = [
        camera_info::load(&seq.dir.join(&raw.cameras.left)).map_err(|e| anyhow!("{e}"))?.0,
        camera_info::load(&seq.dir.join(&raw.cameras.right)).map_err(|e| anyhow!("{e}"))?.0,
    ];
    for (i, f) in seq.frames.iter().enumerate() {
        let (l, r) = seq.decode(i).map_err(|e| anyhow!("{e}"))?;
        let t = [stamp(f.t_s), stamp(f.t_s) + opts.right_delay_ns];
        let sides = [("left", LEFT_FRAME, &opts.left_encoding, &l), ("right", RIGHT_FRAME, &opts.right_encoding, &r)];
        for (k, (side, frame, encoding, img)) in sides.into_iter().enumerate() {
            let header = Header { stamp_ns: t[k], frame_id: frame.to_owned() };
            if k == 0 || opts.drop_right_every.is_none_or(|n| n == 0 || i % n != 0) {
                out.push(t[k], &format!("/stereo/{side}/image"), image_message(&header, encoding, img)?);
            }
            let mut ci = info(&header, &infos[k]);
            if k == 0 && opts.change_left_info_at.is_some_and(|at| i >= at) {
                ci.k[0] *= 1.01;
            }
            out.push(t[k], &format!("/stereo/{side}/camera_info"), msgs::write_camera_info(&ci));
        }
    }
    out.messages.retain(|(_, topic, _)| !opts.skip_topics.contains(topic));
    out.messages.sort_by_key(|m| m.0);
    std::fs::write(path, mcap_bytes(&out.messages, opts.compression, &opts.silent_topics)?)?;
    Ok(())
}

fn transforms(seq: &Sequence, origin: i64) -> Vec<TransformStamped> {
    let tf = |p: &str, c: &str, iso: nalgebra::Isometry3<f64>| {
        let (t, q) = (iso.translation.vector, iso.rotation.coords);
        TransformStamped {
            header: Header { stamp_ns: origin, frame_id: p.to_owned() },
            child_frame_id: c.to_owned(),
            translation: [t.x, t.y, t.z],
            rotation: [q.x, q.y, q.z, q.w],
        }
    };
    vec![
        tf(&seq.manifest.raw.robot.flange_link, RIGHT_FRAME, seq.manifest.flange_to_right),
        tf(RIGHT_FRAME, LEFT_FRAME, seq.manifest.right_to_left.inverse()),
    ]
}

/// Joint states: names reversed plus two gripper joints, velocities only if asked.
fn joint_messages(seq: &Sequence, opts: &TestBag, stamp: &dyn Fn(f64) -> i64, out: &mut Out) {
    let mut names: Vec<String> = seq.joints.names().iter().rev().cloned().collect();
    names.extend(["gripper_left".to_owned(), "gripper_right".to_owned()]);
    for (i, t) in seq.joints.times().iter().enumerate() {
        if opts.joints_until_s.is_some_and(|end| *t > end) {
            break;
        }
        let (q, qd) = seq.joints.sample(i);
        let mut position: Vec<f64> = q.iter().rev().copied().collect();
        position.extend([0.01, 0.01]);
        let mut velocity: Vec<f64> = qd.iter().rev().copied().collect();
        velocity.extend([0.0, 0.0]);
        let m = JointState {
            header: Header { stamp_ns: stamp(*t), frame_id: String::new() },
            name: names.clone(),
            position,
            velocity: if opts.joint_velocities { velocity } else { Vec::new() },
        };
        out.push(stamp(*t), "/joint_states", msgs::write_joint_state(&m));
    }
}

fn info(header: &Header, c: &camera_info::CameraInfo) -> CameraInfo {
    let arr = |v: &[f64]| -> [f64; 12] { std::array::from_fn(|i| v.get(i).copied().unwrap_or(0.0)) };
    let (k, r, p) = (arr(&c.camera_matrix.data), arr(&c.rectification_matrix.data), arr(&c.projection_matrix.data));
    CameraInfo {
        header: header.clone(),
        height: c.image_height,
        width: c.image_width,
        distortion_model: c.distortion_model.clone(),
        d: c.distortion_coefficients.data.clone(),
        k: std::array::from_fn(|i| k[i]),
        r: std::array::from_fn(|i| r[i]),
        p,
    }
}

/// The message of one image in `encoding` (an encoding this writer does not know labels the
/// RGB bytes).
///
/// # Errors
/// PNG or JPEG encoding errors.
pub fn image_message(header: &Header, encoding: &str, img: &RgbImage) -> Result<Vec<u8>> {
    if let Some(format) = match encoding {
        "png" => Some(image::ImageFormat::Png),
        "jpeg" => Some(image::ImageFormat::Jpeg),
        _ => None,
    } {
        let mut bytes = Cursor::new(Vec::new());
        img.write_to(&mut bytes, format)?;
        let c = msgs::CompressedImage { header: header.clone(), format: encoding.to_owned(), data: bytes.get_ref() };
        return Ok(msgs::write_compressed_image(&c));
    }
    let (w, h) = img.dimensions();
    let px = img.pixels();
    let data: Vec<u8> = match encoding {
        "rgb8" => img.as_raw().clone(),
        "bgr8" => px.flat_map(|p| [p.0[2], p.0[1], p.0[0]]).collect(),
        "rgba8" => px.flat_map(|p| [p.0[0], p.0[1], p.0[2], 255]).collect(),
        "bgra8" => px.flat_map(|p| [p.0[2], p.0[1], p.0[0], 255]).collect(),
        "mono8" => px.map(|p| p.0[1]).collect(),
        e if e.starts_with("bayer_") => {
            let order: Vec<usize> = e["bayer_".len()..e.len() - 1]
                .chars()
                .map(|c| match c {
                    'r' => 0,
                    'g' => 1,
                    _ => 2,
                })
                .collect();
            img.enumerate_pixels().map(|(x, y, p)| p.0[order[((y & 1) * 2 + (x & 1)) as usize]]).collect()
        }
        // Any other name labels the RGB bytes (to test encodings a reader must refuse).
        _ => img.as_raw().clone(),
    };
    let step = u32::try_from(data.len()).unwrap_or(0) / h.max(1);
    let m = msgs::Image {
        header: header.clone(),
        height: h,
        width: w,
        encoding: encoding.to_owned(),
        is_bigendian: 0,
        step,
        data: &data,
    };
    Ok(msgs::write_image(&m))
}

/// An MCAP file of `messages` (log time, topic, CDR bytes), with the ros2msg schemas of
/// [`msgs::input_schemas`] by topic; the channels of `silent` topics are written, their
/// messages not.
///
/// # Errors
/// The writer's errors.
pub fn mcap_bytes(
    messages: &[(u64, String, Vec<u8>)],
    compression: Option<mcap::Compression>,
    silent: &[String],
) -> Result<Vec<u8>> {
    let schemas: BTreeMap<&str, String> = msgs::input_schemas().into_iter().collect();
    let options = mcap::WriteOptions::new().profile("ros2").compression(compression).chunk_size(Some(256 * 1024));
    let mut w = options.create(Cursor::new(Vec::new()))?;
    let mut channels: BTreeMap<String, u16> = BTreeMap::new();
    for (k, (time, topic, data)) in messages.iter().enumerate() {
        let ch = match channels.get(topic) {
            Some(c) => *c,
            None => {
                let name = schema_of(topic, data);
                let text = schemas.get(name).cloned().unwrap_or_default();
                let s = w.add_schema(name, "ros2msg", text.as_bytes())?;
                let c = w.add_channel(s, topic, "cdr", &BTreeMap::new())?;
                channels.insert(topic.clone(), c);
                c
            }
        };
        let header = mcap::records::MessageHeader {
            channel_id: ch,
            sequence: u32::try_from(k).unwrap_or(0),
            log_time: *time,
            publish_time: *time,
        };
        if !silent.contains(topic) {
            w.write_to_known_channel(&header, data)?;
        }
    }
    w.finish()?;
    Ok(w.into_inner().into_inner())
}

fn schema_of(topic: &str, data: &[u8]) -> &'static str {
    match topic {
        "/robot_description" => "std_msgs/msg/String",
        "/tf_static" | "/tf" => "tf2_msgs/msg/TFMessage",
        "/joint_states" => "sensor_msgs/msg/JointState",
        t if t.ends_with("camera_info") => "sensor_msgs/msg/CameraInfo",
        _ if msgs::image(data).is_ok() => "sensor_msgs/msg/Image",
        _ => "sensor_msgs/msg/CompressedImage",
    }
}
