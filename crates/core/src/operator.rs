//! The bond operator: the symmetric pair conductance K of theory §2.2 and its product.
//!
//! `V_i ρc_i dθ_i/dt = Σ_j K_ij (θ_j − θ_i)` with `K_ij = V_i V_j (w_ij + w_ji)` and the
//! directed half-conductances `w_ij = ½ c_i(|ξ_ij|) β_ij` (Wang, Oterkus & Oterkus, eqs. 19–24;
//! w_ij = 0 when j ∉ H_i). K is symmetric, so the bond sum conserves energy exactly. Axisymmetric
//! and spherical clouds multiply each pair by the factor of [`crate::symmetry`] (PCS2022,
//! eqs. 10 and 21).

use crate::cloud::Cloud;
use crate::horizons::Horizons;
use crate::kernel::Kernel;
use crate::material::BondRule;
use crate::math::{NodeId, Vector};
use rayon::prelude::*;
use std::ops::Range;

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
    HalfConductance::new(cloud, horizons, kernel, conductivity, rule).all()
}

/// The half-conductance V_i V_j w_ij of any directed bond, W/K, computed where it is read:
/// what [`directed_weights`] stores, for an assembly that need not hold them
/// ([`Conductance::assemble_rows_with`]).
pub struct HalfConductance<'a> {
    cloud: &'a Cloud,
    horizons: &'a Horizons,
    kernel: &'a Kernel,
    conductivity: &'a [f64],
    rule: BondRule,
    /// C_i for k = 1 per node.
    units: Vec<f64>,
}

impl<'a> HalfConductance<'a> {
    /// The half-conductances of the bonds of `horizons` for the per-node `conductivity`
    /// (W/(m·K)) combined by `rule`.
    pub fn new(
        cloud: &'a Cloud,
        horizons: &'a Horizons,
        kernel: &'a Kernel,
        conductivity: &'a [f64],
        rule: BondRule,
    ) -> Self {
        let units = unit_normalisations(cloud, kernel);
        HalfConductance {
            cloud,
            horizons,
            kernel,
            conductivity,
            rule,
            units,
        }
    }

    /// Every bond's half-conductance, in the bonds' order, W/K.
    pub fn all(&self) -> Vec<f64> {
        let h = self.horizons;
        let mut w = vec![0.0; h.n_bonds()];
        h.rows_mut(&mut w)
            .into_par_iter()
            .with_min_len(256)
            .for_each(|(i, slot)| {
                for (s, b) in slot.iter_mut().zip(h.row(i)) {
                    *s = self.at(i, b);
                }
            });
        w
    }

    /// V_i V_j w_ij of bond `b` of row `i`, W/K.
    #[inline]
    pub fn at(&self, i: usize, b: usize) -> f64 {
        let cloud = self.cloud;
        let j = self.horizons.targets[b] as usize;
        let delta = cloud.horizon[i];
        let r = (cloud.pos[j] - cloud.pos[i]).norm();
        let k = self
            .rule
            .combine(self.conductivity[i], self.conductivity[j]);
        // where Algorithm 1 evaluates the profile (lines 6 and 9), and β_ij
        let (beta, at) = self.kernel.coverage(r, delta, cloud.spacing[j]);
        let c = self.kernel.micro(self.units[i] * k, r, at, delta);
        // planar measures times the ring/shell pair factor (theory §7)
        let sym = cloud.symmetry;
        let (ri, rj) = (cloud.pos[i].x, cloud.pos[j].x);
        let shape = if sym.is_symmetric() {
            sym.pair_factor(ri, rj) / (sym.volume_factor(ri) * sym.volume_factor(rj))
        } else {
            1.0
        };
        0.5 * cloud.volume[i] * cloud.volume[j] * shape * c * beta
    }
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

/// Rows per parallel task of the bond sums (the order inside a row never depends on it).
pub const ROW_CHUNK: usize = 2048;

/// Σ_k v_k (θ\[c_k\] − θ_i) over one row of K, W: four partial sums over the entries 4q + r,
/// added as (s0 + s1) + (s2 + s3) after the remainder joined s0. The order is fixed by the row
/// alone, so every thread count gives the same bits (theory §2, gather form).
#[inline(always)]
pub fn row_sum<V: Copy + Into<f64>>(cols: &[NodeId], vals: &[V], theta: &[f64], ti: f64) -> f64 {
    let n = cols.len().min(vals.len());
    let (cols, vals) = (&cols[..n], &vals[..n]);
    let mut a = [0.0f64; 4];
    let mut cc = cols.chunks_exact(4);
    let mut vc = vals.chunks_exact(4);
    for (c, v) in (&mut cc).zip(&mut vc) {
        a[0] += v[0].into() * (theta[c[0] as usize] - ti);
        a[1] += v[1].into() * (theta[c[1] as usize] - ti);
        a[2] += v[2].into() * (theta[c[2] as usize] - ti);
        a[3] += v[3].into() * (theta[c[3] as usize] - ti);
    }
    for (c, v) in cc.remainder().iter().zip(vc.remainder()) {
        a[0] += (*v).into() * (theta[*c as usize] - ti);
    }
    (a[0] + a[1]) + (a[2] + a[3])
}

/// Splits a per-row array (`data[i]`, rows `0..data.len()`) into tasks of [`ROW_CHUNK`] rows,
/// each tagged with its first row.
fn row_tasks<T: Send>(data: &mut [T]) -> impl IndexedParallelIterator<Item = (usize, &mut [T])> {
    data.par_chunks_mut(ROW_CHUNK)
        .enumerate()
        .map(|(c, s)| (c * ROW_CHUNK, s))
}

/// Splits `per_entry` (one item per CSR entry, rows delimited by `offsets`) into one slice per
/// block of rows `bounds[b]..bounds[b + 1]`.
fn split_blocks<'a, T>(
    offsets: &[usize],
    bounds: &[usize],
    per_entry: &'a mut [T],
) -> Vec<&'a mut [T]> {
    let mut out = Vec::with_capacity(bounds.len().saturating_sub(1));
    let mut rest = per_entry;
    for w in bounds.windows(2) {
        let (a, b) = std::mem::take(&mut rest).split_at_mut(offsets[w[1]] - offsets[w[0]]);
        out.push(a);
        rest = b;
    }
    out
}

