//! What the results bag ([`super::write_mcap`]) says of each tracked frame, beyond the
//! tracker's estimate: the camera's pose in the base link, the estimate's covariance and the
//! block's velocity.
//!
//! - **Camera in the base link**: `^B T_CR = ^B T_H(q) · ^H T_CR`, the chain's forward
//!   kinematics at the frame's joint sample (the one the tracker was given) and the hand-eye
//!   transform.
//! - **Covariance**: the tracker keeps none per estimate (a GA's population is no posterior),
//!   so the estimate is given the measurement covariance the core's target filter assigns it
//!   ([`evorec_core::target_motion`]): with the tuning's image noise `σ` (px,
//!   `target.image_noise_px`), the rig's focal length `f` and baseline `b` and the block at
//!   range `Z`, `σ⊥ = Z·σ/f` across the line of sight and `σ∥ = Z²·σ/(f·b)` along it, i.e.
//!   `R = σ⊥² I + (σ∥² − σ⊥²) u uᵀ` with `u` the unit line of sight from the right camera
//!   (for a block on the optical axis: the diagonal `σ⊥², σ⊥², σ∥²`), and each rotation axis
//!   `(σ⊥ / r)²` with `r` the block's mean half-extent. The cross terms of position and
//!   rotation are 0.
//! - **Velocity**: the core's [`TargetFilter`] (with the tuning's `target.*` parameters and
//!   the rig's optics) fed each frame's `target_measurement` and status through
//!   [`TargetFilter::update_from_estimate`], as the tracker feeds its own with
//!   `--method ff+target`; the velocity once the filter has seen two tracked estimates in a
//!   row, in the base link.

use anyhow::{Result, anyhow, bail};
use evorec_core::kinematics::{Chain, JointSample};
use evorec_core::status::Status;
use evorec_core::target_motion::{Optics, TargetFilter};
use nalgebra::{Isometry3, Matrix3};

use super::BagSequence;
use crate::rig::track::{self, TrackOutput};

/// One tracked frame as the results bag gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameResult {
    /// Capture stamp (ns since the epoch).
    pub stamp_ns: i64,
    /// `^CR T_M`.
    pub pose: Isometry3<f64>,
    /// The pose's covariance, row-major 6 × 6 (x, y, z, rotation about x, y, z; the right
    /// camera's frame).
    pub covariance: [f64; 36],
    /// `^B T_CR`: the right camera in the base link.
    pub camera_in_base: Isometry3<f64>,
    /// The block's velocity (m/s) and angular velocity (rad/s) in the base link, once the
    /// target filter has observed it.
    pub velocity: Option<([f64; 3], [f64; 3])>,
    /// The tracker's status.
    pub status: Status,
    /// Fitness.
    pub fitness: f32,
}

/// The results of every tracked frame of `bag`.
///
/// # Errors
/// A chain the tracker would not have run on, or target filter parameters it refuses.
pub fn frame_results(bag: &BagSequence, out: &TrackOutput) -> Result<Vec<FrameResult>> {
    match bag.seq.robot.dof() {
        6 => frames_dof::<6>(bag, out, bag.seq.robot.chain::<6>()?),
        7 => frames_dof::<7>(bag, out, bag.seq.robot.chain::<7>()?),
        n => bail!("the chain has {n} movable joints; evorec tracks arms of 6 or 7"),
    }
}

