//! `evorec rig BAG`: a rig file (`evorec-rig/1`) drafted from what the bag holds. Topics are
//! found by message type, the camera frames from the images' `header.frame_id`, the base link
//! as the URDF's root and the flange as the first URDF link met going up `/tf_static` from the
//! right camera. Where the bag leaves a choice (two image topics neither named left nor
//! right, several joint state topics…) the key is left as `"TODO"` with the candidates listed
//! in a comment: nothing is guessed. The block cannot be seen in a bag: its `[target]` section
//! is written commented out, for the user to fill in.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Result, anyhow};

use super::BagFiles;
use super::msgs;
use super::scan::{COMPRESSED_IMAGE, IMAGE, Msg, TF_TOPIC, for_each_message};

const CAMERA_INFO: &str = "sensor_msgs/msg/CameraInfo";
const JOINT_STATE: &str = "sensor_msgs/msg/JointState";
const TF_MESSAGE: &str = "tf2_msgs/msg/TFMessage";
const STRING: &str = "std_msgs/msg/String";

/// What the bag says about its rig.
#[derive(Debug, Default)]
struct Found {
    /// Topic → schema.
    channels: BTreeMap<String, String>,
    /// Image and camera_info topics → the first message's `header.frame_id`.
    frame_ids: BTreeMap<String, String>,
    /// Static transforms: child → parent.
    parents: BTreeMap<String, String>,
    /// The URDF, and its topic.
    urdf: Option<(String, String)>,
}

impl Found {
    fn take(&mut self, m: &Msg<'_>) -> Result<()> {
        let frame_id = match m.schema {
            IMAGE => Some(msgs::image(m.data)?.header.frame_id),
            COMPRESSED_IMAGE => Some(msgs::compressed_image(m.data)?.header.frame_id),
            CAMERA_INFO => Some(msgs::camera_info(m.data)?.header.frame_id),
            _ => None,
        };
        if let Some(id) = frame_id {
            self.frame_ids.entry(m.topic.to_owned()).or_insert(id);
        } else if m.schema == TF_MESSAGE && m.topic != TF_TOPIC {
            for t in msgs::tf_message(m.data)? {
                self.parents.insert(t.child_frame_id, t.header.frame_id);
            }
        } else if m.schema == STRING && m.topic.ends_with("robot_description") && self.urdf.is_none() {
            self.urdf = Some((m.topic.to_owned(), msgs::string(m.data)?));
        }
        Ok(())
    }

    fn topics_of(&self, schemas: &[&str]) -> Vec<&str> {
        self.channels.iter().filter(|(_, s)| schemas.contains(&s.as_str())).map(|(t, _)| t.as_str()).collect()
    }
}

/// One key of the draft: its value, or the candidates the user must choose from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Choice {
    /// Found.
    Found(String),
    /// Not decided: why, and the candidates.
    Open(String),
}

impl Choice {
    fn value(&self) -> &str {
        match self {
            Self::Found(v) => v,
            Self::Open(_) => "TODO",
        }
    }
}

/// The one of `candidates` whose name holds `side` (`left` / `right`), if exactly one does.
pub fn by_side(candidates: &[&str], side: &str) -> Choice {
    let named: Vec<&&str> = candidates.iter().filter(|c| c.to_lowercase().contains(side)).collect();
    match named.as_slice() {
        [one] => Choice::Found((**one).to_owned()),
        _ => Choice::Open(format!("no single {side} one among: {}", list(candidates))),
    }
}

fn list(candidates: &[&str]) -> String {
    if candidates.is_empty() { "none in the bag".to_owned() } else { candidates.join(", ") }
}

/// The only candidate, or `preferred` among several.
fn single(candidates: &[&str], preferred: &str, what: &str) -> Choice {
    match candidates {
        [one] => Choice::Found((*one).to_owned()),
        _ if candidates.contains(&preferred) => Choice::Found(preferred.to_owned()),
        _ => Choice::Open(format!("{what}: {}", list(candidates))),
    }
}

/// A drafted rig file: its text and the keys left to the user.
#[derive(Debug, Clone)]
pub struct Draft {
    /// The TOML text.
    pub text: String,
    /// One line per key left as `"TODO"`.
    pub open: Vec<String>,
}

/// Drafts the rig file of `bag`.
///
/// # Errors
/// An unreadable bag or a malformed message of a type read.
pub fn draft(bag: &Path) -> Result<Draft> {
    let files = BagFiles::open(bag)?;
    let name = files.display();
    let mut found = Found::default();
    let pass = for_each_message(&files, |m| {
        found.take(m).map_err(|e| anyhow!("{name}: {} message {}: {e}", m.topic, m.index))?;
        Ok(true)
    })?;
    if let Some(cut) = pass.cut {
        log::warn!("{cut}: the rig file is drafted from the messages before it");
    }
    found.channels = pass.channels;
    Ok(write(&found, &name))
}

