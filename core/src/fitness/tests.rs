//! Tests of the fitness kernel (`super`): exact scores, RGB565 against hue frames, the lens
//! kernel, the affine walk against the projected rows, and the host walk (and the rows it
//! walks) against the board's.

use super::*;
use crate::image::HueImage;
use crate::limits::{DEFAULT_HUE_TOLERANCE, NO_HUE};
use crate::model::{Block, ROW_DISTANCES_M};
use crate::synth::test_scene::{H, W, rig, scene};
use std::vec;

/// The paper's block, its configured hue table and the test rig.
fn paper_block() -> (SurfaceStrips<8>, HueLut, crate::camera::StereoRig) {
    let model = SurfaceStrips::<8>::new(&Block::PAPER).unwrap();
    let lut = HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE);
    (model, lut, rig())
}

#[test]
fn true_pose_scores_one_and_perturbations_score_less() {
    let (model, lut, rig) = paper_block();
    let eval = Evaluator::new(&model, &lut, &rig);
    // A corner towards the camera, so three faces are visible: the model diagonal (1,1,1)
    // turned most of the way onto the camera's −z.
    let q = crate::quat::from_angle_axis(2.0, &Vector3::new(-1.0, 1.0, 0.1)).unwrap();
    let truth = Psi::from_parts(&Vector3::new(0.02, -0.01, 0.75), &q);
    let (l, r) = scene(&truth);
    let left = HueImage::new_checked(&l[..], W, H).unwrap();
    let right = HueImage::new_checked(&r[..], W, H).unwrap();
    let f = eval.evaluate_psi(&truth, &left, &right);
    // The nearest rows of a silhouette edge lie half a pixel width inside it (at the scale of the
    // face's centre), so on this point-sampled image their pixels' centres lie on the edge to
    // within the perspective change of that scale across the face: a point may read the
    // background. Every other point scores.
    assert!(f.total >= 0.995, "{f:?}");
    for c in [f.left, f.right] {
        assert!(c.inner_total - c.inner_matched <= 2 && c.strip_matched == 0, "{f:?}");
    }
    assert_eq!(f.right.visible.count_ones(), 3);
    assert_eq!(f.right.inner_total, 3 * SurfaceStrips::<8>::INNER_PER_FACE as u32);
    // Every perturbation of 8 mm or 0.03 in ε lowers F.
    for i in 0..6 {
        for sign in [-1.0f32, 1.0] {
            let mut p = truth;
            p.0[i] += sign * if i < 3 { 0.008 } else { 0.03 };
            let fp = eval.evaluate_psi(&p, &left, &right).total;
            assert!(fp < 1.0, "gene {i} {sign}: {fp}");
        }
    }
    // Far away poses score (close to) nothing.
    let far = Psi::new([0.25, 0.2, 1.1], [0.0; 3]);
    assert!(eval.evaluate_psi(&far, &left, &right).total < 0.2);
    // A pose behind the camera scores 0 without reading out of bounds.
    let behind = Psi::new([0.0, 0.0, -0.5], [0.0; 3]);
    assert_eq!(eval.evaluate_psi(&behind, &left, &right).total, 0.0);
}

/// A fully saturated, bright RGB565 colour of hue byte `h` (black for `NO_HUE`).
fn hue_to_rgb565(h: u8) -> [u8; 2] {
    if h == NO_HUE {
        return [0, 0];
    }
    let deg = 2.0 * f32::from(h);
    let f = |n: f32| {
        let k = (n + deg / 60.0) % 6.0;
        (255.0 * (1.0 - k.min(4.0 - k).clamp(0.0, 1.0))) as u8
    };
    crate::image::rgb888_to_rgb565(f(5.0), f(3.0), f(1.0)).to_le_bytes()
}

