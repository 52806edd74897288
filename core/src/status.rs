//! The tracker's status: does it have the block?
//!
//! The paper starts every run at the known pose. A real rig does not know it, so the tracker
//! says with every estimate whether it is **searching** (no pose found since the start),
//! **tracking** (the elite fits the images), or has **lost** the block (it was tracking, and the
//! elite no longer fits: occlusion, the block left the view, a burst of bad frames).
//!
//! The decision uses only the elite's fitness `F` of the current generation, the fitness of
//! its worse camera, and their short history (two counters), with hysteresis:
//!
//! ```text
//!              F ≥ acquire_fitness for confirm_generations in a row
//!   Searching ───────────────────────────────────────────────────▶ Tracking
//!       ▲                                                       │   ▲
//!       │ lost_generations_to_search in Lost                    │   │ F ≥ acquire_fitness for
//!       │                                                       ▼   │ confirm_generations
//!       └──────────────────────────────────────────────────── Lost ─┘
//!                  F < lose_fitness for lose_generations in a row (from Tracking)
//! ```
//!
//! `F` is the fraction of the model's inner points that see their face's hue, minus the
//! contour points that see a face hue (eq. 34–35). Without the block in the images no pose
//! scores above 0, so with the default `lose_generations = 1` the very first frame without
//! the block is reported as lost. The default thresholds are far apart (0.75 and 0.4): a
//! tracked block scores 0.9–1.0, a pose a few millimetres off still above 0.75, and a frame
//! with the block gone scores 0.
//!
//! **Both cameras.** `F` is the mean of the two cameras' scores. A stereo pair whose images do
//! not show the same instant (a constant offset of frames between left and right, a frame
//! dropped on one side) has no pose that fits both while the scene moves: the GA fits one
//! camera, or neither, at a wrong depth, and `F` stays between the thresholds. So a generation
//! counts toward acquisition only when the elite's worse camera scores at least
//! [`CAMERA_ACQUIRE_FITNESS`], and as bad when it scores below [`CAMERA_LOSE_FITNESS`]. A tracked
//! block in step scores 0.86–1.0 in its worse camera (the public sample sequences); 15 frames
//! out of step, below 0.85 in 94–96 % of the frames (`docs/method.md`, "Acquisition and
//! status").
//!
//! Bounded work: the update is a few comparisons per generation.

// `!(x > y)` on purpose: true for NaN too, so a NaN never passes a check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

/// What the tracker knows about the block.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Status {
    /// No pose found yet (after a start without an initial pose or a uniform reset).
    #[default]
    Searching,
    /// The elite fits the images: the estimate is the block's pose.
    Tracking,
    /// The block was tracked and no longer fits: the estimate is the last pose carried along
    /// by the feedforward, not a measurement.
    Lost,
}

impl Status {
    /// All statuses, in code order.
    pub const ALL: [Status; 3] = [Status::Searching, Status::Tracking, Status::Lost];

    /// Lower-case name (`"searching"`, `"tracking"`, `"lost"`), as written in traces.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Searching => "searching",
            Self::Tracking => "tracking",
            Self::Lost => "lost",
        }
    }

    /// One-byte code for packets and traces: 0 searching, 1 tracking, 2 lost.
    pub fn code(self) -> u8 {
        match self {
            Self::Searching => 0,
            Self::Tracking => 1,
            Self::Lost => 2,
        }
    }

    /// The status of a [`Status::code`], `None` for an unknown byte.
    pub fn from_code(code: u8) -> Option<Self> {
        Self::ALL.get(usize::from(code)).copied()
    }
}

impl core::fmt::Display for Status {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The elite's worse camera's fitness (relative, as the thresholds of [`StatusConfig`]) at or
/// above which a generation counts toward acquisition.
pub const CAMERA_ACQUIRE_FITNESS: f32 = 0.9;

/// The elite's worse camera's fitness below which a generation counts as bad, as one below
/// [`StatusConfig::lose_fitness`] does.
pub const CAMERA_LOSE_FITNESS: f32 = 0.75;

/// The smallest ratio of the elite's worse camera's fitness to its better camera's at which
/// the tracker learns the face colours from it ([`crate::colour`]). Both cameras see the
/// block under the same light, so a pose in step scores alike in both (a ratio of 0.98 or more
/// once the block is found, in the public sample sequences); a pose fitted to images out of
/// step does not, and learning from it would lower the expected fitness, the scale of the
/// status thresholds, until the wrong pose passed them.
pub const CAMERA_LEARN_RATIO: f32 = 0.95;

/// Thresholds of the status decision; [`StatusConfig::DEFAULT`] documents the defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StatusConfig {
    /// Elite fitness at or above which a pose counts as found.
    pub acquire_fitness: f32,
    /// Status decisions (one per frame) in a row at or above `acquire_fitness` before
    /// reporting `Tracking`.
    pub confirm_generations: u16,
    /// Elite fitness below which a tracked block counts as gone.
    pub lose_fitness: f32,
    /// Status decisions (one per frame) in a row below `lose_fitness` before reporting `Lost`.
    pub lose_generations: u16,
    /// Status decisions (frames) in `Lost` after which the status falls back to `Searching` (the last pose
    /// is then no better than any other).
    pub lost_generations_to_search: u16,
}

