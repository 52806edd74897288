//! The population size is chosen at run time up to the tracker's compiled capacity `P`.

use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::ga::{GaParams, SearchSpace};
use evorec_core::limits::{DEFAULT_POPULATION, POPULATION_CAPACITY};
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::quat;
use evorec_core::tracker::{Estimate, JointSample, Tracker, TrackerConfig};
use nalgebra::{Isometry3, Vector3};

mod common;
use common::{frame, render};

const W: u16 = 160;
const H: u16 = 120;

fn config(population: usize) -> TrackerConfig<7> {
    let cam = Pinhole::new_checked(200.0, 200.0, 80.0, 60.0, W, H).unwrap();
    let rig = StereoRig::parallel(cam, 0.1).unwrap();
    let space = SearchSpace::new_checked([-0.3, -0.3, 0.3], [0.3, 0.3, 1.2]).unwrap();
    let mut c = TrackerConfig::pa10(rig, Block::PAPER, Isometry3::identity(), space)
        .with_seed(11)
        .with_ga(GaParams::DEFAULT.with_population(population));
    // The acquisition's seeded and idle individuals need a population of at least
    // `seed_immigrants + idle_individuals + 2`; below that these tests switch it off.
    if population < c.tuning.acquire.seed_immigrants + c.tuning.acquire.idle_individuals + 2 {
        c.tuning.acquire.seed_immigrants = 0;
        c.tuning.acquire.idle_individuals = 0;
    }
    c
}

fn truth() -> Psi {
    let q = quat::from_angle_axis(0.4, &Vector3::new(0.2, 1.0, 0.1)).unwrap();
    Psi::from_parts(&Vector3::new(0.02, -0.01, 0.7), &q)
}

fn track<const P: usize>(population: usize, steps: usize) -> Vec<Estimate> {
    let c = config(population);
    let (l, r) = render(&c.rig, &truth());
    let frame = frame(&l, &r, W, H);
    let mut t: Tracker<7, P, 5> = Tracker::new(c).unwrap();
    assert_eq!(t.population().len(), population);
    t.reset_around(&truth(), &[0.01, 0.01, 0.01, 0.02, 0.02, 0.02]).unwrap();
    let joints = JointSample { q: [0.0; 7], qd: [0.0; 7], time_us: 0 };
    (0..steps).map(|_| t.step(&frame, &joints, 0.033).unwrap()).collect()
}

#[test]
fn sizes_outside_two_to_the_capacity_are_refused_with_the_capacity_named() {
    for bad in [0, 1, POPULATION_CAPACITY + 1] {
        let e = Tracker::<7>::new(config(bad)).unwrap_err();
        assert_eq!(e.field, "ga.population");
        let mut slot: Option<Tracker<7>> = None;
        assert!(Tracker::new_in(&mut slot, config(bad)).is_err());
        assert!(slot.is_none(), "the slot is unchanged on error");
    }
    assert!(Tracker::<7>::new(config(POPULATION_CAPACITY)).is_ok());
    assert!(Tracker::<7>::new(config(2).with_ga(GaParams::DEFAULT.with_population(2).with_immigrants(0))).is_ok());
}

#[test]
fn a_run_time_size_tracks_exactly_like_a_tracker_compiled_for_that_size() {
    let compiled = track::<DEFAULT_POPULATION>(DEFAULT_POPULATION, 15);
    // In a larger capacity (the host's 64) and in the default one.
    let chosen = track::<64>(DEFAULT_POPULATION, 15);
    assert_eq!(compiled, chosen);
    let chosen = track::<POPULATION_CAPACITY>(DEFAULT_POPULATION, 15);
    assert_eq!(compiled, chosen);
}

#[test]
fn smaller_and_larger_populations_both_track() {
    for p in [12, POPULATION_CAPACITY, 64] {
        let last = *track::<64>(p, 30).last().unwrap();
        let d = (last.psi.translation() - truth().translation()).norm();
        assert!(last.fitness > 0.9 && d < 0.01, "population {p}: F = {}, {d} m off", last.fitness);
    }
}

#[test]
fn new_in_resizes_a_tracker_already_in_the_slot() {
    let mut slot: Option<Tracker<7, 64>> = None;
    assert_eq!(Tracker::new_in(&mut slot, config(40)).unwrap().population().len(), 40);
    assert_eq!(Tracker::new_in(&mut slot, config(17)).unwrap().population().len(), 17);
    assert_eq!(Tracker::new_in(&mut slot, config(64)).unwrap().population().len(), 64);
}
