//! `evorec acquire`: Monte-Carlo statistics of acquisition and recovery.
//!
//! Each trial `i` (seed `base + i`) places the block at a random pose
//! ([`crate::sim::board::random_target_pose`]: centre uniform in the search space, rotation
//! uniform, entirely inside both images for the whole run; the block itself does not move)
//! and runs two cases, the arm static and motion A at ω = 0.5 rad/s with feedforward:
//!
//! - **acquisition**: the tracker starts without a pose (`[start] initial = "unknown"`),
//!   [`ACQUIRE_DURATION_S`] long;
//! - **recovery**: the tracker starts at the true pose and the block is hidden from
//!   [`OCCLUSION_START_S`] for [`OCCLUSION_S`] (an occluder in front of both cameras in even
//!   trials, the block removed in odd ones), [`RECOVERY_DURATION_S`] long.
//!
//! A pose counts as **acquired** at frame `n` when the estimate is within
//! [`ACQUIRED_MM`] and [`ACQUIRED_DEG`] of the truth in every frame `n .. n + ACQUIRED_FRAMES`.
//! The orientation error is taken modulo the block's colour symmetry: opposite faces have
//! one hue, so the half turns about the block's axes look identical, and the error is the
//! smallest over `{I, Rx(π), Ry(π), Rz(π)}`. Recovery time counts from the first frame in
//! which the block is visible again. Frames in which the block is hidden count towards the
//! "tracking while hidden" fraction when the tracker reports `tracking`.

use evorec_core::tuning::Tuning;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Mutex;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use nalgebra::{Quaternion, UnitQuaternion};
use plotters::prelude::*;
use rayon::prelude::*;
use serde::Serialize;

use crate::experiments::experiment;
use crate::sim::board::TraceRow;
use crate::sim::motion::MotionKind;
use crate::sim::occlusion::{Initial, Occlusion, OcclusionKind, Occlusions, Placement};
use crate::sim::render::Light;
use crate::sim::scenario::Scenario;
use evorec_core::pose::Psi;
use evorec_core::status::Status;
use evorec_core::tuning::Feedforward;

/// Position error (mm) within which a pose counts as found: the sequence tracker's
/// [`WITHIN_POSITION_M`](crate::experiments::truth::WITHIN_POSITION_M).
pub const ACQUIRED_MM: f64 = crate::experiments::truth::WITHIN_POSITION_M * 1e3;
/// Orientation error (degrees, modulo the colour symmetry) within which a pose counts as found:
/// [`WITHIN_ROTATION_DEG`](crate::experiments::truth::WITHIN_ROTATION_DEG).
pub const ACQUIRED_DEG: f64 = crate::experiments::truth::WITHIN_ROTATION_DEG;
/// Consecutive frames within both errors that make a pose acquired.
pub const ACQUIRED_FRAMES: usize = 30;
/// Frames within which an unknown start should be acquired (target ≥ 95 %).
pub const ACQUIRE_TARGET_FRAMES: usize = 60;
/// Frames after reappearance within which a hidden block should be found again (≥ 95 %).
pub const RECOVER_TARGET_FRAMES: usize = 30;
/// Length of an acquisition run (s): 122 frames, so acquisition up to frame 92 is seen.
pub const ACQUIRE_DURATION_S: f64 = 4.0;
/// When the block is hidden in a recovery run (s).
pub const OCCLUSION_START_S: f64 = 1.0;
/// How long it is hidden (s).
pub const OCCLUSION_S: f64 = 1.0;
/// Length of a recovery run (s).
pub const RECOVERY_DURATION_S: f64 = 4.0;
/// Points per sample row of the tracker the statistics use by default: the core's default
/// (`DEFAULT_GRID`, the firmware's configuration); 5 and 8 are supported.
pub const DEFAULT_POINTS: usize = evorec_core::limits::DEFAULT_GRID;

/// Motion A's ω in the moving case (rad/s).
pub const MOTION_OMEGA: f64 = 0.5;

/// The two arm motions of the statistics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Case {
    /// The arm holds still.
    #[serde(rename = "static")]
    Static,
    /// Motion A at [`MOTION_OMEGA`] with feedforward.
    #[serde(rename = "motion_a")]
    MotionA,
}

impl Case {
    /// Both cases.
    pub const ALL: [Case; 2] = [Case::Static, Case::MotionA];

    /// A readable name.
    pub fn label(self) -> &'static str {
        match self {
            Self::Static => "static arm",
            Self::MotionA => "motion A, ω = 0.5 rad/s, FF",
        }
    }
}

