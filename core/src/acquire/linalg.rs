//! The few matrix operations of the acquisition whose nalgebra versions keep a dimension or
//! bounds assertion in the firmware (a run-time column index, the LU inverse): written on
//! fixed-size arrays with `get`, so no panic path is left in `Tracker::step`
//! (`hil-stubs/scripts/panic-check.sh`).
//!
//! [`gauss_newton_step`] performs exactly the floating-point operations of nalgebra's
//! `-(a.try_inverse()? * b)` for a 6×6 matrix, in the same order, so the estimates did not
//! change bit for bit (`gauss_newton_step_equals_nalgebra` checks it).

use nalgebra::{Matrix3, Vector3};

/// Column `i` of `r` (the last one for `i ≥ 2`).
pub(super) fn column(r: &Matrix3<f32>, i: usize) -> Vector3<f32> {
    match i {
        0 => r.column(0).into_owned(),
        1 => r.column(1).into_owned(),
        _ => r.column(2).into_owned(),
    }
}

/// The matrix whose column `i` is `cols[i]`.
pub(super) fn from_columns(cols: &[Vector3<f32>; 3]) -> Matrix3<f32> {
    let [a, b, c] = cols;
    Matrix3::new(a.x, b.x, c.x, a.y, b.y, c.y, a.z, b.z, c.z)
}

/// Rows of a 6×6 matrix.
type Rows6 = [[f32; 6]; 6];

fn at(m: &Rows6, r: usize, c: usize) -> f32 {
    m.get(r).and_then(|row| row.get(c)).copied().unwrap_or(0.0)
}

fn swap_rows(m: &mut Rows6, i: usize, j: usize) {
    if let (Some(ri), Some(rj)) = (m.get(i).copied(), m.get(j).copied()) {
        if let Some(x) = m.get_mut(i) {
            *x = rj;
        }
        if let Some(x) = m.get_mut(j) {
            *x = ri;
        }
    }
}

/// `row_r ← row_r − f·pivot` on the columns `k` where `mask(k)`, as nalgebra's `axpy` computes
/// it: `(−pivot_k)·f + row_k`.
fn eliminate(row: &mut [f32; 6], pivot: &[f32; 6], f: f32, mask: impl Fn(usize) -> bool) {
    for (k, (x, p)) in row.iter_mut().zip(pivot).enumerate() {
        if mask(k) {
            *x += -*p * f;
        }
    }
}

/// `Σ_k a[k]·b[k]`, summed from `k = 0` on, starting with the first product (the order of
/// nalgebra's `gemv`).
fn dot_in_order<const N: usize>(a: &[f32; N], b: &[f32; N]) -> f32 {
    let mut terms = a.iter().zip(b).map(|(x, y)| x * y);
    let first = terms.next().unwrap_or(0.0);
    terms.fold(first, |s, t| t + s)
}

/// The normal equations `(JᵀJ, Jᵀr)` of the Jacobian with columns `cols` and the residuals
/// `r`, as nalgebra's `jac.transpose() * jac` and `jac.transpose() * r` compute them (every
/// entry a dot product in residual order), without the two transposed copies of `J` on the
/// stack.
pub(super) fn normal_equations<const N: usize>(cols: &[[f32; N]; 6], r: &[f32; N]) -> (Rows6, [f32; 6]) {
    let jtj = cols.each_ref().map(|a| cols.each_ref().map(|b| dot_in_order(a, b)));
    let jtr = cols.each_ref().map(|a| dot_in_order(a, r));
    (jtj, jtr)
}

