//! The acquisition as a pipeline of bounded stages, one per generation.

use nalgebra::Vector3;

use super::refine::Measured;
use super::{
    AcquireConfig, HueBlobs, REFINE_ITERATIONS, Refinement, Seed, grid_size, scan_part, scene_hues, seed_pose_from,
};
use crate::camera::StereoRig;
use crate::hue::{HueLut, HueSet};
use crate::image::{Image, PixelFormat};
use crate::pose::Psi;
use crate::quat;

/// What the next generation of an [`Acquisition`] does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Scans the grid pixels from this index on (both images).
    Scan(u32),
    /// Solves for the seeds of the finished scan.
    Solve,
    /// Gauss–Newton iteration this many of both solutions.
    Refine(u8),
}

/// The acquisition's state between generations (see the [module docs](super)): the scan's
/// blobs so far, the two solutions being refined, and the latest seed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Acquisition {
    stage: Stage,
    left: HueBlobs,
    right: HueBlobs,
    candidates: [Option<Refinement>; 2],
    /// The camera's motion since the scan ended: the identity pose moved by every
    /// feedforward shift since then (`^{CR now} T_{CR scan}` to first order).
    motion: Psi,
    seed: Option<Seed>,
    /// The scene's hues found by the latest finished scan ([`super::scene_hues`]).
    scene: HueSet,
    /// Whether the scan under way repeats one whose scene's hues differed from those in use.
    repeat: bool,
}

impl Default for Acquisition {
    fn default() -> Self {
        Self::new()
    }
}

impl Acquisition {
    /// Nothing scanned, no seed.
    pub const fn new() -> Self {
        Self {
            stage: Stage::Scan(0),
            left: HueBlobs::EMPTY,
            right: HueBlobs::EMPTY,
            candidates: [None, None],
            motion: Psi::IDENTITY,
            seed: None,
            scene: HueSet::EMPTY,
            repeat: false,
        }
    }

    /// Back to the start: the next stage scans from the first pixel, and the seed is dropped.
    /// The scene's hues are kept: they belong to the scene, not to the block.
    pub fn reset(&mut self) {
        let scene = self.scene;
        *self = Self::new();
        self.scene = scene;
    }

    /// The hues of the scene around the block found by the latest finished scan (none before
    /// the first): the search table leaves them out, so that neither the scan nor the fitness
    /// counts them as the block's.
    pub fn scene(&self) -> &HueSet {
        &self.scene
    }

    /// The next stage.
    pub fn stage(&self) -> Stage {
        self.stage
    }

    /// The latest seed, in the camera frame of the last frame stepped on.
    pub fn seed(&self) -> Option<&Seed> {
        self.seed.as_ref()
    }

    /// Moves the seed and the camera-motion record by the feedforward shift `shift` of the
    /// population (the same closure), so that they follow the camera to the next frame.
    pub fn shift(&mut self, mut shift: impl FnMut(&mut Psi)) {
        shift(&mut self.motion);
        self.motion.project_to_ball();
        if let Some(s) = self.seed.as_mut()
            && let Some(mut psi) = s.psi()
        {
            shift(&mut psi);
            psi.project_to_ball();
            s.centre = psi.translation();
            s.rotation = psi.rotation_unchecked();
        }
    }

    /// Runs the next stage on a frame pair (bounded work, see the module docs).
    #[allow(clippy::too_many_arguments)]
    pub fn step<B: AsRef<[u8]>, F: PixelFormat>(
        &mut self,
        left: &Image<B, F>,
        right: &Image<B, F>,
        lut: &HueLut,
        rig: &StereoRig,
        half: &[f32; 3],
        config: &AcquireConfig,
    ) {
        match self.stage {
            Stage::Scan(start) => self.scan(left, right, lut, config, start),
            Stage::Solve => self.solve(rig, half, config),
            Stage::Refine(i) => self.refine(rig, half, config, i),
        }
    }

