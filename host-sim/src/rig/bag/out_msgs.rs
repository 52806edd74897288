//! The ROS 2 messages of the results bag ([`super::write_mcap`]), in CDR ([`super::cdr`]), with
//! their `ros2msg` schema texts (the ROS 2 Humble to Jazzy definitions, dependencies included).

use super::cdr::Writer;
use super::msgs::{HEADER, Header, TIME, TransformStamped, schema, write_header, write_tf_message};

/// A pose: position x, y, z (m) and orientation x, y, z, w.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Position (m).
    pub position: [f64; 3],
    /// Orientation quaternion x, y, z, w.
    pub orientation: [f64; 4],
}

impl Pose {
    /// The identity pose.
    pub const IDENTITY: Pose = Pose { position: [0.0; 3], orientation: [0.0, 0.0, 0.0, 1.0] };

    fn write(&self, w: &mut Writer) {
        for v in self.position.iter().chain(&self.orientation) {
            w.f64(*v);
        }
    }
}

/// Encodes a `geometry_msgs/PoseWithCovarianceStamped` (covariance row-major 6 × 6: x, y, z,
/// rotation about x, y, z).
pub fn write_pose_with_covariance(header: &Header, pose: &Pose, covariance: &[f64; 36]) -> Vec<u8> {
    let mut w = Writer::new();
    write_header(&mut w, header);
    pose.write(&mut w);
    for v in covariance {
        w.f64(*v);
    }
    w.finish()
}

/// `diagnostic_msgs/DiagnosticStatus` levels.
pub mod level {
    /// `OK`.
    pub const OK: u8 = 0;
    /// `WARN`.
    pub const WARN: u8 = 1;
}

/// One `diagnostic_msgs/DiagnosticStatus`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DiagnosticStatus {
    /// [`level`].
    pub level: u8,
    /// Name of the component.
    pub name: String,
    /// Human-readable status.
    pub message: String,
    /// Hardware id (empty).
    pub hardware_id: String,
    /// Key-value pairs.
    pub values: Vec<(String, String)>,
}

/// Encodes a `diagnostic_msgs/DiagnosticArray`.
pub fn write_diagnostic_array(header: &Header, status: &[DiagnosticStatus]) -> Vec<u8> {
    let mut w = Writer::new();
    write_header(&mut w, header);
    w.u32(u32::try_from(status.len()).unwrap_or(0));
    for s in status {
        w.u8(s.level);
        for text in [&s.name, &s.message, &s.hardware_id] {
            w.string(text);
        }
        w.u32(u32::try_from(s.values.len()).unwrap_or(0));
        for (k, v) in &s.values {
            w.string(k);
            w.string(v);
        }
    }
    w.finish()
}

/// Encodes a `geometry_msgs/TwistStamped`: linear (m/s) and angular (rad/s) velocity.
pub fn write_twist_stamped(header: &Header, linear: [f64; 3], angular: [f64; 3]) -> Vec<u8> {
    let mut w = Writer::new();
    write_header(&mut w, header);
    for v in linear.iter().chain(&angular) {
        w.f64(*v);
    }
    w.finish()
}

/// Encodes a `tf2_msgs/TFMessage`.
pub fn write_tf(transforms: &[TransformStamped]) -> Vec<u8> {
    write_tf_message(transforms)
}

/// `visualization_msgs/Marker` types and actions used.
pub mod marker {
    /// `TRIANGLE_LIST`.
    pub const TRIANGLE_LIST: i32 = 11;
    /// `ADD`.
    pub const ADD: i32 = 0;
    /// `DELETE`.
    pub const DELETE: i32 = 2;
}

/// The fields of a `visualization_msgs/Marker` evorec sets (the texture, mesh and text ones
/// are written empty).
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// Header.
    pub header: Header,
    /// Namespace.
    pub ns: String,
    /// Id within the namespace.
    pub id: i32,
    /// [`marker`] type.
    pub kind: i32,
    /// [`marker`] action.
    pub action: i32,
    /// Pose of the points' frame in `header.frame_id`.
    pub pose: Pose,
    /// Scale (1 for a triangle list).
    pub scale: [f64; 3],
    /// Colour r, g, b, a (0..=1) where `colors` is empty.
    pub color: [f32; 4],
    /// Triangle corners (m).
    pub points: Vec<[f64; 3]>,
    /// One colour per point.
    pub colors: Vec<[f32; 4]>,
}

