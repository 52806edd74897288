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
//! `cx = width/2`. ROS `camera_info` and OpenCV put the *centre* of the top-left pixel at
//! `(0, 0)`; [`Pinhole::from_opencv`] converts (`cx = cx_cv + ½`, `cy = cy_cv + ½`).
//!
//! **Lens distortion** ([`Distortion`], OpenCV's plumb_bob `k1, k2, p1, p2, k3`) acts on the
//! normalised coordinates `(x/z, y/z)` before `K`, exactly as `cv2.projectPoints`, so raw
//! (not undistorted) images are matched directly. [`Pinhole::project`] applies it, and so does
//! the fitness (see [`crate::fitness`]), which picks its distorted or plain kernel once per
//! camera: a camera with `D = 0` costs nothing extra. The right camera frame is `Σ_CR`, the frame in which poses are estimated;
//! the left camera is reached through the fixed transform `^CL T_CR`.

use nalgebra::{Isometry3, Matrix3, Point2, Point3, Translation3, UnitQuaternion, Vector3};

use crate::limits::{MAX_IMAGE_SIDE, MIN_DEPTH_M};

error_enum! {
    /// Why camera parameters were rejected.
    pub enum CameraError {
        /// A parameter is NaN or infinite.
        NonFinite => "camera parameter is not finite",
        /// A focal length is not positive.
        BadFocalLength => "focal length must be positive",
        /// Width or height is 0 or larger than [`MAX_IMAGE_SIDE`].
        BadSize => "image size must be 1..=2048 pixels per side",
        /// The stereo baseline is not positive.
        BadBaseline => "stereo baseline must be positive",
    }
}

error_enum! {
    /// Why a point has no pixel.
    pub enum ProjectError {
        /// The point is behind the camera or closer than [`MIN_DEPTH_M`] to its plane.
        BehindCamera => "point is behind the camera",
        /// The point projects outside `[0, width) × [0, height)`.
        OutsideImage => "point projects outside the image",
        /// The point is not finite.
        NonFinite => "point is not finite",
    }
}

/// OpenCV's plumb_bob lens distortion `D = [k1, k2, p1, p2, k3]` on normalised coordinates:
///
/// ```text
/// r² = x² + y²,  radial = 1 + k1·r² + k2·r⁴ + k3·r⁶
/// x_d = x·radial + 2·p1·x·y + p2·(r² + 2x²)
/// y_d = y·radial + p1·(r² + 2y²) + 2·p2·x·y
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Distortion {
    k: [f32; 5],
}

impl Distortion {
    /// No distortion.
    pub const NONE: Distortion = Distortion { k: [0.0; 5] };

    /// Validated plumb_bob coefficients `[k1, k2, p1, p2, k3]` (ROS `camera_info`'s `D`).
    ///
    /// # Errors
    /// [`CameraError::NonFinite`] if a coefficient is NaN or infinite.
    pub fn plumb_bob(d: [f32; 5]) -> Result<Self, CameraError> {
        if d.iter().all(|v| v.is_finite()) { Ok(Self { k: d }) } else { Err(CameraError::NonFinite) }
    }

    /// The coefficients `[k1, k2, p1, p2, k3]`.
    pub fn coefficients(&self) -> [f32; 5] {
        self.k
    }

    /// True when every coefficient is 0 (the plain pinhole).
    pub fn is_none(&self) -> bool {
        self.k.iter().all(|&v| v == 0.0)
    }

    /// Distorts normalised coordinates `(x, y) = (X/Z, Y/Z)`.
    #[inline(always)]
    pub fn apply(&self, x: f32, y: f32) -> (f32, f32) {
        let [k1, k2, p1, p2, k3] = self.k;
        let (xx, yy, xy) = (x * x, y * y, x * y);
        let r2 = xx + yy;
        let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        let xd = x * radial + 2.0 * p1 * xy + p2 * (r2 + 2.0 * xx);
        let yd = y * radial + p1 * (r2 + 2.0 * yy) + 2.0 * p2 * xy;
        (xd, yd)
    }
}

