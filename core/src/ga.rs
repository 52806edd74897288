//! The 1-step GA: one generation per call, a statically sized population of poses.
//!
//! One generation on the newest frame pair ([`Ga::evaluate`], then [`Ga::breed`]):
//! 1. **evaluate** every individual with the caller's fitness;
//! 2. the **best** (ties keep the lower index, and the elite sits at index 0, so an equally
//!    good newcomer does not displace it) is the estimate;
//! 3. **breed** the next population: the elite unchanged at index 0; `immigrants` fresh
//!    uniform samples of the search space at the end (they let the GA re-acquire a lost
//!    target); every other child from two binary-tournament parents, blend crossover
//!    (BLX-0.25 per gene) with probability `crossover_prob`, then with probability
//!    `mutation_prob` a triangular perturbation at one of three scales picked at random, the
//!    fine scale more often once the elite fits almost perfectly (lateral position, depth
//!    along the viewing ray, and a small turn about the camera's axes in place of ε's genes;
//!    see [`GaParams::mutation_scale`] and [`GaParams::settled_level_cdf`]).
//!    Children are clamped into the search space and `|ε| ≤ 1`.
//!
//! Every child draws the same number of random numbers whatever happens to it, so the work
//! and the generator's state after a generation do not depend on the data. Randomness comes
//! from any [`rand_core::Rng`]; the tracker uses a seeded `Xoshiro128PlusPlus`.

use nalgebra::Vector3;
use rand_core::Rng;

use crate::limits::DEFAULT_POPULATION;
use crate::math;
use crate::pose::Psi;
use crate::quat;

/// Why GA settings were rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum GaError {
    /// A bound or parameter is NaN or infinite.
    NonFinite,
    /// A search-space minimum is not below its maximum.
    EmptySearchSpace,
    /// The population size is below 2 or above the capacity the GA was compiled with.
    PopulationSize {
        /// The size asked for.
        got: usize,
        /// The compiled capacity (the largest size accepted).
        capacity: usize,
    },
}

impl core::fmt::Display for GaError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NonFinite => f.write_str("GA parameter is not finite"),
            Self::EmptySearchSpace => f.write_str("search space is empty"),
            Self::PopulationSize { got, capacity } => {
                write!(f, "population {got} is out of range (2..={capacity}, the compiled capacity)")
            }
        }
    }
}

impl core::error::Error for GaError {}

/// The box of positions (in `Σ_CR`, metres) searched; `ε` ranges over the unit ball.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchSpace {
    t_min: [f32; 3],
    t_max: [f32; 3],
}

impl SearchSpace {
    /// A search box `t_min ≤ t ≤ t_max`.
    ///
    /// # Errors
    /// [`GaError::NonFinite`] or [`GaError::EmptySearchSpace`].
    pub fn new_checked(t_min: [f32; 3], t_max: [f32; 3]) -> Result<Self, GaError> {
        if !t_min.iter().chain(t_max.iter()).all(|v| v.is_finite()) {
            return Err(GaError::NonFinite);
        }
        if t_min.iter().zip(t_max.iter()).any(|(lo, hi)| lo >= hi) {
            return Err(GaError::EmptySearchSpace);
        }
        Ok(Self { t_min, t_max })
    }

    /// Lower position bounds.
    pub fn t_min(&self) -> [f32; 3] {
        self.t_min
    }

    /// Upper position bounds.
    pub fn t_max(&self) -> [f32; 3] {
        self.t_max
    }

    /// Clamps the position into the box and `ε` into the unit ball (non-finite → 0 first).
    pub fn clamp(&self, psi: &mut Psi) {
        psi.project_to_ball();
        for ((x, lo), hi) in psi.0.iter_mut().zip(self.t_min.iter()).zip(self.t_max.iter()) {
            *x = math::clamp(*x, *lo, *hi);
        }
    }

    /// A uniform sample: position uniform in the box, `ε` uniform in the cube `[-1, 1]³`
    /// then projected onto the ball. Draws exactly 6 numbers.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> Psi {
        let mut p = Psi::IDENTITY;
        for (i, x) in p.0.iter_mut().enumerate() {
            let u = unit_f32(rng);
            *x = match (self.t_min.get(i), self.t_max.get(i)) {
                (Some(lo), Some(hi)) => lo + (hi - lo) * u,
                _ => 2.0 * u - 1.0,
            };
        }
        p.project_to_ball();
        p
    }
}

/// Number of mutation scales.
pub const MUTATION_LEVELS: usize = 3;

