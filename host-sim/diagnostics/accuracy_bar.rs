//! What a pose a given distance from the truth scores in each camera, over random views that no
//! test scene uses: the evidence behind `status.confirm_fitness` (docs/tuning.md).
//!
//! For the static views of acquisition trials FIRST..FIRST+N (the block placed at random in the
//! field of view; `evorec acquire` uses trials 1–100), frame 0 as the tracker sees it (flat light,
//! the configured colour model): the lower of the two cameras' fitness of the true pose, and of
//! poses moved from it by each of the distances below (a translation along a random direction, or
//! a turn about a random axis; DIRS draws of each per view). It prints, per distance, quantiles
//! over all draws of the lower camera's fitness, and the share of draws at or above each of a few
//! bars.
//!
//! `cargo run --release -p evorec-sim --example accuracy_bar -- [FIRST] [N] [DIRS]` (defaults 1001 200 32)
mod frames;

use evorec_core::pose::Psi;
use evorec_sim::experiments::acquire::{Case, scenario};
use evorec_sim::experiments::experiment::{SimTracker, tracker_config};
use evorec_sim::sim::board::World;
use nalgebra::{Unit, UnitQuaternion, Vector3};
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// A move away from the truth: millimetres of translation or degrees of turn.
#[derive(Clone, Copy)]
enum Move {
    Shift(f32),
    Turn(f32),
}

const MOVES: [Move; 6] =
    [Move::Shift(2.5), Move::Shift(5.0), Move::Shift(10.0), Move::Turn(1.25), Move::Turn(2.5), Move::Turn(5.0)];
const BARS: [f32; 6] = [0.8, 0.85, 0.88, 0.9, 0.92, 0.95];

fn unit(rng: &mut Xoshiro256PlusPlus) -> Unit<Vector3<f32>> {
    loop {
        let mut c = || (rng.next_u32() as f32 / u32::MAX as f32) * 2.0 - 1.0;
        let v = Vector3::new(c(), c(), c());
        let n = v.norm();
        if n > 0.1 && n <= 1.0 {
            return Unit::new_normalize(v);
        }
    }
}

fn moved(truth: &Psi, m: Move, dir: &Unit<Vector3<f32>>) -> Psi {
    let q = truth.quaternion_unchecked();
    match m {
        Move::Shift(mm) => Psi::from_parts(&(truth.translation() + dir.as_ref() * (mm * 1e-3)), &q),
        Move::Turn(deg) => {
            Psi::from_parts(&truth.translation(), &(UnitQuaternion::from_axis_angle(dir, deg.to_radians()) * q))
        }
    }
}

fn quantile(sorted: &[f32], p: f64) -> f32 {
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted.get(i).copied().unwrap_or(f32::NAN)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<u64> = std::env::args().skip(1).map(|a| a.parse()).collect::<Result<_, _>>()?;
    let first = args.first().copied().unwrap_or(1001);
    let n = args.get(1).copied().unwrap_or(200);
    let dirs = args.get(2).copied().unwrap_or(32);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(first);
    let mut truth_f = Vec::new();
    let mut by_move: Vec<Vec<f32>> = vec![Vec::new(); MOVES.len()];
    let mut worst: Vec<Vec<f32>> = vec![Vec::new(); MOVES.len()];
    for trial in first..first + n {
        let s = scenario(trial, Case::Static, false);
        let mut world = World::new(&s)?;
        let tracker = SimTracker::new(tracker_config(&s)?).map_err(|e| anyhow::anyhow!("{e}"))?;
        let (w, h) = (s.camera.width, s.camera.height);
        let px = 2 * usize::from(w) * usize::from(h);
        let (mut l, mut r) = (vec![0u8; px], vec![0u8; px]);
        world.advance_to(0.0);
        let frame = frames::rgb565_frame(&mut world, &mut l, &mut r, w, h)?;
        let truth = world.truth();
        // The scale the status confirms a pose against.
        let scale = tracker.colours().confirming_fitness();
        let lower = |psi: &Psi| -> anyhow::Result<f32> {
            let f = tracker.fitness_of(psi, &frame).map_err(|e| anyhow::anyhow!("{e}"))?;
            Ok(f.left.score().min(f.right.score()) / scale)
        };
        truth_f.push(lower(&truth)?);
        for (k, m) in MOVES.iter().enumerate() {
            let mut top = 0.0f32;
            for _ in 0..dirs {
                let d = unit(&mut rng);
                let f = lower(&moved(&truth, *m, &d))?;
                top = top.max(f);
                by_move[k].push(f);
            }
            worst[k].push(top);
        }
    }
    let report = |name: String, v: &mut Vec<f32>| {
        v.sort_by(f32::total_cmp);
        let share: Vec<String> = BARS
            .iter()
            .map(|b| format!("≥{b}: {:5.1} %", 100.0 * v.iter().filter(|x| **x >= *b).count() as f64 / v.len() as f64))
            .collect();
        println!(
            "{name:>14}  q10 {:.3} q50 {:.3} q90 {:.3}  {}",
            quantile(v, 0.1),
            quantile(v, 0.5),
            quantile(v, 0.9),
            share.join("  ")
        );
        println!("{:>14}  q99.5 {:.4}", "", quantile(v, 0.995));
    };
    println!(
        "views {first}..{} (static, flat light), {dirs} draws per move; lower camera's F / expected",
        first + n - 1
    );
    report("truth".to_owned(), &mut truth_f);
    for (m, v) in MOVES.iter().zip(by_move.iter_mut()) {
        let name = match m {
            Move::Shift(mm) => format!("shift {mm} mm"),
            Move::Turn(deg) => format!("turn {deg}°"),
        };
        report(name, v);
    }
    println!("the best of the {dirs} draws per view:");
    for (m, v) in MOVES.iter().zip(worst.iter_mut()) {
        let name = match m {
            Move::Shift(mm) => format!("shift {mm} mm"),
            Move::Turn(deg) => format!("turn {deg}°"),
        };
        report(name, v);
    }
    Ok(())
}
