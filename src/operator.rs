//! The bond operator: the symmetric pair conductance K of formulation §2.2 and its product.
//!
//! `V_i ρc_i dθ_i/dt = Σ_j K_ij (θ_j − θ_i)` with `K_ij = V_i V_j (w_ij + w_ji)` and the
//! directed half-conductances `w_ij = ½ c_i(|ξ_ij|) β_ij` (seed 004 eqs 19–24; w_ij = 0 when
//! j ∉ H_i). K is symmetric, so the bond sum conserves energy exactly. Axisymmetric and
//! spherical clouds multiply each pair by the factor of [`crate::symmetry`] (seed 001 eqs 10, 21).

use crate::cloud::Cloud;
use crate::kernel::Kernel;
use crate::material::BondRule;
use crate::math::{NodeId, Vector};
use crate::neighbors::Horizons;
use rayon::prelude::*;

/// Symmetric pair conductances in CSR form, rows for the body nodes only, W/K.
#[derive(Debug, Clone, Default)]
pub struct Conductance {
    /// Row offsets, length n_body + 1.
    pub offsets: Vec<usize>,
    /// Column (neighbour) indices; may point at fictitious nodes.
    pub cols: Vec<NodeId>,
    /// K_ij, W/K.
    pub vals: Vec<f64>,
    /// Row sums Σ_j K_ij, W/K.
    pub diag: Vec<f64>,
}

/// Directed half-conductances V_i V_j w_ij for every bond of `horizons`, W/K.
pub fn directed_weights(
    cloud: &Cloud,
    horizons: &Horizons,
    kernel: &Kernel,
    conductivity: &[f64],
    rule: BondRule,
) -> Vec<f64> {
    let mut w = vec![0.0; horizons.n_bonds()];
    let units = unit_normalisations(cloud, kernel);
    let sym = cloud.symmetry;
    horizons
        .rows_mut(&mut w)
        .into_par_iter()
        .with_min_len(256)
        .for_each(|(i, slot)| {
            let delta = cloud.horizon[i];
            let unit = units[i];
            for (s, b) in slot.iter_mut().zip(horizons.row(i)) {
                let j = horizons.targets[b] as usize;
                let r = (cloud.pos[j] - cloud.pos[i]).norm();
                let k = rule.combine(conductivity[i], conductivity[j]);
                let c = kernel.micro(unit * k, r, horizons.eval_at[b], delta);
                // planar measures times the ring/shell pair factor (formulation §7)
                let (ri, rj) = (cloud.pos[i].x, cloud.pos[j].x);
                let shape = if sym.is_symmetric() {
                    sym.pair_factor(ri, rj) / (sym.volume_factor(ri) * sym.volume_factor(rj))
                } else {
                    1.0
                };
                *s = 0.5 * cloud.volume[i] * cloud.volume[j] * shape * c * horizons.beta[b];
            }
        });
    w
}

/// C_i for k = 1 at every node, computed once per distinct (Δ, δ) pair.
fn unit_normalisations(cloud: &Cloud, kernel: &Kernel) -> Vec<f64> {
    let mut cache: std::collections::HashMap<(u64, u64), f64> = std::collections::HashMap::new();
    (0..cloud.len())
        .map(|i| {
            let (h, d) = (cloud.spacing[i], cloud.horizon[i]);
            *cache
                .entry((h.to_bits(), d.to_bits()))
                .or_insert_with(|| kernel.calibrated(cloud.dim, 1.0, d, cloud.tau, h))
        })
        .collect()
}

