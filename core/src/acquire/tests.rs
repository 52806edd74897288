//! Unit tests of the acquisition.

use super::seed::half_turn;
use super::*;
use crate::ga::unit_f32;
use crate::image::HueImage;
use crate::limits::{DEFAULT_HUE_TOLERANCE, NO_HUE};
use crate::model::{Block, SurfaceStrips};
use crate::pose::Psi;
use crate::synth::test_scene::{H, W, rig, scene};
use nalgebra::{Matrix3, Vector3};
use rand_core::Rng;
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro128PlusPlus;
use std::vec;

fn lut() -> HueLut {
    let model = SurfaceStrips::<4>::new(&Block::PAPER).unwrap();
    HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE)
}

/// Smallest rotation angle between `r` and `truth` over the colour symmetry's half turns.
fn angle_mod_symmetry(r: &Matrix3<f32>, truth: &Matrix3<f32>) -> f32 {
    (0..4)
        .map(|k| {
            let d = half_turn(r, k).transpose() * truth;
            let c = ((d.trace() - 1.0) * 0.5).clamp(-1.0, 1.0);
            c.acos()
        })
        .fold(f32::MAX, f32::min)
}

#[test]
fn scan_reads_a_fixed_grid_and_counts_hues_per_axis() {
    let (w, h) = (40u16, 30u16);
    let mut px = vec![NO_HUE; usize::from(w) * usize::from(h)];
    // One red pixel on the grid (stride 8, offset 4) and one off it.
    px[4 * 40 + 12] = 0;
    px[5 * 40 + 12] = 0;
    px[12 * 40 + 20] = 60; // green
    let img = HueImage::new_checked(&px[..], w, h).unwrap();
    let b = scan(&img, &lut(), 8);
    assert_eq!(b.count, [1, 1, 0]);
    assert_eq!((b.sum_u[0], b.sum_v[0]), (12, 4));
    assert_eq!(b.centroid(1), Some(Point2::new(20.5, 12.5)));
    assert_eq!(b.centroid(2), None);
    assert_eq!(scan(&img, &lut(), 0).total(), 0);
}

#[test]
fn hits_in_the_outermost_grid_rows_and_columns_mark_the_border() {
    let (w, h) = (40u16, 30u16); // grid columns at u = 4, 12, …, 36, rows at v = 4, 12, 20, 28
    let edge = |at: &[(usize, usize)]| {
        let mut px = vec![NO_HUE; usize::from(w) * usize::from(h)];
        for &(u, v) in at {
            px[v * usize::from(w) + u] = 0;
        }
        let img = HueImage::new_checked(&px[..], w, h).unwrap();
        let b = scan(&img, &lut(), 8);
        assert_eq!(b.total(), at.len() as u32);
        (b.edge, b.touches_border())
    };
    assert_eq!(edge(&[(12, 12), (28, 20)]), (0, false));
    for corner_or_side in [(4, 12), (36, 12), (20, 4), (20, 28), (36, 28)] {
        assert_eq!(edge(&[(12, 12), corner_or_side]), (1, true), "{corner_or_side:?}");
    }
}

#[test]
fn a_seed_from_a_block_cut_by_the_border_says_so() {
    let rig = rig();
    let half = Block::PAPER.size_m.map(|s| 0.5 * s);
    let seed_at = |x: f32| {
        let truth = Psi::new([x, -0.01, 0.7], [0.2, 0.3, 0.1]);
        let (l, r) = scene(&truth);
        let (l, r) = (HueImage::new_checked(&l[..], W, H).unwrap(), HueImage::new_checked(&r[..], W, H).unwrap());
        let (bl, br) = (scan(&l, &lut(), 8), scan(&r, &lut(), 8));
        (bl.touches_border() || br.touches_border(), seed_pose(&rig, &half, &bl, &br, 6).map(|s| s.cut))
    };
    assert_eq!(seed_at(0.02), (false, Some(false)));
    // Far enough across the view that part of the block leaves both images.
    let (touches, cut) = seed_at(0.17);
    assert!(touches);
    assert_eq!(cut, Some(true));
}

