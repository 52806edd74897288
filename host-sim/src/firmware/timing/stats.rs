//! Statistics of the measured generations.

use evorec_core::status::Status;
use evorec_firmware::timing::{CaseKind, GenLine, ticks_to_instructions};
use serde_json::{Value, json};

use super::qemu::Run;

/// Min, max and mean of a series.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Mean.
    pub mean: f64,
}

impl Range {
    /// The range of `values`.
    pub(super) fn of(values: impl IntoIterator<Item = f64>) -> Self {
        let (mut min, mut max, mut sum, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0u32);
        for v in values {
            min = min.min(v);
            max = max.max(v);
            sum += v;
            n += 1;
        }
        Self { min, max, mean: if n == 0 { 0.0 } else { sum / f64::from(n) } }
    }

    /// `max / min`.
    pub fn ratio(&self) -> f64 {
        self.max / self.min
    }

    /// `{min, max, mean}`, rounded.
    pub(super) fn json(&self) -> Value {
        json!({ "min": self.min.round(), "max": self.max.round(), "mean": self.mean.round() })
    }
}

/// Instruction counts of one run.
#[derive(Debug, Clone)]
pub struct RunStats {
    /// Population size in use.
    pub population: u32,
    /// Population capacity of the tracker type (its worst case is that many individuals).
    pub capacity: u32,
    /// Points per row.
    pub grid: u32,
    /// Sample points per individual in the model (both cameras, 2 · 60 · G).
    pub points_per_individual: u32,
    /// Sample points the kernel walks per individual (both cameras, 2 · 48 · G).
    pub walked_per_individual: u32,
    /// Generations measured.
    pub generations: usize,
    /// The whole `step_probed` call.
    pub call: Range,
    /// Feedforward phase.
    pub feedforward: Range,
    /// Projection + fitness.
    pub evaluate: Range,
    /// Selection, crossover, mutation.
    pub breed: Range,
    /// Evaluate phase / (population · model points per individual): the convention of the
    /// per-point target (≤ 25 including the per-pose overhead).
    pub per_point: Range,
    /// Evaluate phase / (population · walked points per individual).
    pub per_walked_point: Range,
    /// Largest painted stack high-water mark of a generation (bytes from the top of RAM).
    pub stack: u32,
    /// Whole call per kind of frame.
    pub by_kind: Vec<(CaseKind, usize, Range)>,
    /// Whole call per status the generations started in.
    pub by_status: Vec<(Status, usize, Range)>,
    /// Generations that shifted the individuals by a non-zero target velocity too (`tshift=1`:
    /// the `ff+target` path with `Tracker::target_feedforward_velocity` not zero, i.e. the
    /// target motion model has observed a velocity).
    pub target_shifts: usize,
    /// Whole call of those generations (`None` if there were none).
    pub target_shift_call: Option<Range>,
}

impl Run {
    /// The run's statistics in instructions.
    pub fn stats(&self) -> RunStats {
        let g = &self.generations;
        let ins = |f: fn(&GenLine) -> u32| Range::of(g.iter().map(|x| ticks_to_instructions(u64::from(f(x)))));
        let points = 2 * self.points_per_camera;
        let walked = 2 * self.walked_per_camera;
        let per = |n: u32, r: &Range| {
            let evals = f64::from(self.population) * f64::from(n);
            Range { min: r.min / evals, max: r.max / evals, mean: r.mean / evals }
        };
        let by_kind = CaseKind::ALL
            .into_iter()
            .filter_map(|k| {
                let v: Vec<f64> =
                    g.iter().filter(|x| x.kind == k).map(|x| ticks_to_instructions(u64::from(x.call))).collect();
                (!v.is_empty()).then(|| (k, v.len(), Range::of(v)))
            })
            .collect();
        let by_status = Status::ALL
            .into_iter()
            .filter_map(|st| {
                let v: Vec<f64> =
                    g.iter().filter(|x| x.status == st).map(|x| ticks_to_instructions(u64::from(x.call))).collect();
                (!v.is_empty()).then(|| (st, v.len(), Range::of(v)))
            })
            .collect();
        let evaluate = ins(|x| x.phases.evaluate);
        RunStats {
            population: self.population,
            capacity: self.capacity,
            grid: self.grid,
            points_per_individual: points,
            walked_per_individual: walked,
            generations: g.len(),
            call: ins(|x| x.call),
            feedforward: ins(|x| x.phases.feedforward),
            evaluate,
            breed: ins(|x| x.phases.breed),
            per_point: per(points, &evaluate),
            per_walked_point: per(walked, &evaluate),
            stack: g.iter().map(|x| x.stack).max().unwrap_or(0),
            by_kind,
            by_status,
            target_shifts: g.iter().filter(|x| x.target_shift).count(),
            target_shift_call: g.iter().any(|x| x.target_shift).then(|| {
                Range::of(g.iter().filter(|x| x.target_shift).map(|x| ticks_to_instructions(u64::from(x.call))))
            }),
        }
    }
}
