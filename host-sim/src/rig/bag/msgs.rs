//! The ROS 2 messages evorec reads from a bag, in CDR ([`super::cdr`]), their writers (for test
//! bags) and the `ros2msg` schema texts (those of the results bag are in [`super::out_msgs`]).

use super::cdr::{Reader, Result, Writer};

/// `builtin_interfaces/Time` as nanoseconds since the epoch (negative stamps are refused by
/// the callers, which need increasing capture times).
pub type StampNs = i64;

/// `std_msgs/Header`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Header {
    /// `stamp` in nanoseconds.
    pub stamp_ns: StampNs,
    /// `frame_id`.
    pub frame_id: String,
}

fn header(r: &mut Reader<'_>) -> Result<Header> {
    let sec = r.i32("header.stamp.sec")?;
    let nanosec = r.u32("header.stamp.nanosec")?;
    let frame_id = r.string("header.frame_id")?;
    Ok(Header { stamp_ns: i64::from(sec) * 1_000_000_000 + i64::from(nanosec), frame_id })
}

/// Writes a `std_msgs/Header`.
pub fn write_header(w: &mut Writer, h: &Header) {
    w.i32(i32::try_from(h.stamp_ns.div_euclid(1_000_000_000)).unwrap_or(i32::MAX));
    w.u32(u32::try_from(h.stamp_ns.rem_euclid(1_000_000_000)).unwrap_or(0));
    w.string(&h.frame_id);
}

/// `sensor_msgs/Image`, its pixels borrowed from the message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image<'a> {
    /// Header.
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// `rgb8`, `bgr8`, `bayer_rggb8`, …
    pub encoding: String,
    /// Multi-byte pixels big-endian (irrelevant for the 8-bit encodings evorec reads).
    pub is_bigendian: u8,
    /// Bytes per row.
    pub step: u32,
    /// `step × height` bytes.
    pub data: &'a [u8],
}

/// Decodes a `sensor_msgs/Image`.
///
/// # Errors
/// A malformed message.
pub fn image(bytes: &[u8]) -> Result<Image<'_>> {
    let mut r = Reader::new(bytes)?;
    let header = header(&mut r)?;
    let height = r.u32("height")?;
    let width = r.u32("width")?;
    let encoding = r.string("encoding")?;
    let is_bigendian = r.u8("is_bigendian")?;
    let step = r.u32("step")?;
    let data = r.bytes("data")?;
    Ok(Image { header, height, width, encoding, is_bigendian, step, data })
}

/// Encodes a `sensor_msgs/Image` (for tests and tools that write bags).
pub fn write_image(img: &Image<'_>) -> Vec<u8> {
    let mut w = Writer::new();
    write_header(&mut w, &img.header);
    w.u32(img.height);
    w.u32(img.width);
    w.string(&img.encoding);
    w.u8(img.is_bigendian);
    w.u32(img.step);
    w.bytes(img.data);
    w.finish()
}

/// `sensor_msgs/CompressedImage`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CompressedImage<'a> {
    /// Header.
    pub header: Header,
    /// `png`, `jpeg`, or image_transport's `bgr8; jpeg compressed bgr8`.
    pub format: String,
    /// The compressed file's bytes.
    pub data: &'a [u8],
}

/// Decodes a `sensor_msgs/CompressedImage`.
///
/// # Errors
/// A malformed message.
pub fn compressed_image(bytes: &[u8]) -> Result<CompressedImage<'_>> {
    let mut r = Reader::new(bytes)?;
    let header = header(&mut r)?;
    let format = r.string("format")?;
    let data = r.bytes("data")?;
    Ok(CompressedImage { header, format, data })
}

/// Encodes a `sensor_msgs/CompressedImage`.
pub fn write_compressed_image(img: &CompressedImage<'_>) -> Vec<u8> {
    let mut w = Writer::new();
    write_header(&mut w, &img.header);
    w.string(&img.format);
    w.bytes(img.data);
    w.finish()
}

/// The part of `sensor_msgs/CameraInfo` evorec uses (binning and ROI are read past).
#[derive(Debug, Clone, PartialEq)]
pub struct CameraInfo {
    /// Header.
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// `plumb_bob`, …
    pub distortion_model: String,
    /// D.
    pub d: Vec<f64>,
    /// K, row-major 3×3.
    pub k: [f64; 9],
    /// R, row-major 3×3.
    pub r: [f64; 9],
    /// P, row-major 3×4.
    pub p: [f64; 12],
}

/// Decodes a `sensor_msgs/CameraInfo`.
///
/// # Errors
/// A malformed message.
pub fn camera_info(bytes: &[u8]) -> Result<CameraInfo> {
    let mut r = Reader::new(bytes)?;
    let header = header(&mut r)?;
    let height = r.u32("height")?;
    let width = r.u32("width")?;
    let distortion_model = r.string("distortion_model")?;
    let d = r.f64_seq("d")?;
    let k = r.f64_array::<9>("k")?;
    let rect = r.f64_array::<9>("r")?;
    let p = r.f64_array::<12>("p")?;
    Ok(CameraInfo { header, height, width, distortion_model, d, k, r: rect, p })
}

