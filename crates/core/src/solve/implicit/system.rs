//! The reduced system: the semi-discrete equations on the free body nodes, with every
//! constrained and fictitious node eliminated (theory §4).

use super::refuse;
use crate::error::Result;
use crate::model::Model;
use rayon::prelude::*;
use std::ops::Range;

/// Relative asymmetry below which A is treated as symmetric (of the largest diagonal entry).
pub const SYMMETRY_TOLERANCE: f64 = 1e-10;

/// The semi-discrete system `M dθ/dt = −A θ + f(t)` on the free body nodes (theory §4).
#[derive(Debug, Clone)]
pub struct System {
    /// Body node of each unknown.
    pub free: Vec<usize>,
    /// Row offsets of A (CSR), length n + 1.
    pub offsets: Vec<usize>,
    /// Column (unknown) indices of A, sorted within each row.
    pub cols: Vec<usize>,
    /// Entries of A, W/K.
    pub vals: Vec<f64>,
    /// Position of A_ii in `vals` for each row.
    pub diag_pos: Vec<usize>,
    /// Heat capacity M_i = V_i ρc_i of each unknown, J/K.
    pub mass: Vec<f64>,
    /// Largest |A_ij − A_ji| over the largest diagonal entry (dimensionless).
    pub asymmetry: f64,
    /// True when `asymmetry` ≤ [`SYMMETRY_TOLERANCE`].
    pub symmetric: bool,
    /// The unknowns whose rows are held: all, or those of a share's rows
    /// ([`crate::model::Model::rows`]; the others hold their diagonal M_i·h_i only).
    pub held: Range<usize>,
    /// Row offsets of the coupling to constrained nodes (CSR over the unknowns).
    c_offsets: Vec<usize>,
    /// Constrained node of each coupling entry.
    c_cols: Vec<u32>,
    /// K_ic of each coupling entry, W/K.
    c_vals: Vec<f64>,
}

/// Index of a node that is not an unknown.
const NONE: u32 = u32::MAX;

/// Which nodes are unknowns, and every constrained node's rule expanded over them.
struct Elimination {
    /// Unknown of each node ([`NONE`] for constrained and fictitious nodes).
    index: Vec<u32>,
    /// Body node of each unknown.
    free: Vec<usize>,
    /// θ_c = Σ S_ck θ_k + g_c(t) of each constrained node c: its (unknown k, S_ck), sorted.
    expanded: Vec<Option<Vec<(u32, f64)>>>,
}

impl Elimination {
    /// Numbers the free body nodes and expands each boundary rule over them, in the order the
    /// boundary applies them.
    fn new(model: &Model) -> Result<Elimination> {
        let cloud = &model.cloud;
        let (nb, nn) = (cloud.n_body, cloud.len());
        let rules = model.boundary.linear_rules();
        let mut constrained = vec![false; nn];
        for c in constrained.iter_mut().skip(nb) {
            *c = true;
        }
        for (node, _) in &rules {
            constrained[*node] = true;
        }
        let mut index = vec![NONE; nn];
        let mut free = Vec::new();
        for i in 0..nb {
            if !constrained[i] {
                index[i] = free.len() as u32;
                free.push(i);
            }
        }
        if free.is_empty() {
            return Err(refuse(
                "every body node is constrained: nothing to integrate",
            ));
        }
        let mut expanded: Vec<Option<Vec<(u32, f64)>>> = vec![None; nn];
        for (node, terms) in &rules {
            expanded[*node] = Some(Self::expand(*node, terms, &index, &expanded)?);
        }
        Ok(Elimination {
            index,
            free,
            expanded,
        })
    }

    /// The rule of `node` over the unknowns: its terms on free nodes as they are, those on
    /// constrained nodes through their expanded rules; merged by unknown.
    fn expand(
        node: usize,
        terms: &[(usize, f64)],
        index: &[u32],
        expanded: &[Option<Vec<(u32, f64)>>],
    ) -> Result<Vec<(u32, f64)>> {
        let mut row: Vec<(u32, f64)> = Vec::new();
        for &(src, w) in terms {
            if index[src] != NONE {
                row.push((index[src], w));
            } else if let Some(e) = &expanded[src] {
                row.extend(e.iter().map(|&(k, v)| (k, v * w)));
            } else {
                return Err(refuse(format!(
                    "the boundary rule of node {node} reads node {src} before it is set (chained nodal flux relations); the implicit solvers cannot eliminate it: use euler or rk4"
                )));
            }
        }
        row.sort_by_key(|e| e.0);
        let mut merged: Vec<(u32, f64)> = Vec::with_capacity(row.len());
        for (k, v) in row {
            match merged.last_mut() {
                Some(l) if l.0 == k => l.1 += v,
                _ => merged.push((k, v)),
            }
        }
        Ok(merged)
    }
}

