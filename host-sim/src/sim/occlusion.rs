//! Acquisition scenarios: an unknown start (`[start] initial`), a random block pose
//! (`[target] placement`) and occlusions (`[[occlusion]]`), and the occluder's rendering. The
//! keys are parsed and validated with the rest of the scenario file (`crate::sim::scenario`).
//!
//! ```toml
//! [start]
//! initial = "unknown"      # "truth" (default: the population starts around the true pose,
//!                          # as in the paper) | "unknown" (uniform over the search space)
//!
//! [target]
//! placement = "random"     # "fixed" (default: distance_m ahead, yaw0_deg) | "random": a pose
//!                          # drawn from the seed, centre uniform in the search space, rotation
//!                          # uniform, the block entirely inside both images at t = 0
//!
//! [[occlusion]]            # up to MAX_OCCLUSIONS entries
//! start_s = 3.0            # [0, duration_s]
//! duration_s = 1.0         # (0, 3600]
//! kind = "occluder"        # "occluder" (default: a grey board in front of both cameras hides
//!                          # the block) | "removed" (the block is taken out of the scene)
//! ```

use image::RgbImage;
use nalgebra::{Isometry3, Point3};
use serde::Serialize;
use serde::ser::SerializeSeq;

/// Most `[[occlusion]]` entries a scenario may hold.
pub const MAX_OCCLUSIONS: usize = 8;

/// Margin (pixels) by which the occluder exceeds the block's image in every direction.
pub const OCCLUDER_MARGIN_PX: f32 = 30.0;

/// Grey level of the occluder (no hue).
pub const OCCLUDER_LEVEL: u8 = 85;

/// How the tracker's population starts (`[start] initial`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
pub enum Initial {
    /// Around the true pose at `t = 0` (the paper's set-up).
    #[default]
    #[serde(rename = "truth")]
    Truth,
    /// Uniform over the search space: the tracker must find the block.
    #[serde(rename = "unknown")]
    Unknown,
}

/// Where the block stands (`[target] placement`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
pub enum Placement {
    /// `distance_m` ahead of the stereo pair with yaw `yaw0_deg` (the paper's set-up).
    #[default]
    #[serde(rename = "fixed")]
    Fixed,
    /// A pose drawn from the scenario's seed (see [`crate::sim::board::random_target_pose`]).
    #[serde(rename = "random")]
    Random,
}

/// What hides the block.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum OcclusionKind {
    /// A grey board in front of both cameras covers the block's image.
    #[serde(rename = "occluder")]
    Occluder,
    /// The block is removed from the scene.
    #[serde(rename = "removed")]
    Removed,
}

/// One `[[occlusion]]` entry.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Occlusion {
    /// Start (s).
    pub start_s: f64,
    /// Duration (s).
    pub duration_s: f64,
    /// What hides the block.
    pub kind: OcclusionKind,
}

impl Occlusion {
    /// Whether the block is hidden at time `t` (`start ≤ t < start + duration`).
    pub fn covers(&self, t: f64) -> bool {
        t >= self.start_s && t < self.start_s + self.duration_s
    }
}

/// The occlusions of a scenario (a fixed-capacity list, so scenarios stay `Copy`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Occlusions {
    items: [Option<Occlusion>; MAX_OCCLUSIONS],
}

impl Occlusions {
    /// A list from up to [`MAX_OCCLUSIONS`] entries (later ones are dropped).
    pub fn from_slice(list: &[Occlusion]) -> Self {
        let mut items = [None; MAX_OCCLUSIONS];
        for (slot, o) in items.iter_mut().zip(list) {
            *slot = Some(*o);
        }
        Self { items }
    }

    /// The entries.
    pub fn iter(&self) -> impl Iterator<Item = &Occlusion> {
        self.items.iter().flatten()
    }

    /// No entries.
    pub fn is_empty(&self) -> bool {
        self.items.iter().all(Option::is_none)
    }

    /// The occlusion active at `t`, if any (the first listed wins).
    pub fn at(&self, t: f64) -> Option<OcclusionKind> {
        self.iter().find(|o| o.covers(t)).map(|o| o.kind)
    }
}

impl Serialize for Occlusions {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(self.iter().count()))?;
        for o in self.iter() {
            seq.serialize_element(o)?;
        }
        seq.end()
    }
}

