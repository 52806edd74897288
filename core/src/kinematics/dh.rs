//! Chains from standard (distal) Denavit–Hartenberg tables, and the Mitsubishi PA-10.
//!
//! Link `i` contributes `Rz(q_i + offset_i) · Tz(d_i) · Tx(a_i) · Rx(α_i)`. Regrouped as
//! "fixed transform, then motion about `z`" ([`Chain`]), joint `i`'s origin is
//! `Tz(d_{i−1}) · Tx(a_{i−1}) · Rx(α_{i−1}) · Rz(offset_i)` (`Rz(offset_1)` for the first joint)
//! and the tip is `Tz(d_DOF) · Tx(a_DOF) · Rx(α_DOF)`.

use super::{Chain, Frame, Joint, JointKind};
use crate::math;

/// One link's DH parameters and joint limits (radians, metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DhLink {
    /// Offset along the previous `z` (m).
    pub d: f32,
    /// Length along the new `x` (m).
    pub a: f32,
    /// Twist about the new `x` (rad).
    pub alpha: f32,
    /// Constant added to the joint variable (rad).
    pub offset: f32,
    /// Lower joint limit (rad).
    pub q_min: f32,
    /// Upper joint limit (rad).
    pub q_max: f32,
}

/// `Tz(d) · Tx(a) · Rx(α) · Rz(θ)`.
fn dh_frame(d: f32, a: f32, alpha: f32, theta: f32) -> Frame {
    let (sa, ca) = math::sin_cos(alpha);
    let (st, ct) = math::sin_cos(theta);
    Frame { rotation: [[ct, -st, 0.0], [ca * st, ca * ct, -sa], [sa * st, sa * ct, ca]], translation: [a, 0.0, d] }
}

impl<const DOF: usize> Chain<DOF> {
    /// The chain of a DH table (all joints revolute).
    pub fn from_dh(links: &[DhLink; DOF]) -> Self {
        let mut joints = [Joint::revolute(Frame::IDENTITY, 0.0, 0.0); DOF];
        let mut prev = (0.0, 0.0, 0.0);
        for (link, joint) in links.iter().zip(joints.iter_mut()) {
            let origin = dh_frame(prev.0, prev.1, prev.2, link.offset);
            *joint = Joint { origin, kind: JointKind::Revolute, q_min: link.q_min, q_max: link.q_max };
            prev = (link.d, link.a, link.alpha);
        }
        Chain { joints, tip: dh_frame(prev.0, prev.1, prev.2, 0.0) }
    }
}

const fn deg(x: f32) -> f32 {
    x * (core::f32::consts::PI / 180.0)
}

const fn pa10_link(d: f32, alpha: f32, limit_deg: f32) -> DhLink {
    DhLink { d, a: 0.0, alpha, offset: 0.0, q_min: -deg(limit_deg), q_max: deg(limit_deg) }
}

/// The PA-10's DH table (S1, S2, S3, E1, E2, W1, W2) with the lengths of the manufacturer's
/// model.
pub const PA10_DH: [DhLink; 7] = {
    use core::f32::consts::FRAC_PI_2;
    [
        pa10_link(0.315, -FRAC_PI_2, 177.0),
        pa10_link(0.0, FRAC_PI_2, 94.0),
        pa10_link(0.450, -FRAC_PI_2, 174.0),
        pa10_link(0.0, FRAC_PI_2, 137.0),
        pa10_link(0.500, -FRAC_PI_2, 255.0),
        pa10_link(0.0, FRAC_PI_2, 165.0),
        pa10_link(0.080, 0.0, 255.0),
    ]
};

/// `Tz(d) · Rx(−90°)`, exact.
const fn down(d: f32) -> Frame {
    Frame { rotation: [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]], translation: [0.0, 0.0, d] }
}

/// `Tz(d) · Rx(+90°)`, exact.
const fn up(d: f32) -> Frame {
    Frame { rotation: [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]], translation: [0.0, 0.0, d] }
}

// Only evaluated in the `PA10` constant below: an index out of range fails to compile.
#[allow(clippy::indexing_slicing)]
const fn pa10_joint(origin: Frame, i: usize) -> Joint {
    Joint::revolute(origin, PA10_DH[i].q_min, PA10_DH[i].q_max)
}

/// The PA-10 (7 DOF): [`PA10_DH`] regrouped into joint transforms, written out so that
/// `α = ±90°` gives exact 0/±1 entries. At `q = 0` the arm points straight up with the flange
/// at (0, 0, 1.345) m.
pub const PA10: Chain<7> = Chain {
    joints: [
        pa10_joint(Frame::IDENTITY, 0),
        pa10_joint(down(0.315), 1),
        pa10_joint(up(0.0), 2),
        pa10_joint(down(0.450), 3),
        pa10_joint(up(0.0), 4),
        pa10_joint(down(0.500), 5),
        pa10_joint(up(0.0), 6),
    ],
    tip: Frame::translation(0.0, 0.0, 0.080),
};
