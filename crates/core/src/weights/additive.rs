//! The linear-order correction in additive form: one linear solve, tried before the entropy form.
//!
//! For the first moments alone the smallest change of K relative to K itself that keeps it
//! symmetric is the linearised entropy weight `K'_ij = K_ij (1 + λ_i·φ_i(ξ_ij) + λ_j·φ_j(ξ_ji))`,
//! λ from one Newton system of the dual at λ = 0 ([`super::Problem::hessian`]). The moments are
//! linear in λ, so one solve makes them exact; it is taken whenever every pair stays positive,
//! otherwise [`super::correct`] falls back to the entropy form, which always does.

use super::{direct, solve, Mom, Precond, Problem};
use crate::math::{Real, Vector};
use nalgebra::Matrix3;
use rayon::prelude::*;

/// Relative tolerance of the linear solve (below [`super::TOLERANCE`]).
const SOLVE_TOLERANCE: Real = 1e-12;
/// Conjugate-gradient iterations before the additive form is given up.
const MAX_ITERATIONS: usize = 20_000;

/// The corrected pair conductances and the CG iterations, or None when a pair would not stay
/// positive.
pub(super) fn linear(p: &Problem) -> Option<(Vec<Real>, usize)> {
    let rhs: Vec<Mom> = p.residual(&p.k0).iter().map(|r| -r).collect();
    let mut step = vec![Mom::zeros(); p.n()];
    let it;
    let mut direct = direct::Direct::new(p);
    let factored = direct.as_mut().is_some_and(|d| d.factorise(p, &p.k0));
    match direct.as_mut().filter(|_| factored) {
        Some(d) => {
            // the factor is exact up to its regularisation: CG with it polishes the rest
            it = solve(
                p,
                &p.k0,
                &rhs,
                &mut step,
                &mut Precond::Direct(d),
                SOLVE_TOLERANCE,
            );
        }
        None => {
            // too large to factorise: block-Jacobi CG on the first-moment system alone, whose
            // matrix-vector product reads 3-vectors instead of the general moment vectors
            let h = &p.cloud.horizon;
            // unscaled: Σ_j ½ K_ij ξ ξᵀ (μ_i − μ_j) = −Σ_j K_ij ξ_ij, and λ_i = ½ s_i μ_i
            let b: Vec<Vector> = (0..p.n())
                .map(|i| rhs[i].fixed_rows::<3>(0) * h[i])
                .collect();
            let (mu, n) = cg(p, &b)?;
            it = n;
            for (i, (s, m)) in step.iter_mut().zip(&mu).enumerate() {
                s.fixed_rows_mut::<3>(0).copy_from(&(0.5 * h[i] * m));
            }
        }
    }
    let vals = linearised(p, &step);
    let positive = vals.iter().zip(&p.k0).all(|(v, k0)| *k0 <= 0.0 || *v > 0.0);
    positive.then_some((vals, it))
}

/// K_ij (1 + g_ij(λ)) for every CSR entry, g the pair exponent of [`Problem::exponent`].
fn linearised(p: &Problem, lambda: &[Mom]) -> Vec<Real> {
    (0..p.n())
        .into_par_iter()
        .flat_map_iter(|i| {
            (p.offsets[i]..p.offsets[i + 1])
                .map(move |e| p.k0[e] * (1.0 + p.exponent(lambda, i, p.cols[e] as usize)))
        })
        .collect()
}

fn dot(a: &[Vector], b: &[Vector]) -> Real {
    crate::math::ordered_sum(a.len(), |i| a[i].dot(&b[i]))
}

/// y = A x, A the unscaled first-moment system of the selected nodes (x is 0 elsewhere).
fn apply(p: &Problem, x: &[Vector], y: &mut [Vector]) {
    let c = p.cloud;
    y.par_iter_mut().enumerate().for_each(|(i, yi)| {
        *yi = Vector::zeros();
        if p.sel[i] {
            for e in p.offsets[i]..p.offsets[i + 1] {
                let j = p.cols[e] as usize;
                let xi = c.pos[j] - c.pos[i];
                let xj = if j < p.n() && p.sel[j] {
                    x[j]
                } else {
                    Vector::zeros()
                };
                *yi += 0.5 * p.k0[e] * xi * xi.dot(&(x[i] - xj));
            }
        }
    });
}

/// Inverse diagonal blocks of A (identity on unused axes).
fn block_jacobi(p: &Problem) -> Vec<Matrix3<Real>> {
    let c = p.cloud;
    (0..p.n())
        .into_par_iter()
        .map(|i| {
            let mut d = Matrix3::zeros();
            for e in p.offsets[i]..p.offsets[i + 1] {
                let xi = c.pos[p.cols[e] as usize] - c.pos[i];
                d += 0.5 * p.k0[e] * xi * xi.transpose();
            }
            for a in c.dim..3 {
                d[(a, a)] = 1.0;
            }
            d.try_inverse().unwrap_or_else(Matrix3::identity)
        })
        .collect()
}

/// Block-Jacobi CG for A μ = b to [`SOLVE_TOLERANCE`] of |b|; None when it does not get there.
fn cg(p: &Problem, b: &[Vector]) -> Option<(Vec<Vector>, usize)> {
    let n = b.len();
    let precond = block_jacobi(p);
    let mut x = vec![Vector::zeros(); n];
    let norm_b = dot(b, b).sqrt();
    let mut r = b.to_vec();
    let mut z: Vec<Vector> = r.iter().zip(&precond).map(|(r, m)| m * r).collect();
    let mut d = z.clone();
    let mut ad = vec![Vector::zeros(); n];
    let mut rz = dot(&r, &z);
    for it in 0..MAX_ITERATIONS {
        if dot(&r, &r).sqrt() <= SOLVE_TOLERANCE * norm_b {
            return Some((x, it));
        }
        apply(p, &d, &mut ad);
        let dad = dot(&d, &ad);
        if dad.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let alpha = rz / dad;
        x.par_iter_mut().zip(&d).for_each(|(x, d)| *x += alpha * d);
        r.par_iter_mut().zip(&ad).for_each(|(r, a)| *r -= alpha * a);
        z.par_iter_mut()
            .zip(&r)
            .zip(&precond)
            .for_each(|((z, r), m)| *z = m * r);
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        d.par_iter_mut()
            .zip(&z)
            .for_each(|(d, z)| *d = z + beta * *d);
    }
    None
}
