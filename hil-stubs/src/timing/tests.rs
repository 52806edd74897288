//! Unit tests of the timing firmware's portable half.

use super::*;
use core::cell::Cell;
use evorec_core::image::{PixelFormat, Rgb565, Rgb565Image};
use std::format;
use std::vec;
use std::vec::Vec;

struct Fake(Cell<u32>);

impl DownCounter for Fake {
    fn read(&self) -> u32 {
        let v = self.0.get();
        self.0.set(v.wrapping_sub(7));
        v
    }
}

#[test]
fn probe_measures_each_phase_across_a_wrap() {
    let clock = Fake(Cell::new(10));
    let mut p = PhaseTimer::new(&clock);
    assert_eq!(p.phases(), None);
    for ph in [Phase::Feedforward, Phase::Evaluate, Phase::Breed, Phase::Done] {
        p.mark(ph);
    }
    assert_eq!(p.phases(), Some(PhaseTicks { feedforward: 7, evaluate: 7, breed: 7 }));
}

#[test]
fn ticks_convert_at_shift_10() {
    // 1024 ns per instruction, 40 ns per tick: 128 ticks = 5 instructions.
    assert_eq!(ticks_to_instructions(128), 5.0);
}

#[test]
fn schedule_covers_every_kind_evenly() {
    for frames in [FULL_FRAMES, SWEEP_FRAMES] {
        for kind in CaseKind::ALL {
            let n = (0..frames).filter(|&k| schedule(k, frames) == kind).count() as u32;
            let kinds = CaseKind::ALL.len() as u32;
            assert!(n >= frames / kinds - 1 && n >= 2, "{kind:?}: {n} of {frames}");
        }
    }
    assert_eq!(schedule(0, FULL_FRAMES), CaseKind::Tracking);
    assert_eq!(schedule(FULL_FRAMES - 1, FULL_FRAMES), CaseKind::FastArm);
    // The conveyor runs three blocks in a row: long enough for the target filter to trust.
    let conveyor: Vec<u32> = (0..FULL_FRAMES).filter(|&k| schedule(k, FULL_FRAMES) == CaseKind::Conveyor).collect();
    assert_eq!(conveyor.len(), 33);
    assert!(conveyor.windows(2).all(|w| w[1] == w[0] + 1));
    assert_eq!(SLOTS.len(), CaseKind::ALL.len() + 2);
    assert!(CaseKind::ALL.iter().all(|k| SLOTS.contains(k)));
}

#[test]
fn gen_lines_round_trip() {
    let g = GenLine {
        population: 40,
        grid: 8,
        frame: 3,
        kind: CaseKind::NoisyTarget,
        status: Status::Lost,
        method: Feedforward::OnWithTarget,
        target_shift: true,
        call: 123_456,
        phases: PhaseTicks { feedforward: 1, evaluate: 2, breed: 3 },
        stack: 2048,
        fitness: 0.8125,
    };
    let line = format!("{g}");
    assert!(line.contains(" method=ff+target tshift=1 "), "{line}");
    assert_eq!(GenLine::parse(&line), Some(g));
    let plain = GenLine { method: Feedforward::On, target_shift: false, ..g };
    assert_eq!(GenLine::parse(&format!("{plain}")), Some(plain));
    // The mode and the shift flag are required and checked.
    assert_eq!(GenLine::parse(&line.replace(" tshift=1", "")), None);
    assert_eq!(GenLine::parse(&line.replace("tshift=1", "tshift=2")), None);
    assert_eq!(GenLine::parse(&line.replace("method=ff+target", "method=fft")), None);
    assert_eq!(GenLine::parse("GEN p=40 g=8"), None);
    assert_eq!(GenLine::parse("[INFO ] hello"), None);
}