impl System {
    /// Eliminates fictitious and constrained nodes from the model's equations.
    pub fn build(model: &Model) -> Result<System> {
        if !model.growth.is_empty() {
            return Err(refuse(
                "implicit and steady solvers do not handle growing cracks (crack[].speed): K changes as the tips pass; use euler or rk4",
            ));
        }
        let Elimination {
            index,
            free,
            expanded,
        } = Elimination::new(model)?;
        let n = free.len();
        let k = &model.conductance;
        let mass: Vec<f64> = free
            .iter()
            .map(|&i| model.cloud.volume[i] * model.capacity[i])
            .collect();
        let held = free.partition_point(|&i| i < model.rows.start)
            ..free.partition_point(|&i| i < model.rows.end);
        let mut sys = System {
            held,
            free,
            offsets: Vec::with_capacity(n + 1),
            cols: Vec::with_capacity(k.nnz()),
            vals: Vec::with_capacity(k.nnz()),
            diag_pos: Vec::with_capacity(n),
            mass,
            asymmetry: 0.0,
            symmetric: true,
            c_offsets: Vec::with_capacity(n + 1),
            c_cols: Vec::new(),
            c_vals: Vec::new(),
        };
        sys.assemble(model, &index, &expanded);
        sys.measure_symmetry();
        Ok(sys)
    }

    /// Fills the rows of A and of the coupling to constrained nodes: row r of A is
    /// `D_i + M_i h_i` on the diagonal, −K_ij for free j and −K_ic S_c· for constrained c.
    fn assemble(&mut self, model: &Model, index: &[u32], expanded: &[Option<Vec<(u32, f64)>>]) {
        let k = &model.conductance;
        let n = self.free.len();
        let loads = model.boundary.load_diagonal(model.cloud.n_body);
        self.offsets.push(0);
        self.c_offsets.push(0);
        let mut acc = vec![0.0; n];
        let mut touched = vec![false; n];
        let mut list: Vec<usize> = Vec::new();
        fn touch(c: usize, v: f64, acc: &mut [f64], list: &mut Vec<usize>, touched: &mut [bool]) {
            if !touched[c] {
                touched[c] = true;
                list.push(c);
            }
            acc[c] += v;
        }
        for r in 0..n {
            let i = self.free[r];
            touch(
                r,
                k.diag[i] + self.mass[r] * loads[i],
                &mut acc,
                &mut list,
                &mut touched,
            );
            for e in k.offsets[i]..k.offsets[i + 1] {
                let (j, kij) = (k.cols[e] as usize, k.vals[e]);
                if index[j] != NONE {
                    touch(index[j] as usize, -kij, &mut acc, &mut list, &mut touched);
                } else {
                    self.c_cols.push(j as u32);
                    self.c_vals.push(kij);
                    if let Some(ex) = &expanded[j] {
                        for &(c, w) in ex {
                            touch(c as usize, -kij * w, &mut acc, &mut list, &mut touched);
                        }
                    }
                }
            }
            list.sort_unstable();
            for &c in &list {
                if c == r {
                    self.diag_pos.push(self.cols.len());
                }
                self.cols.push(c);
                self.vals.push(acc[c]);
                acc[c] = 0.0;
            }
            for &c in &list {
                touched[c] = false;
            }
            list.clear();
            self.offsets.push(self.cols.len());
            self.c_offsets.push(self.c_cols.len());
        }
    }

    /// Sets [`System::asymmetry`] (relative to the largest diagonal entry) and
    /// [`System::symmetric`] from the pairs of held rows (a share's pairs with other ranks'
    /// rows are compared by [`super::distributed`]).
    fn measure_symmetry(&mut self) {
        let scale = self.diagonal_max(&self.held);
        let mut asym: f64 = 0.0;
        for r in self.held.clone() {
            for e in self.offsets[r]..self.offsets[r + 1] {
                let c = self.cols[e];
                if self.held.contains(&c) {
                    asym = asym.max((self.vals[e] - self.get(c, r)).abs());
                }
            }
        }
        self.asymmetry = if scale > 0.0 { asym / scale } else { 0.0 };
        self.symmetric = self.asymmetry <= SYMMETRY_TOLERANCE;
    }

