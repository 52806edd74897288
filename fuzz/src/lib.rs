//! The bodies of evorec's fuzz targets: one function per target, taking the fuzzer's bytes.
//!
//! `fuzz_targets/*.rs` hand libFuzzer's input to these functions; the workspace test
//! `tests/tests/fuzz_corpora.rs` includes this same file and replays every input kept under
//! `fuzz/corpus/<target>/` and `fuzz/artifacts/<target>/` through them without libFuzzer, so a
//! fixed crash stays fixed in `cargo test --workspace`.
//!
//! A body returns normally for every input: invalid input must give a typed error. Every
//! `assert!` states a property that holds for all inputs (a round trip, an unchanged tracker
//! after a refused step, a finite estimate), so a failing one is a finding like a panic.
//!
//! This file only uses `std`, `evorec_core`, `evorec_firmware` (feature `host`), `evorec_sim`
//! and `nalgebra`, so it compiles in the fuzz crate and in the workspace's test crate alike.

use std::io::Cursor;

use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::ga::SearchSpace;
use evorec_core::image::Rgb565Image;
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::tracker::{Feedforward, JointSample, StereoFrame, TrackerConfig};
use evorec_firmware::host::IoLink;
use evorec_firmware::link_board::{StackUsage, serve};
use evorec_firmware::protocol::{
    ByteSource, Envelope, LinkReader, Message, ReadError, SliceSource, VecSink, decode, encode_to_vec, max_encoded_len,
    read_message, write_message_with_flags,
};
use evorec_firmware::{FirmwareTracker, IMAGE_BYTES};

/// Every target: its name (the directory under `fuzz/corpus/`) and its body.
pub const TARGETS: &[(&str, fn(&[u8]))] = &[
    ("link_decode", link_decode),
    ("firmware_serve", firmware_serve),
    ("host_replies", host_replies),
    ("tracker_step", tracker_step),
    ("scenario_toml", scenario_toml),
    ("sequence_files", sequence_files),
];

/// Encodes one message with header `flags`.
fn encode(env: &Envelope<'_>, flags: u16) -> Vec<u8> {
    let mut sink = VecSink::default();
    let written = write_message_with_flags(&mut sink, env, flags);
    assert!(written.is_ok(), "a decoded message must encode again: {written:?}");
    assert!(sink.0.len() <= max_encoded_len(&env.message), "max_encoded_len is too small");
    sink.0
}

/// Decodes every message of the stream `rx` (dropping damaged ones and reading on, as the
/// firmware and the host do) until the input ends; checks that each accepted message encodes
/// again and that decoding that encoding gives the same bytes once more. Returns the last
/// message accepted, re-encoded.
fn decode_all<S: ByteSource>(rx: &mut LinkReader<S>, frames: bool) -> Option<Vec<u8>> {
    let (mut left, mut right) =
        if frames { (vec![0u8; IMAGE_BYTES], vec![0u8; IMAGE_BYTES]) } else { (vec![], vec![]) };
    let (mut l2, mut r2) = (vec![0u8; IMAGE_BYTES], vec![0u8; IMAGE_BYTES]);
    let mut last = None;
    loop {
        let env = match read_message(rx, &mut left, &mut right) {
            Ok(env) => env,
            Err(ReadError::Decode(_)) => continue,
            Err(ReadError::Link(_)) => return last,
        };
        assert!(frames || !matches!(env.message, Message::Frame(_)), "a frame was decoded into empty buffers");
        let once = encode(&env, rx.last_flags());
        let again = decode(&once, &mut l2, &mut r2);
        let Ok((env2, used2)) = again else { panic!("re-encoded message does not decode: {again:?}") };
        assert_eq!(used2, once.len());
        assert_eq!(encode(&env2, rx.last_flags()), once, "decode∘encode is not the identity on encoded messages");
        last = Some(once);
    }
}

