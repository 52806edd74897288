//! The first pass over a bag: every message but the pixels (see the [module docs](super)).

use std::collections::{BTreeMap, BTreeSet};
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow, bail};
use mcap::sans_io::LinearReaderOptions;

use super::joints::JointMessages;
use super::msgs::{self, CameraInfo};
use super::rig::{Rig, UrdfSource};
use super::tf::TfTree;
use super::{BagFiles, images};

/// The `/tf` topic, read for transforms that never change.
pub const TF_TOPIC: &str = "/tf";

/// One message of a bag, as the passes see it.
pub struct Msg<'a> {
    /// Its topic.
    pub topic: &'a str,
    /// Its schema's name, e.g. `sensor_msgs/msg/Image`.
    pub schema: &'a str,
    /// Its message encoding (`cdr`).
    pub encoding: &'a str,
    /// 0-based index among its topic's messages, in file order.
    pub index: usize,
    /// The serialized message.
    pub data: &'a [u8],
}

/// Where a bag stops being readable: a file cut short (a recording interrupted) or a corrupt
/// record. Every message before it was read whole (chunk CRCs checked first), so it is used.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cut {
    /// The file.
    pub file: PathBuf,
    /// Messages of that file read before it.
    pub messages: usize,
    /// What the MCAP reader found.
    pub error: String,
}

impl Cut {
    /// What is wrong, without the file's name.
    pub fn what(&self) -> String {
        format!("not a readable MCAP file (truncated or corrupt) after {} messages: {}", self.messages, self.error)
    }
}

impl std::fmt::Display for Cut {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.file.display(), self.what())
    }
}

/// Largest MCAP record (a chunk, compressed or not) the reader buffers: a corrupt length
/// field is an error, not an allocation of that size. Real chunks are far smaller (rosbag2
/// writes 768 KiB ones; a chunk holding one 4K raw image is 25 MiB).
const RECORD_LIMIT: usize = 1 << 30;

/// How a pass over a bag ended.
#[derive(Debug, Clone, Default)]
pub struct Pass {
    /// Where the bag could not be read further, if it could not (see [`Cut`]).
    pub cut: Option<Cut>,
    /// Every channel of the files read to their end or cut, messages or not: topic → schema.
    pub channels: BTreeMap<String, String>,
}

/// Calls `f` on every message of the bag in file order, until it returns `false`. The files
/// are streamed: memory holds one chunk (and its decompressed records) at a time, whatever
/// the bag's size.
///
/// A file that cannot be read to its end ends the pass ([`Pass::cut`]): the messages before
/// that point were handed to `f`, none after it (nor from later files).
///
/// # Errors
/// A file that cannot be opened, or `f`'s error.
pub fn for_each_message(files: &BagFiles, mut f: impl FnMut(&Msg<'_>) -> Result<bool>) -> Result<Pass> {
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    let mut pass = Pass::default();
    for file in &files.files {
        let handle = File::open(file).map_err(|e| anyhow!("{}: cannot read: {e}", file.display()))?;
        // Each chunk's CRC (when the writer stored one) is checked before any of its messages
        // is handed over, so damage inside an uncompressed chunk is found, not read as pixels.
        let options =
            LinearReaderOptions::default().with_prevalidate_chunk_crcs(true).with_record_length_limit(RECORD_LIMIT);
        let mut reader = mcap::io::MessageReader::new_with_options(BufReader::with_capacity(1 << 20, handle), options);
        for (n, m) in reader.by_ref().enumerate() {
            let m = match m {
                Ok(m) => m,
                Err(e) => {
                    pass.cut = Some(Cut { file: file.clone(), messages: n, error: e.to_string() });
                    break;
                }
            };
            let count = counts.entry(m.channel.topic.clone()).or_insert(0);
            let msg = Msg {
                topic: &m.channel.topic,
                schema: m.channel.schema.as_ref().map_or("", |s| s.name.as_str()),
                encoding: &m.channel.message_encoding,
                index: *count,
                data: &m.data,
            };
            *count += 1;
            if !f(&msg)? {
                return Ok(pass);
            }
        }
        // The reader looks channels up by id only: every id is asked for.
        for c in (0..=u16::MAX).filter_map(|id| reader.get_channel(id)) {
            let schema = c.schema.as_ref().map_or_else(String::new, |s| s.name.clone());
            pass.channels.entry(c.topic.clone()).or_insert(schema);
        }
        if pass.cut.is_some() {
            break;
        }
    }
    Ok(pass)
}

/// An image message found in the first pass.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ImageRef {
    /// Index among its topic's messages.
    pub index: usize,
    /// `header.stamp` (ns).
    pub stamp_ns: i64,
    /// Width and height of a raw image (`None` for a compressed one).
    pub size: Option<(u32, u32)>,
}

