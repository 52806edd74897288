//! The fitness's resolution and its bias, over many frames of a scenario: at each frame the true
//! pose is moved along the right camera's viewing ray (depth) and along the camera's x and y
//! axes in 0.1 mm steps over ±6 mm, on the simulator's frames (RGB565, as the tracker sees
//! them) and on exactly rendered hue frames (the core's `synth::render_block`). Per frame and
//! axis it finds the set of offsets where F is at its maximum (the plateau) and reports, over
//! the frames: the mean centre of that plateau (the fitness's own bias: where an estimate that
//! maximises F sits on average), the mean plateau width, and how far F falls 1 mm and 2 mm off
//! the plateau's centre (the resolution).
//!
//! `cargo run --release -p evorec-sim --example depth_profile -- SCENARIO [OMEGA] [FRAMES] [STEP_S]`
mod frames;

use evorec_core::camera::StereoRig;
use evorec_core::image::HueImage;
use evorec_core::limits::NO_HUE;
use evorec_core::pose::Psi;
use evorec_core::synth::render_block;
use evorec_core::tracker::StereoFrame;
use evorec_sim::experiments::experiment::{SimTracker, tracker_config};
use evorec_sim::sim::board::World;
use evorec_sim::sim::scenario::Scenario;

const HALF_STEPS: i32 = 60;
const STEP_M: f32 = 0.0001;

/// F along one axis of offsets for one frame.
fn scan(f: impl Fn(f32) -> f32) -> Vec<(f32, f32)> {
    (-HALF_STEPS..=HALF_STEPS).map(|k| k as f32 * STEP_M).map(|d| (d, f(d))).collect()
}

#[derive(Default)]
struct Acc {
    n: usize,
    centre: Vec<f32>,
    width: Vec<f32>,
    drop1: Vec<f32>,
    drop2: Vec<f32>,
    ftruth: Vec<f32>,
    fmax: Vec<f32>,
}

impl Acc {
    fn add(&mut self, s: &[(f32, f32)]) {
        let max = s.iter().map(|p| p.1).fold(f32::MIN, f32::max);
        let at_max: Vec<f32> = s.iter().filter(|p| p.1 >= max - 1e-6).map(|p| p.0).collect();
        let lo = at_max.iter().copied().fold(f32::MAX, f32::min);
        let hi = at_max.iter().copied().fold(f32::MIN, f32::max);
        let centre = 0.5 * (lo + hi);
        let at =
            |d: f32| s.iter().min_by(|a, b| (a.0 - d).abs().total_cmp(&(b.0 - d).abs())).map(|p| p.1).unwrap_or(0.0);
        self.n += 1;
        self.centre.push(centre * 1e3);
        self.width.push((hi - lo) * 1e3);
        self.drop1.push(max - 0.5 * (at(centre - 0.001) + at(centre + 0.001)));
        self.drop2.push(max - 0.5 * (at(centre - 0.002) + at(centre + 0.002)));
        self.ftruth.push(max - at(0.0));
        self.fmax.push(max);
    }
    fn report(&self, name: &str) {
        let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
        let sd = |v: &[f32]| {
            let m = mean(v);
            (v.iter().map(|x| (x - m) * (x - m)).sum::<f32>() / v.len() as f32).sqrt()
        };
        let rms = |v: &[f32]| (v.iter().map(|x| x * x).sum::<f32>() / v.len() as f32).sqrt();
        println!(
            "{name:>14}: plateau centre mean {:+.3} mm (sd {:.3}, rms {:.3}), width {:.2} mm, F drop at ±1 mm {:.4}, ±2 mm {:.4}, Fmax − F(truth) {:.4}, Fmax {:.4}",
            mean(&self.centre),
            sd(&self.centre),
            rms(&self.centre),
            mean(&self.width),
            mean(&self.drop1),
            mean(&self.drop2),
            mean(&self.ftruth),
            mean(&self.fmax)
        );
    }
}

fn exact_frame(rig: &StereoRig, s: &Scenario, truth: &Psi, l: &mut [u8], r: &mut [u8]) -> anyhow::Result<()> {
    let block = evorec_sim::sim::board::block(s);
    let iso = truth.try_to_isometry().map_err(|e| anyhow::anyhow!("{e:?}"))?;
    l.fill(NO_HUE);
    r.fill(NO_HUE);
    render_block(&block, &rig.right, &iso, r).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    render_block(&block, &rig.left, &(rig.left_from_right * iso), l).map_err(|e| anyhow::anyhow!("{e:?}"))?;
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        anyhow::bail!("usage: depth_profile SCENARIO [OMEGA] [FRAMES] [STEP_S]");
    };
    let mut s = Scenario::load(path)?;
    if let Some(w) = args.get(2).and_then(|v| v.parse().ok()) {
        s.robot.omega_rad_s = w;
    }
    let frames: usize = args.get(3).and_then(|v| v.parse().ok()).unwrap_or(40);
    let step_s: f64 = args.get(4).and_then(|v| v.parse().ok()).unwrap_or(0.9);
    let mut world = World::new(&s)?;
    let tracker = SimTracker::new(tracker_config(&s)?).map_err(|e| anyhow::anyhow!("{e}"))?;
    let rig = *world.rig();
    let (w, h) = (s.camera.width, s.camera.height);
    let n = usize::from(w) * usize::from(h);
    let (mut l, mut r) = (vec![0u8; 2 * n], vec![0u8; 2 * n]);
    let (mut el, mut er) = (vec![0u8; n], vec![0u8; n]);
    let names = ["depth", "x", "y"];
    let mut sim: [Acc; 3] = Default::default();
    let mut exact: [Acc; 3] = Default::default();
    for i in 0..frames {
        world.advance_to(i as f64 * step_s);
        let frame = frames::rgb565_frame(&mut world, &mut l, &mut r, w, h)?;
        let truth = world.truth();
        exact_frame(&rig, &s, &truth, &mut el, &mut er)?;
        let eframe =
            StereoFrame { left: HueImage::new_checked(&el[..], w, h)?, right: HueImage::new_checked(&er[..], w, h)? };
        let moved = |axis: usize, d: f32| {
            if axis == 0 {
                truth.scaled_along_ray(1.0 + d / truth.0[2])
            } else {
                let mut q = truth;
                q.0[axis - 1] += d;
                q
            }
        };
        for axis in 0..3 {
            sim[axis].add(&scan(|d| tracker.fitness_of(&moved(axis, d), &frame).map(|f| f.total).unwrap_or(0.0)));
            exact[axis].add(&scan(|d| tracker.fitness_of(&moved(axis, d), &eframe).map(|f| f.total).unwrap_or(0.0)));
        }
    }
    println!("{} frames of {path} at omega {} rad/s, every {step_s} s", frames, s.robot.omega_rad_s);
    for axis in 0..3 {
        sim[axis].report(&format!("sim {}", names[axis]));
    }
    for axis in 0..3 {
        exact[axis].report(&format!("exact {}", names[axis]));
    }
    Ok(())
}
