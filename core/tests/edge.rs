//! The learnt silhouette shift (`evorec_core::edge`) on a camera whose pixels read as the face
//! when half covered: synthetic frames sampled at pixel centres, where the fixed rows (centred
//! for a quarter) put the block too far. The shift starts at the rows for a half, and the
//! disparity test keeps it near there.

use evorec_core::pose::Psi;
use evorec_core::quat;
use nalgebra::Vector3;

mod common;
use common::{H, STILL, W, frame, median, render, tracker_320};

/// The block swaying ±5 mm across the view and ±3 mm in depth, so that its edges cross the
/// pixels at every phase (a camera's edges do; on a still, noise-free frame every test reads
/// the same phase).
fn truth_at(i: usize) -> Psi {
    let a = i as f32 * 0.13;
    Psi::from_parts(
        &Vector3::new(0.03 + 0.005 * a.sin(), -0.02 + 0.004 * (0.7 * a).cos(), 0.75 + 0.003 * (0.3 * a).sin()),
        &quat::from_angle_axis(2.2, &Vector3::new(0.4, -1.0, 0.3)).unwrap(),
    )
}

/// Mean depth errors (m, estimate − truth) over frames 5–24 and over the second half of
/// `frames`, and the shift at the end, for one GA seed.
fn run(seed: u64, frames: usize) -> (f32, f32, f32) {
    let mut t = tracker_320(seed);
    t.reset_around(&truth_at(0), &[0.002, 0.002, 0.002, 0.01, 0.01, 0.01]).unwrap();
    let rig = t.config().rig;
    let (mut early, mut late) = (Vec::new(), Vec::new());
    for i in 0..frames {
        let truth = truth_at(i);
        let (l, r) = render(&rig, &truth);
        let e = t.step(&frame(&l, &r, W, H), &STILL, 0.033).unwrap();
        let dz = e.psi.0[2] - truth.0[2];
        if (5..25).contains(&i) {
            early.push(dz);
        }
        if 2 * i >= frames {
            late.push(dz);
        }
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    (mean(&early), mean(&late), t.edge_shift_px())
}

/// Over GA seeds 1–6 (one seed's mean over 600 frames still wanders by about half a
/// millimetre): the shift starts in the middle of its range (`EDGE_SHIFT_START_PX`, the rows of
/// a camera that reads a pixel as the face when half covered, as these frames are sampled), so
/// the first frames' depth is not biased by the rows (measured, `cargo test -p evorec-core
/// --test edge -- --nocapture`: frames 5–24 −0.9…+1.4 mm, median −0.1 mm; with the shift
/// starting at 0, the fixed rows, +1.3…+2.6 mm), and the disparity tests keep the shift about
/// there (−0.29…−0.40 px after 1200 frames; the second half +0.4…+1.1 mm).
#[test]
fn the_shift_starts_unbiased_for_a_half_covered_pixel_and_stays_near() {
    let runs: Vec<(f32, f32, f32)> = (1..=6).map(|seed| run(seed, 1200)).collect();
    for (seed, (early, late, shift)) in (1..).zip(&runs) {
        println!(
            "seed {seed}: mean depth error frames 5-24 {:+.2} mm, frames 600-1199 {:+.2} mm, shift {shift:+.3} px",
            early * 1e3,
            late * 1e3
        );
        assert!((-0.5..=-0.2).contains(shift), "seed {seed}: shift {shift} px (the tests keep it near -0.25)");
    }
    let early = median(runs.iter().map(|r| r.0).collect());
    let late = median(runs.iter().map(|r| r.1).collect());
    assert!(early.abs() < 0.0005, "median depth error {early} m over frames 5-24 (the fixed rows: over 1 mm)");
    assert!(late.abs() < 0.0012, "median depth error {late} m over the second half");
}
