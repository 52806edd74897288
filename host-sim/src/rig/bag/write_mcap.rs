//! The tracker's results as a rosbag2 bag: `DIR/estimate.mcap` and `DIR/metadata.yaml`
//! ([`super::metadata`]), so `ros2 bag info/play DIR`, the `rosbags` reader and Foxglove open
//! it. Every message has a standard ROS 2 type (a ROS installation has its type support and
//! RViz/Foxglove display it), is CDR-encoded with a `ros2msg` schema, and is logged and
//! published at its frame's capture stamp. Topic names and the block's frames come from the rig
//! file's `[output]` table ([`super::rig::Output`]; defaults below).
//!
//! - `/evorec/block_pose` — `geometry_msgs/msg/PoseWithCovarianceStamped`: the block's pose
//!   `^CR T_M` in the right camera's optical frame with its covariance
//!   ([`super::results`]); **only while the status is `tracking`**, so a consumer never takes a
//!   searching or lost estimate for the block.
//! - `/evorec/status` — `diagnostic_msgs/msg/DiagnosticArray`, every frame: one status named
//!   `evorec: block`, level `OK` while tracking and `WARN` while searching, uncertain or lost, the status
//!   as its message and the values `status` and `fitness` (status and fitness in one message of
//!   the type ROS tools such as `rqt_robot_monitor` show).
//! - `/tf` — `tf2_msgs/msg/TFMessage`, while tracking: right camera → `evorec_block` (the
//!   estimate) and base link → `evorec_block_base` (the same pose through the arm's forward
//!   kinematics at the frame's joint sample). A tf frame has one parent, so the block's pose
//!   in the base link is a frame of its own; with the input bag's `/tf` playing alongside,
//!   the two coincide.
//! - `/evorec/block_marker` — `visualization_msgs/msg/Marker`, every frame: the block as a
//!   `TRIANGLE_LIST` (12 triangles, each face in its hue) at the estimate in the right camera's
//!   frame while tracking, `DELETE` otherwise.
//! - `/evorec/block_velocity` — `geometry_msgs/msg/TwistStamped` in the base link: the target
//!   filter's velocity of the block, on the frames where it has one.

use std::collections::BTreeMap;
use std::io::Cursor;

use anyhow::{Result, anyhow};
use evorec_core::model::{Block, FACES};
use evorec_core::status::Status;
use nalgebra::Isometry3;

use super::metadata::{self, Metadata};
use super::msgs::{Header, TransformStamped};
use super::out_msgs::{self as out, DiagnosticStatus, Marker, Pose};
use super::results::FrameResult;
use super::rig::Output;

/// The MCAP file's name in the bag directory.
pub const FILE: &str = "estimate.mcap";

/// What the results bag is made of.
#[derive(Debug, Clone, Copy)]
pub struct BagInput<'a> {
    /// The tracked frames.
    pub frames: &'a [FrameResult],
    /// Topic names and frame ids.
    pub output: &'a Output,
    /// The right camera's optical frame.
    pub camera_frame: &'a str,
    /// The base link.
    pub base_frame: &'a str,
    /// The block.
    pub block: &'a Block,
}

/// The bag's two files.
#[derive(Debug, Clone)]
pub struct ResultsBag {
    /// `estimate.mcap`.
    pub mcap: Vec<u8>,
    /// `metadata.yaml`.
    pub metadata: Metadata,
}

const POSE: usize = 0;
const STATUS: usize = 1;
const TF: usize = 2;
const MARKER: usize = 3;
const VELOCITY: usize = 4;

