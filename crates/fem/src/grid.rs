//! Structured meshes of the built-in box geometry: bars of 2-node lines (1D), bilinear
//! quadrangles (2D) and trilinear hexahedra (3D).
//!
//! The grid is a tensor product. Along each axis the breakpoints are the domain's ends, every
//! region's ends and the ends and lines of axis-aligned crack segments; each interval between
//! breakpoints is divided into the fewest equal cells no longer than `h`, so region interfaces
//! and cracks lie on grid lines by construction.

use crate::mesh::{Cell, FemMesh};
use crate::shape::MAX_NODES;
use peritherm_core::cloud::BoxGeometry;
use peritherm_core::error::{Error, Result};
use peritherm_core::math::{Point, GEOMETRIC_TOLERANCE};
use peritherm_core::mesh::ElementKind;
use peritherm_core::model::{Crack, CrackShape};

/// Grid lines along one axis from `[lo, hi]` with breakpoints `cuts`, cells no longer than `h`, m.
fn axis_lines(lo: f64, hi: f64, cuts: &[f64], h: f64, eps: f64) -> Vec<f64> {
    let mut b: Vec<f64> = cuts
        .iter()
        .copied()
        .filter(|&c| c > lo + eps && c < hi - eps)
        .chain([lo, hi])
        .collect();
    b.sort_by(f64::total_cmp);
    b.dedup_by(|a, c| (*a - *c).abs() <= eps);
    let mut lines = vec![lo];
    for w in b.windows(2) {
        let n = ((w[1] - w[0]) / h - 1e-9).ceil().max(1.0) as usize;
        for k in 1..=n {
            lines.push(if k == n {
                w[1]
            } else {
                w[0] + (w[1] - w[0]) * k as f64 / n as f64
            });
        }
    }
    lines
}

/// Breakpoints that the 2D polyline cracks add on each axis; an inclined segment is an error.
fn crack_cuts(g: &BoxGeometry, cracks: &[Crack], eps: f64) -> Result<[Vec<f64>; 3]> {
    let mut cuts: [Vec<f64>; 3] = Default::default();
    for (k, c) in cracks.iter().enumerate() {
        let CrackShape::Polyline(pts) = &c.shape else {
            return Err(Error::model(
                format!("crack[{k}]"),
                "fem: only polyline cracks (2D `points`) are supported on the built-in box geometry; mesh a 3D crack as a physical surface in gmsh",
            ));
        };
        for w in pts.windows(2) {
            let (a, b) = (w[0], w[1]);
            let axis = if (a.y - b.y).abs() <= eps {
                0
            } else if (a.x - b.x).abs() <= eps {
                1
            } else {
                return Err(Error::model(
                    format!("crack[{k}].points"),
                    format!(
                        "fem: the segment ({}, {}) – ({}, {}) is inclined; the structured grid of a box case represents cracks along x or y lines only: mesh it in gmsh as a physical curve",
                        a.x, a.y, b.x, b.y
                    ),
                ));
            };
            let other = 1 - axis;
            cuts[other].push(a[other]);
            cuts[axis].push(a[axis].clamp(g.min[axis], g.max[axis]));
            cuts[axis].push(b[axis].clamp(g.min[axis], g.max[axis]));
        }
    }
    Ok(cuts)
}

