//! Tests of the learnt silhouette shift (`super`): its schedule, its steps and bounds, and the
//! direction of the disparity test on a block placed too far and too near.

use super::*;
use crate::hue::HueLut;
use crate::image::HueImage;
use crate::limits::{DEFAULT_HUE_TOLERANCE, EDGE_SHIFT_MAX_STEP_PX, EDGE_SHIFT_RANGE_PX};
use crate::model::{Block, SurfaceStrips};
use crate::synth::test_scene::{H, W, rig, scene};

#[test]
fn one_frame_in_every_few_is_due_for_the_test() {
    let mut shift = EdgeShift::NONE;
    let due: std::vec::Vec<bool> = (0..3 * usize::from(EDGE_PROBE_EVERY))
        .map(|_| {
            let d = shift.is_due();
            shift.tick();
            d
        })
        .collect();
    assert_eq!(due.iter().filter(|d| **d).count(), 3);
    assert!(due[0], "the first tracked frame is due");
    for (i, d) in due.iter().enumerate() {
        assert_eq!(*d, i % usize::from(EDGE_PROBE_EVERY) == 0, "frame {i}");
    }
}

#[test]
fn each_pull_steps_once_and_the_shift_stays_in_range() {
    let mut shift = EdgeShift::NONE;
    assert_eq!(shift.px(), -0.25, "the middle of the range");
    shift.learn(Pull::Inwards);
    assert_eq!(shift.px(), -0.25 - EDGE_SHIFT_STEP_PX, "the first step is the fine one");
    shift.learn(Pull::Neither);
    assert_eq!(shift.px(), -0.25 - EDGE_SHIFT_STEP_PX, "a tie does not step");
    shift.learn(Pull::Outwards);
    assert!((shift.px() + 0.25).abs() < 1e-6, "back where it started: {}", shift.px());
    assert!(shift.settled(), "a turn at the fine step brackets the balance");
    for _ in 0..1000 {
        shift.learn(Pull::Outwards);
    }
    assert_eq!(shift.px(), EDGE_SHIFT_RANGE_PX[1]);
    for _ in 0..1000 {
        shift.learn(Pull::Inwards);
    }
    assert_eq!(shift.px(), EDGE_SHIFT_RANGE_PX[0]);
    assert_eq!(clamp_edge_shift(f32::NAN), 0.0);
    assert_eq!(clamp_edge_shift(-5.0), EDGE_SHIFT_RANGE_PX[0]);
    assert_eq!(clamp_edge_shift(0.1), 0.1);
}

#[test]
fn the_step_grows_while_the_tests_agree_and_stays_fine_once_they_have_turned_back_to_it() {
    let steps = |pulls: &[Pull]| -> std::vec::Vec<f32> {
        let mut shift = EdgeShift::NONE;
        pulls
            .iter()
            .map(|&p| {
                let before = shift.px();
                shift.learn(p);
                ((shift.px() - before) / EDGE_SHIFT_STEP_PX * 100.0).round() / 100.0
            })
            .collect()
    };
    let (i, o) = (Pull::Inwards, Pull::Outwards);
    // Doubling up to the largest step (6.25 fine steps), halving at each turn, fine for good
    // once a turn has brought it back to the fine step.
    assert_eq!(steps(&[i, i, i, i, i]), [-1.0, -2.0, -4.0, -6.25, -6.25]);
    assert_eq!(steps(&[i, i, i, o, o, i, o, o, o]), [-1.0, -2.0, -4.0, 2.0, 4.0, -2.0, 1.0, 1.0, 1.0]);
    // A tie neither steps nor counts as a turn.
    assert_eq!(steps(&[o, Pull::Neither, o]), [1.0, 0.0, 2.0]);
    // From the start to the outer end of the range (half a pixel) in ten tests.
    let mut shift = EdgeShift::NONE;
    let tests = (1..=20).find(|_| {
        shift.learn(Pull::Outwards);
        shift.px() >= EDGE_SHIFT_RANGE_PX[1]
    });
    assert_eq!(tests, Some(10));
    assert_eq!(EDGE_SHIFT_MAX_STEP_PX / EDGE_SHIFT_STEP_PX, 6.25);
}

