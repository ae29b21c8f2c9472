//! Products with a link's body Jacobian restricted to the DOFs it depends on.
//!
//! A multibody link's body Jacobian (6 × ndofs) is built from its parent's plus its own
//! joint's columns, so it is zero outside the DOFs of the link and its ancestors
//! ([`Multibody::link_dof_ranges`](super::Multibody::link_dof_ranges)). On a floating
//! quadruped (6 + 4 × 3 DOFs) a leg link depends on at most 9 of the 18. Assembling the
//! mass and Coriolis matrices with nalgebra's dense `quadform`, `gemm` and `gemm_tr`
//! spends most of its time multiplying those zero columns.
//!
//! The functions here compute only the entries in the DOF ranges, each one exactly as the
//! dense nalgebra call computes it (the same `gemv`, `gemv_tr` or dot product on the same
//! operands, added once). The entries they skip would have had zeros added to them, and an
//! accumulator that starts at `+0.0` and only ever has sums added to it is never `-0.0`,
//! so adding a zero leaves it unchanged: the results are bit for bit the dense ones.
//! The tests below check this against nalgebra.

use crate::math::{Jacobian, Real, SPATIAL_DIM};
use na::{DMatrix, Dyn, OMatrix, SMatrix, SVector};

/// `out += jᵀ · mid · j` (nalgebra's `out.quadform(1.0, mid, j, 1.0)`) for a body
/// Jacobian `j` that is zero outside the columns in `dof_ranges`.
pub fn add_quadform_on_dofs(
    out: &mut DMatrix<Real>,
    mid: &SMatrix<Real, SPATIAL_DIM, SPATIAL_DIM>,
    j: &Jacobian<Real>,
    dof_ranges: &[(usize, usize)],
) {
    let mut work = SVector::<Real, SPATIAL_DIM>::zeros();
    for &(c0, cn) in dof_ranges {
        for c in c0..c0 + cn {
            work.gemv(1.0, mid, &j.column(c), 0.0);
            let mut out_c = out.column_mut(c);
            for &(r0, rn) in dof_ranges {
                out_c
                    .rows_mut(r0, rn)
                    .gemv_tr(1.0, &j.columns(r0, rn), &work, 1.0);
            }
        }
    }
}

/// `out += aᵀ · b` (nalgebra's `out.gemm_tr(1.0, a, b, 1.0)`) for `a`, `b` that are zero
/// outside the columns in `dof_ranges`.
pub fn add_gemm_tr_on_dofs(
    out: &mut DMatrix<Real>,
    a: &Jacobian<Real>,
    b: &Jacobian<Real>,
    dof_ranges: &[(usize, usize)],
) {
    for &(c0, cn) in dof_ranges {
        for c in c0..c0 + cn {
            let mut out_c = out.column_mut(c);
            for &(r0, rn) in dof_ranges {
                out_c
                    .rows_mut(r0, rn)
                    .gemv_tr(1.0, &a.columns(r0, rn), &b.column(c), 1.0);
            }
        }
    }
}

/// `out += alpha · a · b` (nalgebra's `out.gemm(alpha, a, b, 1.0)`, which computes a 3-row
/// product column by column) for `b` zero outside the columns in `dof_ranges` and `out`
/// zero there.
pub fn gemm_on_dofs<SB: na::Storage<Real, na::U3, Dyn>>(
    out: &mut OMatrix<Real, na::U3, Dyn>,
    alpha: Real,
    a: &na::Matrix3<Real>,
    b: &na::Matrix<Real, na::U3, Dyn, SB>,
    dof_ranges: &[(usize, usize)],
) {
    for &(c0, cn) in dof_ranges {
        out.columns_mut(c0, cn)
            .gemm(alpha, a, &b.columns(c0, cn), 1.0);
    }
}

#[cfg(test)]
mod test {
    use super::*;

    /// A floating base (6 DOFs) and one leg of three hinges (DOFs 12..15) of an 18-DOF
    /// quadruped: the ranges of the leg's last link.
    const RANGES: [(usize, usize); 2] = [(12, 3), (0, 6)];
    const NDOFS: usize = 18;

