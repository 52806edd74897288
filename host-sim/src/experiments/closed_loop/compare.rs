//! Two closed-loop runs of one scenario side by side, frame by frame: `evorec hil` on a
//! `[servo]` scenario (the firmware's estimates) against the host's run of the same loop.

use serde::Serialize;

use super::{ClosedLoopOutput, ServoRow, norm};
use crate::sim::board::TraceRow;

/// How two closed-loop runs of one scenario compare, frame by frame (`evorec hil` on a
/// `[servo]` scenario against the host's run). Frames are paired by capture time; a frame
/// only one run has (refused, or lost on the link) is a difference.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Comparison {
    /// Frames with an estimate in each run.
    pub frames: [usize; 2],
    /// Paired frames whose estimate `ψ`, fitness and status are bit-identical.
    pub identical_estimates: usize,
    /// Paired frames whose joint state `q, q̇` at capture and servo command are bit-identical
    /// (the arm moved the same way).
    pub identical_trajectory: usize,
    /// Capture time of the first frame that differs in either respect (s).
    pub first_difference_s: Option<f64>,
    /// Largest difference of the estimates' translations over the paired frames (m).
    pub max_estimate_diff_m: f64,
    /// Largest difference of a joint angle over the paired frames (rad).
    pub max_joint_diff_rad: f64,
}

impl Comparison {
    /// Whether the runs are bit-identical: as many frames, every estimate and the whole
    /// trajectory.
    pub fn identical(&self) -> bool {
        let [a, b] = self.frames;
        a == b && self.identical_estimates == a && self.identical_trajectory == a
    }

    /// One line for the terminal.
    pub fn describe(&self) -> String {
        let [a, b] = self.frames;
        let verdict = if self.identical() { "bit-identical" } else { "DIFFERENT" };
        let first = self.first_difference_s.map_or(String::new(), |t| format!(", first difference at t = {t:.3} s"));
        format!(
            "firmware against host closed loop: {verdict} ({a} / {b} frames; estimates identical in {}, arm trajectory \
             and command in {}{first}; largest estimate difference {:.3} mm, joint difference {:.2e} rad)",
            self.identical_estimates,
            self.identical_trajectory,
            self.max_estimate_diff_m * 1e3,
            self.max_joint_diff_rad
        )
    }
}

/// Compares run `a` with run `b` (see [`Comparison`]).
pub fn compare(a: &ClosedLoopOutput, b: &ClosedLoopOutput) -> Comparison {
    let mut c = Comparison {
        frames: [a.run.rows.len(), b.run.rows.len()],
        identical_estimates: 0,
        identical_trajectory: 0,
        first_difference_s: None,
        max_estimate_diff_m: 0.0,
        max_joint_diff_rad: 0.0,
    };
    let (mut i, mut j) = (0, 0);
    while let (Some(ra), Some(rb)) = (a.run.rows.get(i), b.run.rows.get(j)) {
        if ra.t < rb.t || rb.t < ra.t {
            // A frame one run has and the other has not (refused or lost on the link).
            c.first_difference_s.get_or_insert(ra.t.min(rb.t));
            if ra.t < rb.t {
                i += 1
            } else {
                j += 1
            }
            continue;
        }
        let (estimate, trajectory) = c.pair((ra, a.servo.get(i)), (rb, b.servo.get(j)));
        if !(estimate && trajectory) {
            c.first_difference_s.get_or_insert(ra.t);
        }
        (i, j) = (i + 1, j + 1);
    }
    // Frames after the end of the other run.
    if let Some(r) = a.run.rows.get(i).or_else(|| b.run.rows.get(j)) {
        c.first_difference_s.get_or_insert(r.t);
    }
    c
}

impl Comparison {
    /// Counts a pair of frames with the same capture time (trace row and servo row of each
    /// run); returns whether the estimates and whether the trajectories are bit-identical.
    fn pair(
        &mut self,
        (ra, sa): (&TraceRow, Option<&ServoRow>),
        (rb, sb): (&TraceRow, Option<&ServoRow>),
    ) -> (bool, bool) {
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let command =
            |s: Option<&ServoRow>| s.map(|s| bits(&[s.command.v.as_slice(), s.command.w.as_slice()].concat()));
        let estimate = bits(&ra.estimate.0) == bits(&rb.estimate.0)
            && ra.fitness.to_bits() == rb.fitness.to_bits()
            && ra.status == rb.status;
        let trajectory = bits(&ra.q) == bits(&rb.q) && bits(&ra.qd) == bits(&rb.qd) && command(sa) == command(sb);
        self.identical_estimates += usize::from(estimate);
        self.identical_trajectory += usize::from(trajectory);
        let de = norm(&(ra.estimate.translation() - rb.estimate.translation()));
        self.max_estimate_diff_m = self.max_estimate_diff_m.max(de);
        let dq = ra.q.iter().zip(&rb.q).map(|(x, y)| f64::from((x - y).abs())).fold(0.0, f64::max);
        self.max_joint_diff_rad = self.max_joint_diff_rad.max(dq);
        (estimate, trajectory)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::closed_loop::tests::scenario;
    use crate::experiments::closed_loop::{LoopOptions, run};

    #[test]
    fn compare_finds_the_first_changed_estimate() {
        let s = scenario(1.0);
        let a = run(&s, &LoopOptions::for_scenario(&s), || {}).unwrap_or_else(|e| unreachable!("{e}"));
        let n = a.run.rows.len();
        assert!(compare(&a, &a).identical());
        let mut b = a.clone();
        b.run.rows[10].estimate.0[2] = f32::from_bits(b.run.rows[10].estimate.0[2].to_bits() ^ 1);
        b.servo[20].command.v.x += 1e-3;
        let c = compare(&a, &b);
        assert!(!c.identical());
        assert_eq!((c.identical_estimates, c.identical_trajectory), (n - 1, n - 1));
        assert_eq!(c.first_difference_s, Some(a.run.rows[10].t));
        b.run.rows.pop();
        assert_eq!(compare(&a, &b).frames, [n, n - 1]);
        // A frame missing in the middle: the others still pair by capture time.
        let mut d = a.clone();
        d.run.rows.remove(5);
        d.servo.remove(5);
        let c = compare(&a, &d);
        assert_eq!((c.identical_estimates, c.identical_trajectory), (n - 1, n - 1));
        assert_eq!(c.first_difference_s, Some(a.run.rows[5].t));
        assert!(!c.identical());
    }
}
