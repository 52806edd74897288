//! Step 5 of the acquisition: seeded individuals around a seed pose.

use nalgebra::{Matrix3, Vector3};
use rand_core::Rng;

use super::{AcquireConfig, SEED_LEVELS, Seed};
use crate::ga::unit_f32;
use crate::math;
use crate::pose::Psi;
use crate::quat;

/// The half turn about block axis `k − 1` (`k = 0`: identity) as a column sign pattern.
pub(super) fn half_turn(r: &Matrix3<f32>, k: u32) -> Matrix3<f32> {
    let mut out = *r;
    for a in 0..3usize {
        if k != 0 && a as u32 != k - 1 {
            let c = -out.column(a);
            out.set_column(a, &c);
        }
    }
    out
}

/// Seeded individual `index` of a generation: index 0 is the seed itself, every other one
/// the seed perturbed at a scale picked at random (uniform within `±spread` per position
/// axis, a rotation vector uniform within `±spread_rad` per component), with a random
/// rotation about the free axis if the seed has one. Every individual is then turned by a
/// random half turn of the colour symmetry. Draws exactly 9 random numbers.
pub fn seed_immigrant<R: Rng + ?Sized>(seed: &Seed, index: usize, config: &AcquireConfig, rng: &mut R) -> Option<Psi> {
    let u: [f32; 9] = core::array::from_fn(|_| unit_f32(rng));
    let exact = index == 0;
    let level = ((u[0] * SEED_LEVELS as f32) as usize).min(SEED_LEVELS - 1);
    let (sm, sr) = if exact {
        (0.0, 0.0)
    } else {
        (config.spread_m.get(level).copied().unwrap_or(0.0), config.spread_rad.get(level).copied().unwrap_or(0.0))
    };
    let centre = seed.centre + Vector3::new(2.0 * u[1] - 1.0, 2.0 * u[2] - 1.0, 2.0 * u[3] - 1.0) * sm;
    let half_rv = Vector3::new(2.0 * u[4] - 1.0, 2.0 * u[5] - 1.0, 2.0 * u[6] - 1.0) * (0.5 * sr);
    let n = math::sqrt(1.0 + half_rv.dot(&half_rv));
    let small = nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(
        1.0 / n,
        half_rv.x / n,
        half_rv.y / n,
        half_rv.z / n,
    ));
    let mut r = quat::to_rotation_matrix(&small) * seed.rotation;
    if let Some(a) = seed.free_axis
        && !exact
    {
        let axis = super::column(&seed.rotation, a);
        let spin = quat::from_angle_axis(core::f32::consts::TAU * u[7], &axis).ok()?;
        r = quat::to_rotation_matrix(&spin) * r;
    }
    let r = half_turn(&r, (u[8] * 4.0) as u32 % 4);
    let q = quat::from_rotation_matrix(&r).ok()?;
    Some(Psi::from_parts(&centre, &q))
}