/// The structured mesh of `g` with cells no longer than `h` (m) whose lines carry every
/// region boundary and every crack segment.
pub fn box_mesh(g: &BoxGeometry, h: f64, cracks: &[Crack]) -> Result<FemMesh> {
    g.validate()?;
    let dim = g.dim;
    let scale = (0..dim).map(|a| g.max[a] - g.min[a]).fold(0.0, f64::max);
    let eps = GEOMETRIC_TOLERANCE * scale;
    if !(h.is_finite() && h > 0.0) {
        return Err(Error::model(
            "h",
            format!("fem: must be a positive size, got {h}"),
        ));
    }
    let cuts = if dim == 2 {
        crack_cuts(g, cracks, eps)?
    } else if cracks.is_empty() {
        Default::default()
    } else {
        return Err(Error::model(
            "crack[0]",
            format!(
                "fem: cracks on a {dim}D box are not supported; use a gmsh mesh with a crack group"
            ),
        ));
    };
    let lines: Vec<Vec<f64>> = (0..3)
        .map(|a| {
            if a >= dim {
                return vec![0.0];
            }
            let mut c: Vec<f64> = g
                .regions
                .iter()
                .flat_map(|r| [r.min[a], r.max[a]])
                .collect();
            c.extend(&cuts[a]);
            axis_lines(g.min[a], g.max[a], &c, h, eps)
        })
        .collect();
    let grid = Grid {
        dim,
        count: [lines[0].len(), lines[1].len(), lines[2].len()],
    };
    if grid.count.iter().product::<usize>() > u32::MAX as usize / 2 {
        return Err(Error::model(
            "h",
            "fem: too many grid nodes; use a larger --h",
        ));
    }
    let mut nodes = Vec::with_capacity(grid.count.iter().product());
    for &z in &lines[2] {
        for &y in &lines[1] {
            for &x in &lines[0] {
                nodes.push(Point::new(x, y, z));
            }
        }
    }
    let mut m = FemMesh {
        dim,
        tau: g.tau,
        nodes,
        cells: grid_cells(g, &grid, &lines)?,
        sets: vec![Vec::new(); 6],
        symmetry: peritherm_core::symmetry::Symmetry::Planar,
    };
    face_sets(&mut m, g, eps);
    Ok(m)
}

/// The node counts of a tensor-product grid along x, y, z (1 along unused axes).
struct Grid {
    dim: usize,
    count: [usize; 3],
}

impl Grid {
    /// Cells along axis `a` (1 along unused axes).
    fn cells_per(&self, a: usize) -> usize {
        if a < self.dim {
            self.count[a] - 1
        } else {
            1
        }
    }

    /// Index of the node (i, j, k), x fastest.
    fn id(&self, i: usize, j: usize, k: usize) -> u32 {
        (i + self.count[0] * (j + self.count[1] * k)) as u32
    }

    /// The nodes of the cell (i, j, k) in the element's order (line, quad or hex).
    fn cell_nodes(&self, i: usize, j: usize, k: usize) -> [u32; MAX_NODES] {
        let id = |i, j, k| self.id(i, j, k);
        let mut n = [0u32; MAX_NODES];
        match self.dim {
            1 => n[..2].copy_from_slice(&[id(i, 0, 0), id(i + 1, 0, 0)]),
            2 => n[..4].copy_from_slice(&[
                id(i, j, 0),
                id(i + 1, j, 0),
                id(i + 1, j + 1, 0),
                id(i, j + 1, 0),
            ]),
            _ => {
                n = [
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ]
            }
        }
        n
    }
}

/// The cells of the grid with grid lines `lines`, each in the region that holds its centre.
fn grid_cells(g: &BoxGeometry, grid: &Grid, lines: &[Vec<f64>]) -> Result<Vec<Cell>> {
    let (dim, count) = (grid.dim, grid.count);
    let kind = match dim {
        1 => ElementKind::Line,
        2 => ElementKind::Quad,
        _ => ElementKind::Hex,
    };
    let mut cells = Vec::with_capacity(grid.cells_per(0) * grid.cells_per(1) * grid.cells_per(2));
    for k in 0..grid.cells_per(2) {
        for j in 0..grid.cells_per(1) {
            for i in 0..grid.cells_per(0) {
                let centre = [
                    0.5 * (lines[0][i] + lines[0][(i + 1).min(count[0] - 1)]),
                    0.5 * (lines[1][j] + lines[1][(j + 1).min(count[1] - 1)]),
                    0.5 * (lines[2][k] + lines[2][(k + 1).min(count[2] - 1)]),
                ];
                let r = g
                    .regions
                    .iter()
                    .position(|r| (0..dim).all(|a| centre[a] >= r.min[a] && centre[a] <= r.max[a]))
                    .ok_or_else(|| Error::model("region", "fem: a grid cell lies in no region"))?;
                cells.push(Cell {
                    kind,
                    nodes: grid.cell_nodes(i, j, k),
                    region: r as u16,
                    material: g.regions[r].material,
                });
            }
        }
    }
    Ok(cells)
}