impl StatusConfig {
    /// Defaults: found at `F ≥ 0.75` for 3 generations, lost at the first generation with
    /// `F < 0.4`, back to searching after 150 generations (5 s at 30 frames/s) lost.
    pub const DEFAULT: StatusConfig = StatusConfig {
        acquire_fitness: 0.75,
        confirm_generations: 3,
        lose_fitness: 0.4,
        lose_generations: 1,
        lost_generations_to_search: 150,
    };
}

impl Default for StatusConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The status and the counters it is decided from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StatusMonitor {
    status: Status,
    /// Generations in a row at or above `acquire_fitness`.
    good: u16,
    /// Generations in a row below `lose_fitness`.
    bad: u16,
    /// Generations since the status became `Lost`.
    lost_for: u16,
}

impl StatusMonitor {
    /// A monitor in `status` with cleared counters.
    pub fn new(status: Status) -> Self {
        Self { status, good: 0, bad: 0, lost_for: 0 }
    }

    /// The current status.
    pub fn status(&self) -> Status {
        self.status
    }

    /// Feeds the elite's fitness of one generation and the fitness of its worse camera (the
    /// smaller of `F_L`, `F_R`, on the scale of `fitness`) and returns the new status.
    pub fn update(&mut self, fitness: f32, worse_camera: f32, config: &StatusConfig) -> Status {
        // NaN counts as bad (it is neither ≥ nor < a threshold otherwise).
        let good = fitness >= config.acquire_fitness && worse_camera >= CAMERA_ACQUIRE_FITNESS;
        let bad = !(fitness >= config.lose_fitness) || !(worse_camera >= CAMERA_LOSE_FITNESS);
        self.good = if good { self.good.saturating_add(1) } else { 0 };
        self.bad = if bad { self.bad.saturating_add(1) } else { 0 };
        self.status = match self.status {
            Status::Tracking if self.bad >= config.lose_generations => {
                self.lost_for = 0;
                Status::Lost
            }
            Status::Tracking => Status::Tracking,
            Status::Searching | Status::Lost if self.good >= config.confirm_generations => Status::Tracking,
            Status::Lost => {
                self.lost_for = self.lost_for.saturating_add(1);
                if self.lost_for >= config.lost_generations_to_search { Status::Searching } else { Status::Lost }
            }
            Status::Searching => Status::Searching,
        };
        self.status
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    #[test]
    fn acquire_needs_confirmation_and_loss_is_immediate() {
        let c = StatusConfig::DEFAULT;
        let mut m = StatusMonitor::new(Status::Searching);
        assert_eq!(m.update(0.9, 1.0, &c), Status::Searching);
        assert_eq!(m.update(0.9, 1.0, &c), Status::Searching);
        assert_eq!(m.update(0.9, 1.0, &c), Status::Tracking);
        // Between the thresholds: keeps tracking.
        assert_eq!(m.update(0.5, 1.0, &c), Status::Tracking);
        assert_eq!(m.update(0.0, 1.0, &c), Status::Lost);
        assert_eq!(m.update(f32::NAN, 1.0, &c), Status::Lost);
        // A single good frame does not re-acquire; three do.
        assert_eq!(m.update(0.9, 1.0, &c), Status::Lost);
        assert_eq!(m.update(0.6, 1.0, &c), Status::Lost);
        for _ in 0..2 {
            assert_eq!(m.update(0.8, 1.0, &c), Status::Lost);
        }
        assert_eq!(m.update(0.8, 1.0, &c), Status::Tracking);
    }

    #[test]
    fn both_cameras_must_fit() {
        let c = StatusConfig::DEFAULT;
        let mut m = StatusMonitor::new(Status::Searching);
        // One camera fitted, the other not: F = 0.8 never acquires.
        for _ in 0..10 {
            assert_eq!(m.update(0.8, 0.6, &c), Status::Searching);
        }
        for _ in 0..2 {
            assert_eq!(m.update(0.95, 0.9, &c), Status::Searching);
        }
        assert_eq!(m.update(0.95, 0.9, &c), Status::Tracking);
        assert_eq!(m.update(0.9, 0.8, &c), Status::Tracking);
        assert_eq!(m.update(0.8, 0.7, &c), Status::Lost);
        assert_eq!(m.update(0.9, f32::NAN, &c), Status::Lost);
    }

    #[test]
    fn long_loss_falls_back_to_searching() {
        let c = StatusConfig { lost_generations_to_search: 4, ..StatusConfig::DEFAULT };
        let mut m = StatusMonitor::new(Status::Tracking);
        assert_eq!(m.update(0.1, 1.0, &c), Status::Lost);
        for _ in 0..3 {
            assert_eq!(m.update(0.1, 1.0, &c), Status::Lost);
        }
        assert_eq!(m.update(0.1, 1.0, &c), Status::Searching);
        assert_eq!(m.update(0.1, 1.0, &c), Status::Searching);
    }

    #[test]
    fn codes_round_trip_and_config_is_checked() {
        for s in Status::ALL {
            assert_eq!(Status::from_code(s.code()), Some(s));
        }
        assert_eq!(Status::from_code(3), None);
        assert_eq!(Status::Lost.to_string(), "lost");
    }
}
