//! Tests of the camera-like light (`super::light`), measured with [`face_stats`].

use super::stats::hsv;
use super::tests::{cam, pose, rng};
use super::*;
use nalgebra::Vector3;

use crate::sim::board::world_at_frame;
use crate::sim::scenario::Scenario;

fn image_with(light: Light, block: &Block) -> RgbImage {
    render(&cam(), &pose(), block, &RenderOptions::default().with_light(light), &mut rng())
}

fn stats_with(light: Light, block: &Block) -> Vec<FaceStats> {
    face_stats(&image_with(light, block), &cam(), &pose(), block)
}

/// Signed hue difference `a − b` in degrees, in `(−180, 180]`.
fn hue_diff(a: f32, b: f32) -> f32 {
    -((b - a + 180.0).rem_euclid(360.0) - 180.0)
}

/// FNV-1a over the bytes of both images.
fn fnv(images: &StereoImages) -> u64 {
    let bytes = images.left.as_raw().iter().chain(images.right.as_raw());
    bytes.fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

#[test]
fn default_frames_are_the_base_commits() {
    // Hashes of the frames `evorec render scenarios/motion_a_ff.toml --frame N` wrote at
    // commit 828a9f46, before the light existed.
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/motion_a_ff.toml");
    let s = Scenario::load(path).unwrap();
    for (frame, want) in [(0, BASE_HASH_0), (100, BASE_HASH_100)] {
        let images = world_at_frame(&s, frame).unwrap().render();
        assert_eq!(fnv(&images), want, "frame {frame}");
    }
}

const BASE_HASH_0: u64 = 0x54d5_7dca_fc5d_9180;
const BASE_HASH_100: u64 = 0xf806_07b5_5ab7_0d2b;

#[test]
fn the_default_statistics_are_the_pure_hues() {
    for f in stats_with(Light::default(), &Block::PAPER) {
        assert!(f.pixels > 2000, "{f:?}");
        assert!(hue_diff(f.median_hue_deg, f.nominal_hue_deg).abs() <= 1.0, "{f:?}");
        assert!(f.median_saturation > 0.99 && f.within_15_deg == 1.0 && f.near_white == 0.0, "{f:?}");
    }
}

#[test]
fn white_balance_moves_each_face_hue_as_the_gains_do() {
    let pale = Light { albedo_saturation: 0.6, ..Light::default() };
    let gains = [1.0, 0.9, 0.75];
    let base = stats_with(pale, &Block::PAPER);
    let moved = stats_with(Light { white_balance: gains, ..pale }, &Block::PAPER);
    let mut largest = 0.0f32;
    for (a, b) in base.iter().zip(&moved) {
        let albedo = light::albedo(hue_rgb(a.nominal_hue_deg), 0.6);
        let c = [0, 1, 2].map(|i| (200.0 * albedo[i] * gains[i]) as u8);
        let want = hsv(c).0.unwrap();
        assert!(hue_diff(b.median_hue_deg, want).abs() <= 3.0, "{b:?} want {want}");
        largest = largest.max(hue_diff(b.median_hue_deg, a.median_hue_deg).abs());
    }
    assert!(largest >= 5.0, "{largest}");
}

#[test]
fn tone_curves_move_saturated_blue_towards_cyan() {
    let block = Block { face_hues_deg: [0.0, 120.0, 230.0, 0.0, 120.0, 230.0], ..Block::PAPER };
    let blue = |l: Light| stats_with(l, &block).into_iter().find(|f| f.nominal_hue_deg == 230.0).unwrap();
    let flat = blue(Light::default());
    assert!(hue_diff(flat.median_hue_deg, 230.0).abs() <= 1.0, "{flat:?}");
    for curve in [ToneCurve::Filmic, ToneCurve::Srgb] {
        let toned = blue(Light { tone_curve: curve, tone_exposure: 2.0, ..Light::default() });
        let shift = hue_diff(toned.median_hue_deg, 230.0);
        assert!(shift < -5.0, "{curve:?}: {toned:?}");
    }
}

#[test]
fn the_highlight_turns_part_of_a_face_nearly_white() {
    // One face almost straight at the camera, lit from the camera: the mirror direction is near
    // the middle of that face.
    let p = Isometry3::new(Vector3::new(0.0, 0.0, 0.7), Vector3::new(0.05, 0.08, 0.0));
    let front = (0..FACES).map(|k| p.rotation * Block::normal(k)).min_by(|a, b| a.z.total_cmp(&b.z)).unwrap();
    let lit = Light { light_dir_cam: front.into(), ..Light::default() };
    let white = |l: Light| {
        let img = render(&cam(), &p, &Block::PAPER, &RenderOptions::default().with_light(l), &mut rng());
        face_stats(&img, &cam(), &p, &Block::PAPER).iter().map(|f| f.near_white).fold(0.0, f32::max)
    };
    assert_eq!(white(lit), 0.0);
    let shiny = white(Light { specular: 1.0, shininess: 20.0, ..lit });
    assert!(shiny > 0.05, "{shiny}");
}

#[test]
fn a_cast_shadow_leaves_only_ambient_light_on_one_side_of_its_edge() {
    // Everything right of x = 0.02 m in the camera frame is in the shadow.
    let shadow =
        Light { shadow_normal: [1.0, 0.0, 0.0], shadow_offset_m: 0.02, shadow_width_m: 10.0, ..Light::default() };
    let (lit, dark) = (image_with(Light::default(), &Block::PAPER), image_with(shadow, &Block::PAPER));
    let (mut darker, mut left_of_centre) = (0, 0);
    for ((x, _, d), l) in dark.enumerate_pixels().zip(lit.pixels()) {
        if d != l {
            assert!(d.0.iter().zip(&l.0).all(|(a, b)| a <= b), "{d:?} {l:?}");
            darker += 1;
            left_of_centre += usize::from(x < 330);
        }
    }
    assert!(darker > 2000 && left_of_centre < darker / 50, "{darker} {left_of_centre}");
    // The shadowed part of a lit face has the ambient level alone.
    let ambient = (0.35f32 * 255.0).round() as u8;
    let faces = screen_faces(&cam(), &pose(), &Block::PAPER, &RenderOptions::default().with_light(shadow));
    let inside =
        |x: u32, y: u32| faces.iter().any(|f| f.distances(x as f32 + 0.5, y as f32 + 0.5).iter().all(|&d| d > 2.0));
    let deep: Vec<_> = dark
        .enumerate_pixels()
        .filter(|(x, y, p)| *x > 400 && inside(*x, *y) && p != &lit.get_pixel(*x, *y))
        .map(|(_, _, p)| p.0)
        .collect();
    assert!(deep.len() > 500, "{}", deep.len());
    assert!(deep.iter().all(|p| p.iter().max().is_some_and(|m| m.abs_diff(ambient) <= 1)));
    let shifted =
        Isometry3::from_parts((pose().translation.vector + Vector3::new(-0.02, 0.0, 0.0)).into(), pose().rotation);
    let count = |l: Light, p: &Isometry3<f32>| {
        let a = render(&cam(), p, &Block::PAPER, &RenderOptions::default(), &mut rng());
        let b = render(&cam(), p, &Block::PAPER, &RenderOptions::default().with_light(l), &mut rng());
        a.pixels().zip(b.pixels()).filter(|(a, b)| a != b).count()
    };
    // Fixed in the camera frame, the edge crosses the block as it moves; in the block's frame it
    // moves with it.
    assert!(count(shadow, &shifted) < darker * 4 / 5, "{} {darker}", count(shadow, &shifted));
    let in_block = Light { shadow_frame: ShadowFrame::Block, shadow_offset_m: 0.0, ..shadow };
    let (here, there) = (count(in_block, &pose()), count(in_block, &shifted));
    assert!(here > 2000 && here.abs_diff(there) < here / 10, "{here} {there}");
}

#[test]
fn motion_blur_spreads_the_edges() {
    let rig = StereoRig::parallel(cam(), 0.1).unwrap();
    let along: Vec<_> = (0..5)
        .map(|i| {
            Isometry3::from_parts(
                (pose().translation.vector + Vector3::new(0.0025 * i as f32, 0.0, 0.0)).into(),
                pose().rotation,
            )
        })
        .collect();
    let opts = RenderOptions::default();
    let sharp = render_stereo_blurred(&rig, &along[..1], &Block::PAPER, &opts, &mut rng()).right;
    let blurred = render_stereo_blurred(&rig, &along, &Block::PAPER, &opts, &mut rng()).right;
    let ends = render_stereo_blurred(&rig, &along[4..], &Block::PAPER, &opts, &mut rng()).right;
    // Pixels neither as at the start nor as at the end of the exposure: edges crossed by it.
    let mixed = |img: &RgbImage| {
        img.pixels().zip(sharp.pixels()).zip(ends.pixels()).filter(|((p, a), b)| p != a && p != b).count()
    };
    assert_eq!(mixed(&sharp), 0);
    assert!(mixed(&blurred) > 2000, "{}", mixed(&blurred));
    let one = render_stereo(&rig, &pose(), &Block::PAPER, &opts, &mut rng());
    assert_eq!(one.right, sharp);
}

#[test]
fn jpeg_changes_pixels_but_keeps_the_face_colours() {
    let plain = image_with(Light::default(), &Block::PAPER);
    let jpeg = image_with(Light { jpeg_quality: 85, ..Light::default() }, &Block::PAPER);
    let changed = plain.pixels().zip(jpeg.pixels()).filter(|(a, b)| a != b).count();
    assert!(changed > 10_000, "{changed}");
    let mean = |img: &RgbImage| img.as_raw().iter().map(|&b| f64::from(b)).sum::<f64>() / img.as_raw().len() as f64;
    assert!((mean(&plain) - mean(&jpeg)).abs() < 1.0, "{} {}", mean(&plain), mean(&jpeg));
    let (a, b) =
        (face_stats(&plain, &cam(), &pose(), &Block::PAPER), face_stats(&jpeg, &cam(), &pose(), &Block::PAPER));
    for (a, b) in a.iter().zip(&b) {
        assert!(hue_diff(a.median_hue_deg, b.median_hue_deg).abs() <= 3.0, "{a:?} {b:?}");
        assert!((a.median_value - b.median_value).abs() <= 0.02, "{a:?} {b:?}");
    }
}

#[test]
fn chroma_noise_keeps_the_luma() {
    let mut buf = vec![140u8; 3 * 100_000];
    light::add_chroma_noise(&mut buf, 3.0, &mut rng());
    let (mut luma_err, mut cb) = (0.0f64, Vec::new());
    for p in buf.chunks_exact(3) {
        let [r, g, b] = [p[0], p[1], p[2]].map(f64::from);
        luma_err = luma_err.max((0.299 * r + 0.587 * g + 0.114 * b - 140.0).abs());
        cb.push((b - (0.299 * r + 0.587 * g + 0.114 * b)) / 1.772);
    }
    let std = (cb.iter().map(|c| c * c).sum::<f64>() / cb.len() as f64).sqrt();
    assert!(luma_err <= 1.0 && (2.6..3.4).contains(&std), "{luma_err} {std}");
}

#[test]
fn the_default_light_draws_no_shader_and_no_tone_table() {
    let l = Light::default();
    assert!(l.is_flat() && l.tone_table().is_none() && l.blur_times() == [0.0]);
    let blur = Light { exposure_s: 0.01, ..l };
    let times = blur.blur_times();
    assert_eq!(times.len(), 5);
    assert!(times.iter().enumerate().all(|(i, t)| (t - 0.0025 * i as f64).abs() < 1e-9), "{times:?}");
}
