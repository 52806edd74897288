//! Tracker time per frame of `evorec track` at 640×480, decoding excluded, on one core: the
//! sequence tracker (`Tracker<7, POPULATION_CAPACITY, DEFAULT_GRID>`, the default population,
//! arm feedforward).
//!
//! `frame/hue` converts both decoded RGB images to hue images (`render::hue_into`, the core's
//! `rgb_to_hue` per pixel), `frame/generation` is one generation on those, `frame/hue+generation`
//! both.
//! `frame/rgb888-generation` is one generation on the decoded 8-bit RGB images themselves, the
//! hue computed only at the pixels the sample points hit (`evorec_core::image::Rgb888`), and
//! `frame/rgb888-frame` the default tuning's `generations_per_frame` generations of it.
//! `frame/table-generation` and `frame/table-frame` are the same with the hue of a sample read
//! from the table of every colour (`evorec_sim::rig::track::hue_table::Rgb888Table`, the same hue
//! bytes): `frame/table-frame` is what `evorec track` does per frame.
//!
//! `cargo bench -p evorec-sim --bench track_frame`. Target: ≤ 1 ms per frame.
//! The frames are rendered by the simulator's renderer (shaded faces, anti-aliased edges,
//! noise), the block about 0.7 m away as in the samples.

use criterion::{Criterion, criterion_group, criterion_main};
use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::ga::SearchSpace;
use evorec_core::image::HueImage;
use evorec_core::image::{Image, Rgb888Image};
use evorec_core::limits::{DEFAULT_GRID, POPULATION_CAPACITY};
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::quat;
use evorec_core::tracker::{JointSample, StereoFrame, Tracker, TrackerConfig};
use evorec_sim::rig::track::hue_table::{self, Rgb888Table};
use evorec_sim::sim::render::{self, RenderOptions};
use nalgebra::{Isometry3, Vector3};
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro128PlusPlus;
use std::hint::black_box;

const W: u16 = 640;
const H: u16 = 480;

fn benches(c: &mut Criterion) {
    let cam = Pinhole::new_checked(600.0, 600.0, 319.5, 239.5, W, H).expect("camera");
    let rig = StereoRig::parallel(cam, 0.1).expect("rig");
    let q = quat::from_angle_axis(0.6, &Vector3::new(0.3, 1.0, 0.2)).expect("quaternion");
    let truth = Psi::from_parts(&Vector3::new(-0.05, 0.0, 0.7), &q);
    let iso = truth.try_to_isometry().expect("pose");
    let block = Block { size_m: [0.1, 0.15, 0.2], face_hues_deg: [0.0, 120.0, 240.0, 0.0, 120.0, 240.0] };
    let mut rng = Xoshiro128PlusPlus::seed_from_u64(1);
    let images = render::render_stereo(&rig, &iso, &block, &RenderOptions::default().with_noise(2.0), &mut rng);
    let n = usize::from(W) * usize::from(H);
    let (mut left, mut right) = (vec![0u8; n], vec![0u8; n]);

    let space = SearchSpace::new_checked([-0.4, -0.4, 0.3], [0.4, 0.4, 1.3]).expect("space");
    let mut config = TrackerConfig::pa10(rig, block, Isometry3::identity(), space).with_seed(1);
    let whole_frames_config = config;
    // One generation per step: the numbers are per generation (a frame runs
    // `generations_per_frame` of them, 2 by default).
    config.tuning.generations_per_frame = 1;
    let mut whole_frames: Tracker<7, POPULATION_CAPACITY, DEFAULT_GRID> =
        Tracker::new(whole_frames_config).expect("tracker");
    let mut tracker: Tracker<7, POPULATION_CAPACITY, DEFAULT_GRID> = Tracker::new(config).expect("tracker");
    let spread = [0.002, 0.002, 0.002, 0.004, 0.004, 0.004];
    whole_frames.reset_around(&truth, &spread).expect("reset");
    tracker.reset_around(&truth, &spread).expect("reset");
    let joints = JointSample { q: [0.1, 0.5, 0.0, 1.2, 0.0, 0.8, 0.0], qd: [0.0; 7], time_us: 0 };

    let mut group = c.benchmark_group("frame");
    group.bench_function("hue", |b| {
        b.iter(|| {
            render::hue_into(black_box(&images.left), &mut left);
            render::hue_into(black_box(&images.right), &mut right);
        })
    });
    render::hue_into(&images.left, &mut left);
    render::hue_into(&images.right, &mut right);
    group.bench_function("generation", |b| {
        b.iter(|| {
            let frame = StereoFrame {
                left: HueImage::new_checked(&left[..], W, H).expect("image"),
                right: HueImage::new_checked(&right[..], W, H).expect("image"),
            };
            tracker.step(black_box(&frame), &joints, 0.033).expect("step")
        })
    });
    group.bench_function("hue+generation", |b| {
        b.iter(|| {
            render::hue_into(black_box(&images.left), &mut left);
            render::hue_into(black_box(&images.right), &mut right);
            let frame = StereoFrame {
                left: HueImage::new_checked(&left[..], W, H).expect("image"),
                right: HueImage::new_checked(&right[..], W, H).expect("image"),
            };
            tracker.step(black_box(&frame), &joints, 0.033).expect("step")
        })
    });
    let rgb = StereoFrame {
        left: Rgb888Image::new_checked(images.left.as_raw().as_slice(), W, H).expect("image"),
        right: Rgb888Image::new_checked(images.right.as_raw().as_slice(), W, H).expect("image"),
    };
    group.bench_function("rgb888-generation", |b| {
        b.iter(|| tracker.step(black_box(&rgb), &joints, 0.033).expect("step"))
    });
    group.bench_function("rgb888-frame", |b| {
        b.iter(|| whole_frames.step(black_box(&rgb), &joints, 0.033).expect("step"))
    });
    hue_table::build();
    let table = StereoFrame {
        left: Image::<_, Rgb888Table>::new_checked(images.left.as_raw().as_slice(), W, H).expect("image"),
        right: Image::<_, Rgb888Table>::new_checked(images.right.as_raw().as_slice(), W, H).expect("image"),
    };
    group.bench_function("table-generation", |b| {
        b.iter(|| tracker.step(black_box(&table), &joints, 0.033).expect("step"))
    });
    group.bench_function("table-frame", |b| {
        b.iter(|| whole_frames.step(black_box(&table), &joints, 0.033).expect("step"))
    });
    group.finish();
}

criterion_group!(track_frame, benches);
criterion_main!(track_frame);
