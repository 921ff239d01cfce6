//! Linear consistency at horizon changes: a symmetric correction of K (beyond the papers).
//!
//! At a jump of δ the dual-horizon operator is conservative but not exact for a linear field:
//! the first moment `r_i = Σ_j K_ij ξ_ij` is not zero there (formulation §2.2, the "slight
//! difference at the interface" of seed 004). We look for the smallest change of K, relative to
//! K itself, that keeps it symmetric and makes every selected node's first moment vanish:
//! `δK_ij = ½ K_ij (λ_i − λ_j)·ξ_ij`, with one vector λ_i per node from the SPD system
//! `Σ_j ½ K_ij ξ_ij ξ_ijᵀ (λ_i − λ_j) = −r_i`, solved by block-Jacobi conjugate gradients.
//! Energy stays exactly conserved (K stays symmetric, bit for bit); a linear field becomes an
//! exact steady state wherever the selected nodes' neighbourhoods are complete.

use crate::cloud::Cloud;
use crate::math::{Real, Vector};
use crate::operator::Conductance;
use nalgebra::Matrix3;
use rayon::prelude::*;

/// Outcome of the correction.
#[derive(Debug, Clone, Copy, Default)]
pub struct Correction {
    /// Conjugate-gradient iterations.
    pub iterations: usize,
    /// max_i |r_i| / Σ_j K_ij |ξ_ij| over the selected nodes, before.
    pub before: Real,
    /// The same after the correction.
    pub after: Real,
    /// Smallest ratio (K_ij + δK_ij) / K_ij over all stored pairs.
    pub min_ratio: Real,
}

fn bond(cloud: &Cloud, i: usize, j: usize) -> Vector {
    cloud.pos[j] - cloud.pos[i]
}

/// First moments r_i = Σ_j K_ij ξ_ij and their scale Σ_j K_ij |ξ_ij|.
fn moments(k: &Conductance, cloud: &Cloud) -> Vec<(Vector, Real)> {
    (0..k.n_rows())
        .into_par_iter()
        .map(|i| {
            let mut r = Vector::zeros();
            let mut s = 0.0;
            for b in k.offsets[i]..k.offsets[i + 1] {
                let xi = bond(cloud, i, k.cols[b] as usize);
                r += k.vals[b] * xi;
                s += k.vals[b] * xi.norm();
            }
            (r, s)
        })
        .collect()
}

/// y = A x for the selected nodes (x is 0 elsewhere).
fn apply(k: &Conductance, cloud: &Cloud, sel: &[bool], x: &[Vector], y: &mut [Vector]) {
    y.par_iter_mut().enumerate().for_each(|(i, yi)| {
        *yi = Vector::zeros();
        if !sel[i] {
            return;
        }
        for b in k.offsets[i]..k.offsets[i + 1] {
            let j = k.cols[b] as usize;
            let xi = bond(cloud, i, j);
            let xj = if j < sel.len() && sel[j] {
                x[j]
            } else {
                Vector::zeros()
            };
            *yi += 0.5 * k.vals[b] * xi * xi.dot(&(x[i] - xj));
        }
    });
}

fn dot(a: &[Vector], b: &[Vector]) -> Real {
    a.par_iter().zip(b).map(|(x, y)| x.dot(y)).sum()
}

/// Corrects `k` in place so that the nodes with `sel[i]` have zero first moment.
pub fn correct(
    k: &mut Conductance,
    cloud: &Cloud,
    sel: &[bool],
    tol: Real,
    max_iter: usize,
) -> Correction {
    let n = k.n_rows();
    let dim = cloud.dim;
    let m0 = moments(k, cloud);
    let measure = |m: &[(Vector, Real)]| {
        m.iter()
            .zip(sel)
            .filter(|(_, &s)| s)
            .map(|((r, s), _)| if *s > 0.0 { r.norm() / s } else { 0.0 })
            .fold(0.0, Real::max)
    };
    let before = measure(&m0);
    if before <= 1e-13 {
        // already consistent to round-off (no horizon change): nothing to correct
        return Correction {
            iterations: 0,
            before,
            after: before,
            min_ratio: 1.0,
        };
    }
    // block-Jacobi preconditioner: the d×d diagonal blocks, identity on unused axes
    let precond: Vec<Matrix3<Real>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut d = Matrix3::zeros();
            for b in k.offsets[i]..k.offsets[i + 1] {
                let xi = bond(cloud, i, k.cols[b] as usize);
                d += 0.5 * k.vals[b] * xi * xi.transpose();
            }
            for a in dim..3 {
                d[(a, a)] = 1.0;
            }
            d.try_inverse().unwrap_or_else(Matrix3::identity)
        })
        .collect();
    let rhs: Vec<Vector> = (0..n)
        .map(|i| if sel[i] { -m0[i].0 } else { Vector::zeros() })
        .collect();
    let norm_b = dot(&rhs, &rhs).sqrt();
    let mut x = vec![Vector::zeros(); n];
    let mut res = rhs.clone();
    let mut z: Vec<Vector> = res.iter().zip(&precond).map(|(r, p)| p * r).collect();
    let mut p = z.clone();
    let mut ap = vec![Vector::zeros(); n];
    let mut rz = dot(&res, &z);
    let mut iterations = 0;
    while iterations < max_iter && dot(&res, &res).sqrt() > tol * norm_b && norm_b > 0.0 {
        apply(k, cloud, sel, &p, &mut ap);
        let alpha = rz / dot(&p, &ap);
        x.par_iter_mut().zip(&p).for_each(|(x, p)| *x += alpha * p);
        res.par_iter_mut()
            .zip(&ap)
            .for_each(|(r, a)| *r -= alpha * a);
        z.par_iter_mut()
            .zip(&res)
            .zip(&precond)
            .for_each(|((z, r), m)| *z = m * r);
        let rz_new = dot(&res, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        p.par_iter_mut()
            .zip(&z)
            .for_each(|(p, z)| *p = z + beta * *p);
        iterations += 1;
    }
    // δK_ij = ½ K_ij (λ_i − λ_j)·ξ_ij, the same bits in rows i and j
    let lambda = |j: usize| {
        if j < sel.len() && sel[j] {
            x[j]
        } else {
            Vector::zeros()
        }
    };
    let offsets = &k.offsets;
    let cols = &k.cols;
    let mut min_ratio = Real::INFINITY;
    let new_vals: Vec<Real> = (0..n)
        .into_par_iter()
        .flat_map_iter(|i| {
            (offsets[i]..offsets[i + 1]).map(move |b| {
                let j = cols[b] as usize;
                1.0 + 0.5 * (lambda(i) - lambda(j)).dot(&bond(cloud, i, j))
            })
        })
        .collect();
    for (v, f) in k.vals.iter_mut().zip(&new_vals) {
        min_ratio = min_ratio.min(*f);
        *v *= f;
    }
    for i in 0..n {
        k.diag[i] = k.vals[k.offsets[i]..k.offsets[i + 1]].iter().sum();
    }
    let after = measure(&moments(k, cloud));
    Correction {
        iterations,
        before,
        after,
        min_ratio,
    }
}
