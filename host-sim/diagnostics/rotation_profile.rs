//! Where the fitness's optimum lies around the ground truth of a recorded sequence: is a bias
//! of the tracker's orientation (or position) already in `F` itself, or does it come from the
//! search?
//!
//! For every K-th frame of an `evorec-seq/1` sequence with `groundtruth.tum`, the true pose
//! `^CR T_M` is
//! - turned about the right camera's x, y and z axes by ±0.8° in 0.02° steps, the turn composed
//!   on the left as the GA's mutation does (`ga::turn`), so an offset here is the rotation error
//!   `estimate ∘ truth⁻¹` of `evorec track`'s trace, as a rotation vector in the right camera
//!   frame;
//! - moved along the right camera's x and y axes and along its viewing ray (depth) by ±2 mm in
//!   0.05 mm steps;
//! - turned about the axis of the truth's own turn from this frame to the next (`+` = ahead).
//!
//! Per frame and axis the set of offsets where `F` is at its maximum (the plateau) is found;
//! over the frames it reports the mean plateau centre (the fitness's own bias along that axis),
//! its sd and median, the plateau width, `Fmax − F(truth)` and `Fmax`, for `F` and for each
//! camera's score alone (`F_R`, `F_L`). A 6-D check: a walk from the truth accepting every
//! random step (±0.02° / ±0.02 mm per coordinate) that does not lower `F`, and the mean offset
//! of its poses at the highest `F` it reached. With `--trace` (an `evorec track` trace.csv),
//! `F` at the tracker's estimates against `F` at the truth on the same frames: an estimate
//! biased by the search scores below the truth, one biased by the fitness above it.
//!
//! The fitness is the tracker's (`Evaluator` on the PNGs as 8-bit RGB, as `evorec track`), with
//! optionally another hue tolerance (`--tol`) or both principal points shifted by `--shift` px
//! (a pixel-centre convention test).
//!
//! `cargo run --release -p evorec-sim --example rotation_profile -- SEQ_DIR [EVERY_K] [--trace TRACE_CSV] [--tol HUE_TOL] [--shift CXY_PX]`
use std::path::Path;

use anyhow::{Context, Result, anyhow, bail};
use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::fitness::{Evaluator, Fitness};
use evorec_core::hue::HueLut;
use evorec_core::image::{Image, Rgb888};
use evorec_core::limits::{DEFAULT_GRID, DEFAULT_HUE_TOLERANCE};
use evorec_core::model::{FACES, SurfaceStrips};
use evorec_core::pose::Psi;
use evorec_sim::recording::sequence::Sequence;
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro128PlusPlus;

const ROT_HALF: i32 = 40;
const ROT_STEP_DEG: f32 = 0.02;
const TR_HALF: i32 = 40;
const TR_STEP_MM: f32 = 0.05;
const WALK_STEPS: usize = 4000;
const WALK_STEP: f32 = 0.02;

/// The three scores of one pose: `F`, `F_R`, `F_L`.
fn scores(f: &Fitness) -> [f32; 3] {
    [f.total, f.right.score(), f.left.score()]
}

/// Plateau statistics of one axis and score over the frames.
#[derive(Default)]
struct Acc {
    centre: Vec<f32>,
    width: Vec<f32>,
    below: Vec<f32>,
    fmax: Vec<f32>,
}

impl Acc {
    fn add(&mut self, offsets: &[f32], f: &[f32]) {
        let max = f.iter().copied().fold(f32::MIN, f32::max);
        let at_max = offsets.iter().zip(f).filter(|p| *p.1 >= max - 1e-6).map(|p| *p.0);
        let (lo, hi) = at_max.fold((f32::MAX, f32::MIN), |(lo, hi), d| (lo.min(d), hi.max(d)));
        let truth = offsets.iter().position(|d| d.abs() < 1e-6).and_then(|i| f.get(i)).copied().unwrap_or(0.0);
        self.centre.push(0.5 * (lo + hi));
        self.width.push(hi - lo);
        self.below.push(max - truth);
        self.fmax.push(max);
    }

