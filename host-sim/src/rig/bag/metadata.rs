//! `metadata.yaml`: what makes a directory of `.mcap` files a rosbag2 bag for `ros2 bag
//! info/play` and the `rosbags` reader. Written as version 5 (ROS 2 Humble's; the later
//! readers read it too): one MCAP file, its topics with their message counts, types,
//! serialization format and offered QoS profiles, the bag's start and duration.

use serde::{Deserialize, Serialize};

/// The metadata version written.
pub const VERSION: u32 = 5;

/// The QoS profile offered by each topic, as rosbag2 records it (a YAML list in a string):
/// reliable, volatile, history and deadlines unset. `ros2 bag play` publishes with it.
pub const QOS_RELIABLE_VOLATILE: &str = "- history: 3\n  depth: 0\n  reliability: 1\n  durability: 2\n  \
deadline:\n    sec: 2147483647\n    nsec: 4294967295\n  lifespan:\n    sec: 2147483647\n    nsec: 4294967295\n  \
liveliness: 1\n  liveliness_lease_duration:\n    sec: 2147483647\n    nsec: 4294967295\n  \
avoid_ros_namespace_conventions: false\n";

/// The file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Metadata {
    /// Its one key.
    pub rosbag2_bagfile_information: BagInfo,
}

/// `rosbag2_bagfile_information`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BagInfo {
    /// [`VERSION`].
    pub version: u32,
    /// `mcap`.
    pub storage_identifier: String,
    /// Last message time minus the first.
    pub duration: Duration,
    /// The first message's time.
    pub starting_time: Time,
    /// All messages.
    pub message_count: u64,
    /// Per topic.
    pub topics_with_message_count: Vec<TopicCount>,
    /// Empty: the MCAP chunks are compressed, not the files.
    pub compression_format: String,
    /// Empty.
    pub compression_mode: String,
    /// The files, relative to the bag directory.
    pub relative_file_paths: Vec<String>,
    /// Per file.
    pub files: Vec<FileInfo>,
}

/// A duration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Duration {
    /// ns.
    pub nanoseconds: u64,
}

/// A time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Time {
    /// ns since the epoch.
    pub nanoseconds_since_epoch: i64,
}

/// One topic and its message count.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TopicCount {
    /// The topic.
    pub topic_metadata: TopicMetadata,
    /// Its messages.
    pub message_count: u64,
}

/// A topic.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TopicMetadata {
    /// Name.
    pub name: String,
    /// Type (`pkg/msg/Type`).
    #[serde(rename = "type")]
    pub kind: String,
    /// `cdr`.
    pub serialization_format: String,
    /// [`QOS_RELIABLE_VOLATILE`].
    pub offered_qos_profiles: String,
}

/// One file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FileInfo {
    /// Relative path.
    pub path: String,
    /// Its first message's time.
    pub starting_time: Time,
    /// Its duration.
    pub duration: Duration,
    /// Its messages.
    pub message_count: u64,
}

/// The metadata of a bag of one MCAP file `file` holding `topics` (name, type, message count),
/// its messages logged from `first_ns` to `last_ns`.
pub fn of_one_file(file: &str, topics: &[(String, String, u64)], (first_ns, last_ns): (i64, i64)) -> Metadata {
    let count = topics.iter().map(|t| t.2).sum();
    let duration = Duration { nanoseconds: u64::try_from(last_ns - first_ns).unwrap_or(0) };
    let starting_time = Time { nanoseconds_since_epoch: first_ns };
    Metadata {
        rosbag2_bagfile_information: BagInfo {
            version: VERSION,
            storage_identifier: "mcap".to_owned(),
            duration,
            starting_time,
            message_count: count,
            topics_with_message_count: topics
                .iter()
                .map(|(name, kind, n)| TopicCount {
                    topic_metadata: TopicMetadata {
                        name: name.clone(),
                        kind: kind.clone(),
                        serialization_format: "cdr".to_owned(),
                        offered_qos_profiles: QOS_RELIABLE_VOLATILE.to_owned(),
                    },
                    message_count: *n,
                })
                .collect(),
            compression_format: String::new(),
            compression_mode: String::new(),
            relative_file_paths: vec![file.to_owned()],
            files: vec![FileInfo { path: file.to_owned(), starting_time, duration, message_count: count }],
        },
    }
}

impl Metadata {
    /// The YAML text.
    ///
    /// # Errors
    /// The serializer's (none expected).
    pub fn to_yaml(&self) -> anyhow::Result<String> {
        serde_saphyr::to_string(self).map_err(|e| anyhow::anyhow!("metadata.yaml: {e}"))
    }

    /// Parses a `metadata.yaml` of this layout.
    ///
    /// # Errors
    /// Malformed YAML or a missing key.
    pub fn parse(text: &str) -> anyhow::Result<Self> {
        serde_saphyr::from_str(text).map_err(|e| anyhow::anyhow!("metadata.yaml: {e}"))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn the_yaml_reads_back() {
        let topics = vec![("/tf".to_owned(), "tf2_msgs/msg/TFMessage".to_owned(), 3)];
        let m = of_one_file("estimate.mcap", &topics, (1_700_000_000_000_000_000, 1_700_000_001_500_000_000));
        let text = m.to_yaml().unwrap();
        assert!(text.starts_with("rosbag2_bagfile_information:\n"), "{text}");
        let back = Metadata::parse(&text).unwrap();
        assert_eq!(back, m);
        assert_eq!(back.rosbag2_bagfile_information.duration.nanoseconds, 1_500_000_000);
        // The QoS string is itself YAML: a list of one profile.
        let qos = &back.rosbag2_bagfile_information.topics_with_message_count[0].topic_metadata.offered_qos_profiles;
        let profiles: Vec<std::collections::BTreeMap<String, serde_json::Value>> = serde_saphyr::from_str(qos).unwrap();
        assert_eq!(profiles[0]["reliability"], 1);
    }
}