/// A topic of the bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicInfo {
    /// Schema name.
    pub schema: String,
    /// Messages.
    pub count: usize,
}

/// What the first pass found.
#[derive(Debug, Clone, Default)]
pub struct Scan {
    /// Every topic of the bag (with no message too).
    pub topics: BTreeMap<String, TopicInfo>,
    /// Left images.
    pub left: Vec<ImageRef>,
    /// Right images.
    pub right: Vec<ImageRef>,
    /// The first left camera_info.
    pub left_info: Option<CameraInfo>,
    /// The first right camera_info.
    pub right_info: Option<CameraInfo>,
    /// Joint states.
    pub joints: JointMessages,
    /// Transforms.
    pub tf: TfTree,
    /// The URDF from the description topic.
    pub urdf: Option<String>,
    /// Where the bag could not be read further (a truncated recording), if it could not.
    pub cut: Option<Cut>,
    /// The encodings met on each image topic (`png` / `jpeg` for compressed images).
    pub encodings: BTreeMap<String, BTreeSet<String>>,
}

/// The image types a camera topic may have.
pub const IMAGE: &str = "sensor_msgs/msg/Image";
/// See [`IMAGE`].
pub const COMPRESSED_IMAGE: &str = "sensor_msgs/msg/CompressedImage";

impl Scan {
    /// The first pass over `files` with the topics of `rig`.
    ///
    /// # Errors
    /// A corrupt MCAP, a message that is not CDR or not of the expected type, a malformed
    /// message, an unknown image encoding, a transform that is not rigid, a camera_info that
    /// changes: naming the topic and the message index.
    pub fn read(files: &BagFiles, rig: &Rig) -> Result<Self> {
        let name = files.display();
        let mut scan = Self::default();
        let pass = for_each_message(files, |m| {
            let info = scan.topics.entry(m.topic.to_owned()).or_insert(TopicInfo { schema: m.schema.into(), count: 0 });
            info.count += 1;
            scan.take(m, rig).map_err(|e| anyhow!("{name}: {} message {}: {e}", m.topic, m.index))?;
            Ok(true)
        })?;
        for (topic, schema) in pass.channels {
            scan.topics.entry(topic).or_insert(TopicInfo { schema, count: 0 });
        }
        scan.cut = pass.cut;
        Ok(scan)
    }

    fn take(&mut self, m: &Msg<'_>, rig: &Rig) -> Result<()> {
        let t = &rig.topics;
        let description = match rig.urdf_source() {
            UrdfSource::Topic(topic) => Some(topic),
            UrdfSource::File(_) => None,
        };
        let wanted = [&t.left_image, &t.right_image, &t.left_info, &t.right_info, &t.joint_states, &t.tf_static];
        let used =
            wanted.iter().any(|w| *w == m.topic) || m.topic == TF_TOPIC || description.as_deref() == Some(m.topic);
        if !used {
            return Ok(());
        }
        if m.encoding != "cdr" {
            bail!("message encoding \"{}\" is not CDR (evorec reads ROS 2 bags)", m.encoding);
        }
        if m.topic == t.left_image || m.topic == t.right_image {
            let (r, encoding) = image_ref(m)?;
            if !self.encodings.get(m.topic).is_some_and(|e| e.contains(&encoding)) {
                self.encodings.entry(m.topic.to_owned()).or_default().insert(encoding);
            }
            if m.topic == t.left_image { self.left.push(r) } else { self.right.push(r) }
        } else if m.topic == t.left_info || m.topic == t.right_info {
            expect_type(m, "sensor_msgs/msg/CameraInfo")?;
            let info = msgs::camera_info(m.data)?;
            let slot = if m.topic == t.left_info { &mut self.left_info } else { &mut self.right_info };
            match slot {
                None => *slot = Some(info),
                Some(first) => same_calibration(first, &info)?,
            }
        } else if m.topic == t.joint_states {
            expect_type(m, "sensor_msgs/msg/JointState")?;
            self.joints.push(m.index, msgs::joint_state(m.data)?).map_err(|e| anyhow!(e))?;
        } else if m.topic == t.tf_static || m.topic == TF_TOPIC {
            expect_type(m, "tf2_msgs/msg/TFMessage")?;
            let transforms = msgs::tf_message(m.data)?;
            self.tf.add(m.topic, m.index, &transforms, m.topic != t.tf_static).map_err(|e| anyhow!(e))?;
        } else if self.urdf.is_none() {
            expect_type(m, "std_msgs/msg/String")?;
            self.urdf = Some(msgs::string(m.data)?);
        }
        Ok(())
    }

