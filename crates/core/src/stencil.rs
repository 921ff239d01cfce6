//! K stored as shared stencils: rows whose (j − i, K_ij) sequences are equal share one copy.
//!
//! On a lattice every interior row of K is the same stencil of offsets and conductances;
//! only rows near faces, cracks or a change of spacing differ. Stored once per block of
//! [`ROW_CHUNK`] rows, the stencils stay in cache and the explicit step streams 2 bytes per
//! row instead of 12 bytes per bond (theory §2: the same K, the same sums, bit for bit).
//! Clouds without repeated rows (gmsh meshes) do not compress and keep the plain CSR.

use crate::operator::{Conductance, ROW_CHUNK};
use rayon::prelude::*;
use std::collections::HashMap;
use std::ops::Range;

/// The stencils of one block of rows.
#[derive(Debug, Clone, Default)]
struct Block {
    /// Entry range of each stencil (length stencils + 1).
    start: Vec<u32>,
    /// j − i of each entry.
    delta: Vec<i32>,
    /// K_ij of each entry, W/K.
    vals: Vec<f64>,
}

/// K of a [`Conductance`] as per-block stencils and one stencil index per row.
#[derive(Debug, Clone, Default)]
pub struct Stencils {
    blocks: Vec<Block>,
    /// Stencil of each body row within its block.
    row: Vec<u16>,
}

/// Σ_k v_k (θ[i + d_k] − θ_i): [`crate::operator::row_sum`] with columns as offsets from i,
/// in the same order and with the same partial sums (the same bits), W.
#[inline(always)]
fn row_sum_delta(delta: &[i32], vals: &[f64], theta: &[f64], i: usize, ti: f64) -> f64 {
    let n = delta.len().min(vals.len());
    let (delta, vals) = (&delta[..n], &vals[..n]);
    let at = |d: i32| theta[i.wrapping_add_signed(d as isize)];
    let mut a = [0.0f64; 4];
    let mut dc = delta.chunks_exact(4);
    let mut vc = vals.chunks_exact(4);
    for (d, v) in (&mut dc).zip(&mut vc) {
        a[0] += v[0] * (at(d[0]) - ti);
        a[1] += v[1] * (at(d[1]) - ti);
        a[2] += v[2] * (at(d[2]) - ti);
        a[3] += v[3] * (at(d[3]) - ti);
    }
    for (d, v) in dc.remainder().iter().zip(vc.remainder()) {
        a[0] += v * (at(*d) - ti);
    }
    (a[0] + a[1]) + (a[2] + a[3])
}

/// A hash of a row's offsets and conductance bits (FxHash-style mixing).
fn row_hash(delta: &[i32], vals: &[f64]) -> u64 {
    let mut h: u64 = delta.len() as u64;
    let mut mix = |x: u64| h = (h.rotate_left(5) ^ x).wrapping_mul(0x517c_c1b7_2722_0a95);
    for (&d, &v) in delta.iter().zip(vals) {
        mix(d as u32 as u64);
        mix(v.to_bits());
    }
    h
}

impl Stencils {
    /// Deduplicates the rows of `k` block by block (in parallel). None when the stencils
    /// would hold more than a quarter of K's entries (no lattice to exploit) or a column
    /// offset does not fit 32 bits.
    pub fn build(k: &Conductance) -> Option<Stencils> {
        let nb = k.n_rows();
        let fits = |i: usize, j: u32| i32::try_from(j as i64 - i as i64).ok();
        let mut row = vec![0u16; nb];
        let blocks: Vec<Option<Block>> = row
            .par_chunks_mut(ROW_CHUNK)
            .enumerate()
            .map(|(b, ids)| {
                let first = b * ROW_CHUNK;
                let mut blk = Block {
                    start: vec![0],
                    ..Default::default()
                };
                let mut seen: HashMap<u64, u16> = HashMap::new();
                let mut delta = Vec::new();
                for (r, id) in ids.iter_mut().enumerate() {
                    let i = first + r;
                    let e = k.offsets[i]..k.offsets[i + 1];
                    delta.clear();
                    for &j in &k.cols[e.clone()] {
                        delta.push(fits(i, j)?);
                    }
                    let vals = &k.vals[e];
                    let h = row_hash(&delta, vals);
                    let same = |s: u16| {
                        let r = blk.start[s as usize] as usize..blk.start[s as usize + 1] as usize;
                        blk.delta[r.clone()] == delta[..]
                            && blk.vals[r]
                                .iter()
                                .zip(vals)
                                .all(|(a, b)| a.to_bits() == b.to_bits())
                    };
                    *id = match seen.get(&h) {
                        Some(&s) if same(s) => s,
                        found => {
                            let s = (blk.start.len() - 1) as u16;
                            if found.is_none() {
                                seen.insert(h, s);
                            }
                            blk.delta.extend_from_slice(&delta);
                            blk.vals.extend_from_slice(vals);
                            blk.start.push(blk.delta.len() as u32);
                            s
                        }
                    };
                }
                blk.start.shrink_to_fit();
                blk.delta.shrink_to_fit();
                blk.vals.shrink_to_fit();
                Some(blk)
            })
            .collect();
        let blocks: Vec<Block> = blocks.into_iter().collect::<Option<_>>()?;
        let held: usize = blocks.iter().map(|b| b.delta.len()).sum();
        if 4 * held > k.nnz() {
            return None;
        }
        Some(Stencils { blocks, row })
    }

    /// Number of stored stencil entries (against [`Conductance::nnz`] for the plain CSR).
    pub fn entries(&self) -> usize {
        self.blocks.iter().map(|b| b.delta.len()).sum()
    }

    /// Bytes held, B.
    pub fn bytes(&self) -> usize {
        self.row.capacity() * 2
            + self
                .blocks
                .iter()
                .map(|b| b.start.capacity() * 4 + b.delta.capacity() * 4 + b.vals.capacity() * 8)
                .sum::<usize>()
    }

    /// Calls `f(i, Σ_j K_ij (θ_j − θ_i), out_i)` for every body row `i` of `rows`, block by
    /// block in parallel (gather form: each row writes only its own slot of `out`, which holds
    /// the rows `rows`).
    #[inline(always)]
    pub fn for_rows(
        &self,
        theta: &[f64],
        out: &mut [f64],
        rows: Range<usize>,
        f: impl Fn(usize, f64, &mut f64) + Sync,
    ) {
        let run = |first: usize, o: &mut [f64]| {
            if o.is_empty() {
                return;
            }
            let blk = &self.blocks[first / ROW_CHUNK];
            for (r, o) in o.iter_mut().enumerate() {
                let i = first + r;
                let s = self.row[i] as usize;
                let e = blk.start[s] as usize..blk.start[s + 1] as usize;
                let flow = row_sum_delta(&blk.delta[e.clone()], &blk.vals[e], theta, i, theta[i]);
                f(i, flow, o);
            }
        };
        // the rows before the first block boundary, then whole blocks
        let head = (rows.start.next_multiple_of(ROW_CHUNK)).min(rows.end) - rows.start;
        let (first, rest) = out.split_at_mut(head);
        let start = rows.start + head;
        rayon::join(
            || run(rows.start, first),
            || {
                rest.par_chunks_mut(ROW_CHUNK)
                    .enumerate()
                    .for_each(|(c, o)| run(start + c * ROW_CHUNK, o))
            },
        );
    }
}