    /// The [`Stage::Scan`] stage. Each stage is a function of its own, never inlined, so that
    /// a generation's stack holds the locals of one stage only.
    #[inline(never)]
    fn scan<B: AsRef<[u8]>, F: PixelFormat>(
        &mut self,
        left: &Image<B, F>,
        right: &Image<B, F>,
        lut: &HueLut,
        config: &AcquireConfig,
        start: u32,
    ) {
        let (stride, chunk) = (config.scan_stride, config.scan_chunk);
        let next = scan_part(left, lut, stride, start, chunk, &mut self.left);
        scan_part(right, lut, stride, start, chunk, &mut self.right);
        let (gw, gh) = grid_size(right.width(), right.height(), stride);
        self.stage = if next >= gw * gh { Stage::Solve } else { Stage::Scan(next) };
        self.motion = Psi::IDENTITY;
    }

    /// Takes the scene's hues of the finished scan; returns whether the scan must be repeated
    /// before it is solved: they differ from those it counted with (once in a row: a scene whose
    /// border hues change from scan to scan is solved with the latest).
    fn take_scene(&mut self) -> bool {
        let scene = scene_hues(&self.left, &self.right);
        let changed = scene != self.scene;
        self.scene = scene;
        self.repeat = changed && !self.repeat;
        self.repeat
    }

    /// The [`Stage::Solve`] stage: the scene's hues of the finished scan, and unless they
    /// changed (the scan is then repeated), the solutions from all seen faces and from the two
    /// with most hits, each started as a refinement in its place.
    #[inline(never)]
    fn solve(&mut self, rig: &StereoRig, half: &[f32; 3], config: &AcquireConfig) {
        if self.take_scene() {
            self.stage = self.restart();
            return;
        }
        let m = measured(rig, half, &self.left, &self.right, config);
        for (candidate, faces) in self.candidates.iter_mut().zip([3, 2]) {
            *candidate = seed_pose_from(rig, half, m.left, m.right, config.min_face_hits, faces)
                .map(|s| Refinement::start(&m, &s));
        }
        self.stage = if self.candidates.iter().any(Option::is_some) { Stage::Refine(0) } else { self.restart() };
    }

    /// The [`Stage::Refine`] stage `i`: one iteration of both solutions in their places, and
    /// after the last one the seed.
    #[inline(never)]
    fn refine(&mut self, rig: &StereoRig, half: &[f32; 3], config: &AcquireConfig, i: u8) {
        let m = measured(rig, half, &self.left, &self.right, config);
        for c in self.candidates.iter_mut().flatten() {
            c.iterate(&m);
        }
        self.stage = if usize::from(i) + 1 < REFINE_ITERATIONS {
            Stage::Refine(i + 1)
        } else {
            self.finish();
            self.restart()
        };
    }

    /// The best refined solution becomes the seed, moved from the scan's camera frame to the
    /// current one.
    fn finish(&mut self) {
        let best =
            self.candidates.iter().flatten().map(Refinement::result).fold(None, |best: Option<(Seed, f32)>, c| {
                if best.is_none_or(|(_, b)| c.1 < b) { Some(c) } else { best }
            });
        let Some((seed, _)) = best else { return };
        let Ok(motion) = self.motion.try_to_isometry() else { return };
        let centre = motion * nalgebra::Point3::from(seed.centre);
        let rotation = quat::to_rotation_matrix(&motion.rotation) * seed.rotation;
        let centre: Vector3<f32> = centre.coords;
        if centre.iter().chain(rotation.iter()).all(|v| v.is_finite()) {
            self.seed = Some(Seed { centre, rotation, ..seed });
        }
    }

    /// Clears the scan for the next round; returns its first stage.
    fn restart(&mut self) -> Stage {
        self.left = HueBlobs::default();
        self.right = HueBlobs::default();
        self.candidates = [None, None];
        Stage::Scan(0)
    }
}

/// What the refinements are measured against: the scan's blobs `left` and `right`.
fn measured<'a>(
    rig: &'a StereoRig,
    half: &'a [f32; 3],
    left: &'a HueBlobs,
    right: &'a HueBlobs,
    config: &AcquireConfig,
) -> Measured<'a> {
    Measured { rig, half, left, right, stride: config.scan_stride, min_hits: config.min_face_hits }
}
