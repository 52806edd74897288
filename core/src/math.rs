//! The one door to transcendental float functions in the core.
//!
//! Every `sqrt`, `sin`, `cos`, `atan2`, … of the core goes through here, and here only to `libm`,
//! never to `std`'s float methods. `libm` is the same pure-Rust code on the host and on the
//! Cortex-M4, and the core's other operations are plain IEEE-754 single-precision `+ - * /`
//! (which Rust never contracts into fused multiply-adds), so the same inputs give bit-identical
//! results on both. `abs`/`min`/`max` are exact and come from `core`.

/// Square root (correctly rounded, as the M4's `VSQRT`).
#[inline(always)]
pub fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// `eˣ`.
#[inline(always)]
pub fn exp(x: f32) -> f32 {
    libm::expf(x)
}

/// Sine of an angle in radians.
#[inline(always)]
pub fn sin(x: f32) -> f32 {
    libm::sinf(x)
}

/// Cosine of an angle in radians.
#[inline(always)]
pub fn cos(x: f32) -> f32 {
    libm::cosf(x)
}

/// Four-quadrant arc tangent of `y / x`, in radians.
#[inline(always)]
pub fn atan2(y: f32, x: f32) -> f32 {
    libm::atan2f(y, x)
}

/// Largest integer not above `x`.
#[inline(always)]
pub fn floor(x: f32) -> f32 {
    libm::floorf(x)
}

/// Nearest integer, halves away from zero.
#[inline(always)]
pub fn round(x: f32) -> f32 {
    libm::roundf(x)
}

/// Sine and cosine of the same angle.
#[inline(always)]
pub fn sin_cos(x: f32) -> (f32, f32) {
    libm::sincosf(x)
}

/// `x` clamped into `[lo, hi]`; NaN becomes `lo`, so the result is always inside the range.
#[inline(always)]
pub fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    if x >= lo { if x <= hi { x } else { hi } } else { lo }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamp_keeps_range_and_maps_nan_to_lower_bound() {
        assert_eq!(clamp(2.0, -1.0, 1.0), 1.0);
        assert_eq!(clamp(-2.0, -1.0, 1.0), -1.0);
        assert_eq!(clamp(0.25, -1.0, 1.0), 0.25);
        assert_eq!(clamp(f32::NAN, -1.0, 1.0), -1.0);
    }

    #[test]
    fn libm_matches_known_values() {
        assert!((sqrt(2.0) - core::f32::consts::SQRT_2).abs() < 1e-7);
        assert!((sin(core::f32::consts::FRAC_PI_6) - 0.5).abs() < 1e-7);
        assert!((cos(core::f32::consts::FRAC_PI_3) - 0.5).abs() < 1e-7);
        assert!((atan2(1.0, -1.0) - 3.0 * core::f32::consts::FRAC_PI_4).abs() < 1e-6);
    }
}