/// A well-formed message appended to every input (the resynchronisation property).
fn marker() -> Vec<u8> {
    let env = Envelope { sequence: 0x5EC5, capture_time_us: 77, message: Message::Rejected };
    let bytes = encode_to_vec(&env);
    let Ok(bytes) = bytes else { panic!("marker does not encode: {bytes:?}") };
    bytes
}

/// The firmware's link decoder (the COBS reader over a byte stream, frames read into buffers
/// of the firmware's size): decodes every message of the input, dropping damaged ones as the
/// firmware does. Every accepted message must encode again, and decoding that encoding must
/// give the same bytes once more. And after any input, a well-formed message appended to it
/// is decoded (resynchronisation): it is the last message accepted.
pub fn link_decode(data: &[u8]) {
    let mut rx = LinkReader::new(SliceSource::new(data));
    decode_all(&mut rx, true);
    let mut stream = data.to_vec();
    let marker = marker();
    stream.extend(&marker);
    let mut rx = LinkReader::new(SliceSource::new(&stream));
    assert_eq!(decode_all(&mut rx, true), Some(marker), "the message after the input was not decoded");
}

/// The firmware's whole conversation ([`serve`]: `CONFIG`, frames through the core's board
/// loop, `END`) on the input as the host→firmware stream, with the firmware's frame buffers.
/// Whatever arrives, `serve` must return (damaged messages are dropped and counted), and what
/// it sent back must be a sequence of valid messages.
pub fn firmware_serve(data: &[u8]) {
    let (mut left, mut right) = (vec![0u8; IMAGE_BYTES], vec![0u8; IMAGE_BYTES]);
    let mut slot: Option<FirmwareTracker> = None;
    let mut tx = VecSink::default();
    let _ = serve(SliceSource::new(data), &mut tx, &mut slot, &mut left, &mut right, StackUsage::default);
    let mut rx = LinkReader::new(SliceSource::new(&tx.0));
    while !rx.get_ref().remaining().is_empty() || !rx.buffered().is_empty() {
        let reply = read_message(&mut rx, &mut [], &mut []);
        assert!(reply.is_ok(), "the firmware sent a malformed message: {reply:?}");
    }
}

/// The host's reader of the firmware's replies (as in `host::HilSession`: the COBS reader over
/// an `std::io` stream with no frame buffers): decodes every reply, dropping damaged ones;
/// every accepted reply must encode again and decode to the same bytes; and a well-formed
/// reply after the input is decoded.
pub fn host_replies(data: &[u8]) {
    let mut stream = data.to_vec();
    let marker = marker();
    stream.extend(&marker);
    let mut rx = LinkReader::new(IoLink(Cursor::new(stream)));
    assert_eq!(decode_all(&mut rx, false), Some(marker), "the reply after the input was not decoded");
}

/// A little-endian reader over the fuzzer's bytes that yields zeros once they run out.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        let n = N.min(self.0.len());
        out[..n].copy_from_slice(&self.0[..n]);
        self.0 = &self.0[n..];
        out
    }
    fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }
    fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.take())
    }
    /// Any `f32` bit pattern (NaNs and infinities included).
    fn f32(&mut self) -> f32 {
        f32::from_bits(u32::from_le_bytes(self.take()))
    }
    /// Up to `n` raw bytes.
    fn bytes(&mut self, n: usize) -> &[u8] {
        let (head, tail) = self.0.split_at(n.min(self.0.len()));
        self.0 = tail;
        head
    }
}

/// Bit patterns of the population (`Psi` holds `f32`s; NaN ≠ NaN, so compare bits).
fn population_bits(t: &FirmwareTracker) -> Vec<[u32; 6]> {
    t.population().iter().map(|p| p.0.map(f32::to_bits)).collect()
}