/// Encodes a `visualization_msgs/Marker` (lifetime 0: until replaced or deleted).
pub fn write_marker(m: &Marker) -> Vec<u8> {
    let mut w = Writer::new();
    write_header(&mut w, &m.header);
    w.string(&m.ns);
    for v in [m.id, m.kind, m.action] {
        w.i32(v);
    }
    m.pose.write(&mut w);
    for v in m.scale {
        w.f64(v);
    }
    let rgba = |w: &mut Writer, c: &[f32; 4]| c.iter().for_each(|v| w.f32(*v));
    rgba(&mut w, &m.color);
    w.i32(0); // lifetime.sec
    w.u32(0); // lifetime.nanosec
    w.u8(0); // frame_locked
    w.u32(u32::try_from(m.points.len()).unwrap_or(0));
    for p in &m.points {
        p.iter().for_each(|v| w.f64(*v));
    }
    w.u32(u32::try_from(m.colors.len()).unwrap_or(0));
    for c in &m.colors {
        rgba(&mut w, c);
    }
    w.string(""); // texture_resource
    write_header(&mut w, &Header { stamp_ns: 0, frame_id: String::new() }); // texture.header
    w.string(""); // texture.format
    w.bytes(&[]); // texture.data
    w.u32(0); // uv_coordinates
    w.string(""); // text
    w.string(""); // mesh_resource
    w.string(""); // mesh_file.filename
    w.bytes(&[]); // mesh_file.data
    w.u8(0); // mesh_use_embedded_materials
    w.finish()
}

const POSE: (&str, &str) = ("geometry_msgs/Pose", "Point position\nQuaternion orientation\n");
const POINT: (&str, &str) = ("geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n");
const QUATERNION: (&str, &str) = ("geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n");
const VECTOR3: (&str, &str) = ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n");
const COLOR: (&str, &str) = ("std_msgs/ColorRGBA", "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n");

/// The `ros2msg` schema of `geometry_msgs/msg/PoseWithCovarianceStamped`.
pub fn pose_with_covariance_schema() -> String {
    schema(
        "std_msgs/Header header\nPoseWithCovariance pose\n",
        &[
            HEADER,
            TIME,
            ("geometry_msgs/PoseWithCovariance", "Pose pose\nfloat64[36] covariance\n"),
            POSE,
            POINT,
            QUATERNION,
        ],
    )
}

/// The `ros2msg` schema of `diagnostic_msgs/msg/DiagnosticArray`.
pub fn diagnostic_array_schema() -> String {
    schema(
        "std_msgs/Header header\nDiagnosticStatus[] status\n",
        &[
            HEADER,
            TIME,
            (
                "diagnostic_msgs/DiagnosticStatus",
                "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\n\
                 byte level\nstring name\nstring message\nstring hardware_id\nKeyValue[] values\n",
            ),
            ("diagnostic_msgs/KeyValue", "string key\nstring value\n"),
        ],
    )
}

/// The `ros2msg` schema of `geometry_msgs/msg/TwistStamped`.
pub fn twist_stamped_schema() -> String {
    schema(
        "std_msgs/Header header\nTwist twist\n",
        &[HEADER, TIME, ("geometry_msgs/Twist", "Vector3 linear\nVector3 angular\n"), VECTOR3],
    )
}

/// The `ros2msg` schema of `tf2_msgs/msg/TFMessage`.
pub fn tf_schema() -> String {
    schema(
        "geometry_msgs/TransformStamped[] transforms\n",
        &[
            ("geometry_msgs/TransformStamped", "std_msgs/Header header\nstring child_frame_id\nTransform transform\n"),
            HEADER,
            TIME,
            ("geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation\n"),
            VECTOR3,
            QUATERNION,
        ],
    )
}

