//! Payload layouts: every field little-endian, every `f32` as its raw bits.

use evorec_core::pose::Psi;
use evorec_core::status::Status;
use evorec_core::tracker::Estimate;
use evorec_core::tuning::{FIELDS, Kind, TABLE_ID, Tuning, Value};

use super::{DecodeError, Done, DropCounts, FRAME_FIXED_LEN, MAX_SMALL_PAYLOAD, Message, MsgType, Setup};

/// A frame's left and right images.
pub(super) type Images<'m> = (&'m [u8], &'m [u8]);

/// Writes the payload (without images) into `out`; returns its length and a frame's images.
pub(super) fn encode_payload<'m>(
    message: &Message<'m>,
    out: &mut [u8; MAX_SMALL_PAYLOAD],
) -> (usize, Option<Images<'m>>) {
    let mut e = Enc::new(out);
    let mut images = None;
    match *message {
        Message::Config(ref s) => encode_setup(&mut e, s),
        Message::Frame(ref f) => {
            e.u16(f.width);
            e.u16(f.height);
            e.u64(f.joints.time_us);
            e.f32s(&f.joints.q);
            e.f32s(&f.joints.qd);
            images = Some((f.left, f.right));
        }
        Message::Estimate(ref est) => {
            e.f32s(&est.psi.0);
            e.f32(est.fitness);
            e.f32s(&est.camera_fitness);
            e.u32(est.generation);
            e.u8(est.status.code());
            e.f32s(&est.target_measurement.0);
        }
        Message::End | Message::Rejected => {}
        Message::Ack(status) => e.u32(status),
        Message::Done(ref d) => {
            e.u32(d.frames);
            e.u32(d.published);
            e.u32(d.rejected);
            e.u32(d.stack_used_bytes);
            e.u32(d.stack_size_bytes);
            for c in d.drops.to_array() {
                e.u32(c);
            }
        }
        Message::Error(code) => e.u32(code),
    }
    debug_assert!(
        message.kind().fixed_payload_len().unwrap_or(FRAME_FIXED_LEN) == e.pos,
        "payload layout and size constant disagree"
    );
    (e.pos, images)
}

fn encode_setup(e: &mut Enc<'_>, s: &Setup) {
    e.f32s(&[s.fx, s.fy, s.cx, s.cy]);
    e.u16(s.width);
    e.u16(s.height);
    e.f32(s.baseline_m);
    e.f32s(&s.block_size_m);
    e.f32s(&s.face_hues_deg);
    e.f32s(&s.flange_to_camera_t);
    e.f32s(&s.flange_to_camera_q);
    e.f32s(&s.search_min);
    e.f32s(&s.search_max);
    e.u64(s.seed);
    encode_tuning(e, &s.tuning);
    e.f32s(&s.initial_psi.0);
    e.f32s(&s.initial_spread);
}

/// The tuning as the core's table lists it: fingerprint, count, then each field's 4 bytes.
fn encode_tuning(e: &mut Enc<'_>, t: &Tuning) {
    e.u32(TABLE_ID);
    e.u16(FIELDS.len() as u16);
    e.u16(0);
    for f in &FIELDS {
        e.u32(match ((f.get)(t), f.kind) {
            (Value::Real(x), _) => x.to_bits(),
            (Value::Int(n), _) => n,
            (Value::Name(name), Kind::Name(names)) => names.iter().position(|c| *c == name).unwrap_or(0) as u32,
            (Value::Name(_), _) => 0,
        });
    }
}

/// The tuning sent by [`encode_tuning`], set field by field through the core's table; a
/// different table (fingerprint or count), an unknown name index or an integer too large for
/// its field is [`DecodeError::BadValue`]. The values' rules are checked when the tracker is
/// built ([`crate::setup::SetupError::Tracker`]).
fn decode_tuning(d: &mut Dec<'_>) -> Result<Tuning, DecodeError> {
    let (id, count, _reserved) = (d.u32(), d.u16(), d.u16());
    if id != TABLE_ID || usize::from(count) != FIELDS.len() {
        return Err(DecodeError::BadValue);
    }
    let mut t = Tuning::DEFAULT;
    for f in &FIELDS {
        let raw = d.u32();
        let value = match f.kind {
            Kind::Real => Value::Real(f32::from_bits(raw)),
            Kind::Int => Value::Int(raw),
            Kind::Name(names) => Value::Name(names.get(raw as usize).copied().ok_or(DecodeError::BadValue)?),
        };
        (f.set)(&mut t, value).map_err(|_| DecodeError::BadValue)?;
    }
    Ok(t)
}

