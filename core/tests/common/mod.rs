//! What the integration tests of the core share: synthetic stereo frames of the paper's block.

use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::ga::SearchSpace;
use evorec_core::image::HueImage;
use evorec_core::limits::NO_HUE;
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::synth;
use evorec_core::tracker::{Feedforward, JointSample, StereoFrame, Tracker, TrackerConfig};
use nalgebra::Isometry3;

/// Width of [`tracker_320`]'s images.
#[allow(dead_code)]
pub const W: u16 = 320;
/// Height of [`tracker_320`]'s images.
#[allow(dead_code)]
pub const H: u16 = 240;
/// The joints of an arm that stands still.
#[allow(dead_code)]
pub const STILL: JointSample<7> = JointSample { q: [0.0; 7], qd: [0.0; 7], time_us: 0 };

/// A tracker of [`Block::PAPER`] on a still arm without feedforward: a parallel rig of
/// `W × H` cameras with f = 400 px and a 0.1 m baseline, searching 0.3–1.3 m ahead.
#[allow(dead_code)]
pub fn tracker_320(seed: u64) -> Tracker<7, 40, 8> {
    let rig = StereoRig::parallel(Pinhole::new_checked(400.0, 400.0, 160.0, 120.0, W, H).unwrap(), 0.1).unwrap();
    let space = SearchSpace::new_checked([-0.4, -0.4, 0.3], [0.4, 0.4, 1.3]).unwrap();
    let config = TrackerConfig::pa10(rig, Block::PAPER, Isometry3::identity(), space);
    Tracker::new(config.with_seed(seed).with_feedforward(Feedforward::Off)).unwrap()
}

#[allow(dead_code)]
/// The left and right hue images of [`Block::PAPER`] at `truth` (right camera frame), the size
/// of the rig's cameras, rendered exactly ([`synth::render_block`]).
pub fn render(rig: &StereoRig, truth: &Psi) -> (Vec<u8>, Vec<u8>) {
    render_block(rig, &Block::PAPER, truth)
}

/// As [`render`], for any block (e.g. the paper's with other face hues: the block as a camera
/// with another white balance sees it).
pub fn render_block(rig: &StereoRig, block: &Block, truth: &Psi) -> (Vec<u8>, Vec<u8>) {
    let (w, h) = (usize::from(rig.right.width()), usize::from(rig.right.height()));
    let iso = truth.try_to_isometry().unwrap();
    let (mut l, mut r) = (vec![NO_HUE; w * h], vec![NO_HUE; w * h]);
    synth::render_block(block, &rig.right, &iso, &mut r).unwrap();
    synth::render_block(block, &rig.left, &(rig.left_from_right * iso), &mut l).unwrap();
    (l, r)
}

/// The frame pair of the images `l` and `r` of `w × h` pixels.
pub fn frame<'a>(l: &'a [u8], r: &'a [u8], w: u16, h: u16) -> StereoFrame<'a> {
    StereoFrame { left: HueImage::new_checked(l, w, h).unwrap(), right: HueImage::new_checked(r, w, h).unwrap() }
}

/// The median of `v` (over GA seeds: one seed's error is a draw).
#[allow(dead_code)]
pub fn median(mut v: Vec<f32>) -> f32 {
    v.sort_by(f32::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}