/// The `ros2msg` schema of `visualization_msgs/msg/Marker`.
pub fn marker_schema() -> String {
    schema(
        "int32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\nint32 LINE_STRIP=4\nint32 LINE_LIST=5\n\
         int32 CUBE_LIST=6\nint32 SPHERE_LIST=7\nint32 POINTS=8\nint32 TEXT_VIEW_FACING=9\nint32 MESH_RESOURCE=10\n\
         int32 TRIANGLE_LIST=11\nint32 ADD=0\nint32 MODIFY=0\nint32 DELETE=2\nint32 DELETEALL=3\n\
         std_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\ngeometry_msgs/Pose pose\n\
         geometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\nbuiltin_interfaces/Duration lifetime\n\
         bool frame_locked\ngeometry_msgs/Point[] points\nstd_msgs/ColorRGBA[] colors\nstring texture_resource\n\
         sensor_msgs/CompressedImage texture\nUVCoordinate[] uv_coordinates\nstring text\nstring mesh_resource\n\
         MeshFile mesh_file\nbool mesh_use_embedded_materials\n",
        &[
            HEADER,
            TIME,
            POSE,
            POINT,
            QUATERNION,
            VECTOR3,
            COLOR,
            ("builtin_interfaces/Duration", "int32 sec\nuint32 nanosec\n"),
            ("sensor_msgs/CompressedImage", "std_msgs/Header header\nstring format\nuint8[] data\n"),
            ("visualization_msgs/UVCoordinate", "float32 u\nfloat32 v\n"),
            ("visualization_msgs/MeshFile", "string filename\nuint8[] data\n"),
        ],
    )
}

/// Decoders of the results bag's messages (for tests and tools reading it back); each checks
/// that the message ends with its last field.
pub mod read {
    use super::{DiagnosticStatus, Marker, Pose};
    use crate::rig::bag::cdr::{Reader, Result};
    use crate::rig::bag::msgs::{Header, read_header};

    fn pose(r: &mut Reader<'_>) -> Result<Pose> {
        Ok(Pose { position: r.f64_array::<3>("pose.position")?, orientation: r.f64_array::<4>("pose.orientation")? })
    }

    fn rgba(r: &mut Reader<'_>, field: &str) -> Result<[f32; 4]> {
        Ok([r.f32(field)?, r.f32(field)?, r.f32(field)?, r.f32(field)?])
    }

    /// A `geometry_msgs/PoseWithCovarianceStamped`.
    ///
    /// # Errors
    /// A malformed message.
    pub fn pose_with_covariance(bytes: &[u8]) -> Result<(Header, Pose, [f64; 36])> {
        let mut r = Reader::new(bytes)?;
        let out = (read_header(&mut r)?, pose(&mut r)?, r.f64_array::<36>("pose.covariance")?);
        r.finish()?;
        Ok(out)
    }

    /// A `diagnostic_msgs/DiagnosticArray`.
    ///
    /// # Errors
    /// A malformed message.
    pub fn diagnostic_array(bytes: &[u8]) -> Result<(Header, Vec<DiagnosticStatus>)> {
        let mut r = Reader::new(bytes)?;
        let header = read_header(&mut r)?;
        let n = r.len("status", 17)?;
        let mut status = Vec::with_capacity(n);
        for _ in 0..n {
            let level = r.u8("status.level")?;
            let (name, message, hardware_id) =
                (r.string("status.name")?, r.string("status.message")?, r.string("status.hardware_id")?);
            let m = r.len("status.values", 8)?;
            let values = (0..m)
                .map(|_| Ok((r.string("status.values.key")?, r.string("status.values.value")?)))
                .collect::<Result<Vec<_>>>()?;
            status.push(DiagnosticStatus { level, name, message, hardware_id, values });
        }
        r.finish()?;
        Ok((header, status))
    }

