//! The tracker's status: does it have the block, and can a robot act on the pose?
//!
//! The paper starts every run at the known pose. A real rig does not know it, so the tracker
//! says with every estimate whether it is **searching** (no pose found since the start),
//! **tracking** (the elite fits both images well enough to be within the stated accuracy),
//! **uncertain** (it follows the block, but the pose is not confirmed to that accuracy), or has
//! **lost** the block (it was following it, and the elite no longer fits: occlusion, the block
//! left the view, a burst of bad frames).
//!
//! Two decisions are made once per frame, each with hysteresis, on the elite's fitness of the
//! frame's last generation relative to what the colour model expects the true pose to score
//! under the current light ([`crate::colour::ColourModel::expected_fitness`], 1 on a flat
//! image):
//!
//! 1. **Held or not**, on the mean of the two cameras' relative fitness `F` and its short history
//!    (two counters). It decides the tracker's work: a held block is followed (the learnt hue
//!    table, elite copies, the target filter fed), one that is not is searched for.
//!    While searching or lost, the tracker counts a frame whose elite lies away from the
//!    acquisition's colour-blob seed as one below every threshold (see `Tracker::step`), so
//!    such a candidate is never confirmed:
//!
//! ```text
//!              F ≥ acquire_fitness for confirm_frames in a row
//!   Searching ───────────────────────────────────────────────────▶ held
//!       ▲                                                       │   ▲
//!       │ lost_frames_to_search in Lost                         │   │ F ≥ acquire_fitness for
//!       │                                                       ▼   │ confirm_frames
//!       └──────────────────────────────────────────────────── Lost ─┘
//!        F < lose_fitness for lose_frames in a row, or F < acquire_fitness for
//!        DOUBT_FRAMES in a row (from held)
//! ```
//!
//! 2. **Confirmed or not**, while held: the pose is reported [`Status::Tracking`] once the lower
//!    of the two cameras' fitness `F_min`, relative to the confirmation's own scale
//!    ([`crate::colour::ColourModel::confirming_fitness`], which poses a little off lower only
//!    slowly), has been at or above `certain_fitness` for `confirm_frames` in a row, and
//!    [`Status::Uncertain`] from the first frame below. Both
//!    cameras must fit on their own: a lock one camera sees well and the other does not (most
//!    often a wrong depth) is not confirmed. Nor is a pose whose view leaves its orientation
//!    open: the tracker counts a frame in which either camera sees fewer than
//!    [`CONFIRM_FULL_FACES`](crate::limits::CONFIRM_FULL_FACES) faces of the pose at full weight
//!    as one below the bar (a block seen face-on can tilt by 6–12° at almost no cost in score).
//!
//! `F` is the fraction of the model's inner points that see their face's hue, minus the
//! contour points that see a face hue (eq. 34–35). Without the block in the images no pose
//! scores above 0, so with the default `lose_frames = 1` the very first frame without
//! the block is reported as lost. The held thresholds are far apart (0.75 and 0.4): a held
//! block scores 0.75–1.0, and a frame with the block gone scores 0. A lock on a wrong pose
//! scores between them (most often 0.6–0.8), so a held block that stays below
//! `acquire_fitness` for [`DOUBT_FRAMES`] frames is no longer held and reported lost.
//!
//! The sharper bar `certain_fitness` (0.9) is what a pose a stated accuracy away from the truth
//! (10 mm or 5°) does not reach: over 400 random static views that no test scene uses, such a
//! pose in a random direction scores `F_min` ≥ 0.8917 in 0.5 % of the draws (`accuracy_bar` in
//! `host-sim/diagnostics`; docs/tuning.md). The bar is that quantile rounded up. The block is held on a
//! pose a few millimetres off while it manoeuvres (such poses score 0.75–0.9), which keeps the
//! target filter and the feedforward with it; only the report waits for the fit.
//!
//! Bounded work: the update is a few comparisons per frame.

// `!(x > y)` on purpose: true for NaN too, so a NaN never passes a check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