fn frames_dof<const DOF: usize>(bag: &BagSequence, out: &TrackOutput, chain: Chain<DOF>) -> Result<Vec<FrameResult>> {
    let seq = &bag.seq;
    let mount = seq.manifest.flange_to_right.cast::<f32>();
    let optics = Optics::of(&seq.rig, &seq.block);
    let params = out.options.tuning.target;
    let mut filter = TargetFilter::new(params).map_err(|e| anyhow!("target filter: {e}"))?.with_optics(optics);
    let t0 = seq.frames.first().map_or(0.0, |f| f.t_s);
    let array = |v: &[f32]| std::array::from_fn(|k| v.get(k).copied().unwrap_or(f32::NAN));
    let mut results = Vec::with_capacity(out.tracked.len());
    for t in &out.tracked {
        // The joint sample the board gave the tracker (`track::board`).
        let time_us = ((seq.frames[t.i].t_s - t0) * 1e6).round().max(0.0) as u64;
        let joints = JointSample::<DOF> { q: array(&t.q), qd: array(&t.qd), time_us };
        filter.update_from_estimate(&chain, &mount, &joints, &t.target_measurement, t.status);
        let camera = chain.forward(&joints.q) * mount;
        let pose = track::estimate_pose(t);
        let f64s = |v: nalgebra::Vector3<f32>| [v.x, v.y, v.z].map(f64::from);
        results.push(FrameResult {
            stamp_ns: bag.stamps_ns.get(t.i).copied().unwrap_or(0),
            pose,
            covariance: covariance(&pose, &optics, params.image_noise_px),
            camera_in_base: camera.cast(),
            velocity: filter.velocity().map(|v| (f64s(v.v), f64s(v.w))),
            status: t.status,
            fitness: t.fitness,
        });
    }
    Ok(results)
}

/// The covariance of an estimate `pose` (`^CR T_M`) seen through `optics` with image noise
/// `sigma_px` (see the module docs).
pub fn covariance(pose: &Isometry3<f64>, optics: &Optics, sigma_px: f32) -> [f64; 36] {
    let sight = pose.translation.vector;
    let range = sight.norm();
    let (across, along) = optics.position_noise(range as f32, sigma_px);
    let (across, along) = (f64::from(across), f64::from(along));
    let u = if range > 1e-9 { sight / range } else { sight * 0.0 };
    let r = Matrix3::identity() * (across * across) + u * u.transpose() * (along * along - across * across);
    let rot = (across / f64::from(optics.radius_m)).powi(2);
    let mut c = [0.0; 36];
    for i in 0..3 {
        for j in 0..3 {
            c[6 * i + j] = r[(i, j)];
        }
        c[6 * (i + 3) + i + 3] = rot;
    }
    c
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    #[test]
    fn a_block_on_the_axis_has_the_diagonal_of_the_stereo_geometry() {
        let optics = Optics { focal_px: 800.0, baseline_m: 0.1, radius_m: 0.075 };
        let pose = Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.8), UnitQuaternion::identity());
        let c = covariance(&pose, &optics, 0.5);
        let lateral = 0.8 * 0.5 / 800.0;
        let depth = 0.8 * 0.8 * 0.5 / (800.0 * 0.1);
        let expected = [lateral * lateral, lateral * lateral, depth * depth];
        for (i, e) in expected.iter().enumerate() {
            assert!((c[7 * i] - e).abs() < 1e-5 * e, "{i}: {} vs {e}", c[7 * i]);
        }
        let rot = (lateral / 0.075) * (lateral / 0.075);
        assert!((c[21] - rot).abs() < 1e-5 * rot && (c[35] - rot).abs() < 1e-5 * rot);
        assert_eq!(c.iter().filter(|v| **v != 0.0).count(), 6);
    }

    #[test]
    fn off_axis_the_depth_lies_along_the_line_of_sight() {
        let optics = Optics { focal_px: 800.0, baseline_m: 0.1, radius_m: 0.075 };
        let pose = Isometry3::from_parts(Translation3::new(0.3, 0.0, 0.4), UnitQuaternion::identity());
        let c = covariance(&pose, &optics, 0.5);
        let u = nalgebra::Vector3::new(0.6, 0.0, 0.8);
        let r = Matrix3::from_fn(|i, j| c[6 * i + j]);
        let (across, along) = optics.position_noise(0.5, 0.5);
        let along_var = (u.transpose() * r * u)[0];
        assert!((along_var - f64::from(along).powi(2)).abs() < 1e-6 * along_var, "{along_var}");
        let side = nalgebra::Vector3::new(0.0, 1.0, 0.0);
        assert!(
            ((side.transpose() * r * side)[0] - f64::from(across).powi(2)).abs() < 1e-5 * f64::from(across).powi(2)
        );
        assert!((c[2] - c[12]).abs() < 1e-18, "symmetric");
    }
}
