//! Tests of the renderer (`super`): coverage, shading, noise, the hue and RGB565 conversions.

use super::*;
use evorec_core::hue::{degrees_to_units, hue_distance};
use evorec_core::limits::NO_HUE;
use evorec_core::synth;
use nalgebra::Vector3;
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;

pub(super) fn cam() -> Pinhole {
    Pinhole::new_checked(800.0, 800.0, 320.0, 240.0, 640, 480).unwrap()
}

pub(super) fn pose() -> Isometry3<f32> {
    // Three faces visible, ~0.7 m ahead.
    Isometry3::new(Vector3::new(0.02, -0.01, 0.7), Vector3::new(0.5, -0.6, 0.3))
}

pub(super) fn rng() -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(7)
}

/// Smallest signed distance of pixel `(x, y)`'s centre to face `k`'s edges.
fn dmin(f: &ScreenFace, x: u32, y: u32) -> f32 {
    let d = f.distances(x as f32 + 0.5, y as f32 + 0.5);
    d[0].min(d[1]).min(d[2]).min(d[3])
}

#[test]
fn ideal_image_has_face_hues_inside_and_no_hue_outside() {
    let odd = Block { face_hues_deg: [30.0, 200.0, 300.0, 30.0, 200.0, 300.0], ..Block::PAPER };
    for (block, tol) in [(Block::PAPER, 0u8), (odd, 1u8)] {
        for aa in [AntiAlias::Exact, AntiAlias::Supersample(4), AntiAlias::Off] {
            let opts = RenderOptions::default().with_antialias(aa);
            let img = render(&cam(), &pose(), &block, &opts, &mut rng());
            let hue = hue_image(&img);
            let faces = screen_faces(&cam(), &pose(), &block, &opts);
            // The model faces behind the screen faces, in the same order.
            let p = pose();
            let visible: Vec<usize> = (0..FACES)
                .filter(|&k| (p.rotation * Block::normal(k)).dot(&(p * block.face_corners(k)[0]).coords) < 0.0)
                .collect();
            assert_eq!((faces.len(), visible.len()), (3, 3));
            let (mut inside, mut outside) = (0, 0);
            for y in 0..480 {
                for x in 0..640 {
                    let hv = hue[(y * 640 + x) as usize];
                    let d: Vec<f32> = faces.iter().map(|f| dmin(f, x, y)).collect();
                    if let Some(k) = d.iter().position(|&d| d >= 1.5) {
                        let deg = block.face_hues_deg[visible[k]];
                        assert!(
                            hv != NO_HUE && hue_distance(hv, degrees_to_units(deg)) <= tol,
                            "{aa:?} pixel {x},{y}: hue {hv}, face {deg}°"
                        );
                        inside += 1;
                    } else if d.iter().all(|&d| d <= -1.0) {
                        assert_eq!(hv, NO_HUE, "{aa:?} background pixel {x},{y}");
                        outside += 1;
                    }
                }
            }
            assert!(inside > 20_000 && outside > 200_000, "{inside} {outside}");
        }
    }
}

#[test]
fn hue_colours_round_trip() {
    for deg in [-1e-6f32, 0.0, 30.0, 59.9, 60.0, 120.0, 180.0, 240.0, 300.0, 359.0, 360.0, 720.0 + 200.0] {
        let c = hue_rgb(deg).map(|v| to_u8(v * 200.0));
        let h = rgb_to_hue(c[0], c[1], c[2]);
        assert!(hue_distance(h, degrees_to_units(deg)) <= 1, "{deg}° -> {c:?} -> {h}");
    }
}

#[test]
fn faces_of_equal_hue_differ_in_brightness() {
    let faces = screen_faces(&cam(), &pose(), &Block::PAPER, &RenderOptions::default());
    let max: Vec<f32> = faces.iter().map(|f| f.colour.iter().copied().fold(0.0, f32::max)).collect();
    assert!(max.iter().all(|&m| m >= 60.0), "{max:?}");
    assert!((max[0] - max[1]).abs() > 1.0 || (max[1] - max[2]).abs() > 1.0);
}

