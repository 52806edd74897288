//! The per-axis Kalman filters of [`super::TargetFilter`]: `[x, ẋ, ẍ]` for a position axis,
//! `[x, ẋ]` for a rotation (error-state) axis.

/// One axis `[x, ẋ]` with covariance `[P₀₀, P₀₁, P₁₁]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Axis {
    pub(super) x: f32,
    pub(super) v: f32,
    pub(super) p: [f32; 3],
}

impl Axis {
    pub(super) fn start(x: f32, var_x: f32, var_v: f32) -> Self {
        Self { x, v: 0.0, p: [var_x, 0.0, var_v] }
    }

    /// `x ← x + v dt`, `P ← F P Fᵀ + Q(dt)` for white acceleration of spectral density `q`.
    pub(super) fn predict(&mut self, dt: f32, q: f32) {
        let [a, b, c] = self.p;
        let dt2 = dt * dt;
        self.x += self.v * dt;
        self.p = [a + 2.0 * b * dt + c * dt2 + q * dt2 * dt / 3.0, b + c * dt + q * dt2 * 0.5, c + q * dt];
    }

    /// Whether innovation `y` is within `gate` standard deviations (`y² ≤ gate² S`).
    pub(super) fn inlier(&self, y: f32, r: f32, gate: f32) -> bool {
        y * y <= gate * gate * (self.p[0] + r)
    }

    /// Measurement update with innovation `y` and measurement variance `r`.
    pub(super) fn update(&mut self, y: f32, r: f32) {
        let [a, b, c] = self.p;
        let s = a + r;
        let (k0, k1) = (a / s, b / s);
        self.x += k0 * y;
        self.v += k1 * y;
        self.p = [(1.0 - k0) * a, (1.0 - k0) * b, c - k1 * b];
    }
}

/// One position axis `[x, ẋ, ẍ]` with covariance `[P₀₀, P₀₁, P₀₂, P₁₁, P₁₂, P₂₂]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PosAxis {
    pub(super) x: f32,
    pub(super) v: f32,
    pub(super) a: f32,
    pub(super) p: [f32; 6],
}

impl PosAxis {
    pub(super) fn start(x: f32, var_x: f32, var_v: f32, var_a: f32) -> Self {
        Self { x, v: 0.0, a: 0.0, p: [var_x, 0.0, 0.0, var_v, 0.0, var_a] }
    }

    /// Velocity variance.
    pub(super) fn var_v(&self) -> f32 {
        self.p[3]
    }

    /// `x ← x + v dt + a dt²/2`, `v ← v + a dt`, `P ← F P Fᵀ + Q(dt)` for white acceleration of
    /// density `qa` on `[x, ẋ]` and white jerk of density `qj` on `[x, ẋ, ẍ]`.
    pub(super) fn predict(&mut self, dt: f32, qa: f32, qj: f32) {
        let [xx, xv, xa, vv, va, aa] = self.p;
        let h = 0.5 * dt * dt;
        let (dt2, dt3) = (dt * dt, dt * dt * dt);
        self.x += self.v * dt + self.a * h;
        self.v += self.a * dt;
        // Rows of F P.
        let r0 = [xx + dt * xv + h * xa, xv + dt * vv + h * va, xa + dt * va + h * aa];
        let r1 = [vv + dt * va, va + dt * aa];
        self.p = [
            r0[0] + dt * r0[1] + h * r0[2] + qa * dt3 / 3.0 + qj * dt3 * dt2 / 20.0,
            r0[1] + dt * r0[2] + qa * dt2 * 0.5 + qj * dt2 * dt2 / 8.0,
            r0[2] + qj * dt3 / 6.0,
            r1[0] + dt * r1[1] + qa * dt + qj * dt3 / 3.0,
            r1[1] + qj * dt2 * 0.5,
            aa + qj * dt,
        ];
    }

    /// Whether innovation `y` is within `gate` standard deviations (`y² ≤ gate² S`).
    pub(super) fn inlier(&self, y: f32, r: f32, gate: f32) -> bool {
        y * y <= gate * gate * (self.p[0] + r)
    }

    /// Measurement update with innovation `y` and measurement variance `r`.
    pub(super) fn update(&mut self, y: f32, r: f32) {
        let [xx, xv, xa, vv, va, aa] = self.p;
        let s = xx + r;
        let (k0, k1, k2) = (xx / s, xv / s, xa / s);
        self.x += k0 * y;
        self.v += k1 * y;
        self.a += k2 * y;
        self.p = [xx - k0 * xx, xv - k0 * xv, xa - k0 * xa, vv - k1 * xv, va - k1 * xa, aa - k2 * xa];
    }
}
