//! The explicit step's one read of K: the bond sum `Σ_j K_ij (θ_j − θ_i)` of every row, in
//! gather form, from whichever storage holds K (theory §2).
//!
//! K lives in the plain CSR arrays of a [`Conductance`], or, on lattices, as the shared
//! [`Stencils`] built from it. [`Rows::gather`] hides which: both give the same sums bit for bit
//! (the same entries in the same order with the same partial sums, [`crate::operator::row_sum`]),
//! so a stepper writes each update once, as a closure, for both.

use crate::operator::{row_sum, Conductance, ROW_CHUNK};
use crate::stencil::Stencils;
use rayon::prelude::*;
use std::ops::Range;

/// The storage of K that a step reads its rows from.
#[derive(Clone, Copy)]
pub enum Rows<'a> {
    /// The CSR rows of K (every cloud).
    Csr(&'a Conductance),
    /// K's shared stencils (lattices; the same bits as the CSR rows they were built from).
    Stencils(&'a Stencils),
}

impl Rows<'_> {
    /// Calls `f(i, Σ_j K_ij (θ_j − θ_i), θ_i, out_i)` (sum in W) for every body row `i` of
    /// `rows`, in parallel tasks of [`ROW_CHUNK`] rows (`out` holds the rows `rows`). For the
    /// rows marked in `skip` (driven nodes, whose update ignores it) the CSR sum is not formed
    /// and 0 is passed; the stencils form it, as cheap as skipping on a lattice.
    #[inline(always)]
    pub fn gather(
        &self,
        theta: &[f64],
        rows: Range<usize>,
        skip: &[bool],
        out: &mut [f64],
        f: impl Fn(usize, f64, f64, &mut f64) + Sync,
    ) {
        match self {
            Rows::Csr(k) => csr(k, theta, rows, skip, out, f),
            Rows::Stencils(st) => st.for_rows(theta, out, rows, |i, s, o| f(i, s, theta[i], o)),
        }
    }
}

/// [`Rows::gather`] over the CSR rows of `k`.
#[inline(always)]
fn csr(
    k: &Conductance,
    theta: &[f64],
    rows: Range<usize>,
    skip: &[bool],
    out: &mut [f64],
    f: impl Fn(usize, f64, f64, &mut f64) + Sync,
) {
    out.par_chunks_mut(ROW_CHUNK)
        .enumerate()
        .for_each(|(c, o)| {
            let first = rows.start + c * ROW_CHUNK;
            let off = &k.offsets[first..=first + o.len()];
            for (r, (o, w)) in o.iter_mut().zip(off.windows(2)).enumerate() {
                let i = first + r;
                let ti = theta[i];
                let s = match skip[i] {
                    true => 0.0,
                    false => row_sum(&k.cols[w[0]..w[1]], &k.vals[w[0]..w[1]], theta, ti),
                };
                f(i, s, ti, o);
            }
        });
}