    /// A `geometry_msgs/TwistStamped`: header, linear, angular.
    ///
    /// # Errors
    /// A malformed message.
    pub fn twist_stamped(bytes: &[u8]) -> Result<(Header, [f64; 3], [f64; 3])> {
        let mut r = Reader::new(bytes)?;
        let out = (read_header(&mut r)?, r.f64_array::<3>("twist.linear")?, r.f64_array::<3>("twist.angular")?);
        r.finish()?;
        Ok(out)
    }

    /// A `visualization_msgs/Marker` (the lifetime, texture, mesh and text fields read past).
    ///
    /// # Errors
    /// A malformed message.
    pub fn marker(bytes: &[u8]) -> Result<Marker> {
        let mut r = Reader::new(bytes)?;
        let header = read_header(&mut r)?;
        let ns = r.string("ns")?;
        let (id, kind, action) = (r.i32("id")?, r.i32("type")?, r.i32("action")?);
        let (pose, scale, color) = (pose(&mut r)?, r.f64_array::<3>("scale")?, rgba(&mut r, "color")?);
        r.i32("lifetime.sec")?;
        r.u32("lifetime.nanosec")?;
        r.u8("frame_locked")?;
        let n = r.len("points", 24)?;
        let points = (0..n).map(|_| r.f64_array::<3>("points")).collect::<Result<Vec<_>>>()?;
        let n = r.len("colors", 16)?;
        let colors = (0..n).map(|_| rgba(&mut r, "colors")).collect::<Result<Vec<_>>>()?;
        r.string("texture_resource")?;
        read_header(&mut r)?;
        r.string("texture.format")?;
        r.bytes("texture.data")?;
        let n = r.len("uv_coordinates", 8)?;
        for _ in 0..2 * n {
            r.f32("uv_coordinates")?;
        }
        for field in ["text", "mesh_resource", "mesh_file.filename"] {
            r.string(field)?;
        }
        r.bytes("mesh_file.data")?;
        r.u8("mesh_use_embedded_materials")?;
        r.finish()?;
        Ok(Marker { header, ns, id, kind, action, pose, scale, color, points, colors })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn h(frame: &str) -> Header {
        Header { stamp_ns: 1_700_000_000_033_333_248, frame_id: frame.into() }
    }

    #[test]
    fn results_bag_messages_read_back() {
        let pose = Pose { position: [0.1, -0.2, 0.9], orientation: [0.0, 0.6, 0.0, 0.8] };
        let cov = std::array::from_fn(|i| i as f64 * 1e-6);
        assert_eq!(
            read::pose_with_covariance(&write_pose_with_covariance(&h("cam"), &pose, &cov)).unwrap(),
            (h("cam"), pose, cov)
        );
        let s = DiagnosticStatus {
            level: level::WARN,
            name: "evorec: block".into(),
            message: "searching".into(),
            hardware_id: String::new(),
            values: vec![("fitness".into(), "0.25".into())],
        };
        assert_eq!(
            read::diagnostic_array(&write_diagnostic_array(&h(""), std::slice::from_ref(&s))).unwrap(),
            (h(""), vec![s])
        );
        let t = read::twist_stamped(&write_twist_stamped(&h("base"), [1.0, 2.0, 3.0], [4.0, 5.0, 6.0])).unwrap();
        assert_eq!(t, (h("base"), [1.0, 2.0, 3.0], [4.0, 5.0, 6.0]));
        let m = Marker {
            header: h("cam"),
            ns: "evorec".into(),
            id: 0,
            kind: marker::TRIANGLE_LIST,
            action: marker::ADD,
            pose,
            scale: [1.0; 3],
            color: [1.0; 4],
            points: vec![[0.05, 0.075, 0.1]; 3],
            colors: vec![[1.0, 0.0, 0.0, 1.0]; 3],
        };
        assert_eq!(read::marker(&write_marker(&m)).unwrap(), m);
        // A byte too many is refused.
        let mut bytes = write_twist_stamped(&h("base"), [0.0; 3], [0.0; 3]);
        bytes.push(0);
        assert!(read::twist_stamped(&bytes).unwrap_err().to_string().contains("1 bytes left"));
    }
}