/// `Rgb565Image` and `Tracker::step` (the firmware's tracker type, on the link's RGB565 frames)
/// on arbitrary image sizes and bytes, joint values and time steps: the camera size and the
/// feedforward mode, then up to 4 steps, each with image sizes, joint values and `dt` from the
/// input. A refused step must leave
/// the tracker unchanged; an accepted one must give a valid pose and a fitness in `[0, 1]`.
pub fn tracker_step(data: &[u8]) {
    let mut b = Bytes(data);
    // Small images keep an execution fast; the per-point cost does not depend on the size.
    let (w, h) = (u16::from(b.u8() % 48) + 1, u16::from(b.u8() % 48) + 1);
    let Ok(cam) = Pinhole::new_checked(f32::from(w), f32::from(w), f32::from(w) / 2.0, f32::from(h) / 2.0, w, h) else {
        return;
    };
    let Ok(rig) = StereoRig::parallel(cam, 0.1) else { return };
    let Ok(space) = SearchSpace::new_checked([-0.2, -0.2, 0.4], [0.2, 0.2, 1.0]) else { return };
    let modes = [Feedforward::Off, Feedforward::On, Feedforward::OnWithTarget];
    let mode = modes[usize::from(b.u8() % 3)];
    let config = TrackerConfig::pa10(rig, Block::PAPER, nalgebra::Isometry3::identity(), space)
        .with_seed(1)
        .with_feedforward(mode);
    let Ok(mut tracker) = FirmwareTracker::new(config) else { return };
    if b.u8() & 1 == 1 {
        let psi = Psi::new([b.f32(), b.f32(), b.f32()], [b.f32(), b.f32(), b.f32()]);
        let spread = [b.f32(); 6];
        let before = population_bits(&tracker);
        if tracker.reset_around(&psi, &spread).is_err() {
            assert_eq!(population_bits(&tracker), before, "a refused reset changed the population");
        }
    }
    for _ in 0..4 {
        if b.0.is_empty() {
            return;
        }
        let (lw, lh, rw, rh) = (b.u16() % 64, b.u16() % 64, b.u16() % 64, b.u16() % 64);
        let fill = b.u8();
        // One byte short, exact or one too many.
        let left_len = (2 * usize::from(lw) * usize::from(lh) + usize::from(b.u8() % 3)).saturating_sub(1);
        let mut left: Vec<u8> = b.bytes(left_len).to_vec();
        left.resize(left_len, fill);
        let right: Vec<u8> = left.iter().rev().copied().take(2 * usize::from(rw) * usize::from(rh)).collect();
        let (Ok(l), Ok(r)) =
            (Rgb565Image::new_checked(&left[..], lw, lh), Rgb565Image::new_checked(&right[..], rw, rh))
        else {
            continue;
        };
        let joints =
            JointSample { q: core::array::from_fn(|_| b.f32()), qd: core::array::from_fn(|_| b.f32()), time_us: 0 };
        let dt = b.f32();
        let (before, generation) = (population_bits(&tracker), tracker.generation());
        match tracker.step(&StereoFrame { left: l, right: r }, &joints, dt) {
            Ok(est) => {
                assert!(est.psi.validate().is_ok(), "estimate is not a valid pose: {est:?}");
                assert!((0.0..=1.0).contains(&est.fitness), "fitness out of [0, 1]: {est:?}");
                assert_eq!(est.generation, generation + u32::from(tracker.config().tuning.generations_per_frame));
            }
            Err(_) => {
                assert_eq!(population_bits(&tracker), before, "a refused step changed the population");
                assert_eq!(tracker.generation(), generation, "a refused step counted a generation");
            }
        }
    }
}

/// The scenario TOML parser: any UTF-8 text either fails with a typed error or gives a
/// scenario that serialises to TOML which parses back to the same scenario.
pub fn scenario_toml(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let scenario = match evorec_sim::sim::scenario::Scenario::from_toml_str(text) {
        Ok(s) => s,
        Err(e) => {
            let _ = (e.to_string(), e.field());
            return;
        }
    };
    let _ = scenario.frame_count();
    let written = scenario.to_toml_string();
    let Ok(toml) = written else { panic!("a valid scenario does not serialise: {written:?}") };
    let back = evorec_sim::sim::scenario::Scenario::from_toml_str(&toml);
    let Ok(back) = back else { panic!("serialised scenario does not parse: {back:?}\n{toml}") };
    assert_eq!(back.to_toml_string().ok(), Some(toml), "serialise∘parse is not the identity");
}

