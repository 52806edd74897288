//! The results bag `evorec track BAG` writes (`DIR/estimate.mcap` + `DIR/metadata.yaml`), read
//! back with the `mcap` crate: every message decodes, the stamps are the images', the pose and
//! `/tf` are there only while tracking, and `metadata.yaml` parses and counts what the file
//! holds.

use std::collections::BTreeMap;
use std::path::Path;

use evorec_sim::rig::bag::metadata::Metadata;
use evorec_sim::rig::bag::msgs;
use evorec_sim::rig::bag::out_msgs::{level, marker, read};
use evorec_sim::rig::bag::rig::{Output, Rig};
use evorec_sim::rig::bag::testbag::RIGHT_FRAME;

/// Per topic of the results bag: (schema name, log times).
type Topics = BTreeMap<String, (String, Vec<u64>)>;

/// The header stamps of the left images of `bag` (one `.mcap` file).
fn image_stamps(bag: &Path, rig: &Rig) -> Vec<u64> {
    let bytes = std::fs::read(bag).expect("bag");
    let mut stamps = Vec::new();
    for m in mcap::MessageStream::new(&bytes).expect("mcap") {
        let m = m.expect("message");
        if m.channel.topic == rig.topics.left_image {
            let ns = match m.channel.schema.as_ref().map(|s| s.name.as_str()) {
                Some("sensor_msgs/msg/CompressedImage") => {
                    msgs::compressed_image(&m.data).expect("image").header.stamp_ns
                }
                _ => msgs::image(&m.data).expect("image").header.stamp_ns,
            };
            stamps.push(u64::try_from(ns).expect("stamp"));
        }
    }
    stamps
}

