//! The learnt silhouette shift (`evorec_core::edge`) on a camera whose pixels read as the face
//! when half covered: synthetic frames sampled at pixel centres, where the fixed rows (centred
//! for a quarter) put the block too far. The disparity test learns the shift that removes it.

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
/// millimetre): the block starts too far (the fixed rows' bias), the shift moves the rows
/// inwards, and the depth error of the second half is less than half of the start's. Measured
/// (`cargo test -p evorec-core --test edge -- --nocapture`): start +1.3…+2.6 mm, second half
/// +0.5…+1.1 mm, shift −0.24…−0.36 px; a shift held at −0.5 px gives −0.2 mm (seeds 1–8).
#[test]
fn the_shift_learnt_from_the_disparity_removes_the_depth_bias() {
    let runs: Vec<(f32, f32, f32)> = (1..=6).map(|seed| run(seed, 1200)).collect();
    for (seed, (early, late, shift)) in (1..).zip(&runs) {
        println!(
            "seed {seed}: mean depth error frames 5-24 {:+.2} mm, frames 600-1199 {:+.2} mm, shift {shift:+.3} px",
            early * 1e3,
            late * 1e3
        );
        assert!(*shift < -0.2, "seed {seed}: shift {shift} px (the rows must move inwards)");
    }
    let early = median(runs.iter().map(|r| r.0).collect());
    let late = median(runs.iter().map(|r| r.1).collect());
    assert!(early > 0.001, "the fixed rows put the block {early} m too far (expected > 1 mm)");
    assert!(late.abs() < 0.5 * early, "median depth error {late} m after the shift, {early} m before");
}