#[test]
fn triangulation_inverts_the_projection() {
    let rig = rig();
    let p = Vector3::new(0.05, -0.03, 0.8);
    let (r, l) = rig.project_model_point(&nalgebra::Isometry3::translation(p.x, p.y, p.z), &nalgebra::Point3::origin());
    let q = triangulate(&rig, &r.unwrap(), &l.unwrap()).unwrap();
    assert!((q - p).norm() < 1e-5, "{q}");
    // Rays that diverge (negative disparity) meet behind the cameras.
    assert_eq!(triangulate(&rig, &Point2::new(400.0, 240.0), &Point2::new(300.0, 240.0)), None);
}

#[test]
fn seed_is_close_to_the_truth_for_random_poses() {
    let rig = rig();
    let half = Block::PAPER.size_m.map(|s| 0.5 * s);
    let mut rng = Xoshiro128PlusPlus::seed_from_u64(5);
    let (mut worst_t, mut worst_r, mut n) = (0.0f32, 0.0f32, 0);
    for _ in 0..40 {
        let u: [f32; 6] = core::array::from_fn(|_| unit_f32(&mut rng));
        let eps = Vector3::new(2.0 * u[3] - 1.0, 2.0 * u[4] - 1.0, 2.0 * u[5] - 1.0);
        if eps.norm() > 1.0 {
            continue;
        }
        let truth = Psi::new([0.1 * u[0] - 0.05, 0.1 * u[1] - 0.05, 0.6 + 0.3 * u[2]], eps.into());
        let (l, r) = scene(&truth);
        let (l, r) = (HueImage::new_checked(&l[..], W, H).unwrap(), HueImage::new_checked(&r[..], W, H).unwrap());
        let (bl, br) = (scan(&l, &lut(), 8), scan(&r, &lut(), 8));
        let seed = seed_pose(&rig, &half, &bl, &br, 6).unwrap();
        let dt = (seed.centre - truth.translation()).norm();
        worst_t = worst_t.max(dt);
        if seed.free_axis.is_none() {
            worst_r = worst_r.max(angle_mod_symmetry(&seed.rotation, &truth.rotation_unchecked()));
        }
        n += 1;
        let psi = seed.psi().unwrap();
        assert!(psi.validate().is_ok());
    }
    assert!(n > 15);
    assert!(worst_t < 0.03, "worst centre error {worst_t} m");
    assert!(worst_r < 0.35, "worst rotation error {worst_r} rad");
}

#[test]
fn nothing_seen_gives_no_seed_and_immigrants_draw_a_fixed_count() {
    let rig = rig();
    let none = HueBlobs::default();
    assert_eq!(seed_pose(&rig, &[0.05, 0.075, 0.1], &none, &none, 6), None);
    let seed = Seed {
        centre: Vector3::new(0.0, 0.0, 0.7),
        rotation: Matrix3::identity(),
        faces: 1,
        free_axis: Some(2),
        cut: false,
    };
    let mut r1 = Xoshiro128PlusPlus::seed_from_u64(3);
    let mut r2 = Xoshiro128PlusPlus::seed_from_u64(3);
    let p0 = seed_immigrant(&seed, 0, &AcquireConfig::DEFAULT, &mut r1).unwrap();
    assert!((p0.translation() - seed.centre).norm() < 1e-7);
    for _ in 0..9 {
        r2.next_u32();
    }
    assert_eq!(r1.next_u32(), r2.next_u32());
    for i in 1..20 {
        let p = seed_immigrant(&seed, i, &AcquireConfig::DEFAULT, &mut r1).unwrap();
        assert!(p.validate().is_ok());
        assert!((p.translation() - seed.centre).norm() < 0.025 * 1.8);
    }
}

#[test]
fn scan_in_chunks_is_the_whole_scan() {
    let truth = Psi::new([0.02, -0.01, 0.7], [0.2, 0.3, 0.1]);
    let (l, _) = scene(&truth);
    let img = HueImage::new_checked(&l[..], W, H).unwrap();
    let whole = scan(&img, &lut(), 8);
    assert!(whole.total() > 100);
    let (gw, gh) = grid_size(W, H, 8);
    assert_eq!((gw, gh), (80, 60));
    for chunk in [1, 7, 80, 1200, 5000] {
        let (mut blobs, mut at, mut calls) = (HueBlobs::default(), 0, 0);
        while at < gw * gh {
            let next = scan_part(&img, &lut(), 8, at, chunk, &mut blobs);
            assert_eq!(next, (at + chunk).min(gw * gh));
            at = next;
            calls += 1;
        }
        assert_eq!(blobs, whole, "chunk {chunk}");
        assert_eq!(calls, (gw * gh).div_ceil(chunk));
    }
    // Past the end nothing is read.
    let mut b = HueBlobs::default();
    assert_eq!(scan_part(&img, &lut(), 8, gw * gh + 5, 10, &mut b), gw * gh);
    assert_eq!(b.total(), 0);
}