impl Conductance {
    /// Assembles K from the directed bonds and their half-conductances (in parallel).
    pub fn assemble(cloud: &Cloud, horizons: &Horizons, weights: &[f64]) -> Self {
        let n = horizons.len();
        let nb = cloud.n_body;
        // transpose: for each node j, the bonds i -> j
        let mut in_off = vec![0usize; n + 1];
        for &j in &horizons.targets {
            in_off[j as usize + 1] += 1;
        }
        for j in 0..n {
            in_off[j + 1] += in_off[j];
        }
        let mut fill = in_off.clone();
        let mut in_src = vec![0 as NodeId; horizons.n_bonds()];
        let mut in_w = vec![0.0; horizons.n_bonds()];
        for i in 0..n {
            for b in horizons.row(i) {
                let j = horizons.targets[b] as usize;
                in_src[fill[j]] = i as NodeId;
                in_w[fill[j]] = weights[b];
                fill[j] += 1;
            }
        }
        // merge out- and in-lists of each body row (both sorted by neighbour index)
        let rows: Vec<(Vec<NodeId>, Vec<f64>)> = (0..nb)
            .into_par_iter()
            .with_min_len(256)
            .map(|i| {
                let out = horizons.row(i);
                let (ot, ow) = (&horizons.targets[out.clone()], &weights[out]);
                let (it, iw) = (
                    &in_src[in_off[i]..in_off[i + 1]],
                    &in_w[in_off[i]..in_off[i + 1]],
                );
                let mut cols = Vec::with_capacity(ot.len().max(it.len()));
                let mut vals = Vec::with_capacity(cols.capacity());
                let (mut a, mut b) = (0, 0);
                while a < ot.len() || b < it.len() {
                    let ja = ot.get(a).copied().unwrap_or(NodeId::MAX);
                    let jb = it.get(b).copied().unwrap_or(NodeId::MAX);
                    if ja == jb {
                        cols.push(ja);
                        vals.push(ow[a] + iw[b]);
                        a += 1;
                        b += 1;
                    } else if ja < jb {
                        cols.push(ja);
                        vals.push(ow[a]);
                        a += 1;
                    } else {
                        cols.push(jb);
                        vals.push(iw[b]);
                        b += 1;
                    }
                }
                (cols, vals)
            })
            .collect();
        let mut k = Conductance {
            offsets: Vec::with_capacity(nb + 1),
            ..Default::default()
        };
        k.offsets.push(0);
        let nnz: usize = rows.iter().map(|r| r.0.len()).sum();
        k.cols.reserve(nnz);
        k.vals.reserve(nnz);
        for (c, v) in rows {
            k.diag.push(v.iter().sum());
            k.cols.extend_from_slice(&c);
            k.vals.extend_from_slice(&v);
            k.offsets.push(k.cols.len());
        }
        k
    }

    /// Number of rows (body nodes).
    pub fn n_rows(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of stored pair entries.
    pub fn nnz(&self) -> usize {
        self.cols.len()
    }

    /// Heat flow into node i, Σ_j K_ij (θ_j − θ_i), W.
    #[inline]
    pub fn row_flow(&self, i: usize, theta: &[f64]) -> f64 {
        let ti = theta[i];
        let row = self.offsets[i]..self.offsets[i + 1];
        let mut s = 0.0;
        for (&j, &k) in self.cols[row.clone()].iter().zip(&self.vals[row]) {
            s += k * (theta[j as usize] - ti);
        }
        s
    }

    /// Writes the bond heat flow of every body node into `out` (gather form, in parallel), W.
    pub fn apply(&self, theta: &[f64], out: &mut [f64]) {
        out.par_iter_mut()
            .with_min_len(1024)
            .enumerate()
            .for_each(|(i, o)| *o = self.row_flow(i, theta));
    }

    /// Serial version of [`Conductance::apply`], for the serial == parallel property.
    pub fn apply_serial(&self, theta: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.row_flow(i, theta);
        }
    }

    /// Peridynamic heat flux of every body node (formulation §8, seed 003 §2.2), W/m²:
    /// q_i = −(1/V_i) Σ_{j hotter than i} K_ij (θ_j − θ_i) ξ_ij. With K_ij = V_i V_j c β this is
    /// the paper's sum over H⁺; it equals −k∇θ for a linear field in the bulk and stays finite
    /// at corners and crack tips.
    pub fn flux(&self, cloud: &Cloud, theta: &[f64]) -> Vec<Vector> {
        (0..self.n_rows())
            .into_par_iter()
            .with_min_len(1024)
            .map(|i| {
                let ti = theta[i];
                let mut q = Vector::zeros();
                for e in self.offsets[i]..self.offsets[i + 1] {
                    let j = self.cols[e] as usize;
                    let dt = theta[j] - ti;
                    if dt > 0.0 {
                        q -= (cloud.pos[j] - cloud.pos[i]) * (self.vals[e] * dt);
                    }
                }
                q / cloud.volume[i]
            })
            .collect()
    }

    /// The entry K_ij if stored, else 0, W/K.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let r = self.offsets[i]..self.offsets[i + 1];
        match self.cols[r.clone()].binary_search(&(j as NodeId)) {
            Ok(p) => self.vals[r.start + p],
            Err(_) => 0.0,
        }
    }
}