/// GA settings; [`GaParams::DEFAULT`] states the defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaParams {
    /// Individuals evaluated and bred per generation, chosen at run time: at least 2 and at
    /// most the capacity `P` of the [`Ga`] (storage is sized for `P`, the work follows this).
    /// The one source of a GA's size: [`Ga::set_population`] takes it from here (the tracker
    /// when it is built), and [`Ga::len`] reports it.
    pub population: usize,
    /// Probability that a child is a blend of its two parents (else a copy of the first).
    pub crossover_prob: f32,
    /// Probability that a child is mutated.
    pub mutation_prob: f32,
    /// Probability that each gene of a mutated child is perturbed. Below 1 the GA makes
    /// moves in few coordinates at a time, which is how it follows ridges of the fitness where
    /// two parameters compensate each other (depth against yaw, say).
    pub gene_mutation_prob: f32,
    /// Fresh uniform samples per generation.
    pub immigrants: usize,
    /// Individuals drawn per tournament (the fittest of them is a parent); at least 1.
    pub tournament: usize,
    /// Cumulative probabilities of picking mutation scale 0, 1 (scale 2 takes the rest).
    pub level_cdf: [f32; MUTATION_LEVELS - 1],
    /// The same, used instead of `level_cdf` when the elite's fitness is at least
    /// `settled_fitness`: a pose that fits almost perfectly is refined with the fine scale
    /// more often. Either choice draws the same random numbers (same work).
    pub settled_level_cdf: [f32; MUTATION_LEVELS - 1],
    /// The elite fitness from which `settled_level_cdf` is used (above 1: never).
    pub settled_fitness: f32,
    /// Half-widths of the triangular mutation per gene, one row per scale; a mutated child
    /// uses one row picked uniformly. Columns: lateral `x`, `y` (m), depth along the viewing
    /// ray (m of `t_z`), then the turn about the camera's `x`, `y`, `z` axes as the vector part
    /// of its quaternion (`½·angle` in rad; at `η = 1` the change of `ε₁, ε₂, ε₃`).
    pub mutation_scale: [[f32; 6]; MUTATION_LEVELS],
}

impl GaParams {
    /// Defaults for a target about 0.5–1 m away at 30 frames/s: population
    /// [`DEFAULT_POPULATION`], tournaments of 3, crossover
    /// 0.2, mutation 0.9 with each gene perturbed with probability 0.35, one immigrant,
    /// mutation scales 20 mm / 0.04, 4 mm / 0.008, 1 mm / 0.004 (the turn, in ε) picked with
    /// probabilities 0.25, 0.35, 0.4, or 0.15, 0.35, 0.5 once the elite's fitness is 0.95.
    ///
    /// The evidence for the finest turn and the settled probabilities is in `docs/method.md`:
    /// over GA seeds 1–20 of the paper's FF grid, where the fitness stays near 0.99, they give
    /// lower median ε₂ and ε₃ in every cell than a turn of 0.002 with fixed probabilities,
    /// while a finer turn (0.001) raises ε₃ by about a quarter. The settled probabilities on
    /// every frame lose the 0.2 m/s conveyor (fitness 0.7–0.9) in 5 of 20 runs; hence the gate.
    pub const DEFAULT: GaParams = GaParams {
        population: DEFAULT_POPULATION,
        crossover_prob: 0.2,
        mutation_prob: 0.9,
        gene_mutation_prob: 0.35,
        immigrants: 1,
        tournament: 3,
        level_cdf: [0.25, 0.6],
        settled_level_cdf: [0.15, 0.5],
        settled_fitness: 0.95,
        mutation_scale: [
            [0.020, 0.020, 0.020, 0.04, 0.04, 0.04],
            [0.004, 0.004, 0.004, 0.008, 0.008, 0.008],
            [0.001, 0.001, 0.001, 0.004, 0.004, 0.004],
        ],
    };

    /// Builder: population size (checked against the capacity by [`crate::tuning::Tuning::validate`]).
    #[must_use]
    pub fn with_population(mut self, n: usize) -> Self {
        self.population = n;
        self
    }

    /// Builder: crossover probability.
    #[must_use]
    pub fn with_crossover_prob(mut self, p: f32) -> Self {
        self.crossover_prob = p;
        self
    }

    /// Builder: mutation probability.
    #[must_use]
    pub fn with_mutation_prob(mut self, p: f32) -> Self {
        self.mutation_prob = p;
        self
    }

    /// Builder: per-gene mutation probability.
    #[must_use]
    pub fn with_gene_mutation_prob(mut self, p: f32) -> Self {
        self.gene_mutation_prob = p;
        self
    }

    /// Builder: immigrants per generation.
    #[must_use]
    pub fn with_immigrants(mut self, n: usize) -> Self {
        self.immigrants = n;
        self
    }