/// Fills the six face sets of `m`: the boundary facets (facets of one cell only), each in
/// the set of the box face plane it lies on.
fn face_sets(m: &mut FemMesh, g: &BoxGeometry, eps: f64) {
    let map = m.facet_map();
    let mut boundary: Vec<_> = map
        .values()
        .filter(|v| v.len() == 1)
        .map(|v| v[0])
        .collect();
    boundary.sort_unstable();
    for f in boundary {
        let pts: Vec<Point> = m.facet_nodes(f).map(|n| m.nodes[n as usize]).collect();
        for face in 0..2 * m.dim {
            let (a, plane) = (
                face / 2,
                if face % 2 == 0 {
                    g.min[face / 2]
                } else {
                    g.max[face / 2]
                },
            );
            if pts.iter().all(|p| (p[a] - plane).abs() <= eps) {
                m.sets[face].push(f);
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use peritherm_core::cloud::{BoxRegion, HorizonRule};

    fn region(name: &str, min: [f64; 3], max: [f64; 3], cells: [usize; 3]) -> BoxRegion {
        BoxRegion {
            name: name.into(),
            min,
            max,
            cells,
            horizon: HorizonRule::Factor(3.0),
            material: 0,
        }
    }

    /// Region boundaries and a crack that h does not divide still fall on grid lines, cells
    /// stay no longer than h, and every face gets its boundary facets (tolerance: round-off).
    #[test]
    fn interfaces_and_cracks_lie_on_grid_lines() {
        let g = BoxGeometry {
            dim: 2,
            tau: 1.0,
            min: [0.0, 0.0, 0.0],
            max: [1.0, 1.0, 0.0],
            boundary_placement: false,
            regions: vec![
                region("a", [0.0, 0.0, 0.0], [0.3, 1.0, 0.0], [3, 10, 1]),
                region("b", [0.3, 0.0, 0.0], [1.0, 1.0, 0.0], [7, 10, 1]),
            ],
        };
        let crack = Crack {
            shape: CrackShape::Polyline(vec![
                Point::new(0.1, 0.37, 0.0),
                Point::new(0.9, 0.37, 0.0),
            ]),
            mu: 0.0,
            growth: None,
        };
        let m = box_mesh(&g, 0.25, &[crack]).unwrap();
        for x in [0.1, 0.3, 0.9] {
            assert!(
                m.nodes.iter().any(|p| (p.x - x).abs() < 1e-12),
                "no line x = {x}"
            );
        }
        assert!(m.nodes.iter().any(|p| (p.y - 0.37).abs() < 1e-12));
        for c in &m.cells {
            let p = m.corners(c);
            assert!(p[2].x - p[0].x <= 0.25 + 1e-12 && p[2].y - p[0].y <= 0.25 + 1e-12);
            let cx = 0.25 * (p[0].x + p[1].x + p[2].x + p[3].x);
            assert_eq!(c.region, u16::from(cx > 0.3));
        }
        for face in 0..4 {
            let length: f64 = m.sets[face]
                .iter()
                .map(|&f| {
                    let n: Vec<u32> = m.facet_nodes(f).collect();
                    (m.nodes[n[0] as usize] - m.nodes[n[1] as usize]).norm()
                })
                .sum();
            assert!((length - 1.0).abs() < 1e-12, "face {face}: {length}");
        }
    }
}
