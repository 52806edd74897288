//! Transforms from `/tf_static` (and `/tf` where a transform never changes): the pose of one
//! frame in another, composed through any chain of frames, in either direction.
//!
//! tf's convention: a `TransformStamped` with `header.frame_id = P` and `child_frame_id = C`
//! is C's pose in P (it maps points given in C into P).

use std::collections::{BTreeMap, BTreeSet, VecDeque};

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

use super::msgs::TransformStamped;

/// Largest deviation of a rotation quaternion's norm from 1 accepted.
pub const UNIT_TOLERANCE: f64 = 1e-3;

/// Two publications of one `/tf` transform differing by more than this (m, or quaternion
/// component) make it a moving transform.
pub const STATIC_TOLERANCE: f64 = 1e-9;

#[derive(Debug, Clone)]
struct Edge {
    pose: Isometry3<f64>,
    raw: ([f64; 3], [f64; 4]),
    /// Where it was published: topic and message index.
    source: (String, usize),
    /// Set when a later `/tf` message gave it another value (that message's index).
    moves_at: Option<usize>,
}

/// The transforms of a bag.
#[derive(Debug, Clone, Default)]
pub struct TfTree {
    edges: BTreeMap<(String, String), Edge>,
}

impl TfTree {
    /// Adds the transforms of one message of `topic` (`dynamic`: `/tf`, where only transforms
    /// that never change are usable).
    ///
    /// # Errors
    /// A non-finite value or a rotation that is not a unit quaternion, naming the frames.
    pub fn add(
        &mut self,
        topic: &str,
        index: usize,
        transforms: &[TransformStamped],
        dynamic: bool,
    ) -> Result<(), String> {
        for t in transforms {
            let name = format!("transform {} → {}", t.header.frame_id, t.child_frame_id);
            let pose = rigid(t).map_err(|e| format!("{name}: {e}"))?;
            let key = (t.header.frame_id.clone(), t.child_frame_id.clone());
            let raw = (t.translation, t.rotation);
            match self.edges.get_mut(&key) {
                Some(e) if dynamic && e.moves_at.is_none() && differs(&e.raw, &raw) => e.moves_at = Some(index),
                Some(_) if dynamic => {}
                _ => {
                    let source = (topic.to_owned(), index);
                    self.edges.insert(key, Edge { pose, raw, source, moves_at: None });
                }
            }
        }
        Ok(())
    }

    /// The frames named by any transform.
    pub fn frames(&self) -> BTreeSet<&str> {
        self.edges.keys().flat_map(|(p, c)| [p.as_str(), c.as_str()]).collect()
    }

    /// `child`'s pose in `parent`, composed along the chain of transforms between them.
    ///
    /// # Errors
    /// No chain between them (listing the frames known), or a transform on it that moves.
    pub fn pose_of(&self, child: &str, parent: &str) -> Result<Isometry3<f64>, String> {
        if child == parent {
            return Ok(Isometry3::identity());
        }
        // Breadth-first from `parent`; each step's pose is the next frame's pose in `parent`.
        let mut seen: BTreeMap<&str, Isometry3<f64>> = BTreeMap::from([(parent, Isometry3::identity())]);
        let mut queue = VecDeque::from([parent]);
        while let Some(frame) = queue.pop_front() {
            let here = seen.get(frame).copied().unwrap_or_else(Isometry3::identity);
            for ((p, c), e) in &self.edges {
                let (next, step) = match (p.as_str() == frame, c.as_str() == frame) {
                    (true, _) => (c.as_str(), e.pose),
                    (_, true) => (p.as_str(), e.pose.inverse()),
                    _ => continue,
                };
                if seen.contains_key(next) {
                    continue;
                }
                if let Some(k) = e.moves_at {
                    return Err(format!(
                        "transform {p} → {c} on {} changes at message {k}: it is not static, so it cannot place the cameras",
                        e.source.0
                    ));
                }
                seen.insert(next, here * step);
                if next == child {
                    return Ok(here * step);
                }
                queue.push_back(next);
            }
        }
        let known: Vec<&str> = self.frames().into_iter().collect();
        Err(format!("no transform between '{parent}' and '{child}' (frames known: {})", known.join(", ")))
    }
}

