//! Round trips and rejection of corrupt input.

use super::payload::decode_small;
use super::payload::encode_payload;
use super::*;
use std::vec;
use std::vec::Vec;

pub(crate) fn sample_setup() -> Setup {
    Setup {
        fx: 200.0,
        fy: 201.5,
        cx: 80.0,
        cy: 60.25,
        width: 160,
        height: 120,
        baseline_m: 0.1,
        block_size_m: [0.1, 0.15, 0.2],
        face_hues_deg: [0.0, 120.0, 240.0, 0.0, 120.0, 240.0],
        flange_to_camera_t: [0.0, 0.06, 0.1],
        flange_to_camera_q: [0.998_750_26, 0.0, 0.0, 0.049_979_17],
        search_min: [-0.2, -0.2, 0.4],
        search_max: [0.2, 0.2, 1.0],
        seed: 0x0123_4567_89AB_CDEF,
        tuning: Tuning::DEFAULT,
        initial_psi: Psi::new([0.01, -0.02, 0.7], [0.05, 0.1, -0.03]),
        initial_spread: [0.02; 6],
    }
}

fn encode(env: &Envelope<'_>) -> Vec<u8> {
    let bytes = encode_to_vec(env).unwrap();
    assert!(bytes.len() <= max_encoded_len(&env.message));
    // Through a slice sink the same bytes come out.
    let mut buf = vec![0u8; bytes.len()];
    let mut sink = SliceSink::new(&mut buf);
    write_message(&mut sink, env).unwrap();
    assert_eq!(sink.written(), &bytes[..]);
    bytes
}

/// The message before framing (header, payload, CRC), through the `cobs` crate's decoder.
fn unframe(wire: &[u8]) -> Vec<u8> {
    assert_eq!((wire[0], wire[wire.len() - 1]), (0, 0), "delimiters");
    let mut raw = vec![0u8; wire.len()];
    let n = cobs::decode(&wire[1..wire.len() - 1], &mut raw).unwrap().frame_size();
    raw.truncate(n);
    raw
}

/// Frames raw bytes with the `cobs` crate's encoder (the reference for ours).
fn frame_raw(raw: &[u8]) -> Vec<u8> {
    let mut out = vec![0u8; raw.len() + raw.len() / 254 + 3];
    let n = cobs::encode(raw, &mut out[1..]);
    out.truncate(n + 2);
    out[0] = 0;
    out[n + 1] = 0;
    out
}

/// `good` with its raw message changed by `f` and framed again.
fn reframe(good: &[u8], f: impl FnOnce(&mut Vec<u8>)) -> Vec<u8> {
    let mut raw = unframe(good);
    f(&mut raw);
    frame_raw(&raw)
}

fn small_messages() -> Vec<Envelope<'static>> {
    vec![
        Envelope::bare(Message::Config(sample_setup())),
        Envelope {
            sequence: 41,
            capture_time_us: 1_366_653,
            message: Message::Estimate(Estimate {
                psi: Psi::new([0.01, -0.02, 0.7], [f32::MIN_POSITIVE, -0.0, 1.0e-30]),
                fitness: 0.875,
                camera_fitness: [0.75, 1.0],
                generation: 42,
                capture_time_us: 0,
                status: evorec_core::status::Status::Lost,
                target_measurement: Psi::new([0.011, -0.019, 0.703], [f32::MIN_POSITIVE, -0.0, 1.0e-30]),
            }),
        },
        Envelope::bare(Message::End),
        Envelope::bare(Message::Ack(4)),
        Envelope { sequence: 7, capture_time_us: 99, message: Message::Rejected },
        Envelope::bare(Message::Done(Done {
            frames: 120,
            published: 119,
            rejected: 1,
            stack_used_bytes: 5000,
            stack_size_bytes: 80_000,
            drops: DropCounts { framing: 1, crc: 2, superseded: 3, unexpected: u32::MAX, ..DropCounts::default() },
        })),
        Envelope::bare(Message::Error(2)),
    ]
}