/// What the tracker knows about the block.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Status {
    /// No pose found yet (after a start without an initial pose or a uniform reset).
    #[default]
    Searching,
    /// The elite fits both images: the estimate is the block's pose, within the stated
    /// accuracy. The only status to act on.
    Tracking,
    /// The block was held and no longer fits: the estimate is the last pose carried along
    /// by the feedforward, not a measurement.
    Lost,
    /// The tracker follows the block (the estimate is a measurement, and it feeds the target
    /// filter), but the pose does not fit both cameras well enough to be within the stated
    /// accuracy: not to be acted on.
    Uncertain,
}

impl Status {
    /// All statuses, in code order.
    pub const ALL: [Status; 4] = [Status::Searching, Status::Tracking, Status::Lost, Status::Uncertain];

    /// Lower-case name (`"searching"`, `"tracking"`, `"lost"`, `"uncertain"`), as written in
    /// traces.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Searching => "searching",
            Self::Tracking => "tracking",
            Self::Lost => "lost",
            Self::Uncertain => "uncertain",
        }
    }

    /// One-byte code for packets and traces: 0 searching, 1 tracking, 2 lost, 3 uncertain.
    pub fn code(self) -> u8 {
        match self {
            Self::Searching => 0,
            Self::Tracking => 1,
            Self::Lost => 2,
            Self::Uncertain => 3,
        }
    }

    /// Whether the tracker holds the block ([`Status::Tracking`] or [`Status::Uncertain`]): it
    /// follows it rather than searching, and the estimate is a measurement of it.
    pub fn holds(self) -> bool {
        matches!(self, Self::Tracking | Self::Uncertain)
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

/// Status decisions (frames) in a row below [`StatusConfig::acquire_fitness`] after which a
/// held block counts as lost even though it stays above [`StatusConfig::lose_fitness`]: a
/// third of a second at 30 frames/s. A pose that no longer meets the acquisition's own bar for
/// that long is no longer held: a lock on a wrong pose (most often at a wrong depth, where
/// part of the model still sees the block's colours) scores between the two thresholds for as
/// long as it lasts, while the right pose falls below the acquisition's bar only for a few
/// frames at a time (a sudden start or stop, a pose the GA has not caught up with yet).
pub const DOUBT_FRAMES: u16 = 10;

/// Thresholds of the status decision; [`StatusConfig::DEFAULT`] documents the defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StatusConfig {
    /// Elite fitness at or above which a pose counts as found.
    pub acquire_fitness: f32,
    /// Status decisions (one per frame) in a row at or above `acquire_fitness` before the
    /// block is held, and at or above `certain_fitness` before a held block is reported
    /// `Tracking`.
    pub confirm_frames: u16,
    /// The lower camera's fitness at or above which a held pose is within the stated accuracy
    /// (the module's docs say how it was chosen).
    pub certain_fitness: f32,
    /// Elite fitness below which a tracked block counts as gone.
    pub lose_fitness: f32,
    /// Status decisions (one per frame) in a row below `lose_fitness` before reporting `Lost`.
    pub lose_frames: u16,
    /// Status decisions (frames) in `Lost` after which the status falls back to `Searching` (the last pose
    /// is then no better than any other).
    pub lost_frames_to_search: u16,
}

impl StatusConfig {
    /// Defaults: held at `F ≥ 0.75` for 3 frames, reported tracking at `F_min ≥ 0.9` for 3
    /// frames, lost at the first frame with `F < 0.4`, back to searching after 150 frames
    /// (5 s at 30 frames/s) lost.
    pub const DEFAULT: StatusConfig = StatusConfig {
        acquire_fitness: 0.75,
        confirm_frames: 3,
        certain_fitness: 0.9,
        lose_fitness: 0.4,
        lose_frames: 1,
        lost_frames_to_search: 150,
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
    /// Frames in a row at or above `acquire_fitness`.
    good: u16,
    /// Frames in a row below `lose_fitness`.
    bad: u16,
    /// Frames in a row below `acquire_fitness`.
    doubt: u16,
    /// Frames in a row whose lower camera was at or above `certain_fitness`.
    sure: u16,
    /// Frames since the status became `Lost`.
    lost_for: u16,
    /// Frames in a row held (`Tracking` or `Uncertain`) with the lower camera's fitness below
    /// `certain_fitness`.
    unsure: u16,
}

impl StatusMonitor {
    /// A monitor in `status` with cleared counters.
    pub fn new(status: Status) -> Self {
        Self { status, good: 0, bad: 0, doubt: 0, sure: 0, lost_for: 0, unsure: 0 }
    }

