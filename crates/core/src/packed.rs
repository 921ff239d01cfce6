//! K's column index packed into bytes, for the explicit step on clouds whose rows do not repeat
//! (gmsh meshes).
//!
//! A row of K lists its neighbours in ascending order, and a cloud in space-filling-curve order
//! puts most of them in short runs of consecutive indices: on the 10⁶-triangle square 94 % of
//! the gaps between consecutive columns are below 16, 99.4 % below 256 and 99.9 % below 65 536.
//! So a row keeps its first column (u32) and its count (u16), and then the gaps to the previous
//! column in the narrowest of three widths that holds all of them: one byte (54 % of that
//! mesh's rows), two bytes (43 %), or the u32 columns themselves (a wider gap, or a row that is
//! not sorted). A row is decoded as a running sum, without a test per entry. Each task of
//! [`ROW_CHUNK`] rows knows where it starts in K's entries and in the three lists. The step
//! then streams about 1.7 B per bond for the column instead of 4, and no row offsets. The sums
//! take the entries in the same order with the same partial sums as
//! [`crate::operator::row_sum`]: the same bits as the CSR rows.

use crate::math::NodeId;
use crate::operator::{Conductance, ROW_CHUNK};
use rayon::prelude::*;
use std::ops::Range;

/// Width of a row's gaps, in the two top bits of its count.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Width {
    /// Every gap in 1..=255: one byte each.
    U8 = 0,
    /// Every gap in 1..=65 535: two bytes each.
    U16 = 1,
    /// The columns themselves.
    U32 = 2,
}

/// Bits of a row's count below its width.
const COUNT_BITS: u32 = 14;

/// The column index of the rows `rows` of a [`Conductance`], packed (module doc).
#[derive(Debug, Clone, Default)]
pub struct PackedColumns {
    /// The body rows packed.
    rows: Range<usize>,
    /// First column of each row (0 for an empty row).
    first: Vec<NodeId>,
    /// Entries of each row, with its [`Width`] in the top two bits.
    counts: Vec<u16>,
    /// One-byte gaps of the rows of that width (after each row's first column).
    gaps8: Vec<u8>,
    /// Two-byte gaps of the rows of that width.
    gaps16: Vec<u16>,
    /// The columns (after the first) of the other rows.
    wide: Vec<NodeId>,
    /// Where each task of [`ROW_CHUNK`] rows starts: its entry of K, and its item of `gaps8`,
    /// `gaps16` and `wide`.
    starts: Vec<[usize; 4]>,
}

/// What a row stores for a column after its first: a gap, or the column itself.
trait Step: Copy {
    /// The column after `prev`.
    fn after(self, prev: u32) -> u32;
}

impl Step for u8 {
    #[inline(always)]
    fn after(self, prev: u32) -> u32 {
        prev.wrapping_add(self as u32)
    }
}

impl Step for u16 {
    #[inline(always)]
    fn after(self, prev: u32) -> u32 {
        prev.wrapping_add(self as u32)
    }
}

/// A wide row stores the column itself.
impl Step for u32 {
    #[inline(always)]
    fn after(self, _prev: u32) -> u32 {
        self
    }
}

/// The narrowest width that holds every gap of `cols` (sorted or not).
fn width(cols: &[NodeId]) -> Width {
    let mut w = Width::U8;
    for p in cols.windows(2) {
        match p[1].checked_sub(p[0]) {
            Some(1..=255) => {}
            Some(1..=65_535) => w = Width::U16,
            _ => return Width::U32,
        }
    }
    w
}

/// Σ_k v_k (θ\[c_k\] − θ_i) over a row whose first column is `c` and whose other columns
/// follow by `steps`: [`crate::operator::row_sum`]'s partial sums in its order (the same bits),
/// W.
#[inline(always)]
fn row_sum_steps<S: Step, V: Copy + Into<f64>>(
    (c, steps): (u32, &[S]),
    vals: &[V],
    theta: &[f64],
    ti: f64,
) -> f64 {
    let Some((&v0, vals)) = vals.split_first() else {
        return 0.0;
    };
    let n = steps.len().min(vals.len());
    let (steps, vals) = (&steps[..n], &vals[..n]);
    let t = |c: u32| theta[c as usize] - ti;
    // entry 0 is the first column; entries 4q + r go to a[r], the rest to a[0], as in row_sum
    let mut a = [0.0f64; 4];
    a[0] += v0.into() * t(c);
    if n < 3 {
        let mut c = c;
        for (&s, &v) in steps.iter().zip(vals) {
            c = s.after(c);
            a[0] += v.into() * t(c);
        }
        return (a[0] + a[1]) + (a[2] + a[3]);
    }
    let c1 = steps[0].after(c);
    let c2 = steps[1].after(c1);
    let mut c = steps[2].after(c2);
    a[1] += vals[0].into() * t(c1);
    a[2] += vals[1].into() * t(c2);
    a[3] += vals[2].into() * t(c);
    let full = (n + 1) - (n + 1) % 4; // entries in whole groups of four
    let mut sc = steps[3..full - 1].chunks_exact(4);
    let mut vc = vals[3..full - 1].chunks_exact(4);
    for (s, v) in (&mut sc).zip(&mut vc) {
        let c0 = s[0].after(c);
        let c1 = s[1].after(c0);
        let c2 = s[2].after(c1);
        c = s[3].after(c2);
        a[0] += v[0].into() * t(c0);
        a[1] += v[1].into() * t(c1);
        a[2] += v[2].into() * t(c2);
        a[3] += v[3].into() * t(c);
    }
    for (&s, &v) in steps[full - 1..].iter().zip(&vals[full - 1..]) {
        c = s.after(c);
        a[0] += v.into() * t(c);
    }
    (a[0] + a[1]) + (a[2] + a[3])
}