fn decode_setup(d: &mut Dec<'_>) -> Result<Setup, DecodeError> {
    let [fx, fy, cx, cy] = d.f32s::<4>();
    let width = d.u16();
    let height = d.u16();
    let baseline_m = d.f32();
    let block_size_m = d.f32s();
    let face_hues_deg = d.f32s();
    let flange_to_camera_t = d.f32s();
    let flange_to_camera_q = d.f32s();
    let search_min = d.f32s();
    let search_max = d.f32s();
    let seed = d.u64();
    let tuning = decode_tuning(d)?;
    let initial_psi = Psi(d.f32s());
    let initial_spread = d.f32s();
    Ok(Setup {
        fx,
        fy,
        cx,
        cy,
        width,
        height,
        baseline_m,
        block_size_m,
        face_hues_deg,
        flange_to_camera_t,
        flange_to_camera_q,
        search_min,
        search_max,
        seed,
        tuning,
        initial_psi,
        initial_spread,
    })
}

/// Decodes a non-frame payload whose size the header already checked.
pub(super) fn decode_small(kind: MsgType, payload: &[u8]) -> Result<Message<'static>, DecodeError> {
    let mut d = Dec::new(payload);
    Ok(match kind {
        MsgType::Config => Message::Config(decode_setup(&mut d)?),
        MsgType::Estimate => {
            let psi = Psi(d.f32s());
            let fitness = d.f32();
            let camera_fitness = d.f32s();
            let generation = d.u32();
            let status = Status::from_code(d.u8()).ok_or(DecodeError::BadValue)?;
            // The filter's measurement travels whole: its orientation is the best individual's,
            // which differs from ψ's (the mean of the best's neighbours).
            let target_measurement = Psi(d.f32s());
            // The capture time is not in the payload; the host fills it in from its frame.
            Message::Estimate(Estimate {
                psi,
                fitness,
                camera_fitness,
                generation,
                capture_time_us: 0,
                status,
                target_measurement,
            })
        }
        MsgType::End => Message::End,
        MsgType::Ack => Message::Ack(d.u32()),
        MsgType::Rejected => Message::Rejected,
        MsgType::Done => Message::Done(Done {
            frames: d.u32(),
            published: d.u32(),
            rejected: d.u32(),
            stack_used_bytes: d.u32(),
            stack_size_bytes: d.u32(),
            drops: DropCounts::from_array(core::array::from_fn(|_| d.u32())),
        }),
        MsgType::Error => Message::Error(d.u32()),
        MsgType::Frame => return Err(DecodeError::BadLength { kind, len: payload.len() as u32 }),
    })
}

/// Little-endian writer into a buffer whose size the caller has checked (bytes past the end
/// are dropped; `pos` still counts them, which the size `debug_assert` catches).
pub(super) struct Enc<'a> {
    buf: &'a mut [u8],
    pos: usize,
}

impl<'a> Enc<'a> {
    pub(super) fn new(buf: &'a mut [u8]) -> Self {
        Self { buf, pos: 0 }
    }
    pub(super) fn bytes(&mut self, b: &[u8]) {
        let end = self.pos + b.len();
        if let Some(dst) = self.buf.get_mut(self.pos..end) {
            dst.copy_from_slice(b);
        }
        self.pos = end;
    }
    pub(super) fn u8(&mut self, v: u8) {
        self.bytes(&[v]);
    }
    pub(super) fn u16(&mut self, v: u16) {
        self.bytes(&v.to_le_bytes());
    }
    pub(super) fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    pub(super) fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    pub(super) fn f32(&mut self, v: f32) {
        self.u32(v.to_bits());
    }
    pub(super) fn f32s(&mut self, v: &[f32]) {
        for x in v {
            self.f32(*x);
        }
    }
}

/// Little-endian reader over a buffer whose size the caller has checked (reads past the end
/// give zeros).
pub(super) struct Dec<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Dec<'a> {
    pub(super) fn new(buf: &'a [u8]) -> Self {
        Self { buf, pos: 0 }
    }
    pub(super) fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        if let Some(src) = self.buf.get(self.pos..self.pos + N) {
            out.copy_from_slice(src);
        }
        self.pos += N;
        out
    }
    pub(super) fn u8(&mut self) -> u8 {
        u8::from_le_bytes(self.take())
    }
    pub(super) fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.take())
    }
    pub(super) fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    pub(super) fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }
    pub(super) fn f32(&mut self) -> f32 {
        f32::from_bits(self.u32())
    }
    pub(super) fn f32s<const N: usize>(&mut self) -> [f32; N] {
        core::array::from_fn(|_| self.f32())
    }
}