#[test]
fn small_messages_round_trip() {
    for env in small_messages() {
        let bytes = encode(&env);
        let (back, used) = decode(&bytes, &mut [], &mut []).unwrap();
        assert_eq!(used, bytes.len());
        assert_eq!(back, env);
    }
}

/// Every field of the table crosses the link bit for bit, each set to a value of its own.
#[test]
fn every_tuning_field_crosses_the_link() {
    use evorec_core::tuning::{FIELDS, Kind, Value};
    for (i, f) in FIELDS.iter().enumerate() {
        let mut setup = sample_setup();
        let value = match f.kind {
            Kind::Real => Value::Real(0.125 + i as f32),
            Kind::Int => Value::Int(3 + i as u32),
            Kind::Name(names) => {
                let current = (f.get)(&setup.tuning);
                let other = names.iter().find(|&&n| Value::Name(n) != current);
                Value::Name(other.copied().unwrap_or_else(|| panic!("{} has a single name", f.name)))
            }
        };
        setup.tuning.set(f.name, value).unwrap();
        assert_ne!(setup, sample_setup(), "{}", f.name);
        let bytes = encode(&Envelope::bare(Message::Config(setup)));
        let (back, _) = decode(&bytes, &mut [], &mut []).unwrap();
        assert_eq!(back.message, Message::Config(setup), "{}", f.name);
    }
}

/// A `CONFIG` from another table (fingerprint or field count) or with a name index out of
/// range is refused.
#[test]
fn a_config_from_another_table_is_refused() {
    let mut payload = [0u8; MAX_SMALL_PAYLOAD];
    let (len, _) = encode_payload(&Message::Config(sample_setup()), &mut payload);
    assert_eq!(len, CONFIG_LEN);
    // The tuning starts after 30 f32 fields, the image size and the seed.
    let at = 4 * 4 + 2 * 2 + 4 + 12 + 24 + 12 + 16 + 12 + 12 + 8;
    assert_eq!(payload[at..at + 4], evorec_core::tuning::TABLE_ID.to_le_bytes());
    for (offset, byte) in [(at, 1u8), (at + 4, 1)] {
        let mut bad = payload;
        bad[offset] ^= byte;
        assert_eq!(decode_small(MsgType::Config, &bad[..len]), Err(DecodeError::BadValue));
    }
    // `method` is the first field: its name index 3 does not exist.
    let mut bad = payload;
    bad[at + 8] = 3;
    assert_eq!(decode_small(MsgType::Config, &bad[..len]), Err(DecodeError::BadValue));
}

/// `fuzz/make_seeds.py` writes the link seeds by hand, field by field: its `CONFIG` must be
/// one this protocol decodes and the firmware accepts (the tests' sample setup at 16×12, with
/// seed 1, no hand-eye rotation and a plainer initial pose), or the fuzzers start from a
/// message the decoder refuses on its length (a `CONFIG` missing one field is 4 bytes short).
#[test]
fn the_fuzz_seeds_config_decodes_to_the_sample_setup() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../fuzz/corpus/link_decode/seed-config");
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let (env, used) = decode(&bytes, &mut [], &mut []).unwrap_or_else(|e| panic!("{path}: {e:?}"));
    assert_eq!(used, bytes.len());
    let mut want = sample_setup();
    (want.width, want.height, want.fx, want.fy, want.cx, want.cy) = (16, 12, 20.0, 20.0, 8.0, 6.0);
    (want.seed, want.flange_to_camera_q) = (1, [1.0, 0.0, 0.0, 0.0]);
    want.initial_psi = Psi::new([0.0, 0.0, 0.7], [0.0, 0.0, 0.0]);
    assert_eq!(env.message, Message::Config(want));
    let tracker: Result<evorec_core::Tracker, _> = want.build_tracker();
    assert!(tracker.is_ok(), "{:?}", tracker.err());
}