    /// Builder: the level probabilities used from `fitness` on (see
    /// [`GaParams::settled_level_cdf`]); a `fitness` above 1 turns them off.
    #[must_use]
    pub fn with_settled_levels(mut self, cdf: [f32; MUTATION_LEVELS - 1], fitness: f32) -> Self {
        self.settled_level_cdf = cdf;
        self.settled_fitness = fitness;
        self
    }

    /// Builder: mutation scales.
    #[must_use]
    pub fn with_mutation_scale(mut self, s: [[f32; 6]; MUTATION_LEVELS]) -> Self {
        self.mutation_scale = s;
        self
    }
}

impl Default for GaParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A uniform `f32` in `[0, 1)` from the top 24 bits of one `u32` (exact, portable).
#[inline]
pub fn unit_f32<R: Rng + ?Sized>(rng: &mut R) -> f32 {
    (rng.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Triangular noise on `(-1, 1)` (sum of two uniforms): cheap, bounded, peaked at 0.
#[inline]
fn triangular<R: Rng + ?Sized>(rng: &mut R) -> f32 {
    unit_f32(rng) + unit_f32(rng) - 1.0
}

/// Applies one mutation: `noise` (each in `(-1, 1)`) times `scale`. The third position gene
/// moves the pose **along its viewing ray** (all of `t` scaled so that `t_z` changes by
/// `scale[2]·noise[2]`) rather than along `z`: depth is the poorly observed direction of a
/// camera, and a move along the ray keeps the target's image position, so the GA can refine
/// depth without undoing the lateral fit. The three ε genes **turn** the pose about the
/// camera's axes ([`turn`]) instead of being added to ε.
fn mutate(c: &mut Psi, scale: &[f32; 6], noise: &[f32; 6]) {
    let z = c.0[2];
    let k = if z > 1e-3 { scale[2] * noise[2] / z } else { 0.0 };
    for x in c.0.iter_mut().take(3) {
        *x += *x * k;
    }
    c.0[0] += scale[0] * noise[0];
    c.0[1] += scale[1] * noise[1];
    let [.., s3, s4, s5] = *scale;
    let [.., n3, n4, n5] = *noise;
    turn(c, [s3 * n3, s4 * n4, s5 * n5]);
}

/// Turns the orientation of `c` by the small rotation whose quaternion has vector part `h`
/// (`h ≈ ½·angle·axis`, axis in the camera frame): `Q ← normalise(1, h) ⊗ Q`, the
/// representative with `η ≥ 0` kept.
///
/// Why not add `h` to ε: the turn that `Δε` makes depends on the pose. With `η = √(1−|ε|²)`
/// a step along ε also changes η by `−ε·Δε/η`, so near a half turn (small η) a step of
/// ε's size turns the block several times further than the same step at `η ≈ 1`, and the
/// mutation scales lose their meaning; a turn composed on the left is the same turn at every
/// orientation, and at `η = 1` it changes ε by `h` (to first order), as the paper's operator.
fn turn(c: &mut Psi, h: [f32; 3]) {
    let q = quat::canonical(&quat::compose(&quat::normalized(1.0, Vector3::from(h)), &c.quaternion_unchecked()));
    let e = q.imag();
    if e.iter().all(|v| v.is_finite()) {
        let [.., a, b, d] = &mut c.0;
        (*a, *b, *d) = (e.x, e.y, e.z);
    }
}

/// A population of up to `P` poses and their last fitness values.
///
/// `P` is the capacity (the storage, fixed at compile time); the number of individuals in
/// use, [`Ga::len`], is chosen at run time up to it (the `heapless` way). Every loop runs over
/// the individuals in use only, so the work of a generation is bounded by that of `P`.
#[derive(Debug, Clone)]
pub struct Ga<const P: usize> {
    pop: [Psi; P],
    fitness: [f32; P],
    len: usize,
}

/// The outcome of one generation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Best {
    /// The best individual of the evaluated population.
    pub psi: Psi,
    /// Its fitness.
    pub fitness: f32,
}

/// The crowd at the top of the best's fitness peak ([`Ga::crowd`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crowd {
    /// The mean pose of the crowd's members within the reach of the best (the position's
    /// offset, and the vector part of the turn from the best's orientation, per gene, as
    /// [`GaParams::mutation_scale`] measures a step). The orientation is the normalised sum of
    /// their quaternions, each taken on the best's side of the sphere (`q` and `−q` are one
    /// rotation). The best's own pose when nothing else is near or the sum vanishes.
    pub centre: Psi,
    /// The mean position of the whole crowd, reach or not.
    pub translation: [f32; 3],
}