    /// A system without unknowns, to be filled.
    pub(super) fn empty() -> System {
        System {
            free: Vec::new(),
            offsets: Vec::new(),
            cols: Vec::new(),
            vals: Vec::new(),
            diag_pos: Vec::new(),
            mass: Vec::new(),
            asymmetry: 0.0,
            symmetric: true,
            held: 0..0,
            c_offsets: Vec::new(),
            c_cols: Vec::new(),
            c_vals: Vec::new(),
        }
    }

    /// The largest |A_rr| over the rows `rows`, W/K.
    pub(super) fn diagonal_max(&self, rows: &Range<usize>) -> f64 {
        self.diag_pos[rows.clone()]
            .iter()
            .map(|&p| self.vals[p].abs())
            .fold(0.0, f64::max)
    }

    /// The sparsity pattern of A (CSR; A is stored symmetric in pattern, so it is the CSC
    /// pattern too), as faer reads it.
    pub(super) fn pattern(&self) -> faer::sparse::SymbolicSparseColMatRef<'_, usize> {
        let n = self.len();
        faer::sparse::SymbolicSparseColMatRef::new_checked(n, n, &self.offsets, None, &self.cols)
    }

    /// Number of unknowns (free body nodes).
    pub fn len(&self) -> usize {
        self.free.len()
    }

    /// True when there are no unknowns.
    pub fn is_empty(&self) -> bool {
        self.free.is_empty()
    }

    /// The entry A_rc if stored, else 0, W/K.
    pub fn get(&self, r: usize, c: usize) -> f64 {
        let range = self.offsets[r]..self.offsets[r + 1];
        match self.cols[range.clone()].binary_search(&c) {
            Ok(p) => self.vals[range.start + p],
            Err(_) => 0.0,
        }
    }

    /// True when the constant field is in the null space of A (no boundary fixes the level):
    /// every held row sum below 1e-9 of its diagonal entry.
    pub fn is_floating(&self) -> bool {
        self.held.clone().all(|r| {
            let s: f64 = self.vals[self.offsets[r]..self.offsets[r + 1]].iter().sum();
            s.abs() <= 1e-9 * self.vals[self.diag_pos[r]].abs()
        })
    }

    /// `out = c·M·u − a·A·u` (W) on the held rows, in parallel when asked.
    pub(super) fn combine(&self, c: f64, a: f64, u: &[f64], out: &mut [f64], parallel: bool) {
        let row = |r: usize| {
            let mut s = 0.0;
            for e in self.offsets[r]..self.offsets[r + 1] {
                s += self.vals[e] * u[self.cols[e]];
            }
            c * self.mass[r] * u[r] - a * s
        };
        let held = self.held.clone();
        let out = &mut out[held.clone()];
        if parallel {
            out.par_iter_mut()
                .with_min_len(1024)
                .enumerate()
                .for_each(|(k, o)| *o = row(held.start + k));
        } else {
            for (k, o) in out.iter_mut().enumerate() {
                *o = row(held.start + k);
            }
        }
    }

    /// The forcing f(t) (W) into `out`; `scratch` is a whole-cloud field whose free entries are
    /// 0 (only constrained entries are written), `rate` a body-sized buffer.
    pub(super) fn forcing(
        &self,
        model: &Model,
        t: f64,
        scratch: &mut [f64],
        rate: &mut [f64],
        out: &mut [f64],
    ) {
        model.boundary.apply(&model.cloud, scratch, t);
        for (r, o) in out.iter_mut().enumerate() {
            let mut s = 0.0;
            for e in self.c_offsets[r]..self.c_offsets[r + 1] {
                s += self.c_vals[e] * scratch[self.c_cols[e] as usize];
            }
            *o = s;
        }
        if model.boundary.has_loads() {
            rate.fill(0.0);
            model
                .boundary
                .add_loads(&model.cloud, &model.capacity, scratch, t, rate);
            for (r, o) in out.iter_mut().enumerate() {
                *o += self.mass[r] * rate[self.free[r]];
            }
        }
    }
}