#[test]
fn payload_sizes_match_the_constants() {
    let config = Envelope::bare(Message::Config(sample_setup()));
    assert_eq!(unframe(&encode(&config)).len(), HEADER_LEN + CONFIG_LEN + CRC_LEN);
    assert_eq!(raw_len(&config.message), HEADER_LEN + CONFIG_LEN + CRC_LEN);
    assert_eq!(FRAME_FIXED_LEN, 68);
    assert_eq!(ESTIMATE_LEN, 65);
}

#[test]
fn nan_bits_cross_unchanged() {
    let odd_nan = f32::from_bits(0x7FC0_1234);
    let env = Envelope::bare(Message::Estimate(Estimate {
        psi: Psi::new([odd_nan, 0.0, 0.0], [0.0; 3]),
        fitness: f32::from_bits(0xFFA0_0001),
        camera_fitness: [f32::from_bits(0x7FC0_0002), -0.0],
        generation: 1,
        capture_time_us: 0,
        status: evorec_core::status::Status::Searching,
        target_measurement: Psi::new([0.0, f32::from_bits(0xFF80_0007), 0.0], [0.0; 3]),
    }));
    let bytes = encode(&env);
    let (back, _) = decode(&bytes, &mut [], &mut []).unwrap();
    let Message::Estimate(e) = back.message else { panic!("not an estimate") };
    assert_eq!(e.psi.0[0].to_bits(), 0x7FC0_1234);
    assert_eq!(e.fitness.to_bits(), 0xFFA0_0001);
    assert_eq!(e.camera_fitness.map(f32::to_bits), [0x7FC0_0002, (-0.0f32).to_bits()]);
    assert_eq!(e.target_measurement.0[1].to_bits(), 0xFF80_0007);
}

/// Two RGB565 images of `w × h` pixels (2 bytes each).
fn frame_bytes(w: u16, h: u16) -> (Vec<u8>, Vec<u8>) {
    let n = usize::from(w) * usize::from(h) * BYTES_PER_PIXEL;
    ((0..n).map(|i| (i % 181) as u8).collect(), (0..n).map(|i| (i % 7) as u8 + 60).collect())
}

fn joints() -> JointSample<DOF> {
    JointSample { q: [0.1, -0.2, 0.3, 1.2, 0.0, -0.5, 2.0], qd: [0.05; DOF], time_us: 1234 }
}

#[test]
fn frame_round_trip_into_receive_buffers() {
    let (l, r) = frame_bytes(16, 9);
    let env = Envelope {
        sequence: 3,
        capture_time_us: 100_000,
        message: Message::Frame(Frame { width: 16, height: 9, joints: joints(), left: &l, right: &r }),
    };
    let bytes = encode(&env);
    assert_eq!(unframe(&bytes).len(), HEADER_LEN + FRAME_FIXED_LEN + 2 * 2 * 144 + CRC_LEN);
    let (mut lb, mut rb) = ([0u8; 400], [0u8; 400]);
    let (back, used) = decode(&bytes, &mut lb, &mut rb).unwrap();
    assert_eq!(used, bytes.len());
    assert_eq!(back, env);
}

#[test]
fn frame_larger_than_buffers_is_refused() {
    let (l, r) = frame_bytes(16, 9);
    let env = Envelope::bare(Message::Frame(Frame { width: 16, height: 9, joints: joints(), left: &l, right: &r }));
    let bytes = encode(&env);
    // 287 bytes hold 143 RGB565 pixels (and a half).
    let (mut lb, mut rb) = ([0u8; 287], [0u8; 400]);
    assert_eq!(
        decode(&bytes, &mut lb, &mut rb).unwrap_err(),
        ReadError::Decode(DecodeError::FrameTooLarge { pixels: 144, capacity: 143 })
    );
    // Hue-sized buffers (1 byte per pixel) are too small for RGB565 frames.
    let (mut lb, mut rb) = ([0u8; 144], [0u8; 144]);
    assert_eq!(
        decode(&bytes, &mut lb, &mut rb).unwrap_err(),
        ReadError::Decode(DecodeError::FrameTooLarge { pixels: 144, capacity: 72 })
    );
}

