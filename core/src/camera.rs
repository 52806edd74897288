//! Pinhole cameras and the stereo rig (paper §4.1, eq. 26–31).
//!
//! Conventions (OpenCV's):
//!
//! ```text
//!   camera frame Σ_C            image (pixels)
//!        z (optical axis, forward)   (0,0) ──────► u
//!       ╱                              │  pixel (i, j) covers
//!      ╱                               │  [i, i+1) × [j, j+1)
//!     o────► x (right)                 ▼ v
//!     │
//!     ▼ y (down)
//! ```
//!
//! `u = fx·x/z + cx`, `v = fy·y/z + cy`, all in pixels; a centred camera has
//! `cx = width/2`. The right camera frame is `Σ_CR`, the frame in which poses are estimated;
//! the left camera is reached through the fixed transform `^CL T_CR`.

use nalgebra::{Isometry3, Matrix3, Point2, Point3, Translation3, UnitQuaternion, Vector3};

use crate::config::{MAX_IMAGE_SIDE, MIN_DEPTH_M};

/// Why camera parameters were rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum CameraError {
    /// A parameter is NaN or infinite.
    NonFinite,
    /// A focal length is not positive.
    BadFocalLength,
    /// Width or height is 0 or larger than [`MAX_IMAGE_SIDE`].
    BadSize,
    /// The stereo baseline is not positive.
    BadBaseline,
}

impl core::fmt::Display for CameraError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NonFinite => f.write_str("camera parameter is not finite"),
            Self::BadFocalLength => f.write_str("focal length must be positive"),
            Self::BadSize => f.write_str("image size must be 1..=2048 pixels per side"),
            Self::BadBaseline => f.write_str("stereo baseline must be positive"),
        }
    }
}

impl core::error::Error for CameraError {}

/// Why a point has no pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ProjectError {
    /// The point is behind the camera or closer than [`MIN_DEPTH_M`] to its plane.
    BehindCamera,
    /// The point projects outside `[0, width) × [0, height)`.
    OutsideImage,
    /// The point is not finite.
    NonFinite,
}

impl core::fmt::Display for ProjectError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BehindCamera => f.write_str("point is behind the camera"),
            Self::OutsideImage => f.write_str("point projects outside the image"),
            Self::NonFinite => f.write_str("point is not finite"),
        }
    }
}

impl core::error::Error for ProjectError {}

/// Pinhole intrinsics of one camera (no distortion), in pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pinhole {
    fx: f32,
    fy: f32,
    cx: f32,
    cy: f32,
    width: u16,
    height: u16,
}

impl Pinhole {
    /// Validated intrinsics.
    ///
    /// # Errors
    /// [`CameraError::NonFinite`], [`CameraError::BadFocalLength`] (`fx, fy ≤ 0`) or
    /// [`CameraError::BadSize`].
    pub fn new_checked(fx: f32, fy: f32, cx: f32, cy: f32, width: u16, height: u16) -> Result<Self, CameraError> {
        if ![fx, fy, cx, cy].iter().all(|v| v.is_finite()) {
            return Err(CameraError::NonFinite);
        }
        if fx <= 0.0 || fy <= 0.0 {
            return Err(CameraError::BadFocalLength);
        }
        if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
            return Err(CameraError::BadSize);
        }
        Ok(Self { fx, fy, cx, cy, width, height })
    }

    /// Focal length along u (pixels).
    pub fn fx(&self) -> f32 {
        self.fx
    }
    /// Focal length along v (pixels).
    pub fn fy(&self) -> f32 {
        self.fy
    }
    /// Principal point u (pixels).
    pub fn cx(&self) -> f32 {
        self.cx
    }
    /// Principal point v (pixels).
    pub fn cy(&self) -> f32 {
        self.cy
    }
    /// Image width (pixels).
    pub fn width(&self) -> u16 {
        self.width
    }
    /// Image height (pixels).
    pub fn height(&self) -> u16 {
        self.height
    }

    /// The 3×3 intrinsic matrix `K` (the paper's `P` without the `[I|0]`).
    pub fn k_matrix(&self) -> Matrix3<f32> {
        Matrix3::new(self.fx, 0.0, self.cx, 0.0, self.fy, self.cy, 0.0, 0.0, 1.0)
    }

    /// Projects a point given in this camera's frame to continuous pixel coordinates
    /// (eq. 28/30).
    ///
    /// # Errors
    /// [`ProjectError::BehindCamera`] if `z < MIN_DEPTH_M`, [`ProjectError::OutsideImage`] if
    /// the pixel is outside the image, [`ProjectError::NonFinite`] for NaN/inf input.
    pub fn project(&self, p: &Point3<f32>) -> Result<Point2<f32>, ProjectError> {
        let uv = self.project_unbounded(p)?;
        if uv.x >= 0.0 && uv.y >= 0.0 && uv.x < f32::from(self.width) && uv.y < f32::from(self.height) {
            Ok(uv)
        } else {
            Err(ProjectError::OutsideImage)
        }
    }

    /// As [`Pinhole::project`], but points outside the image are returned too.
    ///
    /// # Errors
    /// [`ProjectError::BehindCamera`] or [`ProjectError::NonFinite`].
    pub fn project_unbounded(&self, p: &Point3<f32>) -> Result<Point2<f32>, ProjectError> {
        if !p.coords.iter().all(|c| c.is_finite()) {
            return Err(ProjectError::NonFinite);
        }
        if p.z < MIN_DEPTH_M {
            return Err(ProjectError::BehindCamera);
        }
        Ok(Point2::new(self.fx * p.x / p.z + self.cx, self.fy * p.y / p.z + self.cy))
    }
}