/// Encodes a `sensor_msgs/CameraInfo` (binning 0, empty ROI).
pub fn write_camera_info(c: &CameraInfo) -> Vec<u8> {
    let mut w = Writer::new();
    write_header(&mut w, &c.header);
    w.u32(c.height);
    w.u32(c.width);
    w.string(&c.distortion_model);
    w.u32(u32::try_from(c.d.len()).unwrap_or(0));
    for v in c.d.iter().chain(&c.k).chain(&c.r).chain(&c.p) {
        w.f64(*v);
    }
    for _ in 0..6 {
        w.u32(0); // binning_x, binning_y, roi x_offset, y_offset, height, width
    }
    w.u8(0); // roi.do_rectify
    w.finish()
}

/// `sensor_msgs/JointState` (efforts read past).
#[derive(Debug, Clone, PartialEq)]
pub struct JointState {
    /// Header.
    pub header: Header,
    /// Joint names.
    pub name: Vec<String>,
    /// Positions, one per name.
    pub position: Vec<f64>,
    /// Velocities: one per name, or empty.
    pub velocity: Vec<f64>,
}

/// Decodes a `sensor_msgs/JointState`.
///
/// # Errors
/// A malformed message.
pub fn joint_state(bytes: &[u8]) -> Result<JointState> {
    let mut r = Reader::new(bytes)?;
    let header = header(&mut r)?;
    let name = r.string_seq("name")?;
    let position = r.f64_seq("position")?;
    let velocity = r.f64_seq("velocity")?;
    Ok(JointState { header, name, position, velocity })
}

/// Encodes a `sensor_msgs/JointState` (no efforts).
pub fn write_joint_state(j: &JointState) -> Vec<u8> {
    let mut w = Writer::new();
    write_header(&mut w, &j.header);
    w.u32(u32::try_from(j.name.len()).unwrap_or(0));
    for n in &j.name {
        w.string(n);
    }
    for seq in [&j.position, &j.velocity, &Vec::new()] {
        w.u32(u32::try_from(seq.len()).unwrap_or(0));
        for v in seq {
            w.f64(*v);
        }
    }
    w.finish()
}

/// `geometry_msgs/TransformStamped`.
#[derive(Debug, Clone, PartialEq)]
pub struct TransformStamped {
    /// Header (`frame_id` is the parent frame).
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// Translation x, y, z (m).
    pub translation: [f64; 3],
    /// Rotation x, y, z, w.
    pub rotation: [f64; 4],
}

/// Decodes a `tf2_msgs/TFMessage`.
///
/// # Errors
/// A malformed message.
pub fn tf_message(bytes: &[u8]) -> Result<Vec<TransformStamped>> {
    let mut r = Reader::new(bytes)?;
    let n = r.len("transforms", 4 + 4 + 4 + 4 + 56)?;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let header = header(&mut r)?;
        let child_frame_id = r.string("child_frame_id")?;
        let translation = r.f64_array::<3>("transform.translation")?;
        let rotation = r.f64_array::<4>("transform.rotation")?;
        out.push(TransformStamped { header, child_frame_id, translation, rotation });
    }
    Ok(out)
}

/// Encodes a `tf2_msgs/TFMessage`.
pub fn write_tf_message(transforms: &[TransformStamped]) -> Vec<u8> {
    let mut w = Writer::new();
    w.u32(u32::try_from(transforms.len()).unwrap_or(0));
    for t in transforms {
        write_header(&mut w, &t.header);
        w.string(&t.child_frame_id);
        for v in t.translation.iter().chain(&t.rotation) {
            w.f64(*v);
        }
    }
    w.finish()
}

/// Decodes a `std_msgs/String`.
///
/// # Errors
/// A malformed message.
pub fn string(bytes: &[u8]) -> Result<String> {
    Reader::new(bytes)?.string("data")
}

/// Encodes a `std_msgs/String`.
pub fn write_string(s: &str) -> Vec<u8> {
    let mut w = Writer::new();
    w.string(s);
    w.finish()
}

/// Decodes a `std_msgs/Header` (for decoders of other messages, e.g. in tests).
///
/// # Errors
/// A malformed message.
pub fn read_header(r: &mut Reader<'_>) -> Result<Header> {
    header(r)
}

const SEPARATOR: &str = "================================================================================\n";