/// Paints the occluder over `img`: a flat grey rectangle (no hue) covering the image of
/// `corners` (points in this camera's frame) plus [`OCCLUDER_MARGIN_PX`], clipped to the
/// image. Corners behind the camera make it cover the whole image.
pub fn paint_occluder(img: &mut RgbImage, cam: &evorec_core::camera::Pinhole, corners: &[Point3<f32>]) {
    let (w, h) = (img.width() as f32, img.height() as f32);
    let mut bbox = [f32::MAX, f32::MAX, f32::MIN, f32::MIN];
    for c in corners {
        match cam.project_unbounded(c) {
            Ok(p) => bbox = [bbox[0].min(p.x), bbox[1].min(p.y), bbox[2].max(p.x), bbox[3].max(p.y)],
            Err(_) => bbox = [0.0, 0.0, w, h],
        }
    }
    let m = OCCLUDER_MARGIN_PX;
    let (x0, y0) = ((bbox[0] - m).clamp(0.0, w) as u32, (bbox[1] - m).clamp(0.0, h) as u32);
    let (x1, y1) = ((bbox[2] + m).clamp(0.0, w) as u32, (bbox[3] + m).clamp(0.0, h) as u32);
    for y in y0..y1 {
        for x in x0..x1 {
            // A faint texture, still grey (r = g = b has no hue).
            let g = OCCLUDER_LEVEL.wrapping_add(((x * 7 + y * 13) % 9) as u8);
            img.put_pixel(x, y, image::Rgb([g, g, g]));
        }
    }
}

/// The block's corners transformed by `pose` (model → camera).
pub fn corners_in(pose: &Isometry3<f32>, block: &evorec_core::model::Block) -> [Point3<f32>; 8] {
    block.corners().map(|c| pose * c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenario_keys_round_trip_and_are_checked() {
        use crate::sim::scenario::Scenario;
        let text = "seed = 3\nduration_s = 4.0\n[start]\ninitial = \"unknown\"\n[target]\nplacement = \"random\"\n[[occlusion]]\nstart_s = 1.0\nduration_s = 1.0\nkind = \"removed\"\n";
        let s = Scenario::from_toml_str(text).unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(s.start.initial, Initial::Unknown);
        assert_eq!(s.target.placement, Placement::Random);
        assert_eq!(s.occlusion.at(1.5), Some(OcclusionKind::Removed));
        let back = Scenario::from_toml_str(&s.to_toml_string().unwrap_or_else(|e| unreachable!("{e}")))
            .unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(back, s);
        let err =
            |t: &str| Scenario::from_toml_str(&format!("seed = 1\nduration_s = 2\n{t}")).err().map(|e| e.to_string());
        assert_eq!(
            err("[start]\ninitial = \"maybe\"\n").as_deref(),
            Some("start.initial: expected \"truth\" or \"unknown\", got \"maybe\"")
        );
        assert!(err("[start]\nstart = 1\n").is_some_and(|e| e.starts_with("start.start: unknown key")));
        assert!(
            err("[[occlusion]]\nstart_s = 3\nduration_s = 1\n").is_some_and(|e| e.starts_with("occlusion[0].start_s"))
        );
    }

    #[test]
    fn a_hidden_block_has_no_hue_and_random_poses_differ() {
        use crate::sim::board::World;
        use crate::sim::scenario::Scenario;
        use evorec_core::tuning::Feedforward;
        let mut s = Scenario::small(5, 3.0, Feedforward::On);
        s.occlusion = Occlusions::from_slice(&[
            Occlusion { start_s: 0.0, duration_s: 1.0, kind: OcclusionKind::Occluder },
            Occlusion { start_s: 1.0, duration_s: 1.0, kind: OcclusionKind::Removed },
        ]);
        let mut world = World::new(&s).unwrap_or_else(|e| unreachable!("{e}"));
        let hues = |w: &mut World| {
            let img = w.render();
            [img.left, img.right]
                .iter()
                .map(|i| crate::sim::render::hue_image(i).iter().filter(|h| **h != evorec_core::limits::NO_HUE).count())
                .sum::<usize>()
        };
        assert!(world.occlusion().is_some());
        assert_eq!(hues(&mut world), 0);
        world.advance_to(1.5);
        assert_eq!(world.occlusion(), Some(OcclusionKind::Removed));
        assert_eq!(hues(&mut world), 0);
        world.advance_to(2.5);
        assert_eq!(world.occlusion(), None);
        assert!(hues(&mut world) > 500);
        // Random placements: different seeds, different poses, centres in the search space.
        s.target.placement = Placement::Random;
        let space = crate::sim::board::search_space();
        let mut truths = Vec::new();
        for seed in [1, 2] {
            s.seed = seed;
            let t = World::new(&s).unwrap_or_else(|e| unreachable!("{e}")).truth();
            for i in 0..3 {
                assert!(t.0[i] >= space.t_min()[i] - 1e-3 && t.0[i] <= space.t_max()[i] + 1e-3, "{t:?}");
            }
            truths.push(t);
        }
        assert_ne!(truths[0], truths[1]);
    }
}
