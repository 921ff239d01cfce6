//! Reuse of corrected weights: the content key of a correction problem and the interface of a
//! store that keeps solved corrections (the files of `peritherm_io::weights_cache`).
//!
//! The key is a BLAKE3 hash of everything [`super::correct`] reads: the conductances K (CSR
//! structure and value bits), the positions, horizons and volumes of every node a row reaches,
//! which nodes are selected, their conductivities, the order, the tolerance and the version of
//! the algorithm. Mesh content, regions, horizons, kernel settings, cracks and boundary layers
//! all reach the correction through these arrays, so two problems with one key have the same
//! weights bit for bit, and a change of any input gives another key: a stale entry cannot be
//! found. Hashing reads each input once: O(bonds), a few tenths of a second at 10⁶ nodes.

use super::{Consistency, Order, TOLERANCE};
use crate::cloud::Cloud;
use crate::math::Real;
use crate::operator::Conductance;

/// Changes whenever the correction would give other weights for the same inputs.
const ALGORITHM: &[u8] = b"peritherm consistent weights: entropy dual, Newton, v1";

/// Content key of one correction problem (a BLAKE3 hash of its inputs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Key(pub [u8; 32]);

impl Key {
    /// The key as 64 lower-case hexadecimal digits.
    pub fn hex(&self) -> String {
        self.0.iter().map(|b| format!("{b:02x}")).collect()
    }
}

/// A solved correction: the corrected pair conductances and what was achieved.
#[derive(Debug, Clone, PartialEq)]
pub struct Solved {
    /// K' per CSR entry of K, W/K.
    pub vals: Vec<Real>,
    /// Body nodes whose moments the correction met.
    pub met: Vec<bool>,
    /// The summary of the correction as computed.
    pub summary: Consistency,
}

/// A solved correction as borrowed slices (what [`Store::save`] writes, without a copy).
#[derive(Debug, Clone, Copy)]
pub struct SolvedRef<'a> {
    /// K' per CSR entry of K, W/K.
    pub vals: &'a [Real],
    /// Body nodes whose moments the correction met.
    pub met: &'a [bool],
    /// The summary of the correction as computed.
    pub summary: &'a Consistency,
}

impl Solved {
    /// The correction as borrowed slices.
    pub fn view(&self) -> SolvedRef<'_> {
        SolvedRef {
            vals: &self.vals,
            met: &self.met,
            summary: &self.summary,
        }
    }
}

/// Where solved corrections are kept between runs.
pub trait Store: Sync {
    /// The correction stored under `key`, if there is an intact one with `entries` values and
    /// `nodes` flags; anything else (absent, truncated, corrupt) is None.
    fn load(&self, key: &Key, entries: usize, nodes: usize) -> Option<Solved>;
    /// Keeps `solved` under `key` (a store that cannot write says nothing: reuse is an
    /// optimisation, never a condition of a run).
    fn save(&self, key: &Key, solved: SolvedRef);
}

/// Feeds a slice of plain numbers to the hasher as little-endian bytes, with its length.
fn feed<T: Copy, const B: usize>(h: &mut blake3::Hasher, xs: &[T], bytes: impl Fn(T) -> [u8; B]) {
    h.update(&(xs.len() as u64).to_le_bytes());
    let mut buf = Vec::with_capacity(B * 4096);
    for chunk in xs.chunks(4096) {
        buf.clear();
        for &x in chunk {
            buf.extend_from_slice(&bytes(x));
        }
        h.update(&buf);
    }
}

/// The key of correcting `k` on `cloud` at the nodes `sel` with the conductivities
/// `conductivity` (W/(m·K)) to `order`.
pub fn key(
    k: &Conductance,
    cloud: &Cloud,
    sel: &[bool],
    conductivity: &[Real],
    order: Order,
) -> Key {
    let mut h = blake3::Hasher::new();
    h.update(ALGORITHM);
    h.update(&TOLERANCE.to_le_bytes());
    h.update(&[order as u8, cloud.dim as u8]);
    let n = k.n_rows();
    feed(&mut h, &k.offsets, |x| (x as u64).to_le_bytes());
    feed(&mut h, &k.cols, u32::to_le_bytes);
    feed(&mut h, &k.vals, Real::to_le_bytes);
    // every node a row reaches: the body and the layers beyond it
    let reach = k
        .cols
        .iter()
        .map(|&c| c as usize + 1)
        .max()
        .unwrap_or(0)
        .max(n);
    let reach = reach.min(cloud.pos.len());
    feed(&mut h, &cloud.pos[..reach], |p| {
        let mut b = [0u8; 24];
        for (c, x) in b.chunks_exact_mut(8).zip([p.x, p.y, p.z]) {
            c.copy_from_slice(&x.to_le_bytes());
        }
        b
    });
    feed(
        &mut h,
        &cloud.horizon[..reach.min(cloud.horizon.len())],
        Real::to_le_bytes,
    );
    feed(
        &mut h,
        &cloud.volume[..reach.min(cloud.volume.len())],
        Real::to_le_bytes,
    );
    feed(&mut h, &sel[..n.min(sel.len())], |s| [s as u8]);
    feed(
        &mut h,
        &conductivity[..n.min(conductivity.len())],
        Real::to_le_bytes,
    );
    Key(*h.finalize().as_bytes())
}
