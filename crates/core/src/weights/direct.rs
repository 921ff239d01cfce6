//! The Newton matrix of the consistent-weights problem assembled and factorised (faer's sparse
//! Cholesky), for clouds small enough that a direct solve beats preconditioned CG.
//!
//! H = Σ_pairs K'_ij a_ij a_ijᵀ with a_ij = (φ_i(ξ_ij) at node i, φ_j(ξ_ji) at node j): blocks of
//! the used moment components, one block row per selected node, the sparsity of K.

use super::{Mom, Problem};
use crate::math::Real;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Side};
use rayon::prelude::*;

/// Largest number of stored entries of H's lower triangle solved directly (beyond it, or in
/// 3D where the fill of a horizon of ~100 neighbours grows too fast: CG with the two-level
/// preconditioner, which on large 2D meshes needs thousands of iterations per Newton step).
/// The set-up's memory estimate (the budget module) counts the factor.
const MAX_ENTRIES: usize = crate::limits::MAX_DIRECT_ENTRIES as usize;

/// Fraction of the machine's available memory (read when the structure is analysed) that the
/// factorisation may take; a larger factor is left to CG, slower but within memory, since
/// the set-up's estimate can only guess the factor's fill before the cloud exists.
const FACTOR_MEMORY_FRACTION: f64 = 0.9;

/// [`FACTOR_MEMORY_FRACTION`] of the machine's available memory now, bytes (None where it
/// cannot be read).
pub(super) fn machine_room() -> Option<f64> {
    let available = crate::machine::Memory::of_machine().available;
    available.map(|a| a * FACTOR_MEMORY_FRACTION)
}

/// Bytes of a factorisation of H: the factor's values, H's row indices and values
/// (`entries`) and faer's scratch (`scratch` bytes).
fn factor_bytes(symbolic: &SymbolicCholesky<usize>, entries: usize, scratch: usize) -> f64 {
    let value = std::mem::size_of::<Real>();
    let index = std::mem::size_of::<usize>();
    (symbolic.len_val() * value + entries * (value + index) + scratch) as f64
}

/// The lower triangle of H in compressed columns, and its Cholesky factor.
pub(super) struct Direct {
    /// Used moment components.
    comps: Vec<usize>,
    /// Position of each body node among the selected ones (u32::MAX: not selected).
    pos: Vec<u32>,
    /// Selected nodes in order.
    nodes: Vec<u32>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    values: Vec<Real>,
    scratch: MemBuffer,
}

impl Direct {
    /// The structure of H for the selection of `p`, analysed once; None when it is too large
    /// (more than [`MAX_ENTRIES`], in 3D, or a factor above `p.factor_room` bytes, by default
    /// [`machine_room`]): the callers then take CG.
    pub(super) fn new(p: &Problem) -> Option<Direct> {
        let comps: Vec<usize> = (0..super::NC).filter(|&c| p.used[c] != 0.0).collect();
        let nu = comps.len();
        let nodes: Vec<u32> = (0..p.n() as u32).filter(|&i| p.sel[i as usize]).collect();
        let unknowns = nodes.len() * nu;
        let later: usize = nodes
            .iter()
            .map(|&i| Self::later_count(p, i as usize))
            .sum();
        let entries = later * nu * nu + nodes.len() * nu * (nu + 1) / 2;
        if unknowns == 0 || entries > MAX_ENTRIES || p.cloud.dim == 3 {
            return None;
        }
        let mut pos = vec![u32::MAX; p.n()];
        for (k, &i) in nodes.iter().enumerate() {
            pos[i as usize] = k as u32;
        }
        let (mut col_ptr, mut row_idx) = (vec![0usize], Vec::new());
        for &i in &nodes {
            let later: Vec<usize> = Self::later(p, &pos, i as usize).collect();
            for q in 0..nu {
                let base = pos[i as usize] as usize * nu;
                row_idx.extend((q..nu).map(|r| base + r));
                for &j in &later {
                    row_idx.extend((0..nu).map(|r| pos[j] as usize * nu + r));
                }
                col_ptr.push(row_idx.len());
            }
        }
        let structure =
            SymbolicSparseColMatRef::new_checked(unknowns, unknowns, &col_ptr, None, &row_idx);
        let symbolic = factorize_symbolic_cholesky(
            structure,
            Side::Lower,
            Default::default(),
            Default::default(),
        )
        .ok()?;
        let par = super::FACTOR_PAR;
        let scratch = symbolic
            .factorize_numeric_llt_scratch::<Real>(par, Default::default())
            .or(symbolic.solve_in_place_scratch::<Real>(1, par));
        let bytes = factor_bytes(&symbolic, row_idx.len(), scratch.size_bytes());
        if p.factor_room.is_some_and(|room| bytes > room) {
            return None;
        }
        let scratch = MemBuffer::new(scratch);
        Some(Direct {
            comps,
            pos,
            nodes,
            col_ptr,
            row_idx,
            values: vec![0.0; symbolic.len_val()],
            symbolic,
            scratch,
        })
    }