    /// Every topic the rig file names has messages.
    ///
    /// # Errors
    /// The first that has none, naming it, its key in the rig file, and the bag's topics.
    pub fn check_topics(&self, name: &str, rig: &Rig) -> Result<()> {
        let t = &rig.topics;
        let mut needed = vec![
            ("left_image", &t.left_image),
            ("right_image", &t.right_image),
            ("left_info", &t.left_info),
            ("right_info", &t.right_info),
            ("joint_states", &t.joint_states),
            ("tf_static", &t.tf_static),
        ];
        let description = match rig.urdf_source() {
            UrdfSource::Topic(topic) => Some(topic),
            UrdfSource::File(_) => None,
        };
        if let Some(d) = &description {
            needed.push(("robot_description", d));
        }
        for (key, topic) in needed {
            let what = match self.topics.get(topic.as_str()) {
                Some(info) if info.count > 0 => continue,
                Some(_) => format!("topic {topic} (topics.{key} of the rig file) is in the bag but holds no message"),
                None => format!("no topic {topic} (topics.{key} of the rig file)"),
            };
            let list: Vec<String> =
                self.topics.iter().map(|(n, i)| format!("{n} ({}, {} messages)", i.schema, i.count)).collect();
            bail!(
                "{name}: {what}; the bag's topics: {}",
                if list.is_empty() { "none".to_owned() } else { list.join(", ") }
            );
        }
        Ok(())
    }
}

fn expect_type(m: &Msg<'_>, schema: &str) -> Result<()> {
    if m.schema != schema {
        bail!("type {} is not {schema}", if m.schema.is_empty() { "(no schema)" } else { m.schema });
    }
    Ok(())
}

/// The image's header and its encoding.
fn image_ref(m: &Msg<'_>) -> Result<(ImageRef, String)> {
    match m.schema {
        IMAGE => {
            let img = msgs::image(m.data)?;
            images::check_encoding(&img.encoding).map_err(|e| anyhow!(e))?;
            let size = Some((img.width, img.height));
            Ok((ImageRef { index: m.index, stamp_ns: img.header.stamp_ns, size }, img.encoding))
        }
        COMPRESSED_IMAGE => {
            let img = msgs::compressed_image(m.data)?;
            let encoding = match image::guess_format(img.data) {
                Ok(image::ImageFormat::Png) => "png",
                Ok(image::ImageFormat::Jpeg) => "jpeg",
                _ => bail!("unknown encoding: format \"{}\", the data is neither PNG nor JPEG", img.format),
            };
            Ok((ImageRef { index: m.index, stamp_ns: img.header.stamp_ns, size: None }, encoding.to_owned()))
        }
        other => bail!("type {other} is not {IMAGE} or {COMPRESSED_IMAGE}"),
    }
}

fn same_calibration(first: &CameraInfo, info: &CameraInfo) -> Result<()> {
    let same = first.width == info.width
        && first.height == info.height
        && first.distortion_model == info.distortion_model
        && first.d == info.d
        && first.k == info.k;
    if !same {
        bail!(
            "the calibration changed mid-bag (size, distortion or K differ from message 0); evorec takes one calibration per bag"
        );
    }
    Ok(())
}

/// Whether `path` looks like a ROS 2 bag rather than an `evorec-seq/1` directory.
pub fn is_bag(path: &Path) -> bool {
    if path.is_file() {
        return path.extension().is_some_and(|e| e == "mcap");
    }
    path.is_dir()
        && !path.join("sequence.toml").exists()
        && (path.join("metadata.yaml").exists()
            || std::fs::read_dir(path)
                .map(|d| d.flatten().any(|e| e.path().extension().is_some_and(|x| x == "mcap" || x == "db3")))
                .unwrap_or(false))
}
