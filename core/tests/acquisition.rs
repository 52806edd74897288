//! Acquisition without an initial pose, the status, loss and recovery on synthetic frames
//! (`Tracker<7, 40, 8>`, the firmware's planned configuration).

use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::ga::SearchSpace;
use evorec_core::limits::NO_HUE;
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::quat;
use evorec_core::status::Status;
use evorec_core::tracker::{Feedforward, JointSample, Tracker, TrackerConfig};
use nalgebra::{Isometry3, Vector3};

mod common;
use common::{frame, render};

const W: u16 = 320;
const H: u16 = 240;

fn rig() -> StereoRig {
    StereoRig::parallel(Pinhole::new_checked(400.0, 400.0, 160.0, 120.0, W, H).unwrap(), 0.1).unwrap()
}

fn tracker(seed: u64) -> Tracker<7, 40, 8> {
    let space = SearchSpace::new_checked([-0.4, -0.4, 0.3], [0.4, 0.4, 1.3]).unwrap();
    Tracker::new(
        TrackerConfig::pa10(rig(), Block::PAPER, Isometry3::identity(), space)
            .with_seed(seed)
            .with_feedforward(Feedforward::Off),
    )
    .unwrap()
}

const STILL: JointSample<7> = JointSample { q: [0.0; 7], qd: [0.0; 7], time_us: 0 };

#[test]
fn finds_the_block_says_so_loses_it_on_blank_frames_and_recovers() {
    let rig = rig();
    let q = quat::from_angle_axis(2.2, &Vector3::new(0.4, -1.0, 0.3)).unwrap();
    let truth = Psi::from_parts(&Vector3::new(-0.04, 0.03, 0.8), &q);
    let (l, r) = render(&rig, &truth);
    let blank = vec![NO_HUE; usize::from(W) * usize::from(H)];
    for seed in [1, 2, 3] {
        let mut t = tracker(seed);
        assert_eq!(t.status(), Status::Searching);
        let (mut first_held, mut first_tracking, mut worst_tracked) = (None, None, 0.0f32);
        let mut last = None;
        // 40 generations: the refinement seeds the GA within ~4 mm by generation 10; the GA
        // then trades depth against orientation for a few generations (1 px of disparity is
        // 16 mm at 0.8 m in this 320 x 240 rig) and settles within 10 mm by generation ~30.
        for i in 0..40 {
            let e = t.step(&frame(&l, &r, W, H), &STILL, 0.033).unwrap();
            if e.status.holds() && first_held.is_none() {
                first_held = Some(i);
            }
            if e.status == Status::Tracking {
                first_tracking = first_tracking.or(Some(i));
                worst_tracked = worst_tracked.max((e.psi.translation() - truth.translation()).norm());
            }
            last = Some(e);
        }
        let e = last.unwrap();
        let err = (e.psi.translation() - truth.translation()).norm();
        // Held once a candidate fits; reported tracking once both cameras confirm it, and then
        // within the stated accuracy.
        assert!(first_held.is_some_and(|i| i <= 10), "seed {seed}: first held {first_held:?}");
        assert!(first_tracking.is_some_and(|i| i <= 20), "seed {seed}: first tracking {first_tracking:?}");
        assert!(worst_tracked < 0.01, "seed {seed}: tracking {worst_tracked} m off");
        assert_eq!(e.status, Status::Tracking);
        assert!(err < 0.01, "seed {seed}: {err} m");
        // The block disappears: lost at once, never tracking while it is gone.
        for _ in 0..10 {
            let e = t.step(&frame(&blank, &blank, W, H), &STILL, 0.033).unwrap();
            assert_eq!(e.status, Status::Lost);
            assert_eq!(e.fitness, 0.0);
        }
        // It comes back: tracking again after the confirmation generations.
        let mut back = None;
        for i in 0..10 {
            let e = t.step(&frame(&l, &r, W, H), &STILL, 0.033).unwrap();
            if e.status == Status::Tracking && back.is_none() {
                back = Some(i);
            }
        }
        assert!(back.is_some_and(|i| i <= 5), "seed {seed}: back {back:?}");
    }
}

#[test]
fn a_known_start_is_tracking_and_set_status_forces_a_status() {
    let rig = rig();
    // Three faces seen whole by both cameras: a view that confirms the orientation.
    let truth = Psi::new([0.0, 0.0, 0.7], [0.2, 0.3, 0.0]);
    let (l, r) = render(&rig, &truth);
    let mut t = tracker(4);
    t.reset_around(&truth, &[0.002; 6]).unwrap();
    assert_eq!(t.status(), Status::Tracking);
    let e = t.step(&frame(&l, &r, W, H), &STILL, 0.0).unwrap();
    assert_eq!(e.status, Status::Tracking);
    t.set_status(Status::Lost);
    assert_eq!(t.status(), Status::Lost);
    t.reset_uniform();
    assert_eq!(t.status(), Status::Searching);
}

#[test]
fn a_background_in_a_faces_search_band_is_not_taken_for_the_block() {
    // A grey scene tinted by the white balance: hues of 86°–94° everywhere the block is not,
    // inside the search band of its green faces (120° ± 36°). Counted as green, it would put
    // the green faces' blob in the middle of the view and the block far from where it is.
    let rig = rig();
    let truth = Psi::new([0.1, 0.05, 0.8], [0.2, 0.3, 0.0]);
    let (mut l, mut r) = render(&rig, &truth);
    for img in [&mut l, &mut r] {
        for (i, px) in img.iter_mut().enumerate().filter(|(_, px)| **px == NO_HUE) {
            *px = 43 + (i * 7 % 5) as u8;
        }
    }
    for seed in [1, 2, 3] {
        let mut t = tracker(seed);
        let (mut first_tracking, mut worst_tracked, mut last) = (None, 0.0f32, None);
        for i in 0..60 {
            let e = t.step(&frame(&l, &r, W, H), &STILL, 0.033).unwrap();
            if e.status == Status::Tracking {
                first_tracking = first_tracking.or(Some(i));
                worst_tracked = worst_tracked.max((e.psi.translation() - truth.translation()).norm());
            }
            last = Some(e);
        }
        assert!(first_tracking.is_some_and(|i| i <= 40), "seed {seed}: first tracking {first_tracking:?}");
        assert!(worst_tracked < 0.01, "seed {seed}: tracking {worst_tracked} m off");
        assert_eq!(last.map(|e| e.status), Some(Status::Tracking), "seed {seed}");
    }
}