/// The keys, in the rig file's order, and their choices.
fn choices(found: &Found) -> Vec<(&'static str, Choice)> {
    let images = found.topics_of(&[IMAGE, COMPRESSED_IMAGE]);
    let infos = found.topics_of(&[CAMERA_INFO]);
    let (left, right) = (by_side(&images, "left"), by_side(&images, "right"));
    let info_of = |image: &Choice, side: &str| match image {
        Choice::Found(topic) => {
            let id = found.frame_ids.get(topic);
            let same: Vec<&str> = infos.iter().copied().filter(|i| found.frame_ids.get(*i) == id).collect();
            if same.len() == 1 { Choice::Found(same[0].to_owned()) } else { by_side(&infos, side) }
        }
        Choice::Open(_) => by_side(&infos, side),
    };
    let frame_of = |image: &Choice| match image {
        Choice::Found(t) => found
            .frame_ids
            .get(t)
            .map_or_else(|| Choice::Open(format!("{t} has no frame_id")), |f| Choice::Found(f.clone())),
        Choice::Open(_) => Choice::Open("the image topic is not decided".to_owned()),
    };
    let (left_camera, right_camera) = (frame_of(&left), frame_of(&right));
    let (base, flange) = links(found, &right_camera);
    vec![
        ("left_info", info_of(&left, "left")),
        ("right_info", info_of(&right, "right")),
        ("joint_states", single(&found.topics_of(&[JOINT_STATE]), "/joint_states", "sensor_msgs/JointState topics")),
        (
            "robot_description",
            found.urdf.as_ref().map_or_else(
                || Choice::Open("no robot_description topic: give urdf = \"FILE\" instead".to_owned()),
                |(t, _)| Choice::Found(t.clone()),
            ),
        ),
        (
            "tf_static",
            single(
                &found.topics_of(&[TF_MESSAGE]).into_iter().filter(|t| *t != TF_TOPIC).collect::<Vec<_>>(),
                "/tf_static",
                "tf2_msgs/TFMessage topics",
            ),
        ),
        ("base_link", base),
        ("flange_link", flange),
        ("left_camera", left_camera),
        ("right_camera", right_camera),
        ("left_image", left),
        ("right_image", right),
    ]
}

/// The URDF's root link, and the first URDF link above the right camera in `/tf_static`.
fn links(found: &Found, right_camera: &Choice) -> (Choice, Choice) {
    let Some((_, text)) = &found.urdf else {
        let open = || Choice::Open("no URDF in the bag".to_owned());
        return (open(), open());
    };
    let Ok(robot) = urdf_rs::read_from_string(text) else {
        let open = || Choice::Open("the URDF does not parse".to_owned());
        return (open(), open());
    };
    let children: Vec<&str> = robot.joints.iter().map(|j| j.child.link.as_str()).collect();
    let roots: Vec<&str> = robot.links.iter().map(|l| l.name.as_str()).filter(|l| !children.contains(l)).collect();
    let base = single(&roots, "", "URDF root links");
    let mut frame = right_camera.value().to_owned();
    let mut hops = 0;
    while let Some(parent) = found.parents.get(&frame).filter(|_| hops < 64) {
        if robot.links.iter().any(|l| l.name == *parent) {
            return (base, Choice::Found(parent.clone()));
        }
        (frame, hops) = (parent.clone(), hops + 1);
    }
    (base, Choice::Open(format!("no URDF link above {} in the static transforms", right_camera.value())))
}

fn write(found: &Found, name: &str) -> Draft {
    let choices = choices(found);
    let get = |key: &str| {
        choices.iter().find(|(k, _)| *k == key).map(|(_, c)| c.clone()).unwrap_or(Choice::Open(String::new()))
    };
    let mut text =
        format!("format = \"evorec-rig/1\"\n# drafted by `evorec rig` from {name}: check it, then fill in [target]\n");
    let mut open = Vec::new();
    for (section, keys) in [
        (
            "topics",
            &["left_image", "right_image", "left_info", "right_info", "joint_states", "robot_description", "tf_static"]
                [..],
        ),
        ("frames", &["base_link", "flange_link", "left_camera", "right_camera"][..]),
    ] {
        let _ = writeln!(text, "\n[{section}]");
        for key in keys {
            let choice = get(key);
            let _ = write!(text, "{key} = {:?}", choice.value());
            if let Choice::Open(why) = &choice {
                let _ = write!(text, "  # TODO {why}");
                open.push(format!("{section}.{key}: {why}"));
            }
            text.push('\n');
        }
    }
    text.push_str(
        "\n# TODO the block, which a bag does not show: uncomment and fill in (docs/own-rig.md, ROS 2 bags)\n\
         # [target]\n\
         # size_m = [0.1, 0.15, 0.2]                                 # edges along the block's x, y, z (m)\n\
         # face_hues_deg = [0.0, 120.0, 240.0, 0.0, 120.0, 240.0]    # faces +x, +y, +z, -x, -y, -z\n",
    );
    Draft { text, open }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn sides_are_taken_from_names_or_left_open() {
        let named = ["/cam/left/image_raw", "/cam/right/image_raw"];
        assert_eq!(by_side(&named, "left"), Choice::Found("/cam/left/image_raw".into()));
        let unnamed = ["/cam0/image_raw", "/cam1/image_raw"];
        assert_eq!(
            by_side(&unnamed, "right"),
            Choice::Open("no single right one among: /cam0/image_raw, /cam1/image_raw".into())
        );
        assert_eq!(single(&["/a", "/joint_states"], "/joint_states", "x"), Choice::Found("/joint_states".into()));
        assert!(matches!(single(&["/a", "/b"], "/joint_states", "x"), Choice::Open(_)));
    }
}
