//! The tracker's private rules, on exact synthetic frames.

use nalgebra::{Isometry3, Vector3};

use super::*;
use crate::image::HueImage;
use crate::limits::NO_HUE;
use crate::quat;
use crate::synth;

const W: u16 = 320;
const H: u16 = 240;
const STILL: JointSample<7> = JointSample { q: [0.0; 7], qd: [0.0; 7], time_us: 0 };

/// A tracker without feedforward and a stereo pair of exact hue images of the block at `truth`.
fn tracker_and_frame(truth: &Psi) -> (Tracker<7, 40, 8>, std::vec::Vec<u8>, std::vec::Vec<u8>) {
    let rig = StereoRig::parallel(Pinhole::new_checked(400.0, 400.0, 160.0, 120.0, W, H).unwrap(), 0.1).unwrap();
    let iso = truth.try_to_isometry().unwrap();
    let n = usize::from(W) * usize::from(H);
    let (mut l, mut r) = (std::vec![NO_HUE; n], std::vec![NO_HUE; n]);
    synth::render_block(&Block::PAPER, &rig.right, &iso, &mut r).unwrap();
    synth::render_block(&Block::PAPER, &rig.left, &(rig.left_from_right * iso), &mut l).unwrap();
    let space = SearchSpace::new_checked([-0.4, -0.4, 0.3], [0.4, 0.4, 1.3]).unwrap();
    let config = TrackerConfig::pa10(rig, Block::PAPER, Isometry3::identity(), space)
        .with_seed(1)
        .with_feedforward(Feedforward::Off);
    (Tracker::new(config).unwrap(), l, r)
}

/// Steps `t` on the pair until the acquisition has a seed.
fn step_to_a_seed(t: &mut Tracker<7, 40, 8>, l: &[u8], r: &[u8]) {
    let frame =
        StereoFrame { left: HueImage::new_checked(l, W, H).unwrap(), right: HueImage::new_checked(r, W, H).unwrap() };
    let mut frames = 0;
    while t.acquisition.seed().is_none() {
        t.step(&frame, &STILL, 0.033).unwrap();
        frames += 1;
        assert!(frames < 20, "no seed after {frames} frames");
    }
}

#[test]
fn a_candidate_is_confirmed_only_where_the_blobs_put_the_block() {
    let q = quat::from_angle_axis(2.2, &Vector3::new(0.4, -1.0, 0.3)).unwrap();
    let truth = Psi::from_parts(&Vector3::new(-0.04, 0.03, 0.8), &q);
    let (mut t, l, r) = tracker_and_frame(&truth);
    // Without a seed yet, every candidate may be confirmed.
    assert!(t.agrees_with_seed(&Psi::from_parts(&Vector3::new(0.3, 0.3, 1.2), &q)));
    step_to_a_seed(&mut t, &l, &r);
    assert!(!t.acquisition.seed().unwrap().cut);
    let reach = t.model.half_size().norm();
    let along = |d: f32| Psi::from_parts(&(truth.translation() + Vector3::new(0.0, 0.0, d)), &q);
    assert!(t.agrees_with_seed(&truth));
    // A pose at the wrong depth by more than the block's own extent is another hypothesis.
    assert!(!t.agrees_with_seed(&along(2.0 * reach)));
    assert!(!t.agrees_with_seed(&along(-2.0 * reach)));
}

#[test]
fn a_seed_from_a_block_cut_by_the_image_border_refuses_no_candidate() {
    // The block's centre 10 px inside the right image's border: part of it is outside.
    let q = quat::from_angle_axis(2.2, &Vector3::new(0.4, -1.0, 0.3)).unwrap();
    let truth = Psi::from_parts(&Vector3::new(0.3, 0.03, 0.8), &q);
    let (mut t, l, r) = tracker_and_frame(&truth);
    step_to_a_seed(&mut t, &l, &r);
    assert!(t.acquisition.seed().unwrap().cut);
    let reach = t.model.half_size().norm();
    let along = |d: f32| Psi::from_parts(&(truth.translation() + Vector3::new(0.0, 0.0, d)), &q);
    assert!(t.agrees_with_seed(&truth));
    assert!(t.agrees_with_seed(&along(2.0 * reach)));
}

/// The statuses of `frames` frames of a tracker started on the block at `truth`.
fn statuses_from_the_truth(truth: &Psi, frames: usize) -> std::vec::Vec<Status> {
    let (mut t, l, r) = tracker_and_frame(truth);
    let frame = StereoFrame {
        left: HueImage::new_checked(&l[..], W, H).unwrap(),
        right: HueImage::new_checked(&r[..], W, H).unwrap(),
    };
    t.reset_around(truth, &[0.0; 6]).unwrap();
    t.set_status(Status::Uncertain);
    (0..frames).map(|_| t.step(&frame, &STILL, 0.033).unwrap().status).collect()
}

#[test]
fn a_view_of_one_whole_face_is_held_but_never_confirmed() {
    // Face-on to the right camera: one face whole, the sides edge-on (the left camera sees one
    // under less than the full-weight angle). The tilt is not pinned down to 5°.
    let face_on = Psi::from_parts(&Vector3::new(0.0, 0.0, 0.8), &nalgebra::UnitQuaternion::identity());
    let seen = statuses_from_the_truth(&face_on, 20);
    assert!(seen.iter().all(|s| *s == Status::Uncertain), "{seen:?}");
    // The same block turned to show two faces whole is confirmed.
    let q = quat::from_angle_axis(0.52, &Vector3::y()).unwrap();
    let seen = statuses_from_the_truth(&Psi::from_parts(&Vector3::new(0.0, 0.0, 0.8), &q), 20);
    assert!(seen.iter().all(|s| s.holds()) && seen.contains(&Status::Tracking), "{seen:?}");
}