#[test]
fn rgb565_frames_score_as_their_hue_frames() {
    use crate::image::{Rgb565, Rgb565Image};
    let (model, lut, rig) = paper_block();
    let eval = Evaluator::new(&model, &lut, &rig);
    let q = crate::quat::from_angle_axis(2.0, &Vector3::new(-1.0, 1.0, 0.1)).unwrap();
    let truth = Psi::from_parts(&Vector3::new(0.02, -0.01, 0.75), &q);
    let (l, r) = scene(&truth);
    let to565 = |img: &[u8]| img.iter().flat_map(|&h| hue_to_rgb565(h)).collect::<std::vec::Vec<u8>>();
    let (l5, r5) = (to565(&l), to565(&r));
    for (h, px) in l.iter().zip(l5.chunks(2)) {
        assert_eq!(crate::image::rgb565_to_hue(u16::from_le_bytes([px[0], px[1]])), *h);
    }
    let (left, right) = (HueImage::new_checked(&l[..], W, H).unwrap(), HueImage::new_checked(&r[..], W, H).unwrap());
    let left5: Rgb565Image<&[u8]> = Rgb565Image::new_checked(&l5[..], W, H).unwrap();
    let right5 = crate::image::Image::<_, Rgb565>::new_checked(&r5[..], W, H).unwrap();
    for i in 0..12 {
        let mut p = truth;
        p.0[i % 6] += if i < 6 { 0.004 } else { -0.02 };
        assert_eq!(eval.evaluate_psi(&p, &left, &right), eval.evaluate_psi(&p, &left5, &right5), "{i}");
    }
    // As the hue frames (see `true_pose_scores_one_and_perturbations_score_less`).
    assert_eq!(eval.evaluate_psi(&truth, &left5, &right5), eval.evaluate_psi(&truth, &left, &right));
    assert!(eval.evaluate_psi(&truth, &left5, &right5).total >= 0.995);
}

#[test]
fn distorted_kernel_samples_where_the_lens_projects() {
    use crate::camera::Distortion;
    let model = SurfaceStrips::<8>::new(&Block::PAPER).unwrap();
    let lut = HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE);
    let q = crate::quat::from_angle_axis(2.0, &Vector3::new(-1.0, 1.0, 0.1)).unwrap();
    let truth = Psi::from_parts(&Vector3::new(0.02, -0.01, 0.75), &q);
    let (_, img) = scene(&truth);
    let image = HueImage::new_checked(&img[..], W, H).unwrap();
    let (r, t) = (truth.rotation_unchecked(), truth.translation());
    let plain = rig().right;
    let plain_counts = camera_counts(&model, &lut, &plain, &image, &r, &t);
    // A negligible lens takes the distorted kernel and must count (almost) the same.
    let tiny = plain.with_distortion(Distortion::plumb_bob([1e-7, 0.0, 0.0, 0.0, 0.0]).unwrap());
    let tiny_counts = camera_counts(&model, &lut, &tiny, &image, &r, &t);
    assert_eq!(tiny_counts.visible, plain_counts.visible);
    assert!(tiny_counts.inner_matched.abs_diff(plain_counts.inner_matched) <= 2, "{tiny_counts:?} {plain_counts:?}");
    // A real lens moves the samples: on the undistorted image, the match drops.
    let barrel = plain.with_distortion(Distortion::plumb_bob([-0.3, 0.1, 0.0, 0.0, 0.0]).unwrap());
    let barrel_counts = camera_counts(&model, &lut, &barrel, &image, &r, &t);
    assert!(barrel_counts.score() < plain_counts.score(), "{barrel_counts:?} {plain_counts:?}");
    assert!(barrel_counts.strip_matched > 0, "{barrel_counts:?}");
    // A point far outside the field never reads a pixel, whatever the polynomial does.
    let p = Psi::new([5.0, 0.0, 0.5], [0.0; 3]);
    let far = camera_counts(&model, &lut, &barrel, &image, &p.rotation_unchecked(), &p.translation());
    assert_eq!(far.inner_matched + far.strip_matched, 0);
}