/// Position of `i` in the sorted list `row`: tries `guess` first (on a lattice the reverse bond
/// of the p-th of n entries is the (n − 1 − p)-th), then a binary search.
#[inline]
fn find(row: &[NodeId], i: NodeId, guess: usize) -> Option<usize> {
    if row.get(guess) == Some(&i) {
        Some(guess)
    } else {
        row.binary_search(&i).ok()
    }
}

/// The bonds j → i into a body node i that has no bond i → j, as (i, j, w_ji) sorted by
/// (i, j); none when every node has the same horizon and spacing (β_ij = β_ji: the relation
/// is symmetric). In parallel.
fn lone_bonds(
    cloud: &Cloud,
    horizons: &Horizons,
    weights: &(impl Fn(usize, usize) -> f64 + Sync),
    rows: &Range<usize>,
) -> Vec<(NodeId, NodeId, f64)> {
    let n = horizons.len();
    let nb = cloud.n_body;
    let targets = &horizons.targets;
    let row = |i: usize| &targets[horizons.row(i)];
    let uniform = |v: &[f64]| v.iter().all(|x| x.to_bits() == v[0].to_bits());
    let symmetric = n > 0 && uniform(&cloud.horizon) && uniform(&cloud.spacing);
    let mut lone: Vec<(NodeId, NodeId, f64)> = (0..if symmetric { 0 } else { n })
        .into_par_iter()
        .with_min_len(1024)
        .flat_map_iter(|j| {
            let out = row(j);
            let start = horizons.offsets[j];
            out.iter().enumerate().filter_map(move |(p, &i)| {
                let iu = i as usize;
                if iu >= nb || !rows.contains(&iu) {
                    return None;
                }
                let back = row(iu);
                let guess = back.len().wrapping_sub(p + 1);
                match find(back, j as NodeId, guess.min(back.len())) {
                    Some(_) => None,
                    None => Some((i, j as NodeId, weights(j, start + p))),
                }
            })
        })
        .collect();
    lone.par_sort_unstable_by_key(|e| (e.0, e.1));
    lone
}

/// The CSR layout of K: where each body row's lone bonds start in `lone` (`nb + 1` entries),
/// and where each row starts in K (its outgoing bonds plus its lone bonds).
fn row_offsets(
    horizons: &Horizons,
    nb: usize,
    rows: &Range<usize>,
    lone: &[(NodeId, NodeId, f64)],
) -> (Vec<usize>, Vec<usize>) {
    let mut lone_off = vec![0usize; nb + 1];
    for e in lone {
        lone_off[e.0 as usize + 1] += 1;
    }
    for i in 0..nb {
        lone_off[i + 1] += lone_off[i];
    }
    let mut offsets = Vec::with_capacity(nb + 1);
    offsets.push(0usize);
    for i in 0..nb {
        let len = match rows.contains(&i) {
            true => horizons.row(i).len() + lone_off[i + 1] - lone_off[i],
            false => 0,
        };
        offsets.push(offsets[i] + len);
    }
    (lone_off, offsets)
}

