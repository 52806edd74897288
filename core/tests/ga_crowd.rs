//! The crowd near the best fitness ([`Ga::crowd`]): the target filter's measurement is its
//! mean position, the estimate its centre within a reach of the best.

use evorec_core::ga::{Best, Ga, SearchSpace};

/// A reach that takes in every individual of [`population`].
const WIDE: [f32; 6] = [1.0; 6];
use evorec_core::pose::Psi;

fn mean(ga: &Ga<4>, best: &Best, margin: f32) -> [f32; 3] {
    ga.crowd(best, margin, &WIDE).translation
}

fn space() -> SearchSpace {
    SearchSpace::new_checked([-1.0, -1.0, 0.0], [1.0, 1.0, 2.0]).unwrap()
}

/// A population of four at known positions with fitness 0.90, 0.95, 0.80 and 0.94 (in that
/// order), evaluated with the last one left idle when `idle` is set.
fn population(idle: bool) -> (Ga<4>, Best) {
    let mut ga = Ga::<4>::new(Psi::IDENTITY);
    let xs = [0.10, 0.20, 0.30, 0.40];
    for (i, x) in xs.iter().enumerate() {
        ga.set_individual(i, Psi::new([*x, -*x, 1.0 + *x], [0.01 * i as f32, 0.0, 0.0]), &space());
    }
    let fit = |p: &Psi| match (p.0[0] * 10.0).round() as i32 {
        1 => 0.90,
        2 => 0.95,
        3 => 0.80,
        _ => 0.94,
    };
    let best = ga.evaluate_first(if idle { 3 } else { 4 }, fit);
    (ga, best)
}

#[test]
fn the_mean_covers_exactly_the_individuals_within_the_margin() {
    let (ga, best) = population(false);
    assert_eq!(best.fitness, 0.95);
    // Within 0.02 of 0.95: the individuals at 0.2 and 0.4.
    let m = mean(&ga, &best, 0.02);
    let want = [0.3, -0.3, 1.3];
    for (a, b) in m.iter().zip(want.iter()) {
        assert!((a - b).abs() < 1e-6, "{m:?} != {want:?}");
    }
    // Within 0.06: also the one at 0.1 (0.90), not the one at 0.3 (0.80).
    let m = mean(&ga, &best, 0.06);
    assert!((m[0] - 0.7 / 3.0).abs() < 1e-6, "{m:?}");
    // Margin 0: the best alone.
    assert_eq!(mean(&ga, &best, 0.0), [0.2, -0.2, 1.2]);
}

#[test]
fn the_centre_keeps_to_the_reach_and_the_mean_position_does_not() {
    let (ga, best) = population(false);
    // Within 0.06 of 0.95, the individuals at 0.1, 0.2 and 0.4; a reach of 0.15 m per axis
    // keeps 0.1 and 0.2 (0.4 is 0.2 m away) in the centre.
    let c = ga.crowd(&best, 0.06, &[0.15, 0.15, 0.15, 1.0, 1.0, 1.0]);
    assert!((c.centre.0[0] - 0.15).abs() < 1e-6, "{c:?}");
    assert!((c.translation[0] - 0.7 / 3.0).abs() < 1e-6, "{c:?}");
}

#[test]
fn idle_individuals_and_a_nan_margin_do_not_count() {
    let (ga, best) = population(true);
    // The idle individual (0.4, fitness 0.94 if it had been evaluated) is stored with 0.
    let m = mean(&ga, &best, 0.06);
    assert!((m[0] - 0.15).abs() < 1e-6, "{m:?}");
    assert_eq!(mean(&ga, &best, f32::NAN), [0.2, -0.2, 1.2]);
}