#[test]
fn the_test_pulls_towards_the_depth_the_disparity_shows() {
    let model = SurfaceStrips::<8>::new(&Block::PAPER).unwrap();
    let lut = HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE);
    let rig = rig();
    let eval = Evaluator::new(&model, &lut, &rig);
    let q = crate::quat::from_angle_axis(2.0, &Vector3::new(-1.0, 1.0, 0.1)).unwrap();
    // One test reads the edges at one phase against the pixels, so its answer is one draw: the
    // block is placed at 24 phases across about a pixel, and the pose at 0.25 % and 1 % of the
    // range too far or too near (a quarter and one pixel of disparity). Measured: 19 to 24 of
    // the 24 tests pull the right way.
    for (scale, expected) in
        [(1.0025, Pull::Inwards), (1.01, Pull::Inwards), (0.9975, Pull::Outwards), (0.99, Pull::Outwards)]
    {
        let right_way = (0..24)
            .filter(|&i| {
                let at = Vector3::new(0.02 + 0.00004 * i as f32, -0.01 + 0.00003 * i as f32, 0.75);
                let truth = Psi::from_parts(&at, &q);
                let (l, r) = scene(&truth);
                let left = HueImage::new_checked(&l[..], W, H).unwrap();
                let right = HueImage::new_checked(&r[..], W, H).unwrap();
                disparity_pull(&eval, &truth.scaled_along_ray(scale), &left, &right) == expected
            })
            .count();
        assert!(right_way >= 18, "pose at {scale} × the range: {right_way} of 24 tests pull {expected:?}");
    }
    // Too near the cameras to test.
    let (l, r) = scene(&Psi::from_parts(&Vector3::new(0.02, -0.01, 0.75), &q));
    let (left, right) = (HueImage::new_checked(&l[..], W, H).unwrap(), HueImage::new_checked(&r[..], W, H).unwrap());
    let near = Psi::from_parts(&Vector3::new(0.0, 0.0, 0.01), &q);
    assert_eq!(disparity_pull(&eval, &near, &left, &right), Pull::Neither);
}

#[test]
fn a_shift_moves_the_silhouette_rows_outwards() {
    // On a point-sampled image (a pixel reads as the face when its centre is on it) rows moved
    // a quarter pixel outwards put the inner row into pixels whose centres are off the face,
    // and rows moved half a pixel inwards the outer row into pixels whose centres may be on it.
    let model = SurfaceStrips::<8>::new(&Block::PAPER).unwrap();
    let lut = HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE);
    let rig = rig();
    let q = crate::quat::from_angle_axis(2.0, &Vector3::new(-1.0, 1.0, 0.1)).unwrap();
    let truth = Psi::from_parts(&Vector3::new(0.02, -0.01, 0.75), &q);
    let (l, r) = scene(&truth);
    let left = HueImage::new_checked(&l[..], W, H).unwrap();
    let right = HueImage::new_checked(&r[..], W, H).unwrap();
    let score = |px: f32| Evaluator::new(&model, &lut, &rig).with_edge_shift(px).evaluate_psi(&truth, &left, &right);
    let (plain, out, inwards) = (score(0.0), score(EDGE_SHIFT_RANGE_PX[1]), score(-0.5));
    assert_eq!(plain, Evaluator::new(&model, &lut, &rig).evaluate_psi(&truth, &left, &right));
    for (moved, still) in [(out.left, plain.left), (out.right, plain.right)] {
        assert!(moved.inner_matched < still.inner_matched, "{moved:?} {still:?}");
    }
    for (moved, still) in [(inwards.left, plain.left), (inwards.right, plain.right)] {
        assert!(moved.strip_matched > still.strip_matched, "{moved:?} {still:?}");
    }
}