/// The scenario of trial `seed` in `case`; `recovery` selects the occlusion run.
pub fn scenario(seed: u64, case: Case, recovery: bool) -> Scenario {
    let duration = if recovery { RECOVERY_DURATION_S } else { ACQUIRE_DURATION_S };
    let mut s = Scenario::new(seed, duration, Feedforward::On);
    s.target.placement = Placement::Random;
    s.target.omega_rad_s = 0.0;
    match case {
        Case::Static => s.robot.motion = MotionKind::Static,
        Case::MotionA => {
            s.robot.motion = MotionKind::A;
            s.robot.omega_rad_s = MOTION_OMEGA;
        }
    }
    if recovery {
        let kind = if seed.is_multiple_of(2) { OcclusionKind::Occluder } else { OcclusionKind::Removed };
        s.occlusion =
            Occlusions::from_slice(&[Occlusion { start_s: OCCLUSION_START_S, duration_s: OCCLUSION_S, kind }]);
    } else {
        s.start.initial = Initial::Unknown;
    }
    s
}

/// Position error (mm) and orientation error (degrees, modulo the colour symmetry).
pub fn pose_error(estimate: &Psi, truth: &Psi) -> (f64, f64) {
    let d: f64 = (0..3).map(|i| (f64::from(estimate.0[i]) - f64::from(truth.0[i])).powi(2)).sum();
    let q = |p: &Psi| {
        let e = [f64::from(p.0[3]), f64::from(p.0[4]), f64::from(p.0[5])];
        let w = (1.0 - e.iter().map(|x| x * x).sum::<f64>()).max(0.0).sqrt();
        UnitQuaternion::from_quaternion(Quaternion::new(w, e[0], e[1], e[2]))
    };
    let (qe, qt) = (q(estimate), q(truth));
    let turns = [
        Quaternion::new(1.0, 0.0, 0.0, 0.0),
        Quaternion::new(0.0, 1.0, 0.0, 0.0),
        Quaternion::new(0.0, 0.0, 1.0, 0.0),
        Quaternion::new(0.0, 0.0, 0.0, 1.0),
    ];
    let angle =
        turns.iter().map(|h| (qe * UnitQuaternion::new_unchecked(*h)).angle_to(&qt)).fold(f64::INFINITY, f64::min);
    (d.sqrt() * 1e3, angle.to_degrees())
}

/// The first frame at or after `from` from which the estimate stays within the errors for
/// [`ACQUIRED_FRAMES`] frames, counted from `from`; `None` if the run ends first.
pub fn frames_to_acquire(rows: &[TraceRow], from: usize) -> Option<usize> {
    let ok: Vec<bool> = rows
        .iter()
        .map(|r| {
            let (mm, deg) = pose_error(&r.estimate, &r.truth);
            mm <= ACQUIRED_MM && deg <= ACQUIRED_DEG
        })
        .collect();
    let mut run = 0usize;
    for (i, good) in ok.iter().enumerate().skip(from) {
        run = if *good { run + 1 } else { 0 };
        if run == ACQUIRED_FRAMES {
            return Some(i + 1 - ACQUIRED_FRAMES - from);
        }
    }
    None
}

/// One trial of one case.
#[derive(Debug, Clone, Serialize)]
pub struct Trial {
    /// Seed.
    pub seed: u64,
    /// Case.
    pub case: Case,
    /// True pose at `t = 0`.
    pub truth0: [f32; 6],
    /// Frames until acquired from an unknown start (`None`: not within the run).
    pub acquire_frames: Option<usize>,
    /// First frame reported as tracking from the unknown start.
    pub first_tracking_frame: Option<usize>,
    /// Frames from the reappearance until acquired again (`None`: not within the run).
    pub recover_frames: Option<usize>,
    /// Hidden frames in the recovery run.
    pub hidden_frames: usize,
    /// Hidden frames reported as tracking.
    pub tracking_while_hidden: usize,
    /// Visible frames of both runs reported as tracking whose estimate was outside the
    /// acquisition errors.
    pub tracking_but_wrong: usize,
    /// Visible frames of both runs reported as tracking.
    pub tracking_frames: usize,
}

fn wrong_tracking(rows: &[TraceRow]) -> (usize, usize) {
    let tracking: Vec<&TraceRow> = rows.iter().filter(|r| !r.hidden && r.status == Status::Tracking).collect();
    let wrong = tracking
        .iter()
        .filter(|r| {
            let (mm, deg) = pose_error(&r.estimate, &r.truth);
            mm > ACQUIRED_MM || deg > ACQUIRED_DEG
        })
        .count();
    (wrong, tracking.len())
}