    /// Number of neighbours j > i of node i in the CSR row (an upper bound on the selected ones).
    fn later_count(p: &Problem, i: usize) -> usize {
        let row = &p.cols[p.offsets[i]..p.offsets[i + 1]];
        row.len() - row.partition_point(|&j| j as usize <= i)
    }

    /// Selected neighbours j > i of node i, in increasing order (the CSR rows are sorted).
    fn later<'a>(p: &'a Problem, pos: &'a [u32], i: usize) -> impl Iterator<Item = usize> + 'a {
        (p.offsets[i]..p.offsets[i + 1])
            .map(|e| p.cols[e] as usize)
            .filter(move |&j| j > i && j < pos.len() && pos[j] != u32::MAX)
    }

    /// The values of H (lower triangle, the structure's order) for the weights `vals`.
    fn matrix(&self, p: &Problem, vals: &[Real]) -> Vec<Real> {
        let nu = self.comps.len();
        let per_node: Vec<Vec<Real>> = self
            .nodes
            .par_iter()
            .map(|&i| {
                let i = i as usize;
                let mut diag = super::Block::zeros();
                let mut off: Vec<(usize, Mom, Mom, Real)> = Vec::new();
                for e in p.offsets[i]..p.offsets[i + 1] {
                    let j = p.cols[e] as usize;
                    let (pi, pj) = p.phis(i, j);
                    diag += vals[e] * pi * pi.transpose();
                    if j > i && j < self.pos.len() && self.pos[j] != u32::MAX {
                        off.push((j, pi, pj, vals[e]));
                    }
                }
                let mut out = Vec::new();
                for q in 0..nu {
                    let c = self.comps[q];
                    out.extend((q..nu).map(|r| diag[(self.comps[r], c)]));
                    for (_, pi, pj, k) in &off {
                        out.extend(self.comps.iter().map(|&r| k * pj[r] * pi[c]));
                    }
                }
                out
            })
            .collect();
        per_node.concat()
    }

    /// Factorises H for the weights `vals` (a tiny diagonal shift keeps it definite).
    pub(super) fn factorise(&mut self, p: &Problem, vals: &[Real]) -> bool {
        let a = self.matrix(p, vals);
        let n = self.col_ptr.len() - 1;
        let scale = (0..n)
            .map(|c| a[self.col_ptr[c]].abs())
            .fold(0.0, Real::max);
        let structure =
            SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        let h = SparseColMatRef::new(structure, &a);
        let par = super::FACTOR_PAR;
        self.symbolic
            .factorize_numeric_llt(
                &mut self.values,
                h,
                Side::Lower,
                LltRegularization {
                    dynamic_regularization_delta: 1e-10 * scale,
                    dynamic_regularization_epsilon: 1e-14 * scale,
                },
                par,
                MemStack::new(&mut self.scratch),
                Default::default(),
            )
            .is_ok()
    }

    /// x = H⁻¹ b on the selected nodes (0 elsewhere).
    pub(super) fn solve(&mut self, b: &[Mom], x: &mut [Mom]) {
        let nu = self.comps.len();
        let mut rhs: Vec<Real> = self
            .nodes
            .iter()
            .flat_map(|&i| self.comps.iter().map(move |&c| b[i as usize][c]))
            .collect();
        let n = rhs.len();
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            faer::MatMut::from_column_major_slice_mut(&mut rhs, n, 1),
            super::FACTOR_PAR,
            MemStack::new(&mut self.scratch),
        );
        x.iter_mut().for_each(|v| *v = Mom::zeros());
        for (k, &i) in self.nodes.iter().enumerate() {
            for (q, &c) in self.comps.iter().enumerate() {
                x[i as usize][c] = rhs[k * nu + q];
            }
        }
    }
}