    fn report(&self, name: &str, unit: &str) {
        let (centre, sd) = mean_sd(&self.centre);
        println!(
            "  {name:<10} centre {centre:+.3} {unit} (sd {sd:.3}, median {:+.3}), width {:.3} {unit}, Fmax−F(truth) {:.4}, Fmax {:.4}",
            median(&self.centre),
            mean_sd(&self.width).0,
            mean_sd(&self.below).0,
            mean_sd(&self.fmax).0
        );
    }
}

fn mean_sd(v: &[f32]) -> (f32, f32) {
    let n = v.len().max(1) as f32;
    let m = v.iter().sum::<f32>() / n;
    (m, (v.iter().map(|x| (x - m) * (x - m)).sum::<f32>() / n).sqrt())
}

fn median(v: &[f32]) -> f32 {
    let mut s = v.to_vec();
    s.sort_by(f32::total_cmp);
    if s.is_empty() { 0.0 } else { 0.5 * (s[(s.len() - 1) / 2] + s[s.len() / 2]) }
}

/// `truth` turned by `deg` about the right camera's axis `a` (composed on the left).
fn turned(truth: &Isometry3<f32>, a: usize, deg: f32) -> Psi {
    let axis = Vector3::ith_axis(a);
    let q = UnitQuaternion::from_axis_angle(&axis, deg.to_radians()) * truth.rotation;
    Psi::from_parts(&truth.translation.vector, &q)
}

/// `truth` moved by `mm` along the right camera's x or y axis (`a` = 0, 1) or along its
/// viewing ray (`a` = 2, `t_z` changing by `mm`).
fn shifted(truth: &Isometry3<f32>, a: usize, mm: f32) -> Psi {
    let p = Psi::from_isometry(truth);
    let d = mm * 1e-3;
    if a == 2 {
        p.scaled_along_ray(1.0 + d / p.0[2])
    } else {
        let mut q = p;
        q.0[a] += d;
        q
    }
}

/// The rig with both principal points shifted by `shift` pixels.
fn shifted_rig(rig: &StereoRig, shift: f32) -> Result<StereoRig> {
    let move_cam = |c: &Pinhole| {
        Pinhole::new_checked(c.fx(), c.fy(), c.cx() + shift, c.cy() + shift, c.width(), c.height())
            .map(|p| p.with_distortion(*c.distortion()))
            .map_err(|e| anyhow!("shifted camera: {e}"))
    };
    Ok(StereoRig { right: move_cam(&rig.right)?, left: move_cam(&rig.left)?, left_from_right: rig.left_from_right })
}

/// A tracker's estimates from `evorec track`'s `trace.csv` while it was tracking: (t, ψ).
fn read_trace(path: &str) -> Result<Vec<(f64, Psi)>> {
    let mut rd = csv::Reader::from_path(path).with_context(|| format!("cannot read the trace {path}"))?;
    let head = rd.headers()?.clone();
    let cols = ["t", "est_x_mm", "est_y_mm", "est_z_mm", "est_e1", "est_e2", "est_e3"]
        .map(|c| head.iter().position(|h| h == c).ok_or_else(|| anyhow!("{path}: no column {c}")));
    let status = head.iter().position(|h| h == "status").ok_or_else(|| anyhow!("{path}: no column status"))?;
    let cols: Vec<usize> = cols.into_iter().collect::<Result<_>>()?;
    let mut out = Vec::new();
    for (line, rec) in rd.records().enumerate() {
        let rec = rec?;
        if rec.get(status) != Some("tracking") {
            continue;
        }
        let v: Vec<f64> = cols
            .iter()
            .map(|&c| rec.get(c).unwrap_or("").parse::<f64>())
            .collect::<Result<_, _>>()
            .with_context(|| format!("{path}: line {}: not a number", line + 2))?;
        out.push((v[0], Psi::new([v[1], v[2], v[3]].map(|x| (x * 1e-3) as f32), [v[4], v[5], v[6]].map(|x| x as f32))));
    }
    Ok(out)
}