#[test]
fn frame_with_wrong_image_slices_is_not_written() {
    let (l, r) = frame_bytes(4, 4);
    let env = Envelope::bare(Message::Frame(Frame { width: 4, height: 5, joints: joints(), left: &l, right: &r }));
    let mut buf = [0u8; 512];
    let mut sink = SliceSink::new(&mut buf);
    assert!(matches!(write_message(&mut sink, &env), Err(WriteError::ImageSize { expected: 40, .. })));
    assert!(sink.written().is_empty());
}

#[test]
fn bad_magic_version_type_and_length_are_rejected() {
    let good = encode(&Envelope::bare(Message::Ack(0)));
    let err = |f: &dyn Fn(&mut Vec<u8>)| decode(&reframe(&good, f), &mut [], &mut []).unwrap_err();
    assert_eq!(err(&|r| r[0] = b'X'), ReadError::Decode(DecodeError::BadMagic(*b"XVRC")));
    assert_eq!(err(&|r| r[4] = VERSION + 1), ReadError::Decode(DecodeError::BadVersion(VERSION + 1)));
    assert_eq!(err(&|r| r[5] = 99), ReadError::Decode(DecodeError::UnknownType(99)));
    assert_eq!(err(&|r| r[12] = 5), ReadError::Decode(DecodeError::BadLength { kind: MsgType::Ack, len: 5 }));
    // One byte too many or too few before the delimiter.
    assert_eq!(err(&|r| r.push(7)), ReadError::Decode(DecodeError::BadLength { kind: MsgType::Ack, len: 4 }));
    assert_eq!(err(&|r| r.truncate(r.len() - 1)), ReadError::Decode(DecodeError::Framing));
}

#[test]
fn bad_crc_is_rejected() {
    let good = encode(&Envelope::bare(Message::Config(sample_setup())));
    // A flipped payload bit, a flipped header bit that keeps the header valid, a bad trailer.
    for pos in [HEADER_LEN + 10, 9, HEADER_LEN + CONFIG_LEN + 3] {
        let b = reframe(&good, |r| r[pos] ^= 0x10);
        assert!(
            matches!(decode(&b, &mut [], &mut []), Err(ReadError::Decode(DecodeError::BadCrc { .. }))),
            "flip at {pos}"
        );
    }
}

#[test]
fn truncated_input_is_rejected() {
    let (l, r) = frame_bytes(8, 8);
    let env = Envelope::bare(Message::Frame(Frame { width: 8, height: 8, joints: joints(), left: &l, right: &r }));
    let good = encode(&env);
    for cut in [0, 1, HEADER_LEN - 1, HEADER_LEN, HEADER_LEN + 30, good.len() - 5, good.len() - 1] {
        let (mut lb, mut rb) = ([0u8; 128], [0u8; 128]);
        assert_eq!(decode(&good[..cut], &mut lb, &mut rb).unwrap_err(), ReadError::Link(Truncated), "cut {cut}");
        // Ended by a delimiter instead (the next message's), the cut message is a framing error.
        let mut cut_then_zero = good[..cut].to_vec();
        cut_then_zero.push(0);
        if cut > 1 && cut < good.len() - 1 {
            assert_eq!(
                decode(&cut_then_zero, &mut lb, &mut rb).unwrap_err(),
                ReadError::Decode(DecodeError::Framing),
                "cut {cut}"
            );
        }
    }
}