impl Default for Distortion {
    fn default() -> Self {
        Self::NONE
    }
}

/// Pinhole intrinsics of one camera with optional lens [`Distortion`], in pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pinhole {
    fx: f32,
    fy: f32,
    cx: f32,
    cy: f32,
    width: u16,
    height: u16,
    distortion: Distortion,
}

impl Pinhole {
    /// Validated intrinsics in the core's pixel convention (pixel `(i, j)` covers
    /// `[i, i+1) × [j, j+1)`), without distortion.
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
        Ok(Self { fx, fy, cx, cy, width, height, distortion: Distortion::NONE })
    }

    /// Intrinsics given in OpenCV's / ROS `camera_info`'s convention (the centre of the
    /// top-left pixel at `(0, 0)`), converted to the core's: `cx + ½`, `cy + ½`.
    ///
    /// # Errors
    /// As [`Pinhole::new_checked`].
    pub fn from_opencv(fx: f32, fy: f32, cx: f32, cy: f32, width: u16, height: u16) -> Result<Self, CameraError> {
        Self::new_checked(fx, fy, cx + 0.5, cy + 0.5, width, height)
    }

    /// The same camera with lens distortion `d`.
    #[must_use]
    pub fn with_distortion(mut self, d: Distortion) -> Self {
        self.distortion = d;
        self
    }

    /// The lens distortion.
    pub fn distortion(&self) -> &Distortion {
        &self.distortion
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
    /// (eq. 28/30), through the lens distortion if any.
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
        let (x, y) = (p.x / p.z, p.y / p.z);
        let (x, y) = if self.distortion.is_none() { (x, y) } else { self.distortion.apply(x, y) };
        Ok(Point2::new(self.fx * x + self.cx, self.fy * y + self.cy))
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

    /// Cases of `cv2.projectPoints` (opencv-python 5.0.0): name, K = (fx, fy, cx, cy) in
    /// OpenCV's pixel convention, D = [k1, k2, p1, p2, k3], points (m) and their pixels.
    #[allow(clippy::type_complexity, clippy::excessive_precision)]
    const OPENCV_CASES: &[(&str, [f64; 4], [f64; 5], &[([f64; 3], [f64; 2])])] = &[
        (
            "pinhole-640",
            [800.0, 800.0, 319.5, 239.5],
            [0.0, 0.0, 0.0, 0.0, 0.0],
            &[
                (
                    [0.06254773330233349, -0.09805216493835017, 0.43924830665095577],
                    [433.41776788710337, 60.91824848737991],
                ),
                (
                    [0.19860690048478774, -0.021969477646941377, 0.9663777022985074],
                    [483.91347933621046, 221.31292668927483],
                ),
                (
                    [0.13784284512259676, 0.001819303583181331, 0.9128266278578181],
                    [440.30527970230696, 241.0944351557323],
                ),
                (
                    [-0.13739640500470407, 0.021398940829796986, 1.4088845505121377],
                    [241.4828736401377, 251.65085555279506],
                ),
                ([-0.09991685754438728, 0.1982001133737571, 1.0921488799401116], [246.310815353404, 384.6817546227767]),
                (
                    [0.18677672269813095, 0.11706476768550123, 0.9655294112594653],
                    [474.25590532617235, 336.4952992174923],
                ),
                (
                    [-0.24736734771721264, 0.048871691776465054, 0.9465607789328547],
                    [110.43378620982571, 280.80464127749946],
                ),
                (
                    [0.16061420919138314, 0.19558405907275395, 0.672266414230064],
                    [510.63161781295537, 472.2458935121764],
                ),
                (
                    [0.1485347143760231, -0.11387652070576043, 0.41297342809675647],
                    [607.2370877067133, 18.901747505982314],
                ),
                (
                    [-0.016032523578139612, -0.13591518645686218, 0.6116423583838417],
                    [298.5301984702266, 61.729203594081525],
                ),
                (
                    [-0.09848378659034324, 0.0450158417092123, 1.1612353329700231],
                    [251.6524009515232, 270.5123816808625],
                ),
                (
                    [-0.11078719394961334, -0.18242319681544666, 0.6206673963856948],
                    [176.70249577180238, 4.368336403370108],
                ),
                ([0.0, 0.0, 1.0], [319.5, 239.5]),
                ([0.1, 0.0, 1.0], [399.5, 239.5]),
                ([0.0, 0.1, 0.5], [319.5, 399.5]),
            ],
        ),
        (
            "offcentre-640",
            [812.3, 806.9, 327.1, 231.8],
            [0.0, 0.0, 0.0, 0.0, 0.0],
            &[
                (
                    [-0.06523184469889665, 0.0031088945201399876, 1.0655618792128365],
                    [277.37240699708826, 234.15421990711053],
                ),
                (
                    [-0.24813287897396202, 0.14853575067715225, 1.1017962388671654],
                    [144.1638721749625, 340.58009290050217],
                ),
                (
                    [0.16502386490087279, -0.055494376394336964, 1.144095268194067],
                    [444.26584202867355, 192.66129052585597],
                ),
                (
                    [-0.17276945946928007, 0.039273626882885215, 0.5658668210852056],
                    [79.08999712025113, 287.8023813925439],
                ),
                (
                    [-0.11620034771810728, -0.17629934306179856, 0.8843448139070064],
                    [220.36613220649915, 70.93973635681405],
                ),
                (
                    [0.19016607699041432, -0.044947279555708514, 0.6635203580124758],
                    [559.9065785381812, 177.1400947905516],
                ),
                (
                    [0.004895404934211589, -0.07078546149671736, 0.8427481279143798],
                    [331.8185360564386, 164.02555234497765],
                ),
                ([0.17357512318293467, -0.13992010837181926, 0.5063745033249202], [605.54030778743, 8.83945458569707]),
                ([0.06985858347126311, 0.1265352415276303, 1.4646108561537035], [365.8448496064895, 301.5122283094219]),
                (
                    [0.12088547368092856, -0.048221531379875004, 0.6365044410914681],
                    [481.37271819601847, 170.6693131446201],
                ),
                (
                    [-0.20425219746847717, 0.19149915376448867, 1.1389416788724134],
                    [181.426114250289, 367.4703947523863],
                ),
                (
                    [0.020571910688244377, 0.0359966772042441, 0.7304620896269773],
                    [349.9767013228496, 271.56348567375653],
                ),
                ([0.0, 0.0, 1.0], [327.1, 231.8]),
                ([0.1, 0.0, 1.0], [408.33000000000004, 231.8]),
                ([0.0, 0.1, 0.5], [327.1, 393.18]),
            ],
        ),
        (
            "barrel-640",
            [800.0, 800.0, 319.5, 239.5],
            [-0.12, 0.05, 0.001, -0.001, 0.0],
            &[
                ([0.18703851307475222, 0.15362275767858796, 0.4277165578819364], [657.3758921838902, 517.478569469061]),
                ([0.0811073691692269, 0.0566286820889923, 0.8094037998217244], [399.5054622439883, 295.37962887455234]),
                (
                    [-0.18419209209584714, 0.02787770978952317, 0.4333853238225228],
                    [-14.028375727010314, 290.10539156473806],
                ),
                (
                    [0.17253716043727646, -0.04948486554803194, 0.5351813124255103],
                    [573.7899255004488, 166.6320478480874],
                ),
                (
                    [0.22247408557248977, -0.03561788713714806, 1.4638630589371044],
                    [440.6778788190165, 220.11545537194638],
                ),
                ([0.2019583940979634, -0.10420431492726207, 1.123536803042366], [462.4968211742073, 165.7338842876074]),
                (
                    [0.03485957392963862, -0.18477708532350437, 0.8710422710284296],
                    [351.28742902256596, 70.84682931982326],
                ),
                ([-0.17727002311953655, 0.1504875232437084, 0.9761141187015284], [175.036723776919, 362.1441796388253]),
                (
                    [-0.15376825251583381, -0.012907913274361554, 1.360090129421252],
                    [229.16400628207887, 231.92800264059278],
                ),
                (
                    [0.2139528423722622, 0.019054079685494107, 0.7786317336956289],
                    [537.2096324136772, 258.9549541514692],
                ),
                (
                    [0.02616324383363189, -0.07113467608790996, 1.0493200805186862],
                    [339.42648234057765, 185.31514507656922],
                ),
                (
                    [-0.15972375077554418, 0.10052996794197117, 1.1520528106734982],
                    [208.86742255746293, 309.1399893426112],
                ),
                ([0.0, 0.0, 1.0], [319.5, 239.5]),
                ([0.1, 0.0, 1.0], [399.3804, 239.508]),
                ([0.0, 0.1, 0.5], [319.468, 398.8408]),
            ],
        ),
        (
            "wide-320",
            [260.0, 261.5, 161.2, 118.7],
            [-0.28, 0.09, -0.0008, 0.0012, -0.012],
            &[
                (
                    [-0.07229311148824397, -0.19429152412615577, 0.7740748741629239],
                    [137.4124162790098, 54.32530185195638],
                ),
                (
                    [0.009549243247995054, 0.05138477914651629, 0.6986770817896639],
                    [164.74946410044714, 137.89934980858035],
                ),
                ([0.1326236916392613, 0.11720946323921366, 1.4472434397782745], [184.9336120659687, 139.7888995646415]),
                (
                    [0.2045896569952751, 0.0052014331288833815, 0.8889260306118247],
                    [220.21592065685377, 120.19754976850491],
                ),
                (
                    [-0.17446886096159225, 0.09033976822043488, 1.4784342259686487],
                    [130.6856630838484, 134.59061780020096],
                ),
                (
                    [0.21670969615371427, -0.10943060692114237, 0.9670749360168982],
                    [218.5169459789813, 89.58682594584366],
                ),
                (
                    [-0.24741056709228393, -0.12059154080293087, 0.9732827419288465],
                    [96.60190116834205, 87.00332704986404],
                ),
                (
                    [0.12648875179887697, -0.05474921977985936, 1.3861945760876009],
                    [184.86903196026947, 108.39529786834547],
                ),
                (
                    [0.15526341515862258, -0.12823758897314141, 1.2170441600365436],
                    [194.14153984967257, 91.33680944837471],
                ),
                (
                    [-0.18161797422870923, -0.06157542435500862, 1.0387181502381049],
                    [116.19402118209365, 103.3424671834233],
                ),
                (
                    [-0.04054817454340742, 0.17924962456432592, 0.8693144542198843],
                    [149.2414957457736, 171.92209649402696],
                ),
                (
                    [0.15762813899752282, 0.02933308704444837, 1.3660066453601085],
                    [191.09863621187307, 124.29226239817363],
                ),
                ([0.0, 0.0, 1.0], [161.2, 118.7]),
                ([0.1, 0.0, 1.0], [187.13679368799998, 118.697908]),
                ([0.0, 0.1, 0.5], [161.21248, 170.3966270336]),
            ],
        ),
        (
            "pincushion-160",
            [200.0, 200.0, 79.5, 59.5],
            [0.08, -0.02, 0.0, 0.0, 0.004],
            &[
                (
                    [-0.04417692504655579, -0.06692741631547006, 0.7373254399777591],
                    [67.50567423960993, 41.328766199933185],
                ),
                (
                    [0.21137978808423374, -0.04068977612825178, 1.4574859292101028],
                    [108.55642531750193, 53.90675264190689],
                ),
                (
                    [-0.21564232393906924, -0.11883529911459352, 0.9124240385672375],
                    [31.961571822684476, 33.30271540068762],
                ),
                (
                    [-0.03500156904941848, -0.1797183778910918, 1.0909109403513977],
                    [73.06869699705263, 26.477956280076775],
                ),
                (
                    [0.009757409938929484, -0.11483672200986433, 1.0987488022896845],
                    [81.27765377670944, 38.57847124765121],
                ),
                (
                    [0.2254690977909249, 0.16618575884956333, 0.6022783361606603],
                    [155.60052178422876, 115.59115876840491],
                ),
                (
                    [-0.12450037666762093, 0.13606752686335588, 0.4680519599720116],
                    [25.664663184825258, 118.33710021097221],
                ),
                ([0.1530195736310544, -0.1550377034029684, 0.8526685058477725], [115.57631147741813, 22.9478887505281]),
                (
                    [0.0882355999992967, 0.041511610126746146, 1.2404330972823157],
                    [93.73360200781991, 66.19638714138739],
                ),
                (
                    [0.10854295214056148, -0.008321402044150078, 1.2967439671209489],
                    [96.25026750275856, 58.21584743653357],
                ),
                (
                    [0.06481109142010177, 0.037873948195311424, 1.2029881739022716],
                    [90.27837034160822, 65.79860462157467],
                ),
                (
                    [0.23578035423079002, 0.06371000264362531, 0.5245254477777453],
                    [170.88085915103045, 84.19194177386912],
                ),
                ([0.0, 0.0, 1.0], [79.5, 59.5]),
                ([0.1, 0.0, 1.0], [99.51596008, 59.5]),
                ([0.0, 0.1, 0.5], [79.5, 99.62673024]),
            ],
        ),
    ];

    #[test]
    fn projection_matches_opencv_project_points() {
        // f32 projection against OpenCV's f64, after the half-pixel change of convention.
        const TOLERANCE_PX: f64 = 1e-3;
        for (name, k, d, points) in OPENCV_CASES {
            let (w, h) = if name.ends_with("640") {
                (640, 480)
            } else if name.ends_with("320") {
                (320, 240)
            } else {
                (160, 120)
            };
            let cam = Pinhole::from_opencv(k[0] as f32, k[1] as f32, k[2] as f32, k[3] as f32, w, h)
                .unwrap()
                .with_distortion(Distortion::plumb_bob(d.map(|v| v as f32)).unwrap());
            assert_eq!(cam.distortion().is_none(), d.iter().all(|&v| v == 0.0));
            for (p, uv) in points.iter() {
                let q = cam.project_unbounded(&Point3::new(p[0] as f32, p[1] as f32, p[2] as f32)).unwrap();
                let (du, dv) = (f64::from(q.x) - 0.5 - uv[0], f64::from(q.y) - 0.5 - uv[1]);
                assert!(du.abs() <= TOLERANCE_PX && dv.abs() <= TOLERANCE_PX, "{name} {p:?}: {du} {dv}");
            }
        }
    }

    #[test]
    fn opencv_convention_is_half_a_pixel_off() {
        let cam = Pinhole::from_opencv(800.0, 800.0, 319.5, 239.5, 640, 480).unwrap();
        assert_eq!((cam.cx(), cam.cy()), (320.0, 240.0));
        // The optical axis hits the centre of the image, the shared corner of the 4 middle pixels.
        let uv = cam.project(&Point3::new(0.0, 0.0, 1.0)).unwrap();
        assert_eq!((uv.x, uv.y), (320.0, 240.0));
        assert_eq!(Distortion::plumb_bob([0.0, f32::NAN, 0.0, 0.0, 0.0]), Err(CameraError::NonFinite));
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