/// The packed rows of one task.
#[derive(Default)]
struct Part {
    first: Vec<NodeId>,
    counts: Vec<u16>,
    gaps8: Vec<u8>,
    gaps16: Vec<u16>,
    wide: Vec<NodeId>,
}

impl Part {
    /// Appends one row; None when it has 2¹⁴ entries or more.
    fn push(&mut self, cols: &[NodeId]) -> Option<()> {
        let n = u16::try_from(cols.len())
            .ok()
            .filter(|&n| n >> COUNT_BITS == 0)?;
        let w = width(cols);
        self.counts.push(n | (w as u16) << COUNT_BITS);
        self.first.push(cols.first().copied().unwrap_or(0));
        let pairs = cols.windows(2);
        match w {
            Width::U8 => self.gaps8.extend(pairs.map(|p| (p[1] - p[0]) as u8)),
            Width::U16 => self.gaps16.extend(pairs.map(|p| (p[1] - p[0]) as u16)),
            Width::U32 => self.wide.extend_from_slice(cols.get(1..).unwrap_or(&[])),
        }
        Some(())
    }
}

impl PackedColumns {
    /// Packs the columns of the body rows `rows` of `k` (in parallel, task by task); None when
    /// a row has 2¹⁴ entries or more.
    pub fn build(k: &Conductance, rows: Range<usize>) -> Option<PackedColumns> {
        let tasks: Vec<Range<usize>> = rows
            .clone()
            .step_by(ROW_CHUNK)
            .map(|r| r..(r + ROW_CHUNK).min(rows.end))
            .collect();
        let parts: Vec<Part> = tasks
            .par_iter()
            .map(|t| {
                let mut part = Part::default();
                for i in t.clone() {
                    part.push(&k.cols[k.offsets[i]..k.offsets[i + 1]])?;
                }
                Some(part)
            })
            .collect::<Option<_>>()?;
        let total = |f: fn(&Part) -> usize| parts.iter().map(f).sum::<usize>();
        let mut p = PackedColumns {
            rows: rows.clone(),
            first: Vec::with_capacity(rows.len()),
            counts: Vec::with_capacity(rows.len()),
            gaps8: Vec::with_capacity(total(|p| p.gaps8.len())),
            gaps16: Vec::with_capacity(total(|p| p.gaps16.len())),
            wide: Vec::with_capacity(total(|p| p.wide.len())),
            starts: Vec::with_capacity(tasks.len()),
        };
        for (t, part) in tasks.iter().zip(parts) {
            let at = [p.gaps8.len(), p.gaps16.len(), p.wide.len()];
            p.starts.push([k.offsets[t.start], at[0], at[1], at[2]]);
            p.first.extend(part.first);
            p.counts.extend(part.counts);
            p.gaps8.extend(part.gaps8);
            p.gaps16.extend(part.gaps16);
            p.wide.extend(part.wide);
        }
        Some(p)
    }

    /// The body rows packed.
    pub fn rows(&self) -> Range<usize> {
        self.rows.clone()
    }

    /// Bytes held, B.
    pub fn bytes(&self) -> usize {
        self.first.capacity() * 4
            + self.counts.capacity() * 2
            + self.gaps8.capacity()
            + self.gaps16.capacity() * 2
            + self.wide.capacity() * 4
            + self.starts.capacity() * 32
    }