/// Two cameras rigidly mounted together. Poses are expressed in the right camera's frame
/// `Σ_CR`; `left_from_right` is `^CL T_CR` (eq. 29), mapping `Σ_CR` coordinates to `Σ_CL`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StereoRig {
    /// Right camera intrinsics (its frame is `Σ_CR`).
    pub right: Pinhole,
    /// Left camera intrinsics.
    pub left: Pinhole,
    /// `^CL T_CR`: the fixed transform from right-camera to left-camera coordinates.
    pub left_from_right: Isometry3<f32>,
}

impl StereoRig {
    /// Two identical, parallel cameras; the left one `baseline_m` to the left (−x of `Σ_CR`)
    /// of the right one, so `^CL r = ^CR r + [baseline, 0, 0]ᵀ`.
    ///
    /// # Errors
    /// [`CameraError::BadBaseline`] unless `baseline_m` is finite and positive.
    pub fn parallel(camera: Pinhole, baseline_m: f32) -> Result<Self, CameraError> {
        if !baseline_m.is_finite() || baseline_m <= 0.0 {
            return Err(CameraError::BadBaseline);
        }
        Ok(Self {
            right: camera,
            left: camera,
            left_from_right: Isometry3::from_parts(Translation3::new(baseline_m, 0.0, 0.0), UnitQuaternion::identity()),
        })
    }

    /// `f_R(ψ, ^M r)` and `f_L(ψ, ^M r)` of eq. 31: a model point `^M r` of a target at pose
    /// `^CR T_M` projected into the right and the left image.
    pub fn project_model_point(
        &self,
        cr_from_model: &Isometry3<f32>,
        model_point: &Point3<f32>,
    ) -> (Result<Point2<f32>, ProjectError>, Result<Point2<f32>, ProjectError>) {
        let p_cr = cr_from_model * model_point;
        let p_cl = self.left_from_right * p_cr;
        (self.right.project(&p_cr), self.left.project(&p_cl))
    }

    /// Position of the left camera's centre in `Σ_CR`.
    pub fn left_center_in_right(&self) -> Vector3<f32> {
        self.left_from_right.inverse().translation.vector
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Pinhole {
        Pinhole::new_checked(800.0, 800.0, 320.0, 240.0, 640, 480).unwrap()
    }

    #[test]
    fn projection_of_known_points() {
        let c = cam();
        let uv = c.project(&Point3::new(0.1, -0.05, 1.0)).unwrap();
        assert!((uv.x - 400.0).abs() < 1e-4 && (uv.y - 200.0).abs() < 1e-4);
        assert_eq!(c.project(&Point3::new(0.0, 0.0, -1.0)), Err(ProjectError::BehindCamera));
        assert_eq!(c.project(&Point3::new(0.0, 0.0, 0.0)), Err(ProjectError::BehindCamera));
        assert_eq!(c.project(&Point3::new(1.0, 0.0, 1.0)), Err(ProjectError::OutsideImage));
        assert_eq!(c.project(&Point3::new(f32::NAN, 0.0, 1.0)), Err(ProjectError::NonFinite));
        // u = -0.5 is outside; u = 0 is the first column.
        assert_eq!(c.project(&Point3::new(-320.5 / 800.0, 0.0, 1.0)), Err(ProjectError::OutsideImage));
        assert!(c.project(&Point3::new(-320.0 / 800.0, 0.0, 1.0)).is_ok());
    }

    #[test]
    fn bad_intrinsics_are_rejected() {
        assert_eq!(Pinhole::new_checked(0.0, 1.0, 0.0, 0.0, 10, 10), Err(CameraError::BadFocalLength));
        assert_eq!(Pinhole::new_checked(1.0, 1.0, f32::NAN, 0.0, 10, 10), Err(CameraError::NonFinite));
        assert_eq!(Pinhole::new_checked(1.0, 1.0, 0.0, 0.0, 0, 10), Err(CameraError::BadSize));
        assert_eq!(StereoRig::parallel(cam(), 0.0), Err(CameraError::BadBaseline));
    }

    #[test]
    fn stereo_disparity_matches_baseline() {
        let rig = StereoRig::parallel(cam(), 0.1).unwrap();
        let pose = Isometry3::translation(0.0, 0.0, 0.8);
        let (r, l) = rig.project_model_point(&pose, &Point3::origin());
        let (r, l) = (r.unwrap(), l.unwrap());
        // disparity = f·b/z = 800·0.1/0.8 = 100 px, the left image sees the point further right.
        assert!((l.x - r.x - 100.0).abs() < 1e-3 && (l.y - r.y).abs() < 1e-6);
        assert!((rig.left_center_in_right() - Vector3::new(-0.1, 0.0, 0.0)).norm() < 1e-7);
    }
}