/// `-(a⁻¹·b)` for the 6×6 matrix with rows `a`, or `None` when `a` is singular: LU
/// decomposition with partial pivoting, forward and back substitution on the identity
/// (nalgebra's `lu::try_invert_to`), then the product with `b` (nalgebra's `gemv`).
pub(super) fn gauss_newton_step(mut a: Rows6, b: &[f32; 6]) -> Option<[f32; 6]> {
    let mut inv: Rows6 = core::array::from_fn(|r| core::array::from_fn(|c| if r == c { 1.0 } else { 0.0 }));
    for i in 0..6 {
        // The first row at or below `i` with the largest |a[r][i]| (NaN never wins).
        let mut piv = i;
        for r in i + 1..6 {
            if at(&a, r, i).abs() > at(&a, piv, i).abs() {
                piv = r;
            }
        }
        let diag = at(&a, piv, i);
        if diag == 0.0 {
            return None;
        }
        swap_rows(&mut a, i, piv);
        swap_rows(&mut inv, i, piv);
        let inv_diag = 1.0 / diag;
        let pivot = a.get(i).copied()?;
        for row in a.iter_mut().skip(i + 1) {
            let coeff = row.get(i).copied().unwrap_or(0.0) * inv_diag;
            if let Some(x) = row.get_mut(i) {
                *x = coeff;
            }
            eliminate(row, &pivot, coeff, |k| k > i);
        }
    }
    // Forward substitution with the unit lower triangle.
    for i in 0..6 {
        let pivot = inv.get(i).copied()?;
        for (r, row) in inv.iter_mut().enumerate().skip(i + 1) {
            eliminate(row, &pivot, at(&a, r, i), |_| true);
        }
    }
    // Back substitution with the upper triangle.
    for i in (0..6).rev() {
        let diag = at(&a, i, i);
        if diag == 0.0 {
            return None;
        }
        let row = inv.get_mut(i)?;
        for x in row.iter_mut() {
            *x /= diag;
        }
        let pivot = *row;
        for (r, row) in inv.iter_mut().enumerate().take(i) {
            eliminate(row, &pivot, at(&a, r, i), |_| true);
        }
    }
    // `-(inv·b)`, each row summed from the first column on.
    Some(inv.map(|row| {
        let mut s = 0.0f32;
        for (k, (m, x)) in row.iter().zip(b).enumerate() {
            s = if k == 0 { m * x } else { m * x + s };
        }
        -s
    }))
}

#[cfg(test)]
mod tests {
    use nalgebra::{SMatrix, SVector};
    use proptest::prelude::*;

    use super::*;

    fn nalgebra_step(rows: &Rows6, b: &[f32; 6]) -> Option<[f32; 6]> {
        let a = SMatrix::<f32, 6, 6>::from_fn(|r, c| rows[r][c]);
        let inv = a.try_inverse()?;
        Some((-(inv * SVector::<f32, 6>::from(*b))).into())
    }

    fn bits(x: Option<[f32; 6]>) -> Option<[u32; 6]> {
        x.map(|v| v.map(f32::to_bits))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        #[test]
        fn gauss_newton_step_equals_nalgebra(
            m in proptest::array::uniform6(proptest::array::uniform6(-1e3f32..1e3)),
            b in proptest::array::uniform6(-1e3f32..1e3),
            zero_col in 0usize..12,
        ) {
            let mut m = m;
            // Some singular matrices too.
            if zero_col < 6 {
                for row in m.iter_mut() {
                    row[zero_col] = 0.0;
                }
            }
            prop_assert_eq!(bits(gauss_newton_step(m, &b)), bits(nalgebra_step(&m, &b)));
        }

        #[test]
        fn normal_equations_equal_nalgebra(
            cols in proptest::array::uniform6(proptest::array::uniform18(-1e3f32..1e3)),
            r in proptest::array::uniform18(-1e3f32..1e3),
        ) {
            let jac = SMatrix::<f32, 18, 6>::from_fn(|i, j| cols[j][i]);
            let want_jtj: Rows6 = (jac.transpose() * jac).transpose().into();
            let want_jtr: [f32; 6] = (jac.transpose() * SVector::<f32, 18>::from(r)).into();
            let (jtj, jtr) = normal_equations(&cols, &r);
            prop_assert_eq!(jtj.map(|row| row.map(f32::to_bits)), want_jtj.map(|row| row.map(f32::to_bits)));
            prop_assert_eq!(jtr.map(f32::to_bits), want_jtr.map(f32::to_bits));
        }

        #[test]
        fn damped_normal_equations_equal_nalgebra(j in proptest::array::uniform6(proptest::array::uniform6(-50f32..50.0)),
            b in proptest::array::uniform6(-1e2f32..1e2), lambda in 1e-6f32..1e3) {
            // JᵀJ + λ·diag, as the refinement builds it.
            let jm = SMatrix::<f32, 6, 6>::from_fn(|r, c| j[r][c]);
            let mut a: Rows6 = (jm.transpose() * jm).transpose().into();
            for (k, row) in a.iter_mut().enumerate() {
                row[k] += lambda * (row[k] + 1e-6);
            }
            prop_assert_eq!(bits(gauss_newton_step(a, &b)), bits(nalgebra_step(&a, &b)));
        }
    }

    #[test]
    fn columns_round_trip() {
        let r = Matrix3::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0);
        let cols = [column(&r, 0), column(&r, 1), column(&r, 2)];
        assert_eq!(from_columns(&cols), r);
        assert_eq!(column(&r, 7), column(&r, 2));
    }
}
