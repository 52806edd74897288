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
use evorec_core::hue::HueImage;
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::tracker::{Feedforward, JointSample, StereoFrame, TrackerConfig};
use evorec_firmware::host::IoLink;
use evorec_firmware::link_board::{StackUsage, serve};
use evorec_firmware::protocol::{
    ByteSink, Envelope, Message, ReadError, SliceSource, Truncated, decode, encoded_len, read_message, write_message,
};
use evorec_firmware::{FirmwareTracker, IMAGE_BYTES};

/// Every target: its name (the directory under `fuzz/corpus/`) and its body.
pub const TARGETS: &[(&str, fn(&[u8]))] = &[
    ("link_decode", link_decode),
    ("firmware_serve", firmware_serve),
    ("host_replies", host_replies),
    ("tracker_step", tracker_step),
    ("scenario_toml", scenario_toml),
];

/// A growable byte sink (the fuzz bodies' stand-in for a link's transmit side).
struct VecSink(Vec<u8>);

impl ByteSink for VecSink {
    type Error = Truncated;
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), Truncated> {
        self.0.extend_from_slice(bytes);
        Ok(())
    }
}

/// Encodes one message.
fn encode(env: &Envelope<'_>) -> Vec<u8> {
    let mut sink = VecSink(Vec::with_capacity(encoded_len(&env.message)));
    let written = write_message(&mut sink, env);
    assert!(written.is_ok(), "a decoded message must encode again: {written:?}");
    assert_eq!(sink.0.len(), encoded_len(&env.message), "encoded_len disagrees with write_message");
    sink.0
}

/// The firmware's link decoder ([`decode`] over a byte stream, frames read into buffers of the
/// firmware's size): decodes messages from the front of the input until an error. Every
/// accepted message must encode again, and decoding that encoding must give the same bytes
/// once more (the only bytes the decoder may ignore are the header's reserved ones).
pub fn link_decode(data: &[u8]) {
    let (mut left, mut right) = (vec![0u8; IMAGE_BYTES], vec![0u8; IMAGE_BYTES]);
    let mut rest = data;
    while !rest.is_empty() {
        let (env, used) = match decode(rest, &mut left, &mut right) {
            Ok(ok) => ok,
            Err(ReadError::Link(Truncated) | ReadError::Decode(_)) => return,
        };
        assert!(used > 0 && used <= rest.len(), "decode used {used} of {} bytes", rest.len());
        assert_eq!(used, encoded_len(&env.message), "decode used other than the message's encoded length");
        let once = encode(&env);
        let (mut l2, mut r2) = (vec![0u8; IMAGE_BYTES], vec![0u8; IMAGE_BYTES]);
        let again = decode(&once, &mut l2, &mut r2);
        let Ok((env2, used2)) = again else { panic!("re-encoded message does not decode: {again:?}") };
        assert_eq!(used2, once.len());
        assert_eq!(encode(&env2), once, "decode∘encode is not the identity on encoded messages");
        rest = rest.get(used..).unwrap_or_default();
    }
}

/// The firmware's whole conversation ([`serve`]: `CONFIG`, frames through the core's board
/// loop, `END`) on the input as the host→firmware stream, with the firmware's frame buffers.
/// Whatever arrives, `serve` must return, and what it sent back must be a sequence of valid
/// messages.
pub fn firmware_serve(data: &[u8]) {
    let (mut left, mut right) = (vec![0u8; IMAGE_BYTES], vec![0u8; IMAGE_BYTES]);
    let mut slot: Option<FirmwareTracker> = None;
    let mut tx = VecSink(Vec::new());
    let _ = serve(SliceSource::new(data), &mut tx, &mut slot, &mut left, &mut right, StackUsage::default);
    let mut src = SliceSource::new(&tx.0);
    while !src.remaining().is_empty() {
        let reply = read_message(&mut src, &mut [], &mut []);
        assert!(reply.is_ok(), "the firmware sent a malformed message: {reply:?}");
    }
}

/// The host's reader of the firmware's replies (as in `host::HilSession`: [`read_message`]
/// over an `std::io` stream with no frame buffers): reads until an error; every accepted
/// reply must re-encode to the bytes it came from, CRC included, except the reserved header
/// bytes.
pub fn host_replies(data: &[u8]) {
    let mut src = IoLink(Cursor::new(data));
    loop {
        let start = usize::try_from(src.0.position()).unwrap_or(usize::MAX);
        let env = match read_message(&mut src, &mut [], &mut []) {
            Ok(env) => env,
            Err(_) => return,
        };
        assert!(!matches!(env.message, Message::Frame(_)), "a frame was decoded into empty buffers");
        let end = usize::try_from(src.0.position()).unwrap_or(usize::MAX);
        let original = data.get(start..end).unwrap_or_default();
        let encoded = encode(&env);
        assert_eq!(encoded.len(), original.len());
        // Bytes 6..8 of the header are reserved (ignored on receipt, 0 when sent), and the
        // CRC covers them; everything else must match exactly.
        let payload_and_crc_len = encoded.len() - 8;
        assert_eq!(encoded[..6], original[..6]);
        assert_eq!(encoded[8..8 + payload_and_crc_len - 4], original[8..8 + payload_and_crc_len - 4]);
    }
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

/// `HueImage` and `Tracker::step` (the firmware's tracker type) on arbitrary image sizes and
/// bytes, joint values and time steps: the camera size, then up to 4 steps, each with image
/// sizes, joint values, `dt` and the feedforward flag from the input. A refused step must leave
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
    let config = TrackerConfig::pa10(rig, Block::PAPER, nalgebra::Isometry3::identity(), space).with_seed(1);
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
        let left_len = (usize::from(lw) * usize::from(lh) + usize::from(b.u8() % 3)).saturating_sub(1);
        let mut left: Vec<u8> = b.bytes(left_len).to_vec();
        left.resize(left_len, fill);
        let right: Vec<u8> = left.iter().rev().copied().take(usize::from(rw) * usize::from(rh)).collect();
        let (Ok(l), Ok(r)) = (HueImage::new_checked(&left[..], lw, lh), HueImage::new_checked(&right[..], rw, rh))
        else {
            continue;
        };
        let joints =
            JointSample { q: core::array::from_fn(|_| b.f32()), qd: core::array::from_fn(|_| b.f32()), time_us: 0 };
        let dt = b.f32();
        let ff = if b.u8() & 1 == 1 { Feedforward::On } else { Feedforward::Off };
        let (before, generation) = (population_bits(&tracker), tracker.generation());
        match tracker.step(&StereoFrame { left: l, right: r }, &joints, dt, ff) {
            Ok(est) => {
                assert!(est.psi.validate().is_ok(), "estimate is not a valid pose: {est:?}");
                assert!((0.0..=1.0).contains(&est.fitness), "fitness out of [0, 1]: {est:?}");
                assert_eq!(est.generation, generation + 1);
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
    let scenario = match evorec_sim::scenario::Scenario::from_toml_str(text) {
        Ok(s) => s,
        Err(e) => {
            let _ = (e.to_string(), e.field());
            return;
        }
    };
    let _ = scenario.frame_count();
    let written = scenario.to_toml_string();
    let Ok(toml) = written else { panic!("a valid scenario does not serialise: {written:?}") };
    let back = evorec_sim::scenario::Scenario::from_toml_str(&toml);
    let Ok(back) = back else { panic!("serialised scenario does not parse: {back:?}\n{toml}") };
    assert_eq!(back.to_toml_string().ok(), Some(toml), "serialise∘parse is not the identity");
}
