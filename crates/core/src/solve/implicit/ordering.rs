//! Fill-reducing orderings of the sparse Cholesky factorisation.

use super::System;
use crate::model::Model;

/// Fill-reducing ordering of the sparse Cholesky factorisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ordering {
    /// Geometric nested dissection on the node positions ([`nested_dissection`]).
    NestedDissection,
    /// faer's approximate minimum degree.
    Amd,
}

/// Elimination order by geometric nested dissection (George 1973): split the unknowns at the
/// median of the longer axis of their bounding box, order each half recursively and the
/// separator (the second half's nodes bonded to the first half) last. On 2D lattices with
/// wide horizons this gives less fill than minimum degree. Returns (new → old, old → new).
pub fn nested_dissection(sys: &System, model: &Model) -> (Vec<usize>, Vec<usize>) {
    let n = sys.len();
    let pos: Vec<[f64; 3]> = sys
        .free
        .iter()
        .map(|&i| {
            let p = model.cloud.pos[i];
            [p.x, p.y, p.z]
        })
        .collect();
    let mut stamp = vec![0u64; n];
    let mut next = 1u64;
    let mut order = Vec::with_capacity(n);
    let mut nodes: Vec<usize> = (0..n).collect();
    // explicit stack: (nodes, separator to emit after both halves)
    enum Job {
        Split(Vec<usize>),
        Emit(Vec<usize>),
    }
    let mut jobs = vec![Job::Split(std::mem::take(&mut nodes))];
    while let Some(job) = jobs.pop() {
        let mut set = match job {
            Job::Emit(sep) => {
                order.extend(sep);
                continue;
            }
            Job::Split(set) => set,
        };
        if set.len() <= 128 {
            order.extend(set);
            continue;
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &k in &set {
            for a in 0..3 {
                lo[a] = lo[a].min(pos[k][a]);
                hi[a] = hi[a].max(pos[k][a]);
            }
        }
        let axis = (0..3)
            .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
            .unwrap_or(0);
        let mid = set.len() / 2;
        set.select_nth_unstable_by(mid, |&a, &b| pos[a][axis].total_cmp(&pos[b][axis]));
        let (first, second) = (next, next + 1);
        next += 2;
        for &k in &set[..mid] {
            stamp[k] = first;
        }
        for &k in &set[mid..] {
            stamp[k] = second;
        }
        let (mut b, mut sep) = (Vec::new(), Vec::new());
        for &k in &set[mid..] {
            let touches = sys.cols[sys.offsets[k]..sys.offsets[k + 1]]
                .iter()
                .any(|&c| stamp[c] == first);
            if touches {
                sep.push(k);
            } else {
                b.push(k);
            }
        }
        set.truncate(mid);
        jobs.push(Job::Emit(sep));
        jobs.push(Job::Split(b));
        jobs.push(Job::Split(set));
    }
    let mut inverse = vec![0usize; n];
    for (new, &old) in order.iter().enumerate() {
        inverse[old] = new;
    }
    (order, inverse)
}