/// Runs both runs of one trial, rendered under `light`.
///
/// # Errors
/// A run's error.
pub fn run_trial(
    seed: u64,
    case: Case,
    points: usize,
    tuning: &Tuning,
    light: &Light,
    on_frame: &(impl Fn() + Sync),
) -> Result<Trial> {
    let go = |mut s: Scenario| {
        s.tracker.0 = *tuning;
        s.render = *light;
        crate::with_rows!("--points", points, G => experiment::run_with_rows::<G>(&s, on_frame))
    };
    let a = go(scenario(seed, case, false))?;
    let b = go(scenario(seed, case, true))?;
    let reappear = b.rows.iter().rposition(|r| r.hidden).map_or(b.rows.len(), |i| i + 1);
    let (w1, t1) = wrong_tracking(&a.rows);
    let (w2, t2) = wrong_tracking(&b.rows);
    Ok(Trial {
        seed,
        case,
        truth0: a.rows.first().map_or([0.0; 6], |r| r.truth.0),
        acquire_frames: frames_to_acquire(&a.rows, 0),
        first_tracking_frame: a.rows.iter().position(|r| r.status == Status::Tracking),
        recover_frames: frames_to_acquire(&b.rows, reappear),
        hidden_frames: b.summary.status.hidden,
        tracking_while_hidden: b.summary.status.tracking_while_hidden,
        tracking_but_wrong: w1 + w2,
        tracking_frames: t1 + t2,
    })
}

/// The statistics of one case.
#[derive(Debug, Clone, Serialize)]
pub struct CaseStats {
    /// Case.
    pub case: Case,
    /// Trials.
    pub trials: usize,
    /// Fraction acquired within [`ACQUIRE_TARGET_FRAMES`].
    pub acquired_within_60: f64,
    /// Median frames to acquire (unacquired trials count as infinite; `None` if more than
    /// half were not acquired).
    pub median_acquire_frames: Option<usize>,
    /// 90th percentile of frames to acquire (as the median).
    pub p90_acquire_frames: Option<usize>,
    /// Fraction of trials never acquired within the run.
    pub never_acquired: f64,
    /// Fraction re-acquired within [`RECOVER_TARGET_FRAMES`] of reappearance.
    pub recovered_within_30: f64,
    /// Median frames to re-acquire.
    pub median_recover_frames: Option<usize>,
    /// Hidden frames reported as tracking / hidden frames.
    pub tracking_while_hidden: f64,
    /// Visible tracking frames whose estimate is outside the acquisition errors / visible
    /// tracking frames.
    pub tracking_but_wrong: f64,
}

fn quantile(values: &[Option<usize>], q: f64) -> Option<usize> {
    let mut v: Vec<usize> = values.iter().map(|x| x.unwrap_or(usize::MAX)).collect();
    v.sort_unstable();
    let i = ((v.len() as f64 * q).ceil() as usize).saturating_sub(1);
    v.get(i).copied().filter(|x| *x != usize::MAX)
}

fn ratio(a: usize, b: usize) -> f64 {
    if b == 0 { 0.0 } else { a as f64 / b as f64 }
}

/// Statistics of the trials of `case`.
pub fn stats(trials: &[Trial], case: Case) -> CaseStats {
    let t: Vec<&Trial> = trials.iter().filter(|t| t.case == case).collect();
    let n = t.len();
    let acq: Vec<Option<usize>> = t.iter().map(|t| t.acquire_frames).collect();
    let rec: Vec<Option<usize>> = t.iter().map(|t| t.recover_frames).collect();
    let within = |v: &[Option<usize>], k: usize| v.iter().filter(|x| x.is_some_and(|f| f <= k)).count();
    let sum = |f: fn(&Trial) -> usize| t.iter().map(|x| f(x)).sum::<usize>();
    CaseStats {
        case,
        trials: n,
        acquired_within_60: ratio(within(&acq, ACQUIRE_TARGET_FRAMES), n),
        median_acquire_frames: quantile(&acq, 0.5),
        p90_acquire_frames: quantile(&acq, 0.9),
        never_acquired: ratio(acq.iter().filter(|x| x.is_none()).count(), n),
        recovered_within_30: ratio(within(&rec, RECOVER_TARGET_FRAMES), n),
        median_recover_frames: quantile(&rec, 0.5),
        tracking_while_hidden: ratio(sum(|x| x.tracking_while_hidden), sum(|x| x.hidden_frames)),
        tracking_but_wrong: ratio(sum(|x| x.tracking_but_wrong), sum(|x| x.tracking_frames)),
    }
}