#[test]
fn affine_walk_stays_on_the_projected_row() {
    const G: usize = 8;
    let cam = rig().right;
    let q = crate::quat::from_angle_axis(0.8, &Vector3::new(0.3, 1.0, 0.2)).unwrap();
    let pose = Psi::from_parts(&Vector3::new(0.05, -0.03, 0.45), &q);
    let (r, t) = (pose.rotation_unchecked(), pose.translation());
    let s = FIX_ONE;
    let proj = Projector::new([cam.fx() * s, cam.fy() * s, cam.cx() * s, cam.cy() * s], &r, &t);
    let model = SurfaceStrips::<G>::new(&Block::PAPER).unwrap();
    let project = |p: &Vector3<f32>| {
        let c = r * p + t;
        (
            (
                f64::from(cam.fx()) * f64::from(c.x) / f64::from(c.z) + f64::from(cam.cx()),
                f64::from(cam.fy()) * f64::from(c.y) / f64::from(c.z) + f64::from(cam.cy()),
            ),
            f64::from(c.z),
        )
    };
    let mut worst_shift = 0.0f64;
    for face in model.faces() {
        for e in &face.edges {
            for d in ROW_DISTANCES_M {
                let first = e.base + e.inward * d;
                let last = first + e.step * (G - 1) as f32;
                let h = |p: &Vector3<f32>| {
                    let m = &proj.m;
                    let row = |i: usize| m[i][0] * p.x + m[i][1] * p.y + m[i][2] * p.z + proj.c[i];
                    [row(0), row(1), row(2)]
                };
                let (a, b) = (h(&first), h(&last));
                let row = FixedRow::new::<G>(a, sub(b, a));
                // The host's batched rows are the board's, bit for bit.
                assert_eq!(FixedRow::edge::<G, 1>(&[a], sub(b, a)), [row]);
                let ((u0, v0), w0) = project(&first);
                let ((u1, v1), w1) = project(&last);
                let (du, dv) = (u1 - u0, v1 - v0);
                let len2 = du * du + dv * dv;
                let bound = (w1 - w0).abs() / (4.0 * w0.min(w1));
                for i in 0..G {
                    let fx = f64::from(row.u.wrapping_add(row.du * i as i32)) / 65536.0;
                    let fy = f64::from(row.v.wrapping_add(row.dv * i as i32)) / 65536.0;
                    // On the projected segment: distance to its line ≤ 0.01 px...
                    let off = ((fx - u0) * dv - (fy - v0) * du).abs() / len2.sqrt();
                    assert!(off < 0.01, "{off} px off the row");
                    // ...and the row point it shows is within the bound of the model's.
                    let s_img = ((fx - u0) * du + (fy - v0) * dv) / len2;
                    let s = i as f64 / (G - 1) as f64;
                    let s_model = s_img * w0 / ((1.0 - s_img) * w1 + s_img * w0);
                    let shift = (s_model - s).abs();
                    assert!(shift <= bound + 1e-3, "shift {shift} > bound {bound}");
                    worst_shift = worst_shift.max(shift);
                }
            }
        }
    }
    // The pose is tilted: the walk does move points along their rows, a little.
    assert!(worst_shift > 1e-3 && worst_shift < 0.1, "{worst_shift}");
}

#[test]
fn host_and_board_walks_count_the_same() {
    // Random rows in, across and outside a small image of random hue bytes (NO_HUE
    // included): the host's checked walk and the board's selected walk give the same sums.
    let (w, h) = (37u16, 23u16);
    let mut x = 0x2545_f491u32;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x
    };
    let pixels: vec::Vec<u8> = (0..usize::from(w) * usize::from(h))
        .map(|_| if next() % 4 == 0 { NO_HUE } else { (next() % 180) as u8 })
        .collect();
    let img = HueImage::new_checked(&pixels[..], w, h).unwrap();
    let view = View::of(&img);
    let lut = HueLut::new(&[0, 60, 120, 30, 90, 150], DEFAULT_HUE_TOLERANCE);
    let reach = |r: u32| (r % (120 << FIX_BITS)) as i32 - (40 << FIX_BITS);
    let (mut inside, mut outside) = (0, 0);
    for k in 0..20_000 {
        let row = FixedRow {
            u: reach(next()),
            v: reach(next()),
            du: (next() % (16 << FIX_BITS)) as i32 - (8 << FIX_BITS),
            dv: (next() % (16 << FIX_BITS)) as i32 - (8 << FIX_BITS),
        };
        let plane = if k % 2 == 0 { lut.plane(k % 6) } else { lut.any((k % 64) as u8) };
        let (checked, selected) = (view.walk_checked::<8>(&row, plane), view.walk_selected::<8>(&row, plane));
        assert_eq!(checked, selected, "{row:?}");
        let col = (row.u >> FIX_BITS) as u32;
        if col < u32::from(w) && ((row.v >> FIX_BITS) as u32) < u32::from(h) {
            inside += 1;
        } else {
            outside += 1;
        }
    }
    assert!(inside > 1000 && outside > 1000, "{inside} / {outside}");
}