#[test]
fn our_encoder_matches_the_cobs_crate() {
    let (l, r) = frame_bytes(23, 17);
    let frame = Envelope::bare(Message::Frame(Frame { width: 23, height: 17, joints: joints(), left: &l, right: &r }));
    let zeros = vec![0u8; 23 * 17 * 2];
    let ones = vec![1u8; 23 * 17 * 2];
    let runs =
        Envelope::bare(Message::Frame(Frame { width: 23, height: 17, joints: joints(), left: &zeros, right: &ones }));
    for env in small_messages().into_iter().chain([frame, runs]) {
        let wire = encode(&env);
        assert_eq!(frame_raw(&unframe(&wire)), wire);
        assert!(wire[1..wire.len() - 1].iter().all(|&b| b != 0), "a zero inside a framed message");
    }
}

#[test]
fn after_garbage_the_next_message_decodes() {
    let env = Envelope::bare(Message::Config(sample_setup()));
    let good = encode(&env);
    let garbage: [&[u8]; 5] = [b"", &[0xFF; 300], &[3, 1, 2], &good[..good.len() / 2], &good[1..good.len() - 1]];
    for g in garbage {
        let mut stream = g.to_vec();
        stream.extend(&good);
        let mut rx = LinkReader::new(SliceSource::new(&stream));
        let (mut errors, mut last) = (0, None);
        loop {
            match read_message(&mut rx, &mut [], &mut []) {
                Ok(e) => last = Some(e),
                Err(ReadError::Decode(_)) => errors += 1,
                Err(ReadError::Link(Truncated)) => break,
            }
        }
        // The last garbage is the message without its delimiters: it decodes as the message.
        assert_eq!(last, Some(env));
        assert!(errors <= 1, "{errors} errors after {g:?}");
    }
}

#[test]
fn stream_of_messages_decodes_in_order() {
    let mut stream = Vec::new();
    for env in small_messages() {
        stream.extend(encode(&env));
    }
    let mut rx = LinkReader::new(SliceSource::new(&stream));
    for env in small_messages() {
        assert_eq!(read_message(&mut rx, &mut [], &mut []).unwrap(), env);
    }
    assert!(rx.get_ref().remaining().is_empty() && rx.buffered().is_empty());
}

mod prop {
    use super::*;
    use proptest::prelude::*;

    fn any_f32() -> impl Strategy<Value = f32> {
        any::<u32>().prop_map(f32::from_bits)
    }