    struct Xorshift(u64);

    impl Xorshift {
        fn next(&mut self) -> Real {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            ((self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) as Real
        }
    }

    fn in_ranges(c: usize) -> bool {
        RANGES.iter().any(|&(c0, cn)| (c0..c0 + cn).contains(&c))
    }

    /// A `rows × NDOFS` matrix, random in the columns of `RANGES`, zero elsewhere.
    fn sparse(rng: &mut Xorshift, rows: usize) -> na::OMatrix<Real, Dyn, Dyn> {
        DMatrix::from_fn(
            rows,
            NDOFS,
            |_, c| if in_ranges(c) { rng.next() } else { 0.0 },
        )
    }

    fn assert_bits_eq(a: &[Real], b: &[Real]) {
        assert_eq!(a.len(), b.len());
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            assert_eq!(x.to_bits(), y.to_bits(), "entry {i}: {x} against {y}");
        }
    }

    #[test]
    fn the_quadform_on_dofs_is_nalgebras_bit_for_bit() {
        let mut rng = Xorshift(0x9e37_79b9_7f4a_7c15);
        let j = Jacobian::<Real>::from_column_slice(sparse(&mut rng, SPATIAL_DIM).as_slice());
        let mid = SMatrix::<Real, SPATIAL_DIM, SPATIAL_DIM>::from_fn(|_, _| rng.next());
        let start = DMatrix::from_fn(NDOFS, NDOFS, |_, _| rng.next());
        let mut dense = start.clone();
        dense.quadform(1.0, &mid, &j, 1.0);
        let mut on_dofs = start;
        add_quadform_on_dofs(&mut on_dofs, &mid, &j, &RANGES);
        assert_bits_eq(dense.as_slice(), on_dofs.as_slice());
        // Starting from zeros, as the mass matrix does, the entries outside stay +0.0.
        let mut dense = DMatrix::zeros(NDOFS, NDOFS);
        dense.quadform(1.0, &mid, &j, 1.0);
        let mut on_dofs = DMatrix::zeros(NDOFS, NDOFS);
        add_quadform_on_dofs(&mut on_dofs, &mid, &j, &RANGES);
        assert_bits_eq(dense.as_slice(), on_dofs.as_slice());
    }

    #[test]
    fn the_gemm_tr_on_dofs_is_nalgebras_bit_for_bit() {
        let mut rng = Xorshift(0x2545_f491_4f6c_dd1d);
        let a = Jacobian::<Real>::from_column_slice(sparse(&mut rng, SPATIAL_DIM).as_slice());
        let b = Jacobian::<Real>::from_column_slice(sparse(&mut rng, SPATIAL_DIM).as_slice());
        let start = DMatrix::from_fn(NDOFS, NDOFS, |_, _| rng.next());
        let mut dense = start.clone();
        dense.gemm_tr(1.0, &a, &b, 1.0);
        let mut on_dofs = start;
        add_gemm_tr_on_dofs(&mut on_dofs, &a, &b, &RANGES);
        assert_bits_eq(dense.as_slice(), on_dofs.as_slice());
    }

    #[test]
    fn the_gemm_on_dofs_is_nalgebras_bit_for_bit() {
        let mut rng = Xorshift(0x1234_5678_9abc_def1);
        let b = OMatrix::<Real, na::U3, Dyn>::from_column_slice(sparse(&mut rng, 3).as_slice());
        let a = na::Matrix3::<Real>::from_fn(|_, _| rng.next());
        // `out` is zero outside the ranges, as the Coriolis matrices are.
        let start = OMatrix::<Real, na::U3, Dyn>::from_column_slice(sparse(&mut rng, 3).as_slice());
        for alpha in [1.0, -1.0, 2.0] {
            let mut dense = start.clone();
            dense.gemm(alpha, &a, &b, 1.0);
            let mut on_dofs = start.clone();
            gemm_on_dofs(&mut on_dofs, alpha, &a, &b, &RANGES);
            assert_bits_eq(dense.as_slice(), on_dofs.as_slice());
        }
    }
}