/// The topics: name, type and schema, indexed by [`POSE`] … [`VELOCITY`].
fn topics(o: &Output) -> [(String, &'static str, String); 5] {
    [
        (o.pose_topic.clone(), "geometry_msgs/msg/PoseWithCovarianceStamped", out::pose_with_covariance_schema()),
        (o.status_topic.clone(), "diagnostic_msgs/msg/DiagnosticArray", out::diagnostic_array_schema()),
        (o.tf_topic.clone(), "tf2_msgs/msg/TFMessage", out::tf_schema()),
        (o.marker_topic.clone(), "visualization_msgs/msg/Marker", out::marker_schema()),
        (o.velocity_topic.clone(), "geometry_msgs/msg/TwistStamped", out::twist_stamped_schema()),
    ]
}

/// The results bag of `input` (zstd chunks).
///
/// # Errors
/// The MCAP writer's errors (none expected in memory).
pub fn results_bag(input: &BagInput<'_>) -> Result<ResultsBag> {
    let err = |e: mcap::McapError| anyhow!("{FILE}: {e}");
    let options = mcap::WriteOptions::new().profile("ros2").compression(Some(mcap::Compression::Zstd));
    let mut w = options.create(Cursor::new(Vec::new())).map_err(err)?;
    // rosbag2's MCAP plugin keeps each topic's QoS in its channel's metadata too; readers
    // (rosbags) match the channels against metadata.yaml's topics by it.
    let qos = BTreeMap::from([("offered_qos_profiles".to_owned(), metadata::QOS_RELIABLE_VOLATILE.to_owned())]);
    let topics = topics(input.output);
    let mut channels = Vec::with_capacity(topics.len());
    for (topic, kind, text) in &topics {
        let schema = w.add_schema(kind, "ros2msg", text.as_bytes()).map_err(err)?;
        channels.push(w.add_channel(schema, topic, "cdr", &qos).map_err(err)?);
    }
    let mut counts = [0u64; 5];
    for r in input.frames {
        let time = u64::try_from(r.stamp_ns).unwrap_or(0);
        for (topic, data) in frame_messages(input, r) {
            let sequence = u32::try_from(counts[topic]).unwrap_or(u32::MAX);
            let header = mcap::records::MessageHeader {
                channel_id: channels[topic],
                sequence,
                log_time: time,
                publish_time: time,
            };
            w.write_to_known_channel(&header, &data).map_err(err)?;
            counts[topic] += 1;
        }
    }
    w.finish().map_err(err)?;
    let counted: Vec<(String, String, u64)> =
        topics.iter().zip(counts).map(|((topic, kind, _), n)| (topic.clone(), (*kind).to_owned(), n)).collect();
    let span = match (input.frames.first(), input.frames.last()) {
        (Some(a), Some(b)) => (a.stamp_ns, b.stamp_ns),
        _ => (0, 0),
    };
    Ok(ResultsBag { mcap: w.into_inner().into_inner(), metadata: metadata::of_one_file(FILE, &counted, span) })
}

/// The messages of one frame: (topic index, CDR bytes).
fn frame_messages(input: &BagInput<'_>, r: &FrameResult) -> Vec<(usize, Vec<u8>)> {
    let o = input.output;
    let at = |frame: &str| Header { stamp_ns: r.stamp_ns, frame_id: frame.to_owned() };
    let tracking = r.status == Status::Tracking;
    let mut messages = Vec::with_capacity(5);
    if tracking {
        messages
            .push((POSE, out::write_pose_with_covariance(&at(input.camera_frame), &pose_of(&r.pose), &r.covariance)));
    }
    let level = if tracking { out::level::OK } else { out::level::WARN };
    let status = DiagnosticStatus {
        level,
        name: "evorec: block".to_owned(),
        message: r.status.as_str().to_owned(),
        hardware_id: String::new(),
        values: vec![
            ("status".to_owned(), r.status.as_str().to_owned()),
            ("fitness".to_owned(), r.fitness.to_string()),
        ],
    };
    messages.push((STATUS, out::write_diagnostic_array(&at(""), &[status])));
    if tracking {
        let transform = |parent: &str, child: &str, pose: &Isometry3<f64>| {
            let p = pose_of(pose);
            TransformStamped {
                header: at(parent),
                child_frame_id: child.to_owned(),
                translation: p.position,
                rotation: p.orientation,
            }
        };
        let in_base = r.camera_in_base * r.pose;
        messages.push((
            TF,
            out::write_tf(&[
                transform(input.camera_frame, &o.block_frame, &r.pose),
                transform(input.base_frame, &o.block_base_frame, &in_base),
            ]),
        ));
    }
    messages.push((
        MARKER,
        out::write_marker(&block_marker(input.block, at(input.camera_frame), tracking.then_some(&r.pose))),
    ));
    if let Some((linear, angular)) = r.velocity {
        messages.push((VELOCITY, out::write_twist_stamped(&at(input.base_frame), linear, angular)));
    }
    messages
}

/// A pose message's fields.
pub fn pose_of(iso: &Isometry3<f64>) -> Pose {
    let (t, q) = (iso.translation.vector, iso.rotation.coords);
    Pose { position: [t.x, t.y, t.z], orientation: [q.x, q.y, q.z, q.w] }
}

/// The block's marker: its faces at `pose` (in `header`'s frame), or a `DELETE` without one.
pub fn block_marker(block: &Block, header: Header, pose: Option<&Isometry3<f64>>) -> Marker {
    let mut m = Marker {
        header,
        ns: "evorec".to_owned(),
        id: 0,
        kind: out::marker::TRIANGLE_LIST,
        action: out::marker::DELETE,
        pose: Pose::IDENTITY,
        scale: [1.0; 3],
        color: [1.0; 4],
        points: Vec::new(),
        colors: Vec::new(),
    };
    let Some(pose) = pose else { return m };
    m.action = out::marker::ADD;
    m.pose = pose_of(pose);
    for k in 0..FACES {
        let c = block.face_corners(k).map(|p| [p.x, p.y, p.z].map(f64::from));
        let [r, g, b] = crate::sim::render::hue_rgb(block.face_hues_deg[k]);
        for i in [0, 1, 2, 0, 2, 3] {
            m.points.push(c[i]);
            m.colors.push([r, g, b, 1.0]);
        }
    }
    m
}