/// The joint names `sequence_files` reads `joints.csv` against (a 2-joint chain keeps the
/// header short enough for the fuzzer to find).
const FUZZ_JOINTS: [&str; 2] = ["j1", "j2"];

/// The recorded-sequence reader (`evorec_sim::recording::sequence`): the first byte picks the file kind,
/// the rest is that file's text — `sequence.toml`, camera_info YAML, URDF (chain `base_link` →
/// `flange_link`), `frames.csv`, `joints.csv` (joints `j1`, `j2`) or a TUM trajectory.
/// Properties: every error is one line naming the file; every accepted file satisfies the
/// reader's documented invariants (strictly increasing times, finite values, a rigid hand-eye
/// transform, a joint state inside the sampled span).
pub fn sequence_files(data: &[u8]) {
    use evorec_sim::recording::sequence::{camera_info, manifest, tables, tum};
    let Some((&kind, rest)) = data.split_first() else { return };
    let Ok(text) = std::str::from_utf8(rest) else { return };
    let path = std::path::Path::new("fuzz-input");
    let one_line = |e: &dyn std::fmt::Display| {
        let msg = e.to_string();
        assert!(!msg.contains('\n'), "a reader error spans several lines: {msg:?}");
        assert!(msg.starts_with("fuzz-input"), "a reader error does not name the file: {msg:?}");
    };
    match kind % 6 {
        0 => match manifest::parse(text, path) {
            Ok(m) => {
                let rot = m.flange_to_right.rotation.coords.norm();
                assert!((rot - 1.0).abs() < 1e-6, "accepted hand-eye rotation is not unit: {rot}");
            }
            Err(e) => one_line(&e),
        },
        1 => match camera_info::parse(text, path) {
            Ok((_, cam)) => assert!(cam.fx() > 0.0 && cam.fy() > 0.0, "accepted camera has a bad focal length"),
            Err(e) => one_line(&e),
        },
        2 => {
            match evorec_sim::recording::robot::ArmModel::from_urdf_str(text, "base_link", "flange_link", "fuzz-input")
            {
                Ok(arm) => {
                    let _ = arm.to_chain::<7>();
                }
                Err(e) => one_line(&e),
            }
        }
        3 => match tables::parse_frames(text.as_bytes(), path, std::path::Path::new("seq")) {
            Ok(rows) => {
                assert!(!rows.is_empty(), "no frames accepted as a sequence");
                assert!(rows.windows(2).all(|w| w[0].index < w[1].index && w[0].t_s < w[1].t_s));
            }
            Err(e) => one_line(&e),
        },
        4 => {
            let names: Vec<String> = FUZZ_JOINTS.iter().map(|n| (*n).to_owned()).collect();
            match tables::JointTable::parse(text.as_bytes(), path, &names) {
                Ok(table) => {
                    let (first, last) = table.span();
                    assert!(first.is_finite() && last.is_finite() && first <= last);
                    let mid = first + (last - first) / 2.0;
                    for t in [first, mid, last] {
                        let s = table.at(t);
                        let Some(s) = s else { panic!("no joint state at {t} inside [{first}, {last}]") };
                        assert_eq!((s.q.len(), s.qd.len()), (names.len(), names.len()));
                        assert!(s.q.iter().chain(&s.qd).all(|v| v.is_finite()), "non-finite joint state at {t}");
                    }
                    assert!(table.at(last + 1.0).is_none() && table.at(f64::NAN).is_none());
                }
                Err(e) => one_line(&e),
            }
        }
        _ => match tum::parse(text, path) {
            Ok(poses) => assert!(poses.windows(2).all(|w| w[0].t < w[1].t), "TUM times accepted out of order"),
            Err(e) => one_line(&e),
        },
    }
}