/// Pixels whose 3 × 3 neighbourhood in `img` is uniform.
fn interior(img: &[u8], w: usize, h: usize) -> Vec<usize> {
    let mut out = Vec::new();
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let c = img[y * w + x];
            if (0..9).all(|n| img[(y + n / 3 - 1) * w + x + n % 3 - 1] == c) {
                out.push(y * w + x);
            }
        }
    }
    out
}

#[test]
fn agrees_with_the_core_rasterizer_away_from_edges() {
    let poses = [
        pose(),
        Isometry3::new(Vector3::new(-0.05, 0.03, 0.9), Vector3::new(-0.3, 0.2, 1.2)),
        Isometry3::new(Vector3::new(0.0, 0.0, 0.5), Vector3::new(0.0, 0.0, 0.0)),
    ];
    for p in &poses {
        let mut exact = vec![NO_HUE; 640 * 480];
        synth::render_block(&Block::PAPER, &cam(), p, &mut exact).unwrap();
        let idx = interior(&exact, 640, 480);
        let face_px = idx.iter().filter(|&&i| exact[i] != NO_HUE).count();
        assert!(face_px > 10_000);
        for (noise, tol) in [(0.0, 0u8), (3.0, 5u8)] {
            let opts = RenderOptions::default().with_noise(noise);
            let ours = hue_image(&render(&cam(), p, &Block::PAPER, &opts, &mut rng()));
            let agree = idx
                .iter()
                .filter(|&&i| {
                    let (a, b) = (exact[i], ours[i]);
                    a == b || (a != NO_HUE && b != NO_HUE && hue_distance(a, b) <= tol)
                })
                .count();
            let frac = agree as f64 / idx.len() as f64;
            assert!(frac >= 0.99, "noise {noise}: {frac}");
        }
    }
}

#[test]
fn sub_pixel_motion_changes_edge_pixels_only() {
    let p = pose();
    let shift = 0.2 * p.translation.vector.z / cam().fx();
    let moved = Isometry3::from_parts((p.translation.vector + Vector3::new(shift, 0.0, 0.0)).into(), p.rotation);
    for aa in [AntiAlias::Exact, AntiAlias::Supersample(4)] {
        let opts = RenderOptions::default().with_antialias(aa);
        let a = render(&cam(), &p, &Block::PAPER, &opts, &mut rng());
        let b = render(&cam(), &moved, &Block::PAPER, &opts, &mut rng());
        let faces = screen_faces(&cam(), &p, &Block::PAPER, &opts);
        let mut changed = 0;
        for (x, y, pa) in a.enumerate_pixels() {
            if pa != b.get_pixel(x, y) {
                changed += 1;
                // Only pixels near an edge may change.
                assert!(faces.iter().any(|f| dmin(f, x, y).abs() < 1.5), "{aa:?} {x},{y}");
            }
        }
        assert!(changed > 200, "{aa:?}: only {changed} pixels changed");
    }
}

#[test]
fn block_behind_or_through_the_camera_is_not_drawn() {
    let opts = RenderOptions::default();
    // Far off axis: the block projects far outside the image.
    let nothing = render(&cam(), &Isometry3::translation(100.0, 0.0, 1.0), &Block::PAPER, &opts, &mut rng());
    assert!(hue_image(&nothing).iter().all(|&h| h == NO_HUE));
    let behind = render(&cam(), &Isometry3::translation(0.0, 0.0, -0.7), &Block::PAPER, &opts, &mut rng());
    assert_eq!(behind, nothing);
    assert!(hue_image(&behind).iter().all(|&h| h == NO_HUE));
    // Straddling the camera plane, at the camera centre, or not finite: no panic.
    for t in [[0.0, 0.0, 0.03], [0.0, 0.0, 0.0], [0.0, 0.0, 0.12], [f32::NAN, 0.0, 0.7], [0.0, f32::INFINITY, 0.7]] {
        let p = Isometry3::new(Vector3::from(t), Vector3::new(0.3, 0.2, 0.1));
        let _ = render(&cam(), &p, &Block::PAPER, &opts.with_noise(4.0), &mut rng());
    }
}

