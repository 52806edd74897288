//! `RIG.toml` (format `evorec-rig/1`): what a ROS 2 bag does not say — which topics and frames
//! are which, and what the block looks like. Parsed with serde + `toml`; an unknown key is an
//! error naming it (and its line).

use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow, bail};
use serde::Deserialize;

use crate::recording::sequence::manifest::{PoseSection, SearchSection, line_of};
use crate::recording::text::one_line;

/// The format tag this reader accepts.
pub const FORMAT: &str = "evorec-rig/1";

/// `RIG.toml` as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rig {
    /// Must be [`FORMAT`].
    pub format: String,
    /// `[topics]`.
    pub topics: Topics,
    /// `[frames]`.
    pub frames: Frames,
    /// `[target]`.
    pub target: Target,
    /// `[output]` (optional): the results bag's topics and frames.
    #[serde(default)]
    pub output: Output,
    /// The file it was read from (names it in errors).
    #[serde(skip)]
    pub path: PathBuf,
}

/// `[topics]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Topics {
    /// Left camera: `sensor_msgs/Image` or `sensor_msgs/CompressedImage`.
    pub left_image: String,
    /// Right camera.
    pub right_image: String,
    /// Left `sensor_msgs/CameraInfo`.
    pub left_info: String,
    /// Right `sensor_msgs/CameraInfo`.
    pub right_info: String,
    /// `sensor_msgs/JointState`.
    pub joint_states: String,
    /// `std_msgs/String` holding the URDF (default `/robot_description` unless `urdf` is given).
    pub robot_description: Option<String>,
    /// A URDF file instead of the topic (relative to the rig file).
    pub urdf: Option<PathBuf>,
    /// `tf2_msgs/TFMessage` with the static transforms.
    pub tf_static: String,
}

/// `[frames]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Frames {
    /// The URDF link q is measured from.
    pub base_link: String,
    /// The URDF link the camera mount is fixed to.
    pub flange_link: String,
    /// tf frame of the left camera (optical).
    pub left_camera: String,
    /// tf frame of the right camera (optical).
    pub right_camera: String,
}

/// `[target]`: as in `sequence.toml`, plus the optional search box.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Target {
    /// Full edge lengths (m).
    pub size_m: [f64; 3],
    /// Hues of faces +x, +y, +z, −x, −y, −z (degrees).
    pub face_hues_deg: [f64; 6],
    /// The block in the right camera frame at the first frame.
    pub initial_pose: Option<PoseSection>,
    /// The search box, right camera frame.
    pub search: Option<SearchSection>,
}

/// `[output]`: the topic names and tf frames of the results bag `evorec track` writes
/// (`super::write_mcap`); every key optional.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Output {
    /// `geometry_msgs/PoseWithCovarianceStamped`, while tracking.
    pub pose_topic: String,
    /// `diagnostic_msgs/DiagnosticArray`, every frame.
    pub status_topic: String,
    /// `tf2_msgs/TFMessage`, while tracking.
    pub tf_topic: String,
    /// `visualization_msgs/Marker`, every frame.
    pub marker_topic: String,
    /// `geometry_msgs/TwistStamped`, where the target filter has a velocity.
    pub velocity_topic: String,
    /// The block's tf frame, child of the right camera's frame.
    pub block_frame: String,
    /// The block's tf frame as a child of the base link.
    pub block_base_frame: String,
}

impl Default for Output {
    fn default() -> Self {
        Self {
            pose_topic: "/evorec/block_pose".to_owned(),
            status_topic: "/evorec/status".to_owned(),
            tf_topic: "/tf".to_owned(),
            marker_topic: "/evorec/block_marker".to_owned(),
            velocity_topic: "/evorec/block_velocity".to_owned(),
            block_frame: "evorec_block".to_owned(),
            block_base_frame: "evorec_block_base".to_owned(),
        }
    }
}

impl Output {
    /// Topic names are absolute ROS names (`/` then letters, digits, `_` and `/`) and distinct;
    /// the block's frames are non-empty, free of `/` at the start and whitespace, distinct
    /// from each other and from the rig's frames.
    fn check(&self, frames: &Frames) -> std::result::Result<(), String> {
        let topics = [
            ("pose_topic", &self.pose_topic),
            ("status_topic", &self.status_topic),
            ("tf_topic", &self.tf_topic),
            ("marker_topic", &self.marker_topic),
            ("velocity_topic", &self.velocity_topic),
        ];
        for (i, (key, t)) in topics.iter().enumerate() {
            let body = t.strip_prefix('/').unwrap_or_default();
            let ok = !body.is_empty()
                && !body.ends_with('/')
                && !body.contains("//")
                && body.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '/')
                && body.split('/').all(|part| !part.starts_with(|c: char| c.is_ascii_digit()));
            if !ok {
                return Err(format!("output.{key}: \"{t}\" is not an absolute ROS topic name (like \"/evorec/x\")"));
            }
            if let Some((other, _)) = topics[..i].iter().find(|(_, u)| u == t) {
                return Err(format!("output.{key}: \"{t}\" is also output.{other}"));
            }
        }
        let rig_frames = [&frames.base_link, &frames.flange_link, &frames.left_camera, &frames.right_camera];
        for (key, f) in [("block_frame", &self.block_frame), ("block_base_frame", &self.block_base_frame)] {
            if f.is_empty() || f.starts_with('/') || f.chars().any(char::is_whitespace) {
                return Err(format!("output.{key}: \"{f}\" is not a tf frame id (non-empty, no leading / or spaces)"));
            }
            if rig_frames.contains(&f) {
                return Err(format!("output.{key}: \"{f}\" is a frame of the rig ([frames])"));
            }
        }
        if self.block_frame == self.block_base_frame {
            return Err(format!("output.block_base_frame: \"{}\" is also output.block_frame", self.block_frame));
        }
        Ok(())
    }
}

