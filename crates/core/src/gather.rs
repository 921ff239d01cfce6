//! The explicit step's one read of K: the bond sum `Σ_j K_ij (θ_j − θ_i)` of every row, in
//! gather form, from whichever storage holds K (theory §2).
//!
//! K lives in the plain CSR arrays of a [`Conductance`], or, on lattices, as the shared
//! [`Stencils`] built from it. [`Rows::gather`] hides which: both give the same sums bit for bit
//! (the same entries in the same order with the same partial sums, [`crate::operator::row_sum`]),
//! so a stepper writes each update once, as a closure, for both. On meshes the step may read
//! the columns packed into bytes ([`PackedColumns`], the same bits) and K rounded to f32
//! ([`Precision::F32`], opt-in: each K_ij rounded once, the sums still in f64).

use crate::operator::{row_sum, Conductance, ROW_CHUNK};
use crate::packed::PackedColumns;
use crate::stencil::Stencils;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::ops::Range;

/// How the explicit step stores K's column index (`kernel.columns`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ColumnIndex {
    /// A u32 per bond, K's own CSR columns (default; nothing more held).
    #[default]
    U32,
    /// About 1 B per bond ([`PackedColumns`]), held beside K's columns; the same sums.
    Packed,
}

/// The precision of K as the explicit step reads it (`kernel.precision`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Precision {
    /// K's own f64 values (default).
    #[default]
    F64,
    /// Each K_ij rounded to f32 once (4 B per bond, held beside K), the sums formed in f64.
    /// K_ij and K_ji round alike, so the bond sums still conserve energy to round-off.
    F32,
}

/// What the explicit step reads K from, as the case asks (lattices still use stencils when
/// they repeat rows and K stays f64).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StepStorage {
    /// The column index.
    pub columns: ColumnIndex,
    /// The precision of K_ij.
    pub precision: Precision,
}

impl StepStorage {
    /// "u32 columns, f64 K", "packed columns, f32 K", …
    pub fn name(&self) -> String {
        let columns = match self.columns {
            ColumnIndex::U32 => "u32",
            ColumnIndex::Packed => "packed",
        };
        let precision = match self.precision {
            Precision::F64 => "f64",
            Precision::F32 => "f32",
        };
        format!("{columns} columns, {precision} K")
    }
}

/// Where a step reads a bond's column from.
#[derive(Clone, Copy)]
pub enum Columns<'a> {
    /// K's CSR offsets and u32 columns.
    Csr(&'a Conductance),
    /// The packed columns of the rows stepped.
    Packed(&'a PackedColumns),
}

/// Where a step reads K_ij from (indexed as K's entries).
#[derive(Clone, Copy)]
pub enum Values<'a> {
    /// K's own values, W/K.
    F64(&'a [f64]),
    /// K's values rounded to f32, W/K.
    F32(&'a [f32]),
}

/// The storage of K that a step reads its rows from.
#[derive(Clone, Copy)]
pub enum Rows<'a> {
    /// K's rows with their columns and values from the given storage (every cloud).
    Bonds(Columns<'a>, Values<'a>),
    /// K's shared stencils (lattices; the same bits as the CSR rows they were built from).
    Stencils(&'a Stencils),
}

impl Rows<'_> {
    /// Calls `f(i, Σ_j K_ij (θ_j − θ_i), θ_i, out_i)` (sum in W) for every body row `i` of
    /// `rows`, in parallel tasks of [`ROW_CHUNK`] rows (`out` holds the rows `rows`). For the
    /// rows marked in `skip` (driven nodes, whose update ignores it) the CSR sum is not formed
    /// and 0 is passed; the stencils and the packed columns form it (the packed rows are read in
    /// sequence, so a row cannot be stepped over without reading it).
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
            Rows::Bonds(Columns::Csr(k), Values::F64(v)) => csr(k, v, theta, rows, skip, out, f),
            Rows::Bonds(Columns::Csr(k), Values::F32(v)) => csr(k, v, theta, rows, skip, out, f),
            Rows::Bonds(Columns::Packed(p), v) => {
                debug_assert_eq!(p.rows(), rows);
                match v {
                    Values::F64(v) => p.gather(v, theta, out, f),
                    Values::F32(v) => p.gather(v, theta, out, f),
                }
            }
            Rows::Stencils(st) => st.for_rows(theta, out, rows, |i, s, o| f(i, s, theta[i], o)),
        }
    }
}

/// [`Rows::gather`] over the CSR rows of `k` with the values `vals` (K's, or rounded).
#[inline(always)]
fn csr<V: Copy + Into<f64> + Sync>(
    k: &Conductance,
    vals: &[V],
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
                    false => row_sum(&k.cols[w[0]..w[1]], &vals[w[0]..w[1]], theta, ti),
                };
                f(i, s, ti, o);
            }
        });
}
