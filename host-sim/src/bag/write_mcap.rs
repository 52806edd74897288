//! `estimate.mcap`: the tracker's results as a ROS 2 bag file that Foxglove and
//! `ros2 bag play` open. Three topics, all standard message types (so a ROS installation has
//! their type support) and CDR-encoded with `ros2msg` schemas, each message logged and
//! published at its frame's capture stamp:
//!
//! - `/evorec/block_pose` — `geometry_msgs/msg/PoseStamped`: the block's pose `^CR T_M` in the
//!   right camera's frame (`header.frame_id` = the rig's right camera frame);
//! - `/evorec/status` — `std_msgs/msg/String`: the tracker's status (`tracking`, `searching`, …);
//! - `/evorec/fitness` — `std_msgs/msg/Float32`: the estimate's fitness.

use std::collections::BTreeMap;
use std::io::Cursor;

use anyhow::{Result, anyhow};
use nalgebra::Isometry3;

use super::msgs::{self, Header};

/// The pose topic.
pub const POSE_TOPIC: &str = "/evorec/block_pose";
/// The status topic.
pub const STATUS_TOPIC: &str = "/evorec/status";
/// The fitness topic.
pub const FITNESS_TOPIC: &str = "/evorec/fitness";

/// One frame's result.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameResult {
    /// Capture stamp (ns since the epoch).
    pub stamp_ns: i64,
    /// `^CR T_M`.
    pub pose: Isometry3<f64>,
    /// The tracker's status.
    pub status: &'static str,
    /// Fitness.
    pub fitness: f32,
}

/// The bytes of `estimate.mcap` (zstd chunks).
///
/// # Errors
/// The MCAP writer's errors (none expected in memory).
pub fn estimate_mcap(results: &[FrameResult], frame_id: &str) -> Result<Vec<u8>> {
    let err = |e: mcap::McapError| anyhow!("estimate.mcap: {e}");
    let options = mcap::WriteOptions::new().profile("ros2").compression(Some(mcap::Compression::Zstd));
    let mut w = options.create(Cursor::new(Vec::new())).map_err(err)?;
    let none = BTreeMap::new();
    let mut channel = |name: &str, text: &str, topic: &str| -> Result<u16> {
        let schema = w.add_schema(name, "ros2msg", text.as_bytes()).map_err(err)?;
        w.add_channel(schema, topic, "cdr", &none).map_err(err)
    };
    let pose_ch = channel("geometry_msgs/msg/PoseStamped", &msgs::pose_stamped_schema(), POSE_TOPIC)?;
    let status_ch = channel("std_msgs/msg/String", msgs::STRING_SCHEMA, STATUS_TOPIC)?;
    let fitness_ch = channel("std_msgs/msg/Float32", msgs::FLOAT32_SCHEMA, FITNESS_TOPIC)?;
    for (k, r) in results.iter().enumerate() {
        let t = r.pose.translation.vector;
        let q = r.pose.rotation.coords;
        let header = Header { stamp_ns: r.stamp_ns, frame_id: frame_id.to_owned() };
        let time = u64::try_from(r.stamp_ns).unwrap_or(0);
        let seq = u32::try_from(k).unwrap_or(u32::MAX);
        let messages = [
            (pose_ch, msgs::write_pose_stamped(&header, [t.x, t.y, t.z], [q.x, q.y, q.z, q.w])),
            (status_ch, msgs::write_string(r.status)),
            (fitness_ch, msgs::write_float32(r.fitness)),
        ];
        for (ch, data) in messages {
            let header =
                mcap::records::MessageHeader { channel_id: ch, sequence: seq, log_time: time, publish_time: time };
            w.write_to_known_channel(&header, &data).map_err(err)?;
        }
    }
    w.finish().map_err(err)?;
    Ok(w.into_inner().into_inner())
}