/// Where the URDF comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum UrdfSource {
    /// A `std_msgs/String` topic of the bag.
    Topic(String),
    /// A file.
    File(PathBuf),
}

impl Rig {
    /// Reads and checks `path`.
    ///
    /// # Errors
    /// Unreadable file, malformed TOML, a missing or unknown key (named, with its line), a wrong
    /// `format`, both `robot_description` and `urdf`.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| anyhow!("{}: cannot read: {e}", path.display()))?;
        Self::parse(&text, path)
    }

    /// Parses the text of a rig file (`path` names it in errors and anchors `urdf`).
    ///
    /// # Errors
    /// As [`Rig::load`].
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let mut rig: Rig = toml::from_str(text).map_err(|e| match e.span() {
            Some(span) => anyhow!("{}:{}: {}", path.display(), line_of(text, span.start), one_line(e.message())),
            None => anyhow!("{}: {}", path.display(), one_line(e.message())),
        })?;
        if rig.format != FORMAT {
            bail!("{}: format: expected \"{FORMAT}\", got \"{}\"", path.display(), rig.format);
        }
        if rig.topics.urdf.is_some() && rig.topics.robot_description.is_some() {
            bail!("{}: topics: give either robot_description or urdf, not both", path.display());
        }
        rig.output.check(&rig.frames).map_err(|e| anyhow!("{}: {e}", path.display()))?;
        rig.path = path.to_path_buf();
        if let Some(u) = &mut rig.topics.urdf {
            *u = path.parent().unwrap_or(Path::new(".")).join(&*u);
        }
        Ok(rig)
    }

    /// Where the URDF comes from.
    pub fn urdf_source(&self) -> UrdfSource {
        match (&self.topics.urdf, &self.topics.robot_description) {
            (Some(f), _) => UrdfSource::File(f.clone()),
            (None, Some(t)) => UrdfSource::Topic(t.clone()),
            (None, None) => UrdfSource::Topic("/robot_description".to_owned()),
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    const SAMPLE: &str = r#"format = "evorec-rig/1"
[topics]
left_image = "/l"
right_image = "/r"
left_info = "/li"
right_info = "/ri"
joint_states = "/joint_states"
tf_static = "/tf_static"
[frames]
base_link = "b"
flange_link = "f"
left_camera = "lc"
right_camera = "rc"
[target]
size_m = [0.1, 0.15, 0.2]
face_hues_deg = [0.0, 120.0, 240.0, 0.0, 120.0, 240.0]
"#;

    #[test]
    fn the_sample_parses_and_defaults_the_description_topic() {
        let rig = Rig::parse(SAMPLE, Path::new("rig.toml")).unwrap();
        assert_eq!(rig.urdf_source(), UrdfSource::Topic("/robot_description".into()));
        let with_file = SAMPLE.replace("tf_static = ", "urdf = \"arm.urdf\"\ntf_static = ");
        let rig = Rig::parse(&with_file, Path::new("dir/rig.toml")).unwrap();
        assert_eq!(rig.urdf_source(), UrdfSource::File(PathBuf::from("dir/arm.urdf")));
    }

    #[test]
    fn an_unknown_key_is_named_with_its_line() {
        let text = SAMPLE.replace("base_link = \"b\"", "base_link = \"b\"\nflange = \"x\"");
        let err = Rig::parse(&text, Path::new("rig.toml")).unwrap_err().to_string();
        assert!(err.starts_with("rig.toml:11:") && err.contains("unknown field `flange`"), "{err}");
        let err = Rig::parse(&SAMPLE.replace("rig/1", "rig/2"), Path::new("rig.toml")).unwrap_err().to_string();
        assert!(err.contains("format"), "{err}");
    }

    #[test]
    fn the_output_table_is_optional_and_checked() {
        let rig = Rig::parse(SAMPLE, Path::new("rig.toml")).unwrap();
        assert_eq!(rig.output, Output::default());
        let named = format!("{SAMPLE}[output]\npose_topic = \"/arm/block\"\nblock_frame = \"box\"\n");
        let rig = Rig::parse(&named, Path::new("rig.toml")).unwrap();
        assert_eq!((rig.output.pose_topic.as_str(), rig.output.block_frame.as_str()), ("/arm/block", "box"));
        assert_eq!(rig.output.tf_topic, "/tf");
        for (table, expected) in [
            ("pose_topic = \"block\"", "output.pose_topic: \"block\" is not an absolute ROS topic name"),
            ("marker_topic = \"/tf\"", "output.marker_topic: \"/tf\" is also output.tf_topic"),
            ("block_frame = \"rc\"", "output.block_frame: \"rc\" is a frame of the rig"),
            ("block_base_frame = \"evorec_block\"", "is also output.block_frame"),
            ("pose = \"/x\"", "unknown field `pose`"),
        ] {
            let err = Rig::parse(&format!("{SAMPLE}[output]\n{table}\n"), Path::new("rig.toml")).unwrap_err();
            assert!(err.to_string().contains(expected), "{table}: {err}");
        }
    }
}