/// Checks the results bag in `out` of tracking `bag` (one `.mcap` file) with `rig`.
pub fn check(out: &Path, bag: &Path, rig: &Path) {
    let rig = Rig::load(rig).unwrap_or_else(|e| panic!("{e:#}"));
    let o = Output::default();
    let images = image_stamps(bag, &rig);
    let bytes = std::fs::read(out.join("estimate.mcap")).expect("estimate.mcap");
    let mut topics = Topics::new();
    let mut tracking = Vec::new();
    for m in mcap::MessageStream::new(&bytes).expect("mcap") {
        let m = m.expect("message");
        let schema = m.channel.schema.as_ref().expect("schema");
        assert_eq!((schema.encoding.as_str(), m.channel.message_encoding.as_str()), ("ros2msg", "cdr"));
        // The QoS in the channel's metadata too, as rosbag2 writes it (rosbags matches by it).
        let qos = m.channel.metadata.get("offered_qos_profiles");
        assert!(qos.is_some_and(|q| q.contains("reliability: 1")), "{:?}", m.channel.metadata);
        let entry = topics.entry(m.channel.topic.clone()).or_insert_with(|| (schema.name.clone(), Vec::new()));
        entry.1.push(m.log_time);
        let stamp = |ns: i64| assert_eq!(u64::try_from(ns).ok(), Some(m.log_time), "{}", m.channel.topic);
        let topic = m.channel.topic.as_str();
        if topic == o.status_topic {
            let (h, s) = read::diagnostic_array(&m.data).expect("DiagnosticArray");
            stamp(h.stamp_ns);
            assert_eq!(s.len(), 1);
            let is_tracking = s[0].message == "tracking";
            assert_eq!(s[0].level, if is_tracking { level::OK } else { level::WARN });
            assert_eq!(s[0].values[0], ("status".to_owned(), s[0].message.clone()));
            let fitness: f32 = s[0].values[1].1.parse().expect("fitness");
            assert!(s[0].values[1].0 == "fitness" && (0.0..=1.0).contains(&fitness), "{:?}", s[0].values);
            if is_tracking {
                tracking.push(m.log_time);
            }
        } else if topic == o.pose_topic {
            let (h, pose, cov) = read::pose_with_covariance(&m.data).expect("PoseWithCovarianceStamped");
            stamp(h.stamp_ns);
            assert_eq!(h.frame_id, RIGHT_FRAME);
            assert!((0..6).all(|i| cov[7 * i] > 0.0) && cov[14] > cov[0], "{cov:?}");
            assert!(pose.position[2] > 0.0, "{pose:?}");
        } else if topic == o.tf_topic {
            let tf = msgs::tf_message(&m.data).expect("TFMessage");
            let pairs: Vec<(&str, &str)> =
                tf.iter().map(|t| (t.header.frame_id.as_str(), t.child_frame_id.as_str())).collect();
            assert_eq!(pairs, [(RIGHT_FRAME, "evorec_block"), (rig.frames.base_link.as_str(), "evorec_block_base")]);
            tf.iter().for_each(|t| stamp(t.header.stamp_ns));
        } else if topic == o.marker_topic {
            let mk = read::marker(&m.data).expect("Marker");
            stamp(mk.header.stamp_ns);
            let points = if mk.action == marker::ADD { 36 } else { 0 };
            assert_eq!((mk.kind, mk.points.len(), mk.colors.len()), (marker::TRIANGLE_LIST, points, points));
        } else if topic == o.velocity_topic {
            let (h, v, _) = read::twist_stamped(&m.data).expect("TwistStamped");
            stamp(h.stamp_ns);
            assert_eq!(h.frame_id, rig.frames.base_link);
            assert!(v.iter().all(|x| x.abs() < 2.0), "{v:?}");
        } else {
            panic!("unexpected topic {topic}");
        }
    }
    let times = |topic: &str| topics.get(topic).map(|t| t.1.clone()).unwrap_or_default();
    assert_eq!(times(&o.status_topic), images, "one status per frame, at its image's stamp");
    assert_eq!(times(&o.marker_topic), images);
    assert!(!tracking.is_empty() && tracking.len() <= images.len());
    assert_eq!(times(&o.pose_topic), tracking, "a pose on every tracking frame and no other");
    assert_eq!(times(&o.tf_topic), tracking);
    assert!(times(&o.velocity_topic).iter().all(|t| tracking.contains(t)) && !times(&o.velocity_topic).is_empty());
    check_metadata(out, &topics);
}

/// `metadata.yaml` parses and says what `estimate.mcap` holds.
fn check_metadata(out: &Path, topics: &Topics) {
    let text = std::fs::read_to_string(out.join("metadata.yaml")).expect("metadata.yaml");
    let info = Metadata::parse(&text).unwrap_or_else(|e| panic!("{e:#}")).rosbag2_bagfile_information;
    assert_eq!((info.version, info.storage_identifier.as_str()), (5, "mcap"));
    assert_eq!(info.relative_file_paths, ["estimate.mcap"]);
    let all: Vec<u64> = topics.values().flat_map(|t| t.1.iter().copied()).collect();
    let (first, last) = (all.iter().min().copied().unwrap_or(0), all.iter().max().copied().unwrap_or(0));
    assert_eq!(info.message_count, all.len() as u64);
    assert_eq!(u64::try_from(info.starting_time.nanoseconds_since_epoch).ok(), Some(first));
    assert_eq!(info.duration.nanoseconds, last - first);
    assert_eq!((info.files.len(), info.files[0].message_count), (1, all.len() as u64));
    assert_eq!(info.topics_with_message_count.len(), topics.len());
    for t in &info.topics_with_message_count {
        let m = &t.topic_metadata;
        let (kind, times) = topics.get(&m.name).unwrap_or_else(|| panic!("{} not in estimate.mcap", m.name));
        assert_eq!((&m.kind, m.serialization_format.as_str(), t.message_count), (kind, "cdr", times.len() as u64));
        assert!(m.offered_qos_profiles.contains("reliability: 1"), "{}", m.offered_qos_profiles);
    }
}
