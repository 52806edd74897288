//! Link fault injection for hardware-in-the-loop runs (feature `host`).
//!
//! A [`FaultInjector`] sits on one direction of the link and passes whole encoded messages
//! (`0x00 ‖ COBS(…) ‖ 0x00`, as [`crate::protocol::write_message`] writes them). Each message is
//! hit with probability `rate` and then suffers one fault, chosen uniformly:
//!
//! | fault       | what goes on the wire                                             |
//! |-------------|-------------------------------------------------------------------|
//! | `flip`      | the message with one random bit flipped (delimiters included)      |
//! | `drop`      | nothing                                                           |
//! | `duplicate` | the message twice                                                 |
//! | `truncate`  | a random prefix of the message (its end delimiter lost)           |
//! | `delay`     | nothing now; the message follows the next one (reordered)         |
//!
//! The random stream is Xoshiro256++ seeded from [`FaultConfig::seed`], so a run is
//! reproducible message for message.

use std::vec::Vec;

use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Fault rate and seed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FaultConfig {
    /// Probability that a message is hit, in parts per million (10 000 = 1 %).
    pub rate_ppm: u32,
    /// Seed of the random stream.
    pub seed: u64,
}

impl FaultConfig {
    /// A rate given as a fraction (`0.01` = 1 %), clamped to `[0, 1]`.
    pub fn from_rate(rate: f64, seed: u64) -> Self {
        let ppm = (rate.clamp(0.0, 1.0) * 1e6).round() as u32;
        Self { rate_ppm: ppm, seed }
    }
}

/// Faults injected so far, by kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FaultCounts {
    /// Messages passed.
    pub messages: u32,
    /// Bit flips.
    pub flip: u32,
    /// Messages dropped.
    pub drop: u32,
    /// Messages sent twice.
    pub duplicate: u32,
    /// Messages cut short.
    pub truncate: u32,
    /// Messages held back behind the next one.
    pub delay: u32,
}

impl FaultCounts {
    /// Messages hit by any fault.
    pub fn total(&self) -> u32 {
        self.flip + self.drop + self.duplicate + self.truncate + self.delay
    }
}

/// Damages messages at a given rate; see the [module docs](self).
#[derive(Debug, Clone)]
pub struct FaultInjector {
    rate_ppm: u32,
    rng: Xoshiro256PlusPlus,
    held: Option<Vec<u8>>,
    counts: FaultCounts,
}

impl FaultInjector {
    /// An injector with `config`'s rate and seed.
    pub fn new(config: FaultConfig) -> Self {
        Self {
            rate_ppm: config.rate_ppm,
            rng: Xoshiro256PlusPlus::seed_from_u64(config.seed),
            held: None,
            counts: FaultCounts::default(),
        }
    }

    /// Faults injected so far.
    pub fn counts(&self) -> FaultCounts {
        self.counts
    }

    fn below(&mut self, n: usize) -> usize {
        (self.rng.next_u64() % n.max(1) as u64) as usize
    }

    /// Passes one encoded message; returns the bytes to put on the wire now (a message held
    /// back earlier comes after this one).
    pub fn pass(&mut self, message: &[u8]) -> Vec<u8> {
        self.counts.messages += 1;
        let mut out = Vec::with_capacity(message.len());
        let hit = (self.rng.next_u64() % 1_000_000) < u64::from(self.rate_ppm);
        let mut held_now = None;
        if !hit || message.is_empty() {
            out.extend_from_slice(message);
        } else {
            match self.below(5) {
                0 => {
                    self.counts.flip += 1;
                    out.extend_from_slice(message);
                    let bit = self.below(out.len() * 8);
                    if let Some(b) = out.get_mut(bit / 8) {
                        *b ^= 1 << (bit % 8);
                    }
                }
                1 => self.counts.drop += 1,
                2 => {
                    self.counts.duplicate += 1;
                    out.extend_from_slice(message);
                    out.extend_from_slice(message);
                }
                3 => {
                    self.counts.truncate += 1;
                    let keep = self.below(message.len());
                    out.extend_from_slice(message.get(..keep).unwrap_or_default());
                }
                _ => {
                    self.counts.delay += 1;
                    held_now = Some(message.to_vec());
                }
            }
        }
        if let Some(older) = self.held.take() {
            out.extend(older);
        }
        self.held = held_now;
        out
    }

    /// The message held back, if any (to send when no next message comes).
    pub fn release(&mut self) -> Vec<u8> {
        self.held.take().unwrap_or_default()
    }
}

/// Splits a byte stream into encoded messages (`0x00 ‖ body ‖ 0x00`) at the delimiters.
#[derive(Debug, Default)]
pub struct MessageSplitter {
    body: Vec<u8>,
}

impl MessageSplitter {
    /// Takes the next bytes; calls `out` with every message completed by them (delimiters
    /// included).
    pub fn push(&mut self, bytes: &[u8], mut out: impl FnMut(Vec<u8>)) {
        for &b in bytes {
            if b != 0 {
                self.body.push(b);
            } else if !self.body.is_empty() {
                let mut m = Vec::with_capacity(self.body.len() + 2);
                m.push(0);
                m.append(&mut self.body);
                m.push(0);
                out(m);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec;

    #[test]
    fn zero_rate_passes_everything_and_full_rate_hits_every_message() {
        let msg = vec![0, 5, 1, 2, 3, 4, 0];
        let mut clean = FaultInjector::new(FaultConfig::from_rate(0.0, 1));
        for _ in 0..100 {
            assert_eq!(clean.pass(&msg), msg);
        }
        let mut all = FaultInjector::new(FaultConfig::from_rate(1.0, 1));
        for _ in 0..1000 {
            let _ = all.pass(&msg);
        }
        let c = all.counts();
        assert_eq!((c.messages, c.total()), (1000, 1000));
        // Every kind occurs (about 200 each).
        assert!([c.flip, c.drop, c.duplicate, c.truncate, c.delay].iter().all(|&k| k > 150), "{c:?}");
    }

    #[test]
    fn the_same_seed_gives_the_same_faults_and_rates_are_met() {
        let run = |seed| {
            let mut f = FaultInjector::new(FaultConfig::from_rate(0.1, seed));
            let out: Vec<Vec<u8>> = (0..5000u32).map(|k| f.pass(&[0, 3, (k % 200 + 1) as u8, 9, 0])).collect();
            (out, f.counts())
        };
        let (a, ca) = run(7);
        assert_eq!(run(7), (a, ca));
        assert_ne!(run(8).1, ca);
        assert!((400..600).contains(&ca.total()), "10 % of 5000: {ca:?}");
    }

    #[test]
    fn a_delayed_message_follows_the_next_one() {
        let mut f = FaultInjector::new(FaultConfig::from_rate(0.0, 1));
        f.held = Some(vec![0, 2, 7, 0]);
        assert_eq!(f.pass(&[0, 2, 8, 0]), [0, 2, 8, 0, 0, 2, 7, 0]);
        assert!(f.release().is_empty());
    }

    #[test]
    fn splitter_finds_messages_across_chunks() {
        let mut s = MessageSplitter::default();
        let mut got = Vec::new();
        s.push(&[0, 3, 1], |m| got.push(m));
        s.push(&[2, 0, 0, 2, 9, 0], |m| got.push(m));
        assert_eq!(got, [vec![0, 3, 1, 2, 0], vec![0, 2, 9, 0]]);
    }
}