/// `F` at the tracker's estimates against `F` at the truth.
#[derive(Default)]
struct Check {
    truth: Vec<f32>,
    est: Vec<f32>,
    est_rot: Vec<f32>,
    err: Vec<[f32; 3]>,
}

impl Check {
    fn add<B: AsRef<[u8]>>(
        &mut self,
        eval: &Evaluator<'_, DEFAULT_GRID>,
        l: &Image<B, Rgb888>,
        r: &Image<B, Rgb888>,
        t: &Isometry3<f32>,
        trace: &[(f64, Psi)],
        t_s: f64,
    ) {
        let Some((_, est)) = trace.iter().find(|e| (e.0 - t_s).abs() < 1e-4) else { return };
        let f = |p: &Psi| eval.evaluate_psi(p, l, r).total;
        let q = est.quaternion_unchecked();
        self.truth.push(f(&Psi::from_isometry(t)));
        self.est.push(f(est));
        self.est_rot.push(f(&Psi::from_parts(&t.translation.vector, &q)));
        let e = (q * t.rotation.inverse()).scaled_axis().map(f32::to_degrees);
        self.err.push([e.x, e.y, e.z]);
    }

    fn report(&self) {
        let n = self.truth.len();
        let d: Vec<f32> = self.est.iter().zip(&self.truth).map(|(e, t)| e - t).collect();
        let above = d.iter().filter(|v| **v > 1e-6).count();
        let below = d.iter().filter(|v| **v < -1e-6).count();
        let e = |k: usize| mean_sd(&self.err.iter().map(|v| v[k]).collect::<Vec<_>>()).0;
        println!(
            "trace, {n} frames: rotation error ({:+.3}, {:+.3}, {:+.3})°; F(truth) {:.4}, F(estimate) {:.4} (above the truth's on {above}, below on {below}), F(truth's position, estimate's orientation) {:.4}",
            e(0),
            e(1),
            e(2),
            mean_sd(&self.truth).0,
            mean_sd(&self.est).0,
            mean_sd(&self.est_rot).0
        );
    }
}

/// The command line: the sequence, every k-th frame, the trace to check, the hue tolerance and
/// the principal points' shift.
struct Args {
    dir: String,
    every: usize,
    trace_path: Option<String>,
    tol: u8,
    shift: f32,
}

fn parse_args() -> Result<Args> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: rotation_profile SEQ_DIR [EVERY_K] [--trace TRACE_CSV] [--tol HUE_TOL] [--shift CXY_PX]";
    let (mut pos, mut trace_path, mut tol, mut shift) = (Vec::new(), None, DEFAULT_HUE_TOLERANCE, 0.0f32);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or_else(|| anyhow!("{a} needs a value; {usage}"));
        match a.as_str() {
            "--trace" => trace_path = Some(value()?.clone()),
            "--tol" => tol = value()?.parse().with_context(|| format!("--tol: not a hue tolerance; {usage}"))?,
            "--shift" => shift = value()?.parse().with_context(|| format!("--shift: not a number; {usage}"))?,
            _ => pos.push(a.clone()),
        }
    }
    let Some(dir) = pos.first() else { bail!(usage) };
    let every = match pos.get(1) {
        Some(v) => v.parse::<usize>().with_context(|| format!("EVERY_K \"{v}\" is not a count; {usage}"))?.max(1),
        None => 5,
    };
    Ok(Args { dir: dir.clone(), every, trace_path, tol, shift })
}

