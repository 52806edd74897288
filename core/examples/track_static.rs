//! Tracks the paper's block in a static synthetic stereo pair and prints the estimate
//! converging, one line per 10 generations.
//!
//! `cargo run --release -p evorec-core --example track_static`

use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::ga::SearchSpace;
use evorec_core::image::HueImage;
use evorec_core::limits::NO_HUE;
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::tracker::{Feedforward, JointSample, StereoFrame, Tracker, TrackerConfig};
use evorec_core::{quat, synth};
use nalgebra::{Isometry3, Vector3};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (w, h) = (640u16, 480u16);
    let cam = Pinhole::new_checked(800.0, 800.0, 320.0, 240.0, w, h)?;
    let rig = StereoRig::parallel(cam, 0.1)?;
    let space = SearchSpace::new_checked([-0.3, -0.3, 0.3], [0.3, 0.3, 1.2])?;
    let config = TrackerConfig::pa10(rig, Block::PAPER, Isometry3::identity(), space)
        .with_seed(1)
        .with_feedforward(Feedforward::Off);
    let mut tracker: Tracker = Tracker::new(config)?;

    let q = quat::from_angle_axis(0.5, &Vector3::new(0.3, 1.0, 0.1))?;
    let truth = Psi::from_parts(&Vector3::new(0.03, -0.02, 0.72), &q);
    let iso = truth.try_to_isometry()?;
    let n = usize::from(w) * usize::from(h);
    let (mut l, mut r) = (vec![NO_HUE; n], vec![NO_HUE; n]);
    synth::render_block(&Block::PAPER, &rig.right, &iso, &mut r)?;
    synth::render_block(&Block::PAPER, &rig.left, &(rig.left_from_right * iso), &mut l)?;
    let frame = StereoFrame { left: HueImage::new_checked(&l[..], w, h)?, right: HueImage::new_checked(&r[..], w, h)? };

    let mut start = truth;
    start.0[0] += 0.010;
    start.0[1] -= 0.005;
    start.0[2] += 0.015;
    start.0[4] += 0.02;
    tracker.reset_around(&start, &[0.01, 0.01, 0.01, 0.02, 0.02, 0.02])?;
    let joints = JointSample { q: [0.0; 7], qd: [0.0; 7], time_us: 0 };
    println!("truth: t = {:?} mm, eps = {:?}", (truth.translation() * 1e3).as_slice(), truth.eps().as_slice());
    println!("{:>5} {:>7} {:>9} {:>9} {:>9} {:>9}", "gen", "F", "|dt| mm", "dx mm", "dz mm", "|deps|");
    for i in 0..300 {
        let est = tracker.step(&frame, &joints, 0.033)?;
        if i % 10 == 0 || i == 299 {
            let d = est.psi.translation() - truth.translation();
            let de = (est.psi.eps() - truth.eps()).norm();
            println!(
                "{:>5} {:>7.4} {:>9.2} {:>9.2} {:>9.2} {:>9.4}",
                est.generation,
                est.fitness,
                d.norm() * 1e3,
                d.x * 1e3,
                d.z * 1e3,
                de
            );
        }
    }
    Ok(())
}