    proptest! {
        #[test]
        fn estimate_round_trips_bit_exactly(
            psi in proptest::array::uniform6(any_f32()),
            measured in proptest::array::uniform6(any_f32()),
            fitness in any_f32(),
            generation in any::<u32>(),
            sequence in any::<u32>(),
            time in any::<u64>(),
        ) {
            let env = Envelope {
                sequence,
                capture_time_us: time,
                message: Message::Estimate(Estimate {
                    psi: Psi(psi),
                    fitness,
                    camera_fitness: [fitness, fitness],
                    generation,
                    capture_time_us: 0,
                    status: evorec_core::status::Status::Tracking,
                    target_measurement: Psi(measured),
                }),
            };
            let bytes = encode(&env);
            let (back, _) = decode(&bytes, &mut [], &mut []).unwrap();
            let Message::Estimate(e) = back.message else { panic!("not an estimate") };
            prop_assert_eq!(e.psi.0.map(f32::to_bits), psi.map(f32::to_bits));
            prop_assert_eq!(e.fitness.to_bits(), fitness.to_bits());
            prop_assert_eq!(e.target_measurement.0.map(f32::to_bits), measured.map(f32::to_bits));
            prop_assert_eq!(e.generation, generation);
            prop_assert_eq!((back.sequence, back.capture_time_us), (sequence, time));
        }

        #[test]
        fn frames_round_trip(
            w in 1u16..24, h in 1u16..24, seed in any::<u8>(),
            q in proptest::array::uniform7(any_f32()), time in any::<u64>(),
        ) {
            let n = usize::from(w) * usize::from(h) * BYTES_PER_PIXEL;
            let l: Vec<u8> = (0..n).map(|i| (i as u8).wrapping_mul(seed)).collect();
            let r: Vec<u8> = (0..n).map(|i| (i as u8) ^ seed).collect();
            let joints = JointSample { q, qd: q, time_us: time };
            let env = Envelope {
                sequence: u32::from(seed),
                capture_time_us: time,
                message: Message::Frame(Frame { width: w, height: h, joints, left: &l, right: &r }),
            };
            let bytes = encode(&env);
            let (mut lb, mut rb) = (vec![0u8; n], vec![0u8; n]);
            let (back, _) = decode(&bytes, &mut lb, &mut rb).unwrap();
            let Message::Frame(f) = back.message else { panic!("not a frame") };
            prop_assert_eq!((f.width, f.height, f.left, f.right), (w, h, &l[..], &r[..]));
            prop_assert_eq!(f.joints.q.map(f32::to_bits), q.map(f32::to_bits));
        }

        /// Any single flipped bit anywhere in a message is detected (as a bad header,
        /// a length mismatch, a framing error or a CRC mismatch), never decoded as valid; and
        /// the message after it decodes.
        #[test]
        fn any_single_bit_flip_is_rejected(which in 0usize..7, bit in any::<usize>()) {
            let env = small_messages()[which];
            let mut bytes = encode(&env);
            let bit = bit % (bytes.len() * 8);
            bytes[bit / 8] ^= 1 << (bit % 8);
            let next = Envelope::bare(Message::Ack(7));
            bytes.extend(encode(&next));
            let mut rx = LinkReader::new(SliceSource::new(&bytes));
            let mut got = Vec::new();
            loop {
                match read_message(&mut rx, &mut [], &mut []) {
                    Ok(e) => got.push(e),
                    Err(ReadError::Decode(_)) => {}
                    Err(ReadError::Link(Truncated)) => break,
                }
            }
            prop_assert_eq!(got, vec![next]);
        }

        /// After any garbage, the next well-formed message is decoded (messages the garbage
        /// happens to hold may decode before it).
        #[test]
        fn after_any_garbage_the_next_message_decodes(garbage in proptest::collection::vec(any::<u8>(), 0..600), which in 0usize..7) {
            let env = small_messages()[which];
            let mut stream = garbage;
            stream.extend(encode(&env));
            let mut rx = LinkReader::new(SliceSource::new(&stream));
            let mut last = None;
            loop {
                match read_message(&mut rx, &mut [], &mut []) {
                    Ok(e) => last = Some(e),
                    Err(ReadError::Decode(_)) => {}
                    Err(ReadError::Link(Truncated)) => break,
                }
            }
            prop_assert_eq!(last, Some(env));
        }
    }
}

/// A [`ByteSource`] that counts its reads.
struct CountingSource<'a> {
    src: SliceSource<'a>,
    reads: usize,
}

impl ByteSource for CountingSource<'_> {
    type Error = Truncated;
    fn read_some(&mut self, buf: &mut [u8]) -> Result<usize, Truncated> {
        self.reads += 1;
        self.src.read_some(buf)
    }
}

/// A full-size frame whose images hold zeros, long non-zero runs and everything between.
fn busy_frame(sequence: u32, left: &[u8], right: &[u8]) -> Envelope<'static> {
    let frame = Frame {
        width: 160,
        height: 120,
        joints: JointSample { q: [0.25; DOF], qd: [-0.5; DOF], time_us: u64::from(sequence) * 33_333 },
        left: left.to_vec().leak(),
        right: right.to_vec().leak(),
    };
    Envelope { sequence, capture_time_us: u64::from(sequence) * 33_333, message: Message::Frame(frame) }
}

fn busy_images() -> (Vec<u8>, Vec<u8>) {
    let n = 160 * 120 * BYTES_PER_PIXEL;
    let left: Vec<u8> = (0..n).map(|i| if i % 700 < 400 { 0xA5 } else { (i % 7) as u8 }).collect();
    let right: Vec<u8> = (0..n).map(|i| (i * 31 % 256) as u8).collect();
    (left, right)
}