/// The 6-D plateau: a walk from the truth that accepts any step not lowering F; the mean offset
/// (turn in degrees, shift in millimetres) of its poses at the highest F it reaches.
fn plateau_walk(f: &impl Fn(&Psi) -> [f32; 3], t: &Isometry3<f32>, uniform: &mut impl FnMut() -> f32) -> [f32; 6] {
    let pose_at = |o: &[f32; 6]| {
        let q = UnitQuaternion::from_scaled_axis(Vector3::new(o[0], o[1], o[2]).map(f32::to_radians)) * t.rotation;
        Psi::from_parts(&(t.translation.vector + Vector3::new(o[3], o[4], o[5]) * 1e-3), &q)
    };
    let (mut at, mut f_at) = ([0.0f32; 6], f(&pose_at(&[0.0; 6]))[0]);
    let (mut sum, mut count) = ([0.0f32; 6], 0usize);
    for _ in 0..WALK_STEPS {
        let o: [f32; 6] = std::array::from_fn(|k| at[k] + uniform() * WALK_STEP);
        let fo = f(&pose_at(&o))[0];
        if fo > f_at + 1e-6 {
            (sum, count) = ([0.0; 6], 0);
        }
        if fo >= f_at - 1e-6 {
            (at, f_at) = (o, f_at.max(fo));
        }
        sum.iter_mut().zip(at).for_each(|(s, v)| *s += v);
        count += 1;
    }
    sum.map(|s| s / count as f32)
}

/// F along the truth's own turn from frame `i` to the next, added to `along`; the turn in
/// degrees per frame, or `None` where the truth does not turn.
fn along_motion(
    f: &impl Fn(&Psi) -> [f32; 3],
    t: &Isometry3<f32>,
    truth: &[Isometry3<f64>],
    i: usize,
    rot: &[f32],
    along: &mut [Acc; 3],
) -> Option<f32> {
    let next = if i + 1 < truth.len() { truth[i + 1] } else { truth[i] };
    let motion = (next.rotation * truth[i].rotation.inverse()).cast::<f32>().scaled_axis();
    if motion.norm() <= 1e-7 {
        return None;
    }
    let axis = motion.normalize();
    let s: Vec<[f32; 3]> = rot
        .iter()
        .map(|d| {
            let q = UnitQuaternion::from_scaled_axis(axis * d.to_radians()) * t.rotation;
            f(&Psi::from_parts(&t.translation.vector, &q))
        })
        .collect();
    for (c, acc) in along.iter_mut().enumerate() {
        acc.add(rot, &s.iter().map(|v| v[c]).collect::<Vec<_>>());
    }
    Some(motion.norm().to_degrees())
}

/// F, F_R and F_L along each axis of turn and shift about the truth, added to `acc`.
fn profile_axes(f: &impl Fn(&Psi) -> [f32; 3], t: &Isometry3<f32>, rot: &[f32], tr: &[f32], acc: &mut [[Acc; 3]; 6]) {
    for (a, accs) in acc.iter_mut().enumerate() {
        let (offsets, pose): (&[f32], Box<dyn Fn(f32) -> Psi>) =
            if a < 3 { (rot, Box::new(|d| turned(t, a, d))) } else { (tr, Box::new(|d| shifted(t, a - 3, d))) };
        let s: Vec<[f32; 3]> = offsets.iter().map(|&d| f(&pose(d))).collect();
        for (c, acc) in accs.iter_mut().enumerate() {
            acc.add(offsets, &s.iter().map(|v| v[c]).collect::<Vec<_>>());
        }
    }
}