    /// A monitor forced into `status` (tests, and the board's worst-case measurement): counters
    /// cleared, and a forced `Uncertain` taken as a hold unconfirmed for [`DOUBT_FRAMES`] frames
    /// already ([`StatusMonitor::unsure_frames`]), so that such a generation does all the work
    /// of an unconfirmed hold.
    pub fn forced(status: Status) -> Self {
        let unsure = if status == Status::Uncertain { DOUBT_FRAMES } else { 0 };
        Self { unsure, ..Self::new(status) }
    }

    /// The current status.
    pub fn status(&self) -> Status {
        self.status
    }

    /// Frames in a row (status decisions, the last included) in which the block was held but its
    /// lower camera's fitness below `certain_fitness`: how long a held pose has gone unconfirmed
    /// by the fitness (a view that leaves the orientation open does not count,
    /// [`StatusMonitor::update_view`]).
    pub fn unsure_frames(&self) -> u16 {
        self.unsure
    }

    /// Feeds the elite's relative fitness of one frame (its last generation): `fitness` the
    /// mean of the two cameras', `lower` the lower camera's. Returns the new status.
    pub fn update(&mut self, fitness: f32, lower: f32, config: &StatusConfig) -> Status {
        self.update_view(fitness, lower, true, config)
    }

    /// [`StatusMonitor::update`] for a view that may leave the pose's orientation open
    /// (`settles` false: too few faces whole in a camera): such a frame is not certain, however
    /// high `lower`, but counts as unconfirmed for [`StatusMonitor::unsure_frames`] only if
    /// `lower` is below `certain_fitness` (the fitness, not the view, leaves it unconfirmed).
    pub fn update_view(&mut self, fitness: f32, lower: f32, settles: bool, config: &StatusConfig) -> Status {
        // NaN counts as bad (it is neither ≥ nor < a threshold otherwise).
        let good = fitness >= config.acquire_fitness;
        let bad = !(fitness >= config.lose_fitness);
        let fits = lower >= config.certain_fitness;
        let certain = fits && settles;
        self.good = if good { self.good.saturating_add(1) } else { 0 };
        self.bad = if bad { self.bad.saturating_add(1) } else { 0 };
        self.doubt = if good { 0 } else { self.doubt.saturating_add(1) };
        self.sure = if certain { self.sure.saturating_add(1) } else { 0 };
        // A held pose is reported tracking once confirmed, and stays so while it stays certain.
        let confirmed = self.sure >= config.confirm_frames || (self.status == Status::Tracking && certain);
        let held = if confirmed { Status::Tracking } else { Status::Uncertain };
        self.status = match self.status {
            Status::Tracking | Status::Uncertain if self.bad >= config.lose_frames || self.doubt >= DOUBT_FRAMES => {
                self.lost_for = 0;
                Status::Lost
            }
            Status::Tracking | Status::Uncertain => held,
            Status::Searching | Status::Lost if self.good >= config.confirm_frames => held,
            Status::Lost => {
                self.lost_for = self.lost_for.saturating_add(1);
                if self.lost_for >= config.lost_frames_to_search { Status::Searching } else { Status::Lost }
            }
            Status::Searching => Status::Searching,
        };
        self.unsure = if self.status.holds() && !fits { self.unsure.saturating_add(1) } else { 0 };
        self.status
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    /// A frame both cameras fit alike: `lower` equals `fitness`.
    fn alike(m: &mut StatusMonitor, fitness: f32, c: &StatusConfig) -> Status {
        m.update(fitness, fitness, c)
    }

    #[test]
    fn acquire_needs_confirmation_and_loss_is_immediate() {
        let c = StatusConfig::DEFAULT;
        let mut m = StatusMonitor::new(Status::Searching);
        assert_eq!(alike(&mut m, 0.95, &c), Status::Searching);
        assert_eq!(alike(&mut m, 0.95, &c), Status::Searching);
        assert_eq!(alike(&mut m, 0.95, &c), Status::Tracking);
        // Between the held thresholds: still held, no longer confirmed.
        assert_eq!(alike(&mut m, 0.5, &c), Status::Uncertain);
        assert_eq!(alike(&mut m, 0.0, &c), Status::Lost);
        assert_eq!(alike(&mut m, f32::NAN, &c), Status::Lost);
        // A single good frame does not re-acquire; three do.
        assert_eq!(alike(&mut m, 0.95, &c), Status::Lost);
        assert_eq!(alike(&mut m, 0.6, &c), Status::Lost);
        for _ in 0..2 {
            assert_eq!(alike(&mut m, 0.95, &c), Status::Lost);
        }
        assert_eq!(alike(&mut m, 0.95, &c), Status::Tracking);
    }

    #[test]
    fn a_held_pose_is_reported_tracking_only_while_both_cameras_fit() {
        let c = StatusConfig::DEFAULT;
        let mut m = StatusMonitor::new(Status::Searching);
        // Held on a pose that fits, but one camera only at 0.8: uncertain.
        for _ in 0..2 {
            assert_eq!(m.update(0.95, 0.8, &c), Status::Searching);
        }
        assert_eq!(m.update(0.95, 0.8, &c), Status::Uncertain);
        // Both cameras certain for confirm_frames: tracking.
        assert_eq!(m.update(0.95, 0.95, &c), Status::Uncertain);
        assert_eq!(m.update(0.95, 0.95, &c), Status::Uncertain);
        assert_eq!(m.update(0.95, 0.95, &c), Status::Tracking);
        // The first frame one camera falls below the bar: uncertain, and the confirmation
        // starts again.
        assert_eq!(m.update(0.95, 0.89, &c), Status::Uncertain);
        assert_eq!(m.update(0.95, 0.95, &c), Status::Uncertain);
        assert_eq!(m.update(0.95, f32::NAN, &c), Status::Uncertain);
        for _ in 0..2 {
            assert_eq!(m.update(0.95, 0.9, &c), Status::Uncertain);
        }
        assert_eq!(m.update(0.95, 0.9, &c), Status::Tracking);
        // Held and uncertain, the held rules still apply: gone is lost at once.
        assert_eq!(m.update(0.95, 0.5, &c), Status::Uncertain);
        assert_eq!(m.update(0.3, 0.3, &c), Status::Lost);
    }

    #[test]
    fn a_tracker_started_tracking_stays_so_while_certain() {
        let c = StatusConfig::DEFAULT;
        let mut m = StatusMonitor::new(Status::Tracking);
        assert_eq!(alike(&mut m, 0.95, &c), Status::Tracking);
        let mut m = StatusMonitor::new(Status::Tracking);
        assert_eq!(alike(&mut m, 0.85, &c), Status::Uncertain);
    }

    #[test]
    fn a_held_block_below_the_acquisition_bar_for_long_is_lost() {
        let c = StatusConfig::DEFAULT;
        let mut m = StatusMonitor::new(Status::Tracking);
        // Dips below the acquisition's bar shorter than DOUBT_FRAMES keep it held.
        for _ in 0..3 {
            for _ in 0..DOUBT_FRAMES - 1 {
                assert_eq!(alike(&mut m, 0.7, &c), Status::Uncertain);
            }
            assert_eq!(alike(&mut m, 0.8, &c), Status::Uncertain);
        }
        // A lock that stays between the thresholds is lost at the DOUBT_FRAMES-th frame.
        for _ in 0..DOUBT_FRAMES - 1 {
            assert_eq!(alike(&mut m, 0.6, &c), Status::Uncertain);
        }
        assert_eq!(alike(&mut m, 0.6, &c), Status::Lost);
        // And needs the confirmation to come back.
        assert_eq!(alike(&mut m, 0.95, &c), Status::Lost);
        assert_eq!(alike(&mut m, 0.95, &c), Status::Lost);
        assert_eq!(alike(&mut m, 0.95, &c), Status::Tracking);
    }

    #[test]
    fn a_view_that_leaves_the_orientation_open_is_held_but_not_counted_unsure() {
        let c = StatusConfig::DEFAULT;
        let mut m = StatusMonitor::new(Status::Searching);
        for _ in 0..c.confirm_frames + 5 {
            assert_ne!(m.update_view(0.95, 0.95, false, &c), Status::Tracking);
        }
        assert_eq!(m.status(), Status::Uncertain);
        assert_eq!(m.unsure_frames(), 0);
        // The fitness below the bar: unconfirmed by the fitness, counted.
        m.update_view(0.8, 0.8, false, &c);
        m.update_view(0.8, 0.8, true, &c);
        assert_eq!(m.unsure_frames(), 2);
        // A certain frame in a view that settles it clears the count and confirms in time.
        for _ in 0..c.confirm_frames {
            m.update_view(0.95, 0.95, true, &c);
        }
        assert_eq!((m.status(), m.unsure_frames()), (Status::Tracking, 0));
    }

    #[test]
    fn long_loss_falls_back_to_searching() {
        let c = StatusConfig { lost_frames_to_search: 4, ..StatusConfig::DEFAULT };
        let mut m = StatusMonitor::new(Status::Tracking);
        assert_eq!(alike(&mut m, 0.1, &c), Status::Lost);
        for _ in 0..3 {
            assert_eq!(alike(&mut m, 0.1, &c), Status::Lost);
        }
        assert_eq!(alike(&mut m, 0.1, &c), Status::Searching);
        assert_eq!(alike(&mut m, 0.1, &c), Status::Searching);
    }

    /// The held decision as it was before the confirmation: three statuses on the mean fitness.
    fn held_reference(status: Status, good: u16, bad: u16, doubt: u16, lost_for: &mut u16, c: &StatusConfig) -> Status {
        match status {
            Status::Tracking if bad >= c.lose_frames || doubt >= DOUBT_FRAMES => {
                *lost_for = 0;
                Status::Lost
            }
            Status::Tracking => Status::Tracking,
            Status::Searching | Status::Lost if good >= c.confirm_frames => Status::Tracking,
            Status::Lost => {
                *lost_for = lost_for.saturating_add(1);
                if *lost_for >= c.lost_frames_to_search { Status::Searching } else { Status::Lost }
            }
            other => other,
        }
    }

    /// Fitness levels on every side of the thresholds, the frames above the held bar likeliest.
    fn level() -> impl proptest::strategy::Strategy<Value = f32> {
        proptest::sample::select(std::vec![0.0f32, 0.3, 0.4, 0.6, 0.75, 0.85, 0.89, 0.9, 0.95, 1.0, 1.0, f32::NAN])
    }

    proptest::proptest! {
        /// Whatever the fitness, the block is held exactly when the three-status machine on the
        /// mean fitness says tracking (so the tracker's work is what it was), and a frame is
        /// reported `tracking` only with its lower camera at the bar.
        #[test]
        fn held_is_the_mean_fitness_machine_and_tracking_needs_the_lower_camera(
            runs in proptest::collection::vec((level(), level(), 1usize..16), 1..60),
            lost_frames_to_search in 1u16..20,
        ) {
            let c = StatusConfig { lost_frames_to_search, ..StatusConfig::DEFAULT };
            let mut m = StatusMonitor::new(Status::Searching);
            let (mut reference, mut good, mut bad, mut doubt, mut lost_for) = (Status::Searching, 0u16, 0u16, 0u16, 0u16);
            // Runs of equal frames, so that every counter reaches its threshold.
            let frames = runs.iter().flat_map(|&(mean, lower, n)| core::iter::repeat_n((mean, lower), n));
            for (mean, lower) in frames {
                let status = m.update(mean, lower, &c);
                let ok = mean >= c.acquire_fitness;
                good = if ok { good + 1 } else { 0 };
                bad = if mean >= c.lose_fitness { 0 } else { bad + 1 };
                doubt = if ok { 0 } else { doubt + 1 };
                reference = held_reference(reference, good, bad, doubt, &mut lost_for, &c);
                proptest::prop_assert_eq!(status.holds(), reference == Status::Tracking);
                if !status.holds() {
                    proptest::prop_assert_eq!(status, reference);
                }
                proptest::prop_assert!(status != Status::Tracking || lower >= c.certain_fitness);
            }
        }
    }

    #[test]
    fn codes_round_trip() {
        for s in Status::ALL {
            assert_eq!(Status::from_code(s.code()), Some(s));
            assert_eq!(s.holds(), matches!(s, Status::Tracking | Status::Uncertain));
        }
        assert_eq!(Status::from_code(4), None);
        assert_eq!(Status::Lost.to_string(), "lost");
        assert_eq!(Status::Uncertain.to_string(), "uncertain");
    }
}
