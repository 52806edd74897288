//! Runs N fitness evaluations of one pose on a synthetic 640×480 pair, for instruction
//! counting under valgrind (`valgrind --tool=callgrind`), which is deterministic where wall
//! time on a shared machine is not.
//!
//! `cargo build --release -p evorec-core --example fitness_probe &&
//!  valgrind --tool=callgrind --callgrind-out-file=/dev/null target/release/examples/fitness_probe 20000 [G] [corner]`
//! with `G` one of 4, 8 (default), 16. The default pose shows each camera two faces (and four
//! silhouette edges); `corner` turns a corner of the block to the cameras, so three faces and
//! six silhouette edges count (the most rows a pose walks).

use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::fitness::Evaluator;
use evorec_core::hue::HueLut;
use evorec_core::image::HueImage;
use evorec_core::limits::{DEFAULT_GRID, DEFAULT_HUE_TOLERANCE, NO_HUE};
use evorec_core::model::{Block, SurfaceStrips};
use evorec_core::pose::Psi;
use evorec_core::{quat, synth};
use nalgebra::Vector3;
use std::hint::black_box;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = std::env::args().nth(1).map(|s| s.parse()).transpose()?.unwrap_or(10_000);
    let (w, h) = (640u16, 480u16);
    let cam = Pinhole::new_checked(800.0, 800.0, 320.0, 240.0, w, h)?;
    let rig = StereoRig::parallel(cam, 0.1)?;
    let corner = std::env::args().nth(3).is_some_and(|a| a == "corner");
    let truth = if corner {
        let q = quat::from_angle_axis(2.0, &Vector3::new(-1.0, 1.0, 0.1))?;
        Psi::from_parts(&Vector3::new(0.02, -0.01, 0.75), &q)
    } else {
        let q = quat::from_angle_axis(0.5, &Vector3::new(0.3, 1.0, 0.1))?;
        Psi::from_parts(&Vector3::new(0.03, -0.02, 0.72), &q)
    };
    let iso = truth.try_to_isometry()?;
    let px = usize::from(w) * usize::from(h);
    let (mut l, mut r) = (vec![NO_HUE; px], vec![NO_HUE; px]);
    synth::render_block(&Block::PAPER, &rig.right, &iso, &mut r)?;
    synth::render_block(&Block::PAPER, &rig.left, &(rig.left_from_right * iso), &mut l)?;
    let (left, right) = (HueImage::new_checked(&l[..], w, h)?, HueImage::new_checked(&r[..], w, h)?);
    let grid = std::env::args().nth(2).unwrap_or_else(|| DEFAULT_GRID.to_string());
    let (points, mean, faces) = match grid.as_str() {
        "4" => probe::<4>(n, &rig, &truth, &left, &right)?,
        "16" => probe::<16>(n, &rig, &truth, &left, &right)?,
        _ => probe::<DEFAULT_GRID>(n, &rig, &truth, &left, &right)?,
    };
    println!("{n} evaluations x {points} sample points (G = {grid}), mean F {mean:.4}, visible faces {faces:?}");
    Ok(())
}

fn probe<const G: usize>(
    n: usize,
    rig: &StereoRig,
    truth: &Psi,
    left: &HueImage<&[u8]>,
    right: &HueImage<&[u8]>,
) -> Result<(usize, f32, [u32; 2]), Box<dyn std::error::Error>> {
    let model = SurfaceStrips::<G>::new(&Block::PAPER)?;
    let lut = HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE);
    let eval = Evaluator::new(&model, &lut, rig);
    let mut acc = 0.0f32;
    for i in 0..n {
        let mut p = *truth;
        p.0[0] += (i % 7) as f32 * 1e-4;
        acc += eval.evaluate_psi(black_box(&p), left, right).total;
    }
    let f = eval.evaluate_psi(truth, left, right);
    let faces = [f.left.visible.count_ones(), f.right.visible.count_ones()];
    Ok((2 * SurfaceStrips::<G>::POINTS_PER_CAMERA, acc / n as f32, faces))
}