fn main() -> Result<()> {
    let Args { dir, every, trace_path, tol, shift } = parse_args()?;
    let dir = dir.as_str();
    let seq = Sequence::load(Path::new(dir)).with_context(|| format!("loading the sequence {dir}"))?;
    let Some(truth) = seq.groundtruth.clone() else {
        bail!("{dir}: no groundtruth.tum: the profile needs the true poses");
    };
    let rig = shifted_rig(&seq.rig, shift)?;
    let model = SurfaceStrips::<DEFAULT_GRID>::new(&seq.block).map_err(|e| anyhow!("target block: {e:?}"))?;
    let hues: [u8; FACES] = model.faces().map(|f| f.hue);
    let lut = HueLut::new(&hues, tol);
    let eval = Evaluator::new(&model, &lut, &rig);
    let (w, h) = (rig.right.width(), rig.right.height());

    let rot: Vec<f32> = (-ROT_HALF..=ROT_HALF).map(|k| k as f32 * ROT_STEP_DEG).collect();
    let tr: Vec<f32> = (-TR_HALF..=TR_HALF).map(|k| k as f32 * TR_STEP_MM).collect();
    // [rotation x, y, z, translation x, y, depth][F, F_R, F_L]
    let mut acc: [[Acc; 3]; 6] = Default::default();
    let mut joint: Vec<[f32; 6]> = Vec::new();
    let mut rng = Xoshiro128PlusPlus::seed_from_u64(1);
    let mut uniform = move || (rng.next_u32() as f32 / u32::MAX as f32) * 2.0 - 1.0;
    let mut along: [Acc; 3] = Default::default();
    let mut speed = Vec::new();
    let trace = trace_path.as_deref().map(read_trace).transpose()?;
    let mut check = Check::default();
    let mut n = 0;
    for i in (0..seq.frames.len()).step_by(every) {
        let (l, r) = seq.decode(i).with_context(|| format!("frame {i}"))?;
        let left = Image::<&[u8], Rgb888>::new_checked(l.as_raw().as_slice(), w, h)?;
        let right = Image::<&[u8], Rgb888>::new_checked(r.as_raw().as_slice(), w, h)?;
        let f = |p: &Psi| scores(&eval.evaluate_psi(p, &left, &right));
        let t: Isometry3<f32> = truth[i].cast();
        profile_axes(&f, &t, &rot, &tr, &mut acc);
        joint.push(plateau_walk(&f, &t, &mut uniform));
        if let Some(tr) = &trace {
            check.add(&eval, &left, &right, &t, tr, seq.frames[i].t_s);
        }
        if let Some(deg) = along_motion(&f, &t, &truth, i, &rot, &mut along) {
            speed.push(deg);
        }
        n += 1;
    }
    println!(
        "{}: {n} frames (every {every}), hue tolerance {tol}, principal points shifted by {shift:+} px",
        seq.name()
    );
    let names = ["rot x", "rot y", "rot z", "x", "y", "depth"];
    for (a, accs) in acc.iter().enumerate() {
        let unit = if a < 3 { "deg" } else { "mm" };
        println!("{}:", names[a]);
        for (c, acc) in accs.iter().enumerate() {
            acc.report(["F", "F_R", "F_L"][c], unit);
        }
    }
    let col = |k: usize| joint.iter().map(|j| j[k]).collect::<Vec<f32>>();
    let ms: Vec<(f32, f32)> = (0..6).map(|k| mean_sd(&col(k))).collect();
    if !speed.is_empty() {
        println!("rot along the truth's motion ({:.4} deg/frame, + = ahead):", mean_sd(&speed).0);
        for (c, acc) in along.iter().enumerate() {
            acc.report(["F", "F_R", "F_L"][c], "deg");
        }
    }
    println!(
        "6-D plateau walk ({WALK_STEPS} steps): mean turn ({:+.3}, {:+.3}, {:+.3})° (sd {:.3}, {:.3}, {:.3}), shift ({:+.3}, {:+.3}, {:+.3}) mm (sd {:.3}, {:.3}, {:.3})",
        ms[0].0, ms[1].0, ms[2].0, ms[0].1, ms[1].1, ms[2].1, ms[3].0, ms[4].0, ms[5].0, ms[3].1, ms[4].1, ms[5].1
    );
    if trace.is_some() {
        check.report();
    }
    Ok(())
}