    /// Calls `f(i, Σ_j K_ij (θ_j − θ_i), θ_i, out_i)` (sum in W) for every row `i` packed, with
    /// K_ij from `vals` (indexed as K's entries), in parallel tasks of [`ROW_CHUNK`] rows (`out`
    /// holds the rows packed).
    #[inline(always)]
    pub fn gather<V: Copy + Into<f64> + Sync>(
        &self,
        vals: &[V],
        theta: &[f64],
        out: &mut [f64],
        f: impl Fn(usize, f64, f64, &mut f64) + Sync,
    ) {
        out.par_chunks_mut(ROW_CHUNK)
            .zip(self.counts.par_chunks(ROW_CHUNK))
            .zip(self.first.par_chunks(ROW_CHUNK))
            .zip(&self.starts)
            .enumerate()
            .for_each(|(c, (((o, counts), first), &at))| {
                let [mut e, mut x8, mut x16, mut x32] = at;
                let start = self.rows.start + c * ROW_CHUNK;
                for (r, ((o, &nw), &c0)) in o.iter_mut().zip(counts).zip(first).enumerate() {
                    let i = start + r;
                    let ti = theta[i];
                    let n = (nw & ((1 << COUNT_BITS) - 1)) as usize;
                    let v = &vals[e..e + n];
                    let rest = n.saturating_sub(1);
                    let s = match nw >> COUNT_BITS {
                        0 => {
                            x8 += rest;
                            row_sum_steps((c0, &self.gaps8[x8 - rest..x8]), v, theta, ti)
                        }
                        1 => {
                            x16 += rest;
                            row_sum_steps((c0, &self.gaps16[x16 - rest..x16]), v, theta, ti)
                        }
                        _ => {
                            x32 += rest;
                            row_sum_steps((c0, &self.wide[x32 - rest..x32]), v, theta, ti)
                        }
                    };
                    e += n;
                    f(i, s, ti, o);
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::operator::row_sum;

    /// A K with rows of every kind: empty, of 1 to 9 entries and of 300, unsorted, of each
    /// width (gaps of 1, 255, 256 and beyond 65 535), first columns far from the previous row's.
    fn awkward() -> Conductance {
        let rows: Vec<Vec<NodeId>> = vec![
            vec![],
            vec![5, 6, 7, 262, 263, 519, 100_000],
            vec![3],
            (0..300).map(|j| 2 * j).collect(),
            vec![9, 4, 200_000, 1],
            vec![700_000, 700_001],
            vec![1, 2, 3, 4, 5],
            vec![10, 11, 12],
            vec![20, 320, 321, 1000, 1001, 1002, 1003, 1004, 60_000],
            (40..48).collect(),
        ];
        let mut k = Conductance {
            offsets: vec![0],
            ..Default::default()
        };
        for r in rows.iter().cycle().take(3 * ROW_CHUNK + 18) {
            k.cols.extend_from_slice(r);
            k.offsets.push(k.cols.len());
        }
        k.vals = (0..k.cols.len())
            .map(|e| 1.0 + (e as f64 * 0.37).sin())
            .collect();
        k
    }

    #[test]
    fn packed_sums_are_the_csr_sums_bit_for_bit() {
        let k = awkward();
        let n = k.offsets.len() - 1;
        let theta: Vec<f64> = (0..=700_001).map(|j| (j as f64 * 1e-3).cos()).collect();
        for rows in [0..n, 5..n - 3, ROW_CHUNK + 1..2 * ROW_CHUNK + 7] {
            let packed = PackedColumns::build(&k, rows.clone()).unwrap();
            let mut out = vec![f64::NAN; rows.len()];
            packed.gather(&k.vals, &theta, &mut out, |i, s, ti, o| {
                assert_eq!(ti.to_bits(), theta[i].to_bits());
                *o = s;
            });
            for (i, got) in rows.clone().zip(&out) {
                let e = k.offsets[i]..k.offsets[i + 1];
                let want = row_sum(&k.cols[e.clone()], &k.vals[e], &theta, theta[i]);
                assert_eq!(got.to_bits(), want.to_bits(), "row {i}");
            }
        }
    }

    #[test]
    fn gaps_of_one_byte_take_one_byte() {
        // 2048 rows of 36 sorted neighbours with gaps of 1 or 2: 1 B per further column
        let mut k = Conductance {
            offsets: vec![0],
            ..Default::default()
        };
        for i in 0..ROW_CHUNK as u32 {
            k.cols.extend((0..36).map(|j| i + j + j / 3));
            k.offsets.push(k.cols.len());
        }
        let p = PackedColumns::build(&k, 0..ROW_CHUNK).unwrap();
        assert_eq!(
            (p.gaps8.len(), p.gaps16.len(), p.wide.len()),
            (ROW_CHUNK * 35, 0, 0)
        );
        assert!(p.counts.iter().all(|&n| n == 36));
    }
}
