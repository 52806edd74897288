//! Host benchmarks on RGB565 frames (what a board's sensor delivers): one fitness evaluation
//! with rows of 8 points (960 sample points per pose), the same through a distorted lens,
//! rows of 4 and 16 (the marginal cost of a point), the same pose on hue frames, and one GA
//! generation of the default tracker (640×480 stereo pair, population 40).
//!
//! `cargo bench -p evorec-core --bench generation`. ns per sample-point evaluation =
//! time of `fitness/g8_rgb565` / 960.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use evorec_core::camera::{Distortion, Pinhole, StereoRig};
use evorec_core::fitness::Evaluator;
use evorec_core::ga::SearchSpace;
use evorec_core::hue::HueLut;
use evorec_core::image::HueImage;
use evorec_core::image::{Rgb565Image, rgb888_to_rgb565};
use evorec_core::limits::{DEFAULT_HUE_TOLERANCE, NO_HUE};
use evorec_core::model::{Block, SurfaceStrips};
use evorec_core::pose::Psi;
use evorec_core::tracker::{JointSample, StereoFrame, Tracker, TrackerConfig};
use evorec_core::{quat, synth};
use nalgebra::{Isometry3, Vector3};
use std::hint::black_box;

const W: u16 = 640;
const H: u16 = 480;

/// A saturated colour of each face hue (0 red, 60 green, 120 blue), black elsewhere.
fn to_rgb565(hue: &[u8]) -> Vec<u8> {
    let px = |h: u8| match h {
        0 => rgb888_to_rgb565(220, 30, 30),
        60 => rgb888_to_rgb565(30, 200, 40),
        120 => rgb888_to_rgb565(20, 40, 210),
        NO_HUE => rgb888_to_rgb565(60, 60, 60),
        _ => 0,
    };
    hue.iter().flat_map(|&h| px(h).to_le_bytes()).collect()
}

fn setup() -> (StereoRig, Psi, Vec<u8>, Vec<u8>) {
    let cam = Pinhole::new_checked(800.0, 800.0, 320.0, 240.0, W, H).expect("camera");
    let rig = StereoRig::parallel(cam, 0.1).expect("rig");
    let q = quat::from_angle_axis(0.5, &Vector3::new(0.3, 1.0, 0.1)).expect("quaternion");
    let truth = Psi::from_parts(&Vector3::new(0.03, -0.02, 0.72), &q);
    let iso = truth.try_to_isometry().expect("pose");
    let n = usize::from(W) * usize::from(H);
    let (mut l, mut r) = (vec![NO_HUE; n], vec![NO_HUE; n]);
    synth::render_block(&Block::PAPER, &rig.right, &iso, &mut r).expect("render");
    synth::render_block(&Block::PAPER, &rig.left, &(rig.left_from_right * iso), &mut l).expect("render");
    (rig, truth, l, r)
}

fn benches(c: &mut Criterion) {
    let (rig, truth, l, r) = setup();
    let (l5, r5) = (to_rgb565(&l), to_rgb565(&r));
    let left = Rgb565Image::new_checked(&l5[..], W, H).expect("image");
    let right = Rgb565Image::new_checked(&r5[..], W, H).expect("image");
    let (left_hue, right_hue) =
        (HueImage::new_checked(&l[..], W, H).expect("image"), HueImage::new_checked(&r[..], W, H).expect("image"));

    let model = SurfaceStrips::<8>::new(&Block::PAPER).expect("model");
    let lut = HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE);
    let eval = Evaluator::new(&model, &lut, &rig);
    let lens = Distortion::plumb_bob([-0.12, 0.05, 0.001, -0.001, 0.0]).expect("distortion");
    let distorted = StereoRig { left: rig.left.with_distortion(lens), right: rig.right.with_distortion(lens), ..rig };
    let eval_distorted = Evaluator::new(&model, &lut, &distorted);
    let mut pose = truth;
    pose.0[0] += 0.003;
    let mut group = c.benchmark_group("fitness");
    group.throughput(Throughput::Elements(2 * SurfaceStrips::<8>::POINTS_PER_CAMERA as u64));
    group.bench_function("g8_rgb565", |b| b.iter(|| eval.evaluate_psi(black_box(&pose), &left, &right)));
    group.bench_function("g8_rgb565_distorted", |b| {
        b.iter(|| eval_distorted.evaluate_psi(black_box(&pose), &left, &right))
    });
    group.bench_function("g8_hue", |b| b.iter(|| eval.evaluate_psi(black_box(&pose), &left_hue, &right_hue)));
    group.finish();
    {
        let model = SurfaceStrips::<4>::new(&Block::PAPER).expect("model");
        let eval = Evaluator::new(&model, &lut, &rig);
        c.bench_function("fitness_g4_rgb565", |b| b.iter(|| eval.evaluate_psi(black_box(&pose), &left, &right)));
        let model = SurfaceStrips::<16>::new(&Block::PAPER).expect("model");
        let eval = Evaluator::new(&model, &lut, &rig);
        c.bench_function("fitness_g16_rgb565", |b| b.iter(|| eval.evaluate_psi(black_box(&pose), &left, &right)));
    }

    let space = SearchSpace::new_checked([-0.3, -0.3, 0.3], [0.3, 0.3, 1.2]).expect("space");
    let config = TrackerConfig::pa10(rig, Block::PAPER, Isometry3::identity(), space).with_seed(1);
    let mut tracker: Tracker = Tracker::new(config).expect("tracker");
    tracker.reset_around(&truth, &[0.005, 0.005, 0.005, 0.01, 0.01, 0.01]).expect("reset");
    let frame = StereoFrame { left, right };
    let joints =
        JointSample { q: [0.1, 0.5, 0.0, 1.2, 0.0, 0.8, 0.0], qd: [0.1, -0.1, 0.05, 0.2, 0.0, -0.1, 0.1], time_us: 0 };
    let points = 2 * SurfaceStrips::<{ evorec_core::limits::DEFAULT_GRID }>::POINTS_PER_CAMERA;
    let mut group = c.benchmark_group("generation");
    group.throughput(Throughput::Elements((points * tracker.population().len()) as u64));
    group.bench_function("default_rgb565_ff", |b| {
        b.iter(|| tracker.step(black_box(&frame), &joints, 0.033).expect("step"))
    });
    group.finish();
}

criterion_group!(generation, benches);
criterion_main!(generation);