#[test]
fn pipeline_gives_the_one_go_seed_after_its_stages() {
    let rig = rig();
    let half = Block::PAPER.size_m.map(|s| 0.5 * s);
    let truth = Psi::new([0.02, -0.01, 0.7], [0.2, 0.3, 0.1]);
    let (l, r) = scene(&truth);
    let (l, r) = (HueImage::new_checked(&l[..], W, H).unwrap(), HueImage::new_checked(&r[..], W, H).unwrap());
    let cfg = AcquireConfig::DEFAULT;
    let direct = best_seed(&rig, &half, &scan(&l, &lut(), 8), &scan(&r, &lut(), 8), 8, cfg.min_face_hits).unwrap();
    let mut acq = Acquisition::new();
    let scans = (80u32 * 60).div_ceil(cfg.scan_chunk) as usize;
    let stages = scans + 1 + REFINE_ITERATIONS;
    for k in 0..stages {
        assert!(acq.seed().is_none(), "seed after {k} stages");
        acq.step(&l, &r, &lut(), &rig, &half, &cfg);
    }
    assert_eq!(acq.stage(), Stage::Scan(0));
    let seed = acq.seed().unwrap();
    // No camera motion: the same seed as in one go (identity motion, up to rounding).
    assert!((seed.centre - direct.centre).norm() < 1e-5, "{} vs {}", seed.centre, direct.centre);
    assert!((seed.rotation - direct.rotation).norm() < 1e-5);
    assert!((seed.centre - truth.translation()).norm() < 0.01);
    // A camera moving 5 cm along x: the seed follows (the block moves −5 cm in Σ_CR).
    acq.shift(|p| p.0[0] -= 0.05);
    assert!((acq.seed().unwrap().centre - direct.centre - Vector3::new(-0.05, 0.0, 0.0)).norm() < 1e-5);
    acq.reset();
    assert_eq!((acq.stage(), acq.seed()), (Stage::Scan(0), None));
}

/// A `w × h` image of hue `background` with the hue-`block` rectangle `u0..u1 × v0..v1`.
fn backdrop(w: u16, h: u16, background: impl Fn(usize, usize) -> u8, block: (u8, [usize; 4])) -> vec::Vec<u8> {
    let (hue, [u0, u1, v0, v1]) = block;
    let w = usize::from(w);
    (0..w * usize::from(h))
        .map(|i| {
            let (u, v) = (i % w, i / w);
            if (u0..u1).contains(&u) && (v0..v1).contains(&v) { hue } else { background(u, v) }
        })
        .collect()
}

#[test]
fn the_scan_records_the_hues_seen_on_each_side_of_the_border() {
    // Grid columns at u = 4, 12, …, 36, rows at v = 4, 12, 20, 28: a green column at u = 4 and
    // a red row at v = 28 (meeting at the bottom-left corner, which is red), blue inside.
    let px = backdrop(
        40,
        30,
        |u, v| {
            if v >= 26 {
                0
            } else if u < 6 {
                60
            } else {
                NO_HUE
            }
        },
        (120, [10, 30, 10, 22]),
    );
    let b = scan(&HueImage::new_checked(&px[..], 40, 30).unwrap(), &lut(), 8);
    assert_eq!(b.sides[60], SIDE_LEFT | SIDE_TOP | SEEN);
    assert_eq!(b.sides[0], SIDE_BOTTOM | SIDE_LEFT | SIDE_RIGHT | SEEN);
    assert_eq!(b.sides[120], SEEN);
    assert_eq!(b.sides.iter().filter(|&&s| s != 0).count(), 3);
}