impl<const P: usize> Ga<P> {
    /// A full population (`P` individuals) with every individual at `psi`.
    pub fn new(psi: Psi) -> Self {
        const { assert!(P >= 2, "a population needs at least two members") };
        Self { pop: [psi; P], fitness: [0.0; P], len: P }
    }

    /// The capacity `P`.
    pub const CAPACITY: usize = P;

    /// Individuals in use.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Never true: a population has at least two members.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Uses `params.population` individuals from now on. New members (when growing) are
    /// copies of the first one; re-seed with [`Ga::reset_around`] or [`Ga::reset_uniform`]
    /// afterwards.
    ///
    /// # Errors
    /// [`GaError::PopulationSize`] unless `2 ≤ params.population ≤ P` (the population is then
    /// unchanged).
    pub fn set_population(&mut self, params: &GaParams) -> Result<(), GaError> {
        let n = params.population;
        if !(2..=P).contains(&n) {
            return Err(GaError::PopulationSize { got: n, capacity: P });
        }
        let first = self.pop.first().copied().unwrap_or(Psi::IDENTITY);
        for ind in self.pop.iter_mut().skip(self.len).take(n.saturating_sub(self.len)) {
            *ind = first;
        }
        self.len = n;
        Ok(())
    }

    /// The individuals in use (index 0 is the elite after a generation).
    pub fn individuals(&self) -> &[Psi] {
        self.pop.get(..self.len).unwrap_or(&self.pop)
    }

    /// Fitness of each individual in use at the last evaluation.
    pub fn fitness(&self) -> &[f32] {
        self.fitness.get(..self.len).unwrap_or(&self.fitness)
    }

    /// The individuals in use, mutable.
    fn active_mut(&mut self) -> impl Iterator<Item = &mut Psi> {
        let len = self.len;
        self.pop.iter_mut().take(len)
    }

    /// Re-seeds the population around `center`: index 0 exactly at it, the others uniformly
    /// within `±spread` per gene, clamped into `space`.
    pub fn reset_around<R: Rng + ?Sized>(&mut self, center: &Psi, spread: &[f32; 6], space: &SearchSpace, rng: &mut R) {
        for (i, ind) in self.active_mut().enumerate() {
            let mut p = *center;
            for (x, s) in p.0.iter_mut().zip(spread.iter()) {
                let u = 2.0 * unit_f32(rng) - 1.0;
                if i > 0 {
                    *x += s * u;
                }
            }
            space.clamp(&mut p);
            *ind = p;
        }
        self.fitness = [0.0; P];
    }

    /// Re-seeds the whole population uniformly over `space`.
    pub fn reset_uniform<R: Rng + ?Sized>(&mut self, space: &SearchSpace, rng: &mut R) {
        for ind in self.active_mut() {
            *ind = space.sample(rng);
        }
        self.fitness = [0.0; P];
    }

    /// The index of the first of `params.immigrants` fresh samples that [`Ga::breed`] puts at
    /// the end of the population (the elite and at least one child stay before it).
    pub fn first_immigrant(&self, params: &GaParams) -> usize {
        let n = self.len.max(1);
        n - params.immigrants.min(n - 1)
    }

    /// Replaces individual `index` by `psi` clamped into `space` (seeded immigrants; an index
    /// out of range is ignored). Its stored fitness is cleared to 0 until the next evaluation.
    pub fn set_individual(&mut self, index: usize, psi: Psi, space: &SearchSpace) {
        if let (Some(ind), Some(f)) = (self.pop.get_mut(index), self.fitness.get_mut(index)) {
            let mut p = psi;
            space.clamp(&mut p);
            *ind = p;
            *f = 0.0;
        }
    }

    /// Applies `f` to every individual, then clamps it into `space` (used for the
    /// feedforward shift, eq. 36).
    pub fn shift_all(&mut self, space: &SearchSpace, mut f: impl FnMut(&mut Psi)) {
        for ind in self.active_mut() {
            f(ind);
            space.clamp(ind);
        }
    }

    /// Step 1–2: evaluates every individual with `fitness` and returns the best.
    pub fn evaluate(&mut self, fitness: impl FnMut(&Psi) -> f32) -> Best {
        self.evaluate_first(self.len, fitness)
    }

    /// Step 1–2 on the first `count` individuals only (at least the elite, at most all): the
    /// others keep their pose, get fitness 0 and are never the best.
    pub fn evaluate_first(&mut self, count: usize, mut fitness: impl FnMut(&Psi) -> f32) -> Best {
        let mut best = Best { psi: Psi::IDENTITY, fitness: f32::NEG_INFINITY };
        let n = count.max(1).min(self.len);
        if let Some(idle) = self.fitness.get_mut(n..) {
            idle.fill(0.0);
        }
        for (ind, f) in self.pop.iter().zip(self.fitness.iter_mut()).take(n) {
            let v = fitness(ind);
            // NaN never wins and is stored as 0.
            *f = if v.is_nan() { 0.0 } else { v };
            if *f > best.fitness {
                best = Best { psi: *ind, fitness: *f };
            }
        }
        best
    }