#[test]
fn conveyor_moves_the_target_along_world_y_and_back() {
    let config = crate::selftest::tracker_config().unwrap();
    let cases = CaseGen::new(config.rig, config.flange_to_camera, 5).unwrap();
    let world = |k: u32, psi: Psi| {
        let cam = PA10.forward(&CaseGen::joints(k, false).q) * config.flange_to_camera;
        (cam * psi.try_to_isometry().unwrap()).translation.vector
    };
    // Continuous with the path at the block's start; then the conveyor's offset alone.
    let from = 20;
    assert!((world(from, cases.truth_on_conveyor(from, from)) - world(from, cases.truth(from, false))).norm() < 1e-5);
    for (steps, expected) in [(15u32, 0.05f32), (30, 0.1), (45, 0.12 - 0.03)] {
        let k = from + steps;
        let d = world(k, cases.truth_on_conveyor(k, from)) - world(k, cases.truth(k, false));
        assert!((d.y - expected).abs() < 2e-3 && d.x.abs() < 1e-4 && d.z.abs() < 1e-4, "{steps}: {d:?}");
    }
}

#[test]
fn rig_for_scales_the_selftest_view() {
    // At 160×120 the rig is the self-test's; at 320×240 the focal length doubles.
    assert_eq!(rig_for(160, 120).unwrap(), crate::selftest::rig().unwrap());
    let m7 = rig_for(320, 240).unwrap();
    assert_eq!((m7.right.width(), m7.right.height()), (320, 240));
    assert!(rig_for(0, 240).is_err());
}

#[test]
fn frames_of_every_kind_are_made() {
    let config = crate::selftest::tracker_config().unwrap();
    let mut cases = CaseGen::new(config.rig, config.flange_to_camera, 5).unwrap();
    let (mut l, mut r) = (vec![0u8; 2 * 160 * 120], vec![0u8; 2 * 160 * 120]);
    for (k, kind) in CaseKind::ALL.into_iter().enumerate() {
        let k = 12 * k as u32 + 12;
        let j = cases.frame(k, kind, &mut l, &mut r).unwrap();
        let img = Rgb565Image::new_checked(&l[..], 160, 120).unwrap();
        let painted = img.pixels().iter().filter(|&&px| Rgb565::hue(px) != NO_HUE).count();
        match kind {
            CaseKind::Blank => assert_eq!(painted, 0),
            CaseKind::Filling | CaseKind::UniformHue => assert!(painted > 150 * 110, "{kind:?}: {painted}"),
            // Random RGB565 values: most have a hue (not too dark, not too grey).
            CaseKind::Noise => assert!(painted > 160 * 120 / 2, "{kind:?}: {painted}"),
            // Three of the five extremes are pure primaries.
            CaseKind::Rgb565Extremes => {
                assert!(painted.abs_diff(160 * 120 * 3 / 5) < 600, "{kind:?}: {painted}");
                assert!(img.pixels().iter().all(|px| RGB565_EXTREMES.contains(&u16::from_le_bytes(*px))));
            }
            // Fast arm motion may carry the target out of view: only the speed is checked.
            CaseKind::FastArm => assert!(j.qd.iter().any(|v| v.abs() > 0.2), "{:?}", j.qd),
            _ => assert!(painted > 100, "{kind:?}: {painted}"),
        }
        assert!(j.qd.iter().any(|v| *v != 0.0));
    }
    assert!(cases.frame(0, CaseKind::Blank, &mut l[..10], &mut r).is_err());
    // Hue-sized buffers are too small for RGB565 frames.
    assert!(cases.frame(0, CaseKind::Blank, &mut l[..160 * 120], &mut r).is_err());
}

#[test]
fn deadline_report_counts_misses_and_round_trips() {
    assert_eq!(DEADLINE_TICKS, 25_600_000); // 10⁶ instructions · 2¹⁰ ns / 40 ns
    let mut r = DeadlineReport::default();
    assert!(r.check(DEADLINE_TICKS));
    assert!(!r.check(DEADLINE_TICKS + 1));
    assert!(r.check(5));
    assert_eq!(r, DeadlineReport { checked: 3, missed: 1, worst: DEADLINE_TICKS + 1 });
    assert_eq!(DeadlineReport::parse(&format!("{r}")), Some(r));
    assert_eq!(DeadlineReport::parse("GEN p=1"), None);
}