#[test]
fn a_superseded_frame_is_skipped_in_a_few_reads_and_the_frame_behind_it_decodes() {
    let (l, r) = busy_images();
    let (older, newer) = (busy_frame(1, &l, &r), busy_frame(2, &r, &l));
    let mut stream = VecSink::default();
    write_message_with_flags(&mut stream, &older, FLAG_NEWER_FOLLOWS).unwrap();
    let skipped_len = stream.0.len();
    write_message(&mut stream, &newer).unwrap();
    write_message(&mut stream, &Envelope::bare(Message::End)).unwrap();
    let (mut lb, mut rb) = (vec![0u8; l.len()], vec![0u8; l.len()]);

    // The board drops the flagged frame after its header and size: a handful of reads.
    let mut rx = LinkReader::newest_frames_only(CountingSource { src: SliceSource::new(&stream.0), reads: 0 });
    assert_eq!(read_message(&mut rx, &mut lb, &mut rb), Err(ReadError::Decode(DecodeError::Superseded)));
    let skip_reads = rx.get_ref().reads;
    assert_eq!(stream.0.len() - rx.get_ref().src.remaining().len() - rx.buffered().len(), skipped_len);
    assert_eq!(read_message(&mut rx, &mut lb, &mut rb).unwrap(), newer);
    let frame_reads = rx.get_ref().reads - skip_reads;
    assert_eq!(read_message(&mut rx, &mut lb, &mut rb).unwrap(), Envelope::bare(Message::End));
    // Decoding a frame reads RX_CHUNK bytes at a time (about 2,400 reads); skipping one reads
    // the header 32 bytes at a time, the images in two bulk reads, the COBS tail again by 32.
    std::println!("a superseded frame: {skip_reads} reads to skip; a frame: {frame_reads} reads to decode");
    assert!(skip_reads * 20 < frame_reads, "skip {skip_reads} reads, decode {frame_reads}");

    // A reader that decodes everything returns the flagged frame, flags and all.
    let mut rx = LinkReader::new(SliceSource::new(&stream.0));
    assert_eq!(read_message(&mut rx, &mut lb, &mut rb).unwrap(), older);
    assert_eq!(rx.last_flags(), FLAG_NEWER_FOLLOWS);
}

#[test]
fn a_cut_superseded_frame_costs_at_most_the_message_behind_it() {
    let (l, r) = busy_images();
    let mut stream = VecSink::default();
    write_message_with_flags(&mut stream, &busy_frame(1, &l, &r), FLAG_NEWER_FOLLOWS).unwrap();
    // Cut in its images: the message behind it starts at the next delimiter.
    let cut = stream.0.len() / 2;
    stream.0.truncate(cut);
    for seq in [2, 3] {
        write_message(&mut stream, &busy_frame(seq, &r, &l)).unwrap();
    }
    write_message(&mut stream, &Envelope::bare(Message::End)).unwrap();
    let (mut lb, mut rb) = (vec![0u8; l.len()], vec![0u8; l.len()]);
    let mut rx = LinkReader::newest_frames_only(SliceSource::new(&stream.0));
    let mut got = Vec::new();
    loop {
        match read_message(&mut rx, &mut lb, &mut rb) {
            Ok(env) => got.push(Ok((env.message.kind(), env.sequence))),
            Err(ReadError::Decode(e)) => got.push(Err(e)),
            Err(ReadError::Link(Truncated)) => break,
        }
    }
    // The cut frame is dropped as superseded; the bulk read took the start of frame 2 along,
    // which is then dropped as damaged; frame 3 and END decode.
    assert_eq!(got.first(), Some(&Err(DecodeError::Superseded)));
    assert_eq!(got[got.len() - 2..], [Ok((MsgType::Frame, 3)), Ok((MsgType::End, 0))]);
    assert!(got.len() <= 4, "{got:?}");
}