impl Conductance {
    /// Assembles K from the directed bonds and their half-conductances (in parallel, no
    /// transpose): K_ij = w_ij + w_ji with w_ji found in row j, plus the bonds j → i whose
    /// reverse does not exist (at horizon changes), collected separately.
    pub fn assemble(cloud: &Cloud, horizons: &Horizons, weights: &[f64]) -> Self {
        Self::assemble_rows(cloud, horizons, weights, 0..cloud.n_body)
    }

    /// [`Conductance::assemble`] of the body rows `rows` alone (one rank's share, from the
    /// rows of [`Horizons::build_rows`]); every other row is empty. Each assembled row has the
    /// bits of the whole assembly's.
    pub fn assemble_rows(
        cloud: &Cloud,
        horizons: &Horizons,
        weights: &[f64],
        rows: Range<usize>,
    ) -> Self {
        Self::assemble_rows_with(cloud, horizons, &|_, b| weights[b], rows)
    }

    /// [`Conductance::assemble_rows`] with the half-conductance of bond `b` of row `i` given
    /// as `weights(i, b)` (a [`HalfConductance`], say, so that no per-bond array is held):
    /// the same bits as the assembly of the stored values.
    pub fn assemble_rows_with(
        cloud: &Cloud,
        horizons: &Horizons,
        weights: &(impl Fn(usize, usize) -> f64 + Sync),
        rows: Range<usize>,
    ) -> Self {
        let nb = cloud.n_body;
        let targets = &horizons.targets;
        let row = |i: usize| &targets[horizons.row(i)];
        let lone = lone_bonds(cloud, horizons, weights, &rows);
        let (lone_off, offsets) = row_offsets(horizons, nb, &rows, &lone);
        let nnz = offsets[nb];
        let mut cols = vec![0 as NodeId; nnz];
        let mut vals = vec![0.0; nnz];
        let mut diag = vec![0.0; nb];
        let bounds: Vec<usize> = (0..nb)
            .step_by(ROW_CHUNK)
            .chain(std::iter::once(nb))
            .collect();
        let cb = split_blocks(&offsets, &bounds, &mut cols);
        let vb = split_blocks(&offsets, &bounds, &mut vals);
        cb.into_par_iter()
            .zip(vb)
            .zip(diag.par_chunks_mut(ROW_CHUNK))
            .enumerate()
            .for_each(|(blk, ((cs, vs), ds))| {
                let first = bounds[blk];
                let mut e = 0;
                for (r, d) in ds.iter_mut().enumerate() {
                    let i = first + r;
                    if !rows.contains(&i) {
                        continue;
                    }
                    let out = row(i);
                    let len = out.len();
                    let own = horizons.offsets[i];
                    let extra = &lone[lone_off[i]..lone_off[i + 1]];
                    let start = e;
                    let (mut a, mut b) = (0, 0);
                    while a < len || b < extra.len() {
                        let ja = out.get(a).copied().unwrap_or(NodeId::MAX);
                        let jb = extra.get(b).map_or(NodeId::MAX, |x| x.1);
                        if ja < jb {
                            let ju = ja as usize;
                            let back = row(ju);
                            let guess = back.len().wrapping_sub(a + 1);
                            let w = match find(back, i as NodeId, guess.min(back.len())) {
                                Some(q) => {
                                    weights(i, own + a) + weights(ju, horizons.offsets[ju] + q)
                                }
                                None => weights(i, own + a),
                            };
                            cs[e] = ja;
                            vs[e] = w;
                            a += 1;
                        } else {
                            cs[e] = jb;
                            vs[e] = extra[b].2;
                            b += 1;
                        }
                        e += 1;
                    }
                    *d = vs[start..e].iter().sum();
                }
            });
        Conductance {
            offsets,
            cols,
            vals,
            diag,
        }
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
        let row = self.offsets[i]..self.offsets[i + 1];
        row_sum(&self.cols[row.clone()], &self.vals[row], theta, theta[i])
    }

    /// Writes the bond heat flow of every body node into `out` (gather form, in parallel), W.
    pub fn apply(&self, theta: &[f64], out: &mut [f64]) {
        row_tasks(out).for_each(|(first, o)| {
            for (r, o) in o.iter_mut().enumerate() {
                *o = self.row_flow(first + r, theta);
            }
        });
    }

    /// Serial version of [`Conductance::apply`], for the serial == parallel property.
    pub fn apply_serial(&self, theta: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.row_flow(i, theta);
        }
    }

    /// Peridynamic heat flux of every body node (theory §8, Bobaru & Duangpanya 2012 §2.2), W/m²:
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