/// A `ros2msg` schema: the message's text, then each dependency's after a separator line.
pub fn schema(top: &str, deps: &[(&str, &str)]) -> String {
    let mut s = top.to_owned();
    for (name, text) in deps {
        s.push('\n');
        s.push_str(SEPARATOR);
        s.push_str("MSG: ");
        s.push_str(name);
        s.push('\n');
        s.push_str(text);
    }
    s
}

/// `builtin_interfaces/Time`.
pub const TIME: (&str, &str) = ("builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n");
/// `std_msgs/Header`.
pub const HEADER: (&str, &str) = ("std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id\n");

/// The `ros2msg` schema of `std_msgs/msg/String`.
pub const STRING_SCHEMA: &str = "string data\n";

/// The `ros2msg` schemas of the messages a test bag holds (name, text).
pub fn input_schemas() -> Vec<(&'static str, String)> {
    vec![
        (
            "sensor_msgs/msg/Image",
            schema(
                "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data\n",
                &[HEADER, TIME],
            ),
        ),
        (
            "sensor_msgs/msg/CompressedImage",
            schema("std_msgs/Header header\nstring format\nuint8[] data\n", &[HEADER, TIME]),
        ),
        (
            "sensor_msgs/msg/CameraInfo",
            schema(
                "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\nRegionOfInterest roi\n",
                &[
                    HEADER,
                    TIME,
                    (
                        "sensor_msgs/RegionOfInterest",
                        "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n",
                    ),
                ],
            ),
        ),
        (
            "sensor_msgs/msg/JointState",
            schema(
                "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n",
                &[HEADER, TIME],
            ),
        ),
        (
            "tf2_msgs/msg/TFMessage",
            schema(
                "geometry_msgs/TransformStamped[] transforms\n",
                &[
                    (
                        "geometry_msgs/TransformStamped",
                        "std_msgs/Header header\nstring child_frame_id\nTransform transform\n",
                    ),
                    HEADER,
                    TIME,
                    ("geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation\n"),
                    ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"),
                    ("geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"),
                ],
            ),
        ),
        ("std_msgs/msg/String", STRING_SCHEMA.to_owned()),
    ]
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn h(ns: i64, frame: &str) -> Header {
        Header { stamp_ns: ns, frame_id: frame.into() }
    }

    #[test]
    fn messages_round_trip() {
        let data = [1u8, 2, 3, 4, 5, 6];
        let img = Image {
            header: h(1_700_000_000_033_333_248, "cam"),
            height: 1,
            width: 2,
            encoding: "rgb8".into(),
            is_bigendian: 0,
            step: 6,
            data: &data,
        };
        assert_eq!(image(&write_image(&img)).unwrap(), img);
        let c = CompressedImage { header: h(5, "c"), format: "png".into(), data: &data };
        assert_eq!(compressed_image(&write_compressed_image(&c)).unwrap(), c);
        let info = CameraInfo {
            header: h(7, "cam"),
            height: 120,
            width: 160,
            distortion_model: "plumb_bob".into(),
            d: vec![0.1, 0.0, 0.0, 0.0, 0.0],
            k: [100.0, 0.0, 79.5, 0.0, 100.0, 59.5, 0.0, 0.0, 1.0],
            r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            p: [0.0; 12],
        };
        assert_eq!(camera_info(&write_camera_info(&info)).unwrap(), info);
        let j = JointState {
            header: h(9, ""),
            name: vec!["a".into(), "bb".into()],
            position: vec![0.5, -1.0],
            velocity: vec![],
        };
        assert_eq!(joint_state(&write_joint_state(&j)).unwrap(), j);
        let t = TransformStamped {
            header: h(0, "p"),
            child_frame_id: "c".into(),
            translation: [1.0, 2.0, 3.0],
            rotation: [0.0, 0.0, 0.0, 1.0],
        };
        assert_eq!(tf_message(&write_tf_message(&[t.clone(), t.clone()])).unwrap(), vec![t.clone(), t]);
        assert_eq!(string(&write_string("<robot/>")).unwrap(), "<robot/>");
    }

    proptest::proptest! {
        /// Any bytes: every decoder returns a value or an error, never panics.
        #[test]
        fn decoders_never_panic(mut bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..400), le in proptest::bool::ANY) {
            if le && bytes.len() >= 2 {
                bytes[0] = 0;
                bytes[1] = 1;
            }
            let _ = image(&bytes);
            let _ = compressed_image(&bytes);
            let _ = camera_info(&bytes);
            let _ = joint_state(&bytes);
            let _ = tf_message(&bytes);
            let _ = string(&bytes);
        }
    }

    #[test]
    fn a_truncated_message_names_the_field() {
        let j = JointState { header: h(9, ""), name: vec!["a".into()], position: vec![0.5], velocity: vec![] };
        let bytes = write_joint_state(&j);
        let err = joint_state(&bytes[..bytes.len() - 10]).unwrap_err();
        assert_eq!(err.field, "position", "{err}");
    }
}
