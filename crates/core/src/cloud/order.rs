//! Space-filling-curve (Morton, Z-order) ordering of nodes, so that nodes close in space are
//! close in memory and a row's neighbours share cache lines.

use crate::math::Point;

/// Spreads the low 21 bits of `v` so that two zero bits separate consecutive bits.
fn spread3(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x1f00000000ffff;
    x = (x | (x << 16)) & 0x1f0000ff0000ff;
    x = (x | (x << 8)) & 0x100f00f00f00f00f;
    x = (x | (x << 4)) & 0x10c30c30c30c30c3;
    (x | (x << 2)) & 0x1249249249249249
}

/// Morton code of a point quantised to 21 bits per axis inside the box `lo..hi`.
fn morton(p: &Point, lo: &Point, scale: f64) -> u64 {
    let q = |a: usize| (((p[a] - lo[a]) * scale).clamp(0.0, 2_097_151.0)) as u64;
    spread3(q(0)) | (spread3(q(1)) << 1) | (spread3(q(2)) << 2)
}

/// Permutation that sorts `points` along the Morton curve: `perm[new] = old` (stable for ties).
pub fn morton_order(points: &[Point]) -> Vec<usize> {
    if points.is_empty() {
        return Vec::new();
    }
    let mut lo = points[0];
    let mut hi = points[0];
    for p in points {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    let scale = if extent > 0.0 {
        2_097_151.0 / extent
    } else {
        0.0
    };
    let mut keyed: Vec<(u64, usize)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| (morton(p, &lo, scale), i))
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Z-order of a 2 × 2 grid is (0,0), (1,0), (0,1), (1,1); the result is a permutation.
    #[test]
    fn z_order_of_a_small_grid() {
        let pts = [
            Point::new(1.0, 1.0, 0.0),
            Point::new(0.0, 1.0, 0.0),
            Point::new(1.0, 0.0, 0.0),
            Point::new(0.0, 0.0, 0.0),
        ];
        assert_eq!(morton_order(&pts), vec![3, 2, 1, 0]);
        let many: Vec<Point> = (0..1000)
            .map(|i| Point::new((i * 37 % 101) as f64, (i * 53 % 97) as f64, 0.0))
            .collect();
        let mut perm = morton_order(&many);
        perm.sort_unstable();
        assert_eq!(perm, (0..1000).collect::<Vec<_>>());
    }
}