    /// The crowd at the top of `best`'s fitness peak, in one pass over the individuals in use
    /// whose fitness at the last evaluation is within `margin` of `best`'s (`best` itself always
    /// counts). Their centre wanders less from frame to frame than the single best individual
    /// does. A `margin` that is not positive (0, or NaN) gives `best`'s own pose for both, not
    /// the mean of the individuals tied with it.
    pub fn crowd(&self, best: &Best, margin: f32, reach: &[f32; 6]) -> Crowd {
        let t = best.psi.translation();
        let alone = Crowd { centre: best.psi, translation: [t.x, t.y, t.z] };
        if margin.is_nan() || margin <= 0.0 {
            return alone;
        }
        let floor = best.fitness - margin;
        let qb = best.psi.quaternion_unchecked();
        let qb_inv = qb.inverse();
        let (mut all, mut n_all) = ([0.0f32; 3], 0u32);
        let (mut t, mut sum, mut n) = ([0.0f32; 3], nalgebra::Quaternion::new(0.0f32, 0.0, 0.0, 0.0), 0u32);
        for (ind, _) in self.individuals().iter().zip(self.fitness().iter()).filter(|(_, f)| **f >= floor) {
            add_to(&mut all, &ind.0);
            n_all += 1;
            let q = ind.quaternion_unchecked();
            let d = quat::canonical(&(q * qb_inv)).imag();
            let offsets = ind.0.iter().zip(best.psi.0.iter()).map(|(a, b)| a - b);
            let near_t = offsets.zip(reach.iter()).take(3).all(|(x, r)| x.abs() <= *r);
            let near_q = d.iter().zip(reach.iter().skip(3)).all(|(x, r)| x.abs() <= *r);
            if near_t && near_q {
                add_to(&mut t, &ind.0);
                let q = q.into_inner();
                sum += if q.dot(qb.as_ref()) < 0.0 { -q } else { q };
                n += 1;
            }
        }
        let translation = if n_all == 0 { alone.translation } else { all.map(|s| s / n_all as f32) };
        let norm = crate::math::sqrt(sum.dot(&sum));
        let centre = if n == 0 || norm.is_nan() || norm <= 1e-6 {
            best.psi
        } else {
            let t = nalgebra::Vector3::from(t) / n as f32;
            Psi::from_parts(&t, &nalgebra::UnitQuaternion::new_unchecked(sum / norm))
        };
        Crowd { centre, translation }
    }

    /// Step 3: breeds the next population from the evaluated one; `best` is the result of
    /// [`Ga::evaluate`].
    ///
    /// Never inlined: it keeps a copy of the parents (the population it overwrites) on the
    /// stack, which must not sit in its caller's frame under the fitness evaluation.
    #[inline(never)]
    pub fn breed<R: Rng + ?Sized>(&mut self, best: &Best, params: &GaParams, space: &SearchSpace, rng: &mut R) {
        let parents = self.pop;
        let fit = self.fitness;
        let n = self.len.max(1);
        let rounds = params.tournament.max(1);
        let pick = |rng: &mut R| -> Psi {
            let mut winner = (rng.next_u32() as usize) % n;
            for _ in 1..rounds {
                let c = (rng.next_u32() as usize) % n;
                if fit.get(c).copied().unwrap_or(0.0) > fit.get(winner).copied().unwrap_or(0.0) {
                    winner = c;
                }
            }
            parents.get(winner).copied().unwrap_or(best.psi)
        };
        let first_immigrant = self.first_immigrant(params);
        let cdf = if best.fitness >= params.settled_fitness { params.settled_level_cdf } else { params.level_cdf };
        for (i, child) in self.active_mut().enumerate() {
            if i == 0 {
                *child = best.psi;
                continue;
            }
            if i >= first_immigrant {
                *child = space.sample(rng);
                continue;
            }
            let a = pick(rng);
            let b = pick(rng);
            let do_cross = unit_f32(rng) < params.crossover_prob;
            let mut c = a;
            for ((x, xa), xb) in c.0.iter_mut().zip(a.0.iter()).zip(b.0.iter()) {
                let alpha = 1.5 * unit_f32(rng) - 0.25;
                if do_cross {
                    *x = xa + alpha * (xb - xa);
                }
            }
            let do_mutate = unit_f32(rng) < params.mutation_prob;
            let u = unit_f32(rng);
            let level = cdf.iter().filter(|&&c| u >= c).count();
            let scale = params.mutation_scale.get(level).copied().unwrap_or([0.0; 6]);
            let mut noise: [f32; 6] = core::array::from_fn(|_| triangular(rng));
            for n in noise.iter_mut() {
                if unit_f32(rng) >= params.gene_mutation_prob {
                    *n = 0.0;
                }
            }
            if do_mutate {
                mutate(&mut c, &scale, &noise);
            }
            space.clamp(&mut c);
            *child = c;
        }
    }
}