#[test]
fn noise_has_the_requested_spread_and_keeps_the_background_grey() {
    let opts = RenderOptions::default().with_noise(5.0);
    let far = Isometry3::translation(100.0, 0.0, 1.0);
    let clean = render(&cam(), &far, &Block::PAPER, &RenderOptions::default(), &mut rng());
    let noisy = render(&cam(), &far, &Block::PAPER, &opts, &mut rng());
    let diffs: Vec<f64> =
        clean.as_raw().iter().zip(noisy.as_raw()).map(|(&a, &b)| f64::from(b) - f64::from(a)).collect();
    let n = diffs.len() as f64;
    let mean = diffs.iter().sum::<f64>() / n;
    let std = (diffs.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n).sqrt();
    assert!(mean.abs() < 0.05 && (std - 5.0).abs() < 0.15, "mean {mean} std {std}");
    let hued = hue_image(&noisy).iter().filter(|&&h| h != NO_HUE).count();
    assert_eq!(hued, 0);
    // Deterministic for a seed, different for another.
    assert_eq!(noisy, render(&cam(), &far, &Block::PAPER, &opts, &mut rng()));
    let other = render(&cam(), &far, &Block::PAPER, &opts, &mut Xoshiro256PlusPlus::seed_from_u64(8));
    assert_ne!(noisy, other);
}

#[test]
fn row_spans_match_the_per_pixel_path() {
    let poses = [
        pose(),
        Isometry3::new(Vector3::new(-0.05, 0.03, 0.9), Vector3::new(-0.3, 0.2, 1.2)),
        Isometry3::new(Vector3::new(0.0, 0.0, 0.5), Vector3::new(0.0, 0.0, 0.0)),
        Isometry3::new(Vector3::new(0.25, 0.1, 0.4), Vector3::new(1.0, 0.4, -0.2)), // clipped at the border
    ];
    for p in &poses {
        for aa in [AntiAlias::Exact, AntiAlias::Supersample(3), AntiAlias::Off] {
            let opts = RenderOptions::default().with_antialias(aa);
            let fast = render(&cam(), p, &Block::PAPER, &opts, &mut rng());
            // Reference: the full per-pixel path everywhere.
            let faces = screen_faces(&cam(), p, &Block::PAPER, &opts);
            let colours: Vec<[u8; 3]> = faces.iter().map(|f| f.colour.map(to_u8)).collect();
            let (cols, rows) = background_tables(640, 480, &opts);
            let mut slow = RgbImage::new(640, 480);
            for (x, y, px) in slow.enumerate_pixels_mut() {
                let bg = cols[x as usize] + rows[y as usize];
                px.0 = [to_u8(bg); 3];
                shade_pixel(&faces, &colours, x as f32 + 0.5, y as f32 + 0.5, bg, aa, &mut px.0);
            }
            let worst = fast.as_raw().iter().zip(slow.as_raw()).map(|(a, b)| a.abs_diff(*b)).max();
            assert!(worst <= Some(1), "{aa:?}: {worst:?}");
        }
    }
}

#[test]
fn exact_coverage_of_a_half_plane() {
    // Vertical edge through the pixel centre: half the square.
    let all_in = [0.0, 0.0, 1.0];
    let half = clipped_square_area(&[[1.0, 0.0, 0.0], all_in, all_in, all_in]);
    assert!((half - 0.5).abs() < 1e-6);
    // Diagonal through the centre: half; shifted by 0.25 px: 1 − 0.5·(0.5 − 0.25·√2)²·2 …
    let s = std::f32::consts::FRAC_1_SQRT_2;
    assert!((clipped_square_area(&[[s, s, 0.0], all_in, all_in, all_in]) - 0.5).abs() < 1e-6);
    let quarter = clipped_square_area(&[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], all_in, all_in]);
    assert!((quarter - 0.25).abs() < 1e-6);
    assert_eq!(clipped_square_area(&[[1.0, 0.0, -0.8], all_in, all_in, all_in]), 0.0);
    assert_eq!(clipped_square_area(&[all_in; 4]), 1.0);
}

