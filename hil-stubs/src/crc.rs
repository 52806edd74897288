//! CRC-32 (IEEE 802.3 / ISO-HDLC, the zlib and PNG CRC): reflected polynomial `0xEDB8_8320`,
//! initial value and final XOR `0xFFFF_FFFF`. Check value: `crc32(b"123456789") == 0xCBF4_3926`.
//!
//! The arithmetic is the [`crc`] crate's (`no_std`, [`crc::CRC_32_ISO_HDLC`], its byte-wise
//! table: 1 KiB of flash built at compile time). This module keeps the link's small API:
//! an incremental [`Crc32`] that is `Copy` and comparable, so a receiver can check a frame while
//! it streams the payload straight into its image buffers.

/// The CRC-32/ISO-HDLC engine (algorithm and lookup table), built at compile time.
static ENGINE: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// An incremental CRC-32.
///
/// # Examples
/// ```
/// use evorec_firmware::crc::{Crc32, crc32};
/// let mut c = Crc32::new();
/// c.update(b"1234");
/// c.update(b"56789");
/// assert_eq!(c.finish(), 0xCBF4_3926);
/// assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Crc32 {
    /// The CRC of the bytes fed so far (the finished value; 0 for no bytes).
    crc: u32,
}

impl Default for Crc32 {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32 {
    /// A CRC over no bytes yet.
    pub const fn new() -> Self {
        Self { crc: 0 }
    }

    /// Feeds `bytes`.
    pub fn update(&mut self, bytes: &[u8]) {
        // `crc` resumes from an initial value given in the algorithm's unreflected form, before
        // the final XOR: for ISO-HDLC (refin = refout, xorout = !0) that is `!crc` bit-reversed.
        let mut digest = ENGINE.digest_with_initial((!self.crc).reverse_bits());
        digest.update(bytes);
        self.crc = digest.finalize();
    }

    /// The CRC of everything fed so far.
    pub const fn finish(&self) -> u32 {
        self.crc
    }
}

/// The CRC-32 of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    ENGINE.checksum(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Published check values of CRC-32/ISO-HDLC.
    const VECTORS: [(&[u8], u32); 4] = [
        (b"", 0x0000_0000),
        (b"a", 0xE8B7_BE43),
        (b"123456789", 0xCBF4_3926),
        (b"The quick brown fox jumps over the lazy dog", 0x414F_A339),
    ];

    /// Whole link messages (header + payload) and their CRC trailers as they travel today
    /// (values from Python's `zlib.crc32`): `END`, and `ACK` with status 0.
    const WIRE: [(&[u8], u32); 2] = [
        (b"EVRC\x01\x04\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0", 0xCA55_7F5B),
        (b"EVRC\x01\x05\0\0\0\0\0\0\x04\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0", 0x91DA_5C3E),
    ];

    #[test]
    fn wire_vectors() {
        let ramp: [u8; 1000] = core::array::from_fn(|i| (i * 7 + 3) as u8);
        assert_eq!(crc32(&ramp), 0x17BC_2A46);
        for (msg, crc) in WIRE {
            assert_eq!(crc32(msg), crc, "{msg:?}");
            let mut c = Crc32::new();
            for b in msg.chunks(5) {
                c.update(b);
            }
            assert_eq!(c.finish(), crc);
        }
    }

    #[test]
    fn check_values() {
        for (input, crc) in VECTORS {
            assert_eq!(crc32(input), crc, "{input:?}");
        }
    }

    /// The bit-wise definition (reflected polynomial `0xEDB8_8320`, init and final XOR `!0`): an
    /// independent reference, so the wire bytes stay those of the former hand-written table code.
    fn bitwise(bytes: &[u8]) -> u32 {
        let mut c = 0xFFFF_FFFFu32;
        for &b in bytes {
            c ^= u32::from(b);
            for _ in 0..8 {
                c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
            }
        }
        !c
    }

    proptest::proptest! {
        #[test]
        fn same_as_bitwise_definition(data in proptest::collection::vec(proptest::num::u8::ANY, 0..600), split in 0usize..600) {
            let split = split.min(data.len());
            let mut c = Crc32::new();
            c.update(&data[..split]);
            c.update(&data[split..]);
            proptest::prop_assert_eq!(c.finish(), bitwise(&data));
            proptest::prop_assert_eq!(crc32(&data), bitwise(&data));
        }
    }

    #[test]
    fn incremental_equals_one_shot() {
        let data: [u8; 300] = core::array::from_fn(|i| (i * 7 + 3) as u8);
        for split in [0, 1, 17, 150, 299, 300] {
            let mut c = Crc32::new();
            c.update(&data[..split]);
            c.update(&data[split..]);
            assert_eq!(c.finish(), crc32(&data));
        }
    }
}