fn differs(a: &([f64; 3], [f64; 4]), b: &([f64; 3], [f64; 4])) -> bool {
    a.0.iter().chain(&a.1).zip(b.0.iter().chain(&b.1)).any(|(x, y)| (x - y).abs() > STATIC_TOLERANCE)
}

fn rigid(t: &TransformStamped) -> Result<Isometry3<f64>, String> {
    let [x, y, z] = t.translation;
    let [qx, qy, qz, qw] = t.rotation;
    if !t.translation.iter().chain(&t.rotation).all(|v| v.is_finite()) {
        return Err("not rigid: a value is not finite".to_owned());
    }
    let q = Quaternion::new(qw, qx, qy, qz);
    if (q.norm() - 1.0).abs() > UNIT_TOLERANCE {
        return Err(format!(
            "not rigid: the rotation quaternion has norm {:.6}, not 1 (tolerance {UNIT_TOLERANCE})",
            q.norm()
        ));
    }
    Ok(Isometry3::from_parts(Translation3::new(x, y, z), UnitQuaternion::from_quaternion(q)))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::rig::bag::msgs::Header;
    use nalgebra::Vector3;

    fn tf(p: &str, c: &str, t: [f64; 3], q: [f64; 4]) -> TransformStamped {
        TransformStamped {
            header: Header { stamp_ns: 0, frame_id: p.into() },
            child_frame_id: c.into(),
            translation: t,
            rotation: q,
        }
    }

    #[test]
    fn chains_compose_in_both_directions() {
        let s = 0.5f64.sqrt();
        let mut tree = TfTree::default();
        // flange → mount (turned 90° about z), mount → right, right → left.
        tree.add("/tf_static", 0, &[tf("flange", "mount", [0.0, 0.0, 0.1], [0.0, 0.0, s, s])], false).unwrap();
        tree.add("/tf_static", 1, &[tf("mount", "right", [0.2, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])], false).unwrap();
        tree.add("/tf_static", 1, &[tf("right", "left", [-0.1, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])], false).unwrap();
        let right_in_flange = tree.pose_of("right", "flange").unwrap();
        assert!((right_in_flange.translation.vector - Vector3::new(0.0, 0.2, 0.1)).norm() < 1e-12);
        let right_in_left = tree.pose_of("right", "left").unwrap();
        assert!((right_in_left.translation.vector - Vector3::new(0.1, 0.0, 0.0)).norm() < 1e-12);
        let err = tree.pose_of("right", "nowhere").unwrap_err();
        assert!(err.contains("no transform between 'nowhere' and 'right'") && err.contains("flange"), "{err}");
    }

    #[test]
    fn non_rigid_and_moving_transforms_are_refused() {
        let mut tree = TfTree::default();
        let err = tree.add("/tf_static", 3, &[tf("a", "b", [0.0; 3], [0.0, 0.0, 0.0, 2.0])], false).unwrap_err();
        assert!(err.contains("a → b") && err.contains("not rigid"), "{err}");
        tree.add("/tf", 0, &[tf("a", "b", [0.0; 3], [0.0, 0.0, 0.0, 1.0])], true).unwrap();
        tree.add("/tf", 1, &[tf("a", "b", [0.0; 3], [0.0, 0.0, 0.0, 1.0])], true).unwrap();
        assert!(tree.pose_of("b", "a").is_ok());
        tree.add("/tf", 2, &[tf("a", "b", [0.1, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])], true).unwrap();
        let err = tree.pose_of("b", "a").unwrap_err();
        assert!(err.contains("changes at message 2"), "{err}");
    }
}