#[test]
fn a_hue_around_the_view_is_the_scenes_and_the_blocks_hues_are_not() {
    let (w, h) = (W, H);
    let scan_of = |px: &[u8]| scan(&HueImage::new_checked(px, w, h).unwrap(), &lut(), 8);
    // A grey scene tinted green-yellow by the white balance: hues 86°–94° with noise, one
    // pixel of 96° on one side only and one of 100° inside (its spread's tail, across an empty
    // unit); the block's green face at 120° in the middle, its red face cut by the left border.
    let tint = |u: usize, v: usize| match (u, v) {
        (636, 124) => 48,
        (300, 300) => 50,
        _ => 43 + ((u * 7 + v * 13) % 5) as u8,
    };
    let mut px = backdrop(w, h, tint, (60, [100, 200, 60, 180]));
    for v in 80..160 {
        for u in 0..40 {
            px[v * usize::from(w) + u] = 0;
        }
    }
    let b = scan_of(&px);
    let scene = scene_hues(&b, &b);
    for unit in 43..=50 {
        assert!(scene.contains(unit), "unit {unit}");
    }
    for unit in [0, 42, 51, 60, 120] {
        assert!(!scene.contains(unit), "unit {unit}");
    }
    // One image seeing the scene's hue on three sides is enough; two sides are not (a block
    // cut by a corner).
    let corner = backdrop(w, h, |_, _| NO_HUE, (60, [0, 100, 0, 80]));
    let c = scan_of(&corner);
    assert_eq!(c.sides[60], SIDE_TOP | SIDE_LEFT | SEEN);
    assert!(scene_hues(&c, &c).is_empty());
    assert!(scene_hues(&b, &c).contains(45) && scene_hues(&c, &b).contains(45));
    // Across the wrap of the hue circle: 358° around the view, 0° and 2° on its border.
    let red = backdrop(w, h, |u, _| [179, 0, 1][u % 3], (120, [100, 200, 60, 180]));
    let r = scan_of(&red);
    let s = scene_hues(&r, &r);
    assert!(s.contains(179) && s.contains(0) && s.contains(1) && !s.contains(2) && !s.contains(178));
}

#[test]
fn a_scan_that_finds_new_scene_hues_is_repeated_once_before_it_is_solved() {
    let rig = rig();
    let half = Block::PAPER.size_m.map(|s| 0.5 * s);
    let cfg = AcquireConfig::DEFAULT;
    let scans = (80u32 * 60).div_ceil(cfg.scan_chunk);
    let none = vec![NO_HUE; usize::from(W) * usize::from(H)];
    let flat = (none.clone(), none);
    // The block on a background of hue 45 (no face's in this table).
    let mut tinted = scene(&Psi::new([0.02, -0.01, 0.7], [0.2, 0.3, 0.1]));
    for px in tinted.0.iter_mut().chain(tinted.1.iter_mut()).filter(|px| **px == NO_HUE) {
        *px = 45;
    }
    let mut acq = Acquisition::new();
    // The scan's stages, then the solve stage; returns the stage after it.
    let cycle = |acq: &mut Acquisition, (l, r): &(vec::Vec<u8>, vec::Vec<u8>)| {
        let (l, r) = (HueImage::new_checked(&l[..], W, H).unwrap(), HueImage::new_checked(&r[..], W, H).unwrap());
        for _ in 0..scans {
            acq.step(&l, &r, &lut(), &rig, &half, &cfg);
        }
        assert_eq!(acq.stage(), Stage::Solve);
        acq.step(&l, &r, &lut(), &rig, &half, &cfg);
        acq.stage()
    };
    // Nothing around the view, nothing seen: back to the scan.
    assert_eq!(cycle(&mut acq, &flat), Stage::Scan(0));
    assert!(acq.scene().is_empty());
    // Hue 45 around the view: taken, and the scan repeated instead of solved.
    assert_eq!(cycle(&mut acq, &tinted), Stage::Scan(0));
    assert!(acq.scene().contains(45) && !acq.scene().contains(44));
    assert!(acq.seed().is_none());
    // The same scene again: solved.
    assert_eq!(cycle(&mut acq, &tinted), Stage::Refine(0));
    // The scene's hues outlive a reset (they belong to the scene, not to the block).
    acq.reset();
    assert!(acq.scene().contains(45));
    assert_eq!(cycle(&mut acq, &tinted), Stage::Refine(0));
}