/// `acquire.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Per case.
    pub cases: Vec<CaseStats>,
    /// Every trial.
    pub trials: Vec<Trial>,
    /// First seed.
    pub first_seed: u64,
    /// Points per sample row of the tracker.
    pub points_per_row: usize,
    /// The light every run was rendered under (`[render]`; written only when not the default).
    #[serde(skip_serializing_if = "Light::is_default")]
    pub light: Light,
    /// Simulator version.
    pub evorec_version: &'static str,
}

/// Runs `trials` trials from seed `first_seed` in parallel with a progress bar, with a
/// tracker of `points` points per sample row (one of [`crate::output::rows::SUPPORTED`]) tuned as
/// `tuning`, rendered under `light`, and writes `acquire.json`, `acquire.md`, `acquire_cdf.png` and `config.toml` (the
/// tuning) into `out`.
///
/// # Errors
/// Any run's or file's error; `points` not in [`crate::output::rows::SUPPORTED`].
pub fn run(
    trials: usize,
    first_seed: u64,
    points: usize,
    tuning: &Tuning,
    light: &Light,
    out: &Path,
    show_progress: bool,
) -> Result<Report> {
    crate::output::rows::check("--points", points)?;
    tuning.validate(crate::sim::scenario::HOST_POPULATION_CAPACITY)?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let jobs: Vec<(u64, Case)> = (0..trials as u64).flat_map(|i| Case::ALL.map(|c| (first_seed + i, c))).collect();
    let frames: u64 = jobs
        .iter()
        .map(|(s, c)| {
            u64::from(
                crate::sim::board::frame_total(&scenario(*s, *c, false))
                    + crate::sim::board::frame_total(&scenario(*s, *c, true)),
            )
        })
        .sum();
    let bar = if show_progress { crate::output::logging::progress_bar(frames) } else { ProgressBar::hidden() };
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {percent:>3}% {pos}/{len} frames, eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let done = Mutex::new(Vec::new());
    jobs.par_iter().try_for_each(|(seed, case)| -> Result<()> {
        let t = run_trial(*seed, *case, points, tuning, light, &|| bar.inc(1))?;
        done.lock().map_err(|_| anyhow::anyhow!("poisoned"))?.push(t);
        Ok(())
    })?;
    bar.finish();
    let mut all = done.into_inner().map_err(|_| anyhow::anyhow!("poisoned"))?;
    all.sort_by_key(|t| (t.seed, t.case == Case::MotionA));
    let report = Report {
        cases: Case::ALL.iter().map(|c| stats(&all, *c)).collect(),
        trials: all,
        first_seed,
        points_per_row: points,
        light: *light,
        evorec_version: env!("CARGO_PKG_VERSION"),
    };
    crate::output::io::write_json(&out.join("acquire.json"), &report)?;
    crate::output::io::write_tracker_config(out, tuning)?;
    crate::output::io::write_bytes(&out.join("acquire.md"), markdown(&report).as_bytes())?;
    plot_cdf(&report, &out.join("acquire_cdf.png"))?;
    Ok(report)
}

fn frames(x: Option<usize>) -> String {
    x.map_or_else(|| "> run".to_owned(), |f| f.to_string())
}

/// The summary table.
pub fn markdown(r: &Report) -> String {
    let mut s = String::new();
    let n = r.cases.first().map_or(0, |c| c.trials);
    let _ = writeln!(
        s,
        "# Acquisition and recovery, {n} trials per case (seeds {}..), population 40, {} points per row\n",
        r.first_seed, r.points_per_row
    );
    let _ = writeln!(
        s,
        "Acquired = within {ACQUIRED_MM} mm and {ACQUIRED_DEG}° (modulo the colour symmetry) for {ACQUIRED_FRAMES} frames in a row.\n"
    );
    let _ = writeln!(
        s,
        "| case | acquired ≤ {ACQUIRE_TARGET_FRAMES} frames (≥ 95 %) | median frames (≤ 20) | p90 frames | never | re-acquired ≤ {RECOVER_TARGET_FRAMES} frames after 1 s occlusion (≥ 95 %) | median frames | tracking while hidden (≤ 1 %) | tracking but wrong |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for c in &r.cases {
        let _ = writeln!(
            s,
            "| {} | {:.1} % | {} | {} | {:.1} % | {:.1} % | {} | {:.2} % | {:.2} % |",
            c.case.label(),
            100.0 * c.acquired_within_60,
            frames(c.median_acquire_frames),
            frames(c.p90_acquire_frames),
            100.0 * c.never_acquired,
            100.0 * c.recovered_within_30,
            frames(c.median_recover_frames),
            100.0 * c.tracking_while_hidden,
            100.0 * c.tracking_but_wrong,
        );
    }
    s
}