#[test]
fn stereo_pair_shows_disparity() {
    let rig = StereoRig::parallel(cam(), 0.1).unwrap();
    // Midway between the cameras: each sees the −z face only (the ±x faces edge-on).
    let p = Isometry3::translation(-0.05, 0.0, 0.8);
    let pair = render_stereo(&rig, &p, &Block::PAPER, &RenderOptions::default(), &mut rng());
    // Centroid weighted by blueness (b − r: 0 on the grey background), i.e. by coverage.
    let centroid = |img: &RgbImage| {
        let (mut sx, mut n) = (0.0, 0.0);
        for (x, _, p) in img.enumerate_pixels() {
            let wgt = f64::from(p.0[2]) - f64::from(p.0[0]);
            sx += wgt * (f64::from(x) + 0.5);
            n += wgt;
        }
        sx / n
    };
    // The blue −z face is 0.7 m away: disparity f·b/z = 800·0.1/0.7 px, left image further
    // right.
    let d = centroid(&pair.left) - centroid(&pair.right);
    assert!((d - 80.0 / 0.7).abs() < 0.5, "{d}");
}

#[test]
fn rgb565_frame_is_the_truncated_pixels_and_keeps_face_hues() {
    let opts = RenderOptions::default().with_antialias(AntiAlias::Off);
    let img = render(&cam(), &pose(), &Block::PAPER, &opts, &mut rng());
    let (w, h) = (img.width() as usize, img.height() as usize);
    let mut out = vec![0u8; 2 * w * h];
    rgb565_into(&img, &mut out);
    let hue = hue_image(&img);
    let mut face_pixels = 0;
    for (i, (px, rgb)) in out.chunks_exact(2).zip(img.pixels()).enumerate() {
        let v = u16::from_le_bytes([px[0], px[1]]);
        assert_eq!(v, rgb888_to_rgb565(rgb[0], rgb[1], rgb[2]));
        // Truncation to 5/6/5 bits moves a face pixel's hue by at most a unit or two.
        let h565 = evorec_core::image::rgb565_to_hue(v);
        if hue[i] != NO_HUE && h565 != NO_HUE {
            assert!(evorec_core::hue::hue_distance(hue[i], h565) <= 2, "pixel {i}: {} vs {h565}", hue[i]);
            face_pixels += 1;
        }
    }
    assert!(face_pixels > 1000, "{face_pixels}");
}

#[test]
fn points_are_drawn_and_clipped() {
    let mut img = RgbImage::new(10, 8);
    draw_points(
        &mut img,
        &[(5.5, 4.2), (0.0, 0.0), (-0.5, 3.0), (10.0, 2.0), (f32::NAN, 1.0), (9.9, 7.9)],
        [255, 0, 0],
    );
    let red = img.pixels().filter(|p| p.0 == [255, 0, 0]).count();
    assert_eq!(red, 5 + 3 + 3);
    assert_eq!(img.get_pixel(5, 4).0, [255, 0, 0]);
    assert_eq!(img.get_pixel(6, 4).0, [255, 0, 0]);
    assert_eq!(img.get_pixel(6, 5).0, [0, 0, 0]);
}

/// Timing of one 640×480 frame (render + noise + hue). Run with
/// `cargo test --release -p evorec-sim --lib render::tests::timing -- --ignored --nocapture`.
#[test]
#[ignore = "timing; run in release"]
fn timing() {
    let opts = RenderOptions::default().with_noise(3.0);
    let mut r = rng();
    let n = 300;
    for aa in [AntiAlias::Exact, AntiAlias::Supersample(4)] {
        let opts = opts.with_antialias(aa);
        let start = std::time::Instant::now();
        let mut sum = 0u64;
        for i in 0..n {
            let p = Isometry3::new(
                Vector3::new(0.001 * (i % 10) as f32, 0.0, 0.7),
                Vector3::new(0.5, -0.6, 0.3 + 0.001 * i as f32),
            );
            let img = render(&cam(), &p, &Block::PAPER, &opts, &mut r);
            sum += u64::from(hue_image(&img)[240 * 640 + 320]);
        }
        let per = start.elapsed().as_secs_f64() / f64::from(n) * 1e3;
        println!("{aa:?}: {per:.3} ms per 640x480 frame (render + noise + hue), checksum {sum}");
    }
}