#[test]
fn walking_only_the_rows_that_count_gives_the_same_counts() {
    // The host walks the rows that count, the board every row (constant work): over poses
    // around a scene showing one, two or three faces, plain and distorted, the same counts.
    use crate::camera::Distortion;
    let model = SurfaceStrips::<8>::new(&Block::PAPER).unwrap();
    let lut = HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE);
    let q = crate::quat::from_angle_axis(0.5, &Vector3::new(0.3, 1.0, 0.1)).unwrap();
    let truth = Psi::from_parts(&Vector3::new(0.03, -0.02, 0.72), &q);
    let (_, img) = scene(&truth);
    let image = HueImage::new_checked(&img[..], W, H).unwrap();
    let plain = rig().right;
    let barrel = plain.with_distortion(Distortion::plumb_bob([-0.3, 0.1, 0.0, 0.0, 0.0]).unwrap());
    let mut x = 0x9e37_79b9u32;
    let mut unit = move || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x as f32 / u32::MAX as f32 * 2.0 - 1.0
    };
    let mut faces_seen = [0usize; 4];
    for k in 0..3000 {
        let mut p = truth;
        for (g, gene) in p.0.iter_mut().enumerate() {
            *gene += unit() * if g < 3 { 0.05 } else { 0.9 };
        }
        if p.validate().is_err() {
            continue;
        }
        let rot = p.rotation_unchecked();
        let (cam, t) = (if k % 4 == 0 { &barrel } else { &plain }, p.translation());
        // Every other pose with the silhouette rows shifted (`crate::edge`).
        let shift = if k % 2 == 0 { 0.0 } else { unit() * 0.5 - 0.25 };
        let some = counts_walking::<8, _, _, false>(&model, &lut, cam, &image, &rot, &t, shift);
        let all = counts_walking::<8, _, _, true>(&model, &lut, cam, &image, &rot, &t, shift);
        assert_eq!(some, all, "{p:?}");
        faces_seen[some.visible.count_ones() as usize] += 1;
    }
    assert!(faces_seen[1..].iter().all(|&n| n > 50), "{faces_seen:?}");
}

#[test]
fn a_blank_image_scores_zero() {
    let model = SurfaceStrips::<4>::new(&Block::PAPER).unwrap();
    let lut = HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE);
    let rig = rig();
    let eval = Evaluator::new(&model, &lut, &rig);
    let blank = vec![NO_HUE; usize::from(W) * usize::from(H)];
    let img = HueImage::new_checked(&blank[..], W, H).unwrap();
    let f = eval.evaluate_psi(&Psi::new([0.0, 0.0, 0.7], [0.0; 3]), &img, &img);
    assert_eq!(f.total, 0.0);
    assert!(f.right.inner_total > 0);
}

#[test]
fn score_clamps_at_zero() {
    let c = Counts { weighted_matched: 3, weighted_total: 10, weighted_strip: 7, visible: 1, ..Counts::default() };
    assert_eq!(c.score(), 0.0);
    let c = Counts { weighted_matched: 7, weighted_total: 10, weighted_strip: 2, visible: 1, ..Counts::default() };
    assert!((c.score() - 0.5).abs() < 1e-7);
}

#[test]
fn full_faces_counts_the_faces_each_camera_sees_whole() {
    let (model, lut, rig) = paper_block();
    let eval = Evaluator::new(&model, &lut, &rig);
    let at =
        |q: &nalgebra::UnitQuaternion<f32>, t: Vector3<f32>| eval.full_faces(&crate::quat::to_rotation_matrix(q), &t);
    // Face-on to the right camera: its −z face whole, the side faces edge-on; the left camera,
    // a baseline away, sees one side face under less than the full-weight angle.
    let ahead = Vector3::new(0.0, 0.0, 0.8);
    assert_eq!(at(&nalgebra::UnitQuaternion::identity(), ahead), [1, 1]);
    // A corner towards the cameras: three faces whole in both.
    let corner = crate::quat::from_angle_axis(2.0, &Vector3::new(-1.0, 1.0, 0.1)).unwrap();
    assert_eq!(at(&corner, ahead), [3, 3]);
    // Turned 30° about the vertical: two faces whole.
    let turned = crate::quat::from_angle_axis(0.52, &Vector3::y()).unwrap();
    assert_eq!(at(&turned, ahead), [2, 2]);
    // Behind the cameras: none.
    assert_eq!(at(&corner, -ahead), [0, 0]);
}