/// The CDF of frames to acquire (unknown start) and to re-acquire (after the occlusion).
///
/// # Errors
/// Drawing or writing the PNG.
pub fn plot_cdf(r: &Report, path: &Path) -> Result<()> {
    crate::output::plot::ensure_font()?;
    let max_x = 92.0;
    crate::output::plot::render_png(path, (1000, 500), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption("Frames until acquired (CDF over random block poses)", (crate::output::plot::FONT, 22))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..max_x, 0.0..1.0)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("frames")
            .y_desc("fraction of trials")
            .label_style((crate::output::plot::FONT, 15))
            .axis_desc_style((crate::output::plot::FONT, 17))
            .draw()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let colours = [RGBColor(31, 119, 180), RGBColor(214, 39, 40), RGBColor(44, 160, 44), RGBColor(148, 103, 189)];
        let mut k = 0;
        for case in Case::ALL {
            for (what, pick) in [("unknown start", 0), ("after 1 s occlusion", 1)] {
                let t: Vec<&Trial> = r.trials.iter().filter(|t| t.case == case).collect();
                let mut v: Vec<f64> = t
                    .iter()
                    .filter_map(|t| if pick == 0 { t.acquire_frames } else { t.recover_frames })
                    .map(|f| f as f64)
                    .collect();
                v.sort_by(f64::total_cmp);
                let n = t.len().max(1) as f64;
                let mut pts = vec![(0.0, 0.0)];
                for (i, x) in v.iter().enumerate() {
                    pts.push((*x, i as f64 / n));
                    pts.push((*x, (i + 1) as f64 / n));
                }
                pts.push((max_x, v.len() as f64 / n));
                let colour = colours[k % colours.len()];
                k += 1;
                chart
                    .draw_series(LineSeries::new(pts, colour.stroke_width(2)))
                    .map_err(|e| anyhow::anyhow!("{e}"))?
                    .label(format!("{}, {what}", case.label()))
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
            }
        }
        for x in [RECOVER_TARGET_FRAMES as f64, ACQUIRE_TARGET_FRAMES as f64] {
            chart
                .draw_series(LineSeries::new([(x, 0.0), (x, 1.0)], RGBColor(150, 150, 150).stroke_width(1)))
                .map_err(|e| anyhow::anyhow!("{e}"))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .label_font((crate::output::plot::FONT, 15))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orientation_error_is_modulo_the_half_turns() {
        let truth = Psi::new([0.0, 0.0, 0.7], [0.1, 0.2, 0.05]);
        let qt =
            UnitQuaternion::from_quaternion(Quaternion::new((1.0f64 - 0.01 - 0.04 - 0.0025).sqrt(), 0.1, 0.2, 0.05));
        for axis in [nalgebra::Vector3::x_axis(), nalgebra::Vector3::y_axis(), nalgebra::Vector3::z_axis()] {
            let turned = qt * UnitQuaternion::from_axis_angle(&axis, std::f64::consts::PI);
            let c = if turned.w < 0.0 { -turned.into_inner() } else { turned.into_inner() };
            let est = Psi::new([0.001, 0.0, 0.7], [c.i as f32, c.j as f32, c.k as f32]);
            let (mm, deg) = pose_error(&est, &truth);
            assert!((mm - 1.0).abs() < 1e-3 && deg < 0.05, "{mm} {deg}");
        }
        // A quarter turn is not a symmetry.
        let q = qt * UnitQuaternion::from_axis_angle(&nalgebra::Vector3::z_axis(), std::f64::consts::FRAC_PI_2);
        let est = Psi::new([0.0, 0.0, 0.7], [q.i as f32, q.j as f32, q.k as f32]);
        let (_, deg) = pose_error(&est, &truth);
        assert!((deg - 90.0).abs() < 0.1, "{deg}");
    }

    #[test]
    fn quantiles_treat_failures_as_infinite() {
        assert_eq!(quantile(&[Some(3), Some(1), None, Some(2)], 0.5), Some(2));
        assert_eq!(quantile(&[Some(3), None, None], 0.5), None);
    }
}
