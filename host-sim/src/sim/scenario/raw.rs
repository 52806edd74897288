//! A scenario file as written: one serde struct per table, every key optional and no other key
//! accepted (`deny_unknown_fields`). The fields are in the order the messages list the keys;
//! integers are `i64` and choices are strings, so that [`super::parse`] checks their ranges
//! and names with the scenario's own messages.

use std::fmt;
use std::marker::PhantomData;

use serde::Deserialize;
use serde::de::value::MapAccessDeserializer;
use serde::de::{Deserializer, Error as _, IgnoredAny, MapAccess, SeqAccess, Visitor};
use toml::Value;

/// The whole file. `method`, `ga` and `target_filter` are read only to be refused with their
/// new places.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawScenario {
    pub seed: Option<i64>,
    pub duration_s: Option<f64>,
    pub frame_period_s: Option<f64>,
    pub method: Option<IgnoredAny>,
    #[serde(default, deserialize_with = "table")]
    pub camera: Option<RawCamera>,
    #[serde(default, deserialize_with = "table")]
    pub target: Option<RawTarget>,
    #[serde(default, deserialize_with = "table")]
    pub robot: Option<RawRobot>,
    pub ga: Option<IgnoredAny>,
    #[serde(default, deserialize_with = "table")]
    pub start: Option<RawStart>,
    /// Walked by the core's field names ([`super::tracker_table`]).
    pub tracker: Option<Value>,
    /// Read by [`super::acquisition::parse_occlusions`].
    pub occlusion: Option<Value>,
    #[serde(default, deserialize_with = "table")]
    pub servo: Option<RawServo>,
    pub target_filter: Option<IgnoredAny>,
    #[serde(default, deserialize_with = "table")]
    pub render: Option<RawRender>,
}

/// A light file: a `[render]` table and nothing else.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawLightFile {
    #[serde(default, deserialize_with = "table")]
    pub render: Option<RawRender>,
}

/// `[camera]`.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCamera {
    pub width: Option<i64>,
    pub height: Option<i64>,
    pub fx: Option<f64>,
    pub fy: Option<f64>,
    pub cx: Option<f64>,
    pub cy: Option<f64>,
    pub baseline_m: Option<f64>,
    pub noise_std: Option<f64>,
    pub supersample: Option<i64>,
}

/// `[target]`.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTarget {
    pub size_m: Option<Floats<3>>,
    pub face_hues_deg: Option<Floats<6>>,
    pub distance_m: Option<f64>,
    pub amplitude_deg: Option<f64>,
    pub omega_rad_s: Option<f64>,
    pub yaw0_deg: Option<f64>,
    /// Read by [`super::acquisition::parse_placement`].
    pub placement: Option<Value>,
    pub conveyor_speed_m_s: Option<f64>,
    pub conveyor_travel_m: Option<f64>,
    pub conveyor_accel_m_s2: Option<f64>,
    pub conveyor_dwell_s: Option<f64>,
    pub conveyor_direction: Option<Floats<3>>,
    pub conveyor_direction_frame: Option<String>,
    pub conveyor_start: Option<String>,
    pub random_amplitude_m: Option<f64>,
    pub random_amplitude_deg: Option<f64>,
    pub random_omega_rad_s: Option<f64>,
}

/// `[robot]`.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRobot {
    pub motion: Option<String>,
    pub omega_rad_s: Option<f64>,
    pub amplitude_m: Option<f64>,
    pub amplitude_deg: Option<f64>,
}

/// `[servo]`.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawServo {
    pub desired_t_m: Option<Floats<3>>,
    pub desired_q_xyzw: Option<Floats<4>>,
    pub gain: Option<f64>,
    pub max_speed_m_s: Option<f64>,
    pub max_rot_speed_rad_s: Option<f64>,
    pub max_accel_m_s2: Option<f64>,
    pub max_rot_accel_rad_s2: Option<f64>,
    pub delay_frames: Option<i64>,
}

/// `[start]`.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStart {
    /// Read by [`super::acquisition::parse_initial`].
    pub initial: Option<Value>,
    pub delay_s: Option<f64>,
}

/// `[render]`, in the order of [`crate::sim::render::Light`]'s fields.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRender {
    pub light_dir_cam: Option<Floats<3>>,
    pub ambient: Option<f64>,
    pub diffuse: Option<f64>,
    pub albedo_saturation: Option<f64>,
    pub specular: Option<f64>,
    pub shininess: Option<f64>,
    pub shadow_frame: Option<String>,
    pub shadow_normal: Option<Floats<3>>,
    pub shadow_offset_m: Option<f64>,
    pub shadow_width_m: Option<f64>,
    pub tone_curve: Option<String>,
    pub tone_exposure: Option<f64>,
    pub white_balance: Option<Floats<3>>,
    pub chroma_noise_std: Option<f64>,
    pub exposure_s: Option<f64>,
    pub blur_samples: Option<i64>,
    pub jpeg_quality: Option<i64>,
}

/// An array of exactly `N` numbers (integers read as floats). A wrong length is refused
/// before the elements' types are looked at: `expected 3 values, got 2`.
#[derive(Clone, Copy)]
pub(super) struct Floats<const N: usize>(pub [f64; N]);

impl<'de, const N: usize> Deserialize<'de> for Floats<N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_seq(FloatsVisitor::<N>(PhantomData))
    }
}

struct FloatsVisitor<const N: usize>(PhantomData<[f64; N]>);

impl<'de, const N: usize> Visitor<'de> for FloatsVisitor<N> {
    type Value = Floats<N>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "an array of {N} numbers")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Floats<N>, A::Error> {
        let wrong_length = |n: usize| A::Error::custom(format!("expected {N} values, got {n}"));
        if let Some(n) = seq.size_hint().filter(|n| *n != N) {
            return Err(wrong_length(n));
        }
        let mut out = [0.0; N];
        let mut n = 0;
        while let Some(x) = seq.next_element::<f64>()? {
            if let Some(o) = out.get_mut(n) {
                *o = x;
            }
            n += 1;
        }
        if n == N { Ok(Floats(out)) } else { Err(wrong_length(n)) }
    }
}

/// A present table key: its struct, read from a TOML table only (a derived struct alone would
/// also take an array of its fields' values).
fn table<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<Option<T>, D::Error> {
    d.deserialize_map(TableVisitor(PhantomData)).map(Some)
}

struct TableVisitor<T>(PhantomData<T>);

impl<'de, T: Deserialize<'de>> Visitor<'de> for TableVisitor<T> {
    type Value = T;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a table")
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
        T::deserialize(MapAccessDeserializer::new(map))
    }
}