/// `sum += x` over the three position genes of `x`.
fn add_to(sum: &mut [f32; 3], x: &[f32; 6]) {
    for (s, v) in sum.iter_mut().zip(x.iter()) {
        *s += v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::SeedableRng;
    use rand_xoshiro::Xoshiro128PlusPlus;

    fn space() -> SearchSpace {
        SearchSpace::new_checked([-0.5, -0.5, 0.2], [0.5, 0.5, 1.5]).unwrap()
    }

    /// A smooth stand-in fitness peaked at `target`.
    fn bowl(target: &Psi) -> impl Fn(&Psi) -> f32 + '_ {
        move |p: &Psi| {
            let d2: f32 = p.0.iter().zip(target.0.iter()).map(|(a, b)| (a - b) * (a - b)).sum();
            1.0 / (1.0 + 100.0 * d2)
        }
    }

    #[test]
    fn crowd_centre_is_the_mean_of_the_individuals_near_the_best() {
        let mut ga = Ga::<4>::new(Psi::IDENTITY);
        let turn = |deg: f32| {
            let half = 0.5 * deg.to_radians();
            [0.0, 0.0, crate::math::sin(half)]
        };
        // Best at 0°, two within the margin at +4° and −2°, one far off below it.
        let poses = [
            Psi::new([0.0, 0.0, 0.7], turn(0.0)),
            Psi::new([0.003, 0.0, 0.7], turn(4.0)),
            Psi::new([0.0, 0.0, 0.703], turn(-2.0)),
            Psi::new([0.1, 0.1, 0.9], turn(60.0)),
        ];
        let fit = [1.0f32, 0.995, 0.992, 0.5];
        for (i, p) in poses.iter().enumerate() {
            ga.set_individual(i, *p, &space());
        }
        let best = ga.evaluate(|p| fit[poses.iter().position(|q| q == p).unwrap()]);
        let reach = GaParams::DEFAULT.mutation_scale[0];
        let m = ga.crowd(&best, 0.01, &reach).centre;
        let angle = 2.0 * libm::asinf(m.eps().z).to_degrees();
        assert!((m.0[0] - 0.001).abs() < 1e-6 && (m.0[2] - 0.701).abs() < 1e-6, "{m:?}");
        assert!((angle - 2.0 / 3.0).abs() < 0.01, "{angle}");
        assert_eq!(ga.crowd(&best, 0.0, &reach).centre, best.psi);
        assert_eq!(ga.crowd(&best, f32::NAN, &reach).centre, best.psi);
        // Out of reach (2 mm against a reach of 1 mm), the others no longer count in the
        // centre; the crowd's mean position still takes all three within the margin.
        let far = ga.crowd(&best, 0.01, &[0.001, 0.001, 0.001, 0.04, 0.04, 0.04]);
        assert_eq!(far.centre, best.psi);
        assert!((far.translation[0] - 0.001).abs() < 1e-6 && (far.translation[2] - 0.701).abs() < 1e-6, "{far:?}");
    }

    #[test]
    fn crowd_centre_takes_a_quaternion_and_its_negative_as_one_rotation() {
        let mut ga = Ga::<2>::new(Psi::IDENTITY);
        // Half turns about z just either side of 180°: η has opposite signs, so ε flips sign.
        let a = Psi::new([0.0, 0.0, 0.7], [0.0, 0.0, crate::math::sin(0.5 * 179f32.to_radians())]);
        let b = Psi::from_parts(
            &nalgebra::Vector3::new(0.0, 0.0, 0.7),
            &nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Vector3::z_axis(), 181f32.to_radians()),
        );
        ga.set_individual(0, a, &space());
        ga.set_individual(1, b, &space());
        let best = ga.evaluate(|p| if *p == a { 1.0 } else { 0.999 });
        let m = ga.crowd(&best, 0.01, &GaParams::DEFAULT.mutation_scale[0]).centre;
        // The mean is the half turn itself (|ε_z| = 1), not the identity that averaging ε gives.
        assert!(m.eps().z.abs() > 0.9999, "{m:?}");
    }

    #[test]
    fn elitism_never_loses_the_best_on_a_static_fitness() {
        let target = Psi::new([0.1, -0.05, 0.7], [0.1, 0.2, -0.1]);
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(7);
        let mut ga = Ga::<30>::new(Psi::IDENTITY);
        ga.reset_uniform(&space(), &mut rng);
        let f = bowl(&target);
        let mut last = f32::NEG_INFINITY;
        for _ in 0..300 {
            let best = ga.evaluate(&f);
            assert!(best.fitness >= last, "{} < {last}", best.fitness);
            last = best.fitness;
            ga.breed(&best, &GaParams::DEFAULT, &space(), &mut rng);
            assert_eq!(ga.individuals()[0], best.psi);
        }
        assert!(last > 0.999, "did not converge: {last}");
    }

    #[test]
    fn same_seed_same_result() {
        let run = |seed| {
            let mut rng = Xoshiro128PlusPlus::seed_from_u64(seed);
            let mut ga = Ga::<20>::new(Psi::IDENTITY);
            ga.reset_uniform(&space(), &mut rng);
            let target = Psi::new([0.0, 0.0, 0.8], [0.0; 3]);
            let f = bowl(&target);
            let mut best = ga.evaluate(&f);
            for _ in 0..50 {
                ga.breed(&best, &GaParams::DEFAULT, &space(), &mut rng);
                best = ga.evaluate(&f);
            }
            best
        };
        assert_eq!(run(3), run(3));
        assert_ne!(run(3).psi, run(4).psi);
    }

    #[test]
    fn children_stay_in_the_search_space() {
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(1);
        let s = space();
        let mut ga = Ga::<16>::new(Psi::new([0.5, 0.5, 1.5], [0.9, 0.4, 0.0]));
        let wild = GaParams::DEFAULT.with_mutation_scale([[10.0; 6]; 3]).with_immigrants(3);
        for _ in 0..100 {
            let best = ga.evaluate(|_| 0.5);
            ga.breed(&best, &wild, &s, &mut rng);
            for p in ga.individuals() {
                assert!(p.validate().is_ok());
                for (i, x) in p.0.iter().take(3).enumerate() {
                    assert!(*x >= s.t_min()[i] && *x <= s.t_max()[i]);
                }
            }
        }
    }

    #[test]
    fn the_elites_fitness_picks_the_level_probabilities() {
        // Coarse steps only below the gate, fine steps only from it on.
        let s = space();
        let start = Psi::new([0.0, 0.0, 0.8], [0.1, 0.0, 0.0]);
        let params = GaParams::DEFAULT
            .with_population(16)
            .with_mutation_prob(1.0)
            .with_mutation_scale([[0.1; 6], [0.1; 6], [1e-4; 6]])
            .with_settled_levels([0.0, 0.0], 0.9);
        let params = GaParams { level_cdf: [1.0, 1.0], ..params };
        let largest_move = |fitness: f32| {
            let mut rng = Xoshiro128PlusPlus::seed_from_u64(2);
            let mut ga = Ga::<16>::new(start);
            ga.breed(&Best { psi: start, fitness }, &params, &s, &mut rng);
            let moved = ga
                .individuals()
                .iter()
                .take(15)
                .map(|p| p.0.iter().zip(start.0.iter()).map(|(a, b)| libm::fabsf(a - b)).fold(0.0, f32::max));
            (moved.fold(0.0, f32::max), rng.next_u32())
        };
        let (below, r_below) = largest_move(0.89);
        let (settled, r_settled) = largest_move(0.9);
        assert!(below > 0.01, "below the gate the coarse scale moved at most {below}");
        assert!(settled < 2e-4, "from the gate on the fine scale moved {settled}");
        assert_eq!(r_below, r_settled, "the gate changes no draw");
    }

    #[test]
    fn rng_use_is_independent_of_the_data() {
        // Two populations with different fitness leave the generator in the same state.
        let s = space();
        let mut r1 = Xoshiro128PlusPlus::seed_from_u64(9);
        let mut r2 = Xoshiro128PlusPlus::seed_from_u64(9);
        let mut g1 = Ga::<12>::new(Psi::IDENTITY);
        let mut g2 = Ga::<12>::new(Psi::new([0.1, 0.1, 0.9], [0.0; 3]));
        let b1 = g1.evaluate(|p| p.0[0]);
        let b2 = g2.evaluate(|_| 0.0);
        g1.breed(&b1, &GaParams::DEFAULT.with_crossover_prob(1.0), &s, &mut r1);
        g2.breed(&b2, &GaParams::DEFAULT.with_mutation_prob(0.0), &s, &mut r2);
        assert_eq!(r1.next_u32(), r2.next_u32());
    }

    #[test]
    fn population_size_is_chosen_at_run_time_up_to_the_capacity() {
        let s = space();
        let mut ga = Ga::<16>::new(Psi::IDENTITY);
        assert_eq!(ga.len(), 16);
        let sized = |n| GaParams::DEFAULT.with_population(n);
        assert_eq!(ga.set_population(&sized(0)), Err(GaError::PopulationSize { got: 0, capacity: 16 }));
        assert_eq!(ga.set_population(&sized(17)), Err(GaError::PopulationSize { got: 17, capacity: 16 }));
        assert_eq!(ga.len(), 16, "a refused size leaves the population as it was");
        ga.set_population(&sized(6)).unwrap();
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(5);
        ga.reset_uniform(&s, &mut rng);
        let mut calls = 0;
        let best = ga.evaluate(|p| {
            calls += 1;
            p.0[0]
        });
        assert_eq!((calls, ga.individuals().len(), ga.fitness().len()), (6, 6, 6));
        ga.breed(&best, &GaParams::DEFAULT.with_immigrants(1), &s, &mut rng);
        assert_eq!(ga.individuals()[0], best.psi);
    }

    #[test]
    fn a_smaller_population_in_a_larger_capacity_evolves_exactly_as_that_capacity() {
        // Ga<10> with 10 in use and Ga<32> with 10 in use: same draws, same populations.
        let s = space();
        let target = Psi::new([0.05, 0.0, 0.8], [0.1, 0.0, 0.0]);
        let f = bowl(&target);
        let (mut r1, mut r2) = (Xoshiro128PlusPlus::seed_from_u64(3), Xoshiro128PlusPlus::seed_from_u64(3));
        let mut small = Ga::<10>::new(Psi::IDENTITY);
        let mut large = Ga::<32>::new(Psi::IDENTITY);
        large.set_population(&GaParams::DEFAULT.with_population(10)).unwrap();
        small.reset_uniform(&s, &mut r1);
        large.reset_uniform(&s, &mut r2);
        for _ in 0..40 {
            let (b1, b2) = (small.evaluate(&f), large.evaluate(&f));
            assert_eq!(b1, b2);
            small.breed(&b1, &GaParams::DEFAULT, &s, &mut r1);
            large.breed(&b2, &GaParams::DEFAULT, &s, &mut r2);
            assert_eq!(small.individuals(), large.individuals());
        }
    }

    /// The angle (rad) between the orientations of two poses.
    fn angle_between(a: &Psi, b: &Psi) -> f32 {
        let (qa, qb) = (a.quaternion_unchecked(), b.quaternion_unchecked());
        qa.angle_to(&qb)
    }

    #[test]
    fn a_turn_has_the_same_angle_at_every_orientation() {
        // Identity, a general orientation, and one near a half turn (η ≈ 0.21, the iiwa
        // sample's start), each turned by h = (0.004, −0.002, 0.003) ⇒ 2·atan(|h|).
        let h = [0.004f32, -0.002, 0.003];
        let want = 2.0 * libm::atanf(libm::sqrtf(h.iter().map(|v| v * v).sum()));
        for eps in [[0.0f32, 0.0, 0.0], [0.3, -0.2, 0.5], [0.453_153_87, -0.784_885_6, 0.365_998_14]] {
            let before = Psi::new([0.0, 0.0, 0.7], eps);
            let mut after = before;
            turn(&mut after, h);
            let got = angle_between(&before, &after);
            assert!((got - want).abs() < 2e-4, "ε {eps:?}: turned {got} rad, want {want}");
            assert!(after.eta() >= 0.0 && after.eps().norm() <= 1.0 + 1e-6);
        }
        // At the identity the turn changes ε by h (to first order), as adding h to ε would.
        let mut id = Psi::new([0.0, 0.0, 0.7], [0.0; 3]);
        turn(&mut id, h);
        for (e, hk) in id.eps().iter().zip(h) {
            assert!((e - hk).abs() < 1e-6, "{e} vs {hk}");
        }
        // Adding h to ε near the half turn would turn the block several times further.
        let near = Psi::new([0.0, 0.0, 0.7], [0.453_153_87, -0.784_885_6, 0.365_998_14]);
        let mut added = near;
        for (x, hk) in added.0.iter_mut().skip(3).zip(h) {
            *x += hk;
        }
        added.project_to_ball();
        assert!(angle_between(&near, &added) > 2.0 * want, "the additive step is the anisotropic one");
    }

    #[test]
    fn search_space_validation() {
        assert_eq!(SearchSpace::new_checked([0.0; 3], [0.0; 3]), Err(GaError::EmptySearchSpace));
        assert_eq!(SearchSpace::new_checked([f32::NAN; 3], [1.0; 3]), Err(GaError::NonFinite));
    }
}
