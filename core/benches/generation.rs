//! Host benchmarks: one fitness evaluation and one GA generation at the default
//! configuration (640×480 stereo pair, population 40, `DEFAULT_GRID` points per row), and the
//! fitness with rows of 4 and 16 points (for the marginal cost of a point).
//!
//! `cargo bench -p evorec-core --bench generation`. ns per sample-point evaluation =
//! time of `fitness/one_pose` / `2 · POINTS_PER_CAMERA`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::config::{DEFAULT_GRID, DEFAULT_HUE_TOLERANCE, NO_HUE};
use evorec_core::fitness::Evaluator;
use evorec_core::ga::SearchSpace;
use evorec_core::hue::{HueImage, HueLut};
use evorec_core::model::{Block, SurfaceStrips};
use evorec_core::pose::Psi;
use evorec_core::tracker::{Feedforward, JointSample, StereoFrame, Tracker, TrackerConfig};
use evorec_core::{quat, synth};
use nalgebra::{Isometry3, Vector3};
use std::hint::black_box;

const W: u16 = 640;
const H: u16 = 480;

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
    let left = HueImage::new_checked(&l[..], W, H).expect("image");
    let right = HueImage::new_checked(&r[..], W, H).expect("image");

    let model = SurfaceStrips::<DEFAULT_GRID>::new(&Block::PAPER).expect("model");
    let lut = HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE);
    let eval = Evaluator::new(&model, &lut, &rig);
    let points = 2 * SurfaceStrips::<DEFAULT_GRID>::POINTS_PER_CAMERA;
    let mut group = c.benchmark_group("fitness");
    group.throughput(Throughput::Elements(points as u64));
    let mut pose = truth;
    pose.0[0] += 0.003;
    group.bench_function("one_pose", |b| b.iter(|| eval.evaluate_psi(black_box(&pose), &left, &right)));
    group.finish();
    {
        let model = SurfaceStrips::<4>::new(&Block::PAPER).expect("model");
        let eval = Evaluator::new(&model, &lut, &rig);
        c.bench_function("fitness_g4", |b| b.iter(|| eval.evaluate_psi(black_box(&pose), &left, &right)));
        let model = SurfaceStrips::<16>::new(&Block::PAPER).expect("model");
        let eval = Evaluator::new(&model, &lut, &rig);
        c.bench_function("fitness_g16", |b| b.iter(|| eval.evaluate_psi(black_box(&pose), &left, &right)));
    }

    let space = SearchSpace::new_checked([-0.3, -0.3, 0.3], [0.3, 0.3, 1.2]).expect("space");
    let config = TrackerConfig::pa10(rig, Block::PAPER, Isometry3::identity(), space).with_seed(1);
    let mut tracker: Tracker = Tracker::new(config).expect("tracker");
    tracker.reset_around(&truth, &[0.005, 0.005, 0.005, 0.01, 0.01, 0.01]).expect("reset");
    let frame = StereoFrame { left, right };
    let joints =
        JointSample { q: [0.1, 0.5, 0.0, 1.2, 0.0, 0.8, 0.0], qd: [0.1, -0.1, 0.05, 0.2, 0.0, -0.1, 0.1], time_us: 0 };
    let mut group = c.benchmark_group("generation");
    group.throughput(Throughput::Elements((points * tracker.population().len()) as u64));
    group.bench_function("population_40_ff", |b| {
        b.iter(|| tracker.step(black_box(&frame), &joints, 0.033, Feedforward::On).expect("step"))
    });
    group.finish();
}

criterion_group!(generation, benches);
criterion_main!(generation);
