//! Insulated cracks as duplicated nodes: the mesh is split along the crack facets so that the
//! cells on either side no longer share the nodes of the crack's interior.
//!
//! For every node on a crack, the cells around it are grouped into sides: two cells are on
//! the same side when they share a facet through the node that is not a crack facet. Each
//! side past the first gets its own copy of the node. A tip inside the body has one side (the
//! cells connect around it) and stays shared; a node inside the crack, or where the crack
//! meets the boundary, has two and is duplicated.

use crate::mesh::{key_of, FacetKey, FemMesh};
use crate::shape::facets;
use peritherm_core::error::{Error, Result};
use peritherm_core::math::{Point, GEOMETRIC_TOLERANCE};
use peritherm_core::model::{Crack, CrackShape};
use std::collections::{HashMap, HashSet};

fn on_segment(p: &Point, a: &Point, b: &Point, eps: f64) -> bool {
    let ab = b - a;
    let len2 = ab.norm_squared();
    if len2 == 0.0 {
        return (p - a).norm() <= eps;
    }
    let s = ((p - a).dot(&ab) / len2).clamp(0.0, 1.0);
    (p - (a + ab * s)).norm() <= eps
}

/// The interior facets lying on crack `k`, and whether they cover it: the facets' total length
/// must equal the length of the polyline inside the mesh's bounding box.
fn polyline_facets(
    mesh: &FemMesh,
    map: &HashMap<FacetKey, Vec<(u32, u8)>>,
    k: usize,
    pts: &[Point],
) -> Result<Vec<FacetKey>> {
    let (lo, hi) = bounds(mesh);
    let eps = GEOMETRIC_TOLERANCE * (hi - lo).norm();
    let mut out = Vec::new();
    let mut covered = 0.0;
    for (key, refs) in map {
        if refs.len() != 2 || key[1] == u32::MAX || key[2] != u32::MAX {
            continue; // boundary facets, or not a segment
        }
        let (p, q) = (mesh.nodes[key[0] as usize], mesh.nodes[key[1] as usize]);
        if pts
            .windows(2)
            .any(|w| on_segment(&p, &w[0], &w[1], eps) && on_segment(&q, &w[0], &w[1], eps))
        {
            out.push(*key);
            covered += (q - p).norm();
        }
    }
    let inside: f64 = pts
        .windows(2)
        .map(|w| clipped_length(&w[0], &w[1], &lo, &hi))
        .sum();
    if (covered - inside).abs() > 1e-6 * inside.max(eps) {
        return Err(Error::model(
            format!("crack[{k}].points"),
            format!(
                "fem: only {covered:e} m of the crack's {inside:e} m lies along mesh edges; a crack must follow element edges (an inclined crack on the structured grid, or a polyline across a gmsh mesh, cannot be represented: make it a physical curve of the mesh)"
            ),
        ));
    }
    out.sort_unstable();
    Ok(out)
}

fn bounds(mesh: &FemMesh) -> (Point, Point) {
    let mut lo = Point::new(f64::MAX, f64::MAX, f64::MAX);
    let mut hi = Point::new(f64::MIN, f64::MIN, f64::MIN);
    for p in &mesh.nodes {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (lo, hi)
}

/// Length of segment a–b inside the box [lo, hi] (Liang–Barsky clipping), m.
fn clipped_length(a: &Point, b: &Point, lo: &Point, hi: &Point) -> f64 {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for ax in 0..3 {
        if d[ax] == 0.0 {
            if a[ax] < lo[ax] || a[ax] > hi[ax] {
                return 0.0;
            }
            continue;
        }
        let (u, v) = ((lo[ax] - a[ax]) / d[ax], (hi[ax] - a[ax]) / d[ax]);
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
    }
    (t1 - t0).max(0.0) * d.norm()
}

/// Checks that every crack is one the FEM solver represents: standing and insulated.
pub fn check_cracks(cracks: &[Crack]) -> Result<()> {
    for (k, c) in cracks.iter().enumerate() {
        if c.growth.is_some() {
            return Err(Error::model(
                format!("crack[{k}].speed"),
                "fem: growing cracks are not supported (the FEM reference splits the mesh once, before the run)",
            ));
        }
        if c.mu != 0.0 {
            return Err(Error::model(
                format!("crack[{k}].conductance"),
                format!("fem: partially conducting cracks are not supported (conductance = {}); only insulated cracks (0)", c.mu),
            ));
        }
    }
    Ok(())
}

/// Facet keys of every crack (see [`check_cracks`] first); an error when a polyline crack
/// does not follow element facets.
pub fn crack_facets(mesh: &FemMesh, cracks: &[Crack]) -> Result<Vec<FacetKey>> {
    let mut keys = Vec::new();
    if cracks.is_empty() {
        return Ok(keys);
    }
    let map = mesh.facet_map();
    for (k, c) in cracks.iter().enumerate() {
        match &c.shape {
            CrackShape::Set(s) => keys.extend(mesh.set_keys(*s)),
            CrackShape::Polyline(pts) if mesh.dim == 2 => {
                keys.extend(polyline_facets(mesh, &map, k, pts)?)
            }
            _ => {
                return Err(Error::model(
                    format!("crack[{k}].points"),
                    "fem: a polygon crack is not supported; make the crack a physical surface (group) of the gmsh mesh",
                ))
            }
        }
    }
    keys.sort_unstable();
    keys.dedup();
    Ok(keys)
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Splits the mesh along the facets `crack` (keys in the current numbering); returns the
/// number of nodes added. Boundary sets follow because they refer to cell facets.
pub fn split(mesh: &mut FemMesh, crack: &[FacetKey]) -> usize {
    if crack.is_empty() {
        return 0;
    }
    let on_crack: HashSet<FacetKey> = crack.iter().copied().collect();
    let mut crack_nodes: Vec<u32> = crack
        .iter()
        .flat_map(|k| k.iter().copied().filter(|&n| n != u32::MAX))
        .collect();
    crack_nodes.sort_unstable();
    crack_nodes.dedup();
    let (offsets, around) = mesh.node_cells();
    let mut added = 0;
    // (cell, local index, new node) to apply after every node has been examined
    let mut moves = Vec::new();
    for &v in &crack_nodes {
        let ring = &around[offsets[v as usize]..offsets[v as usize + 1]];
        let mut parent: Vec<usize> = (0..ring.len()).collect();
        let mut seen: HashMap<FacetKey, usize> = HashMap::new();
        for (r, &(e, _)) in ring.iter().enumerate() {
            let c = &mesh.cells[e as usize];
            for f in facets(c.kind) {
                if !f.iter().any(|&a| c.nodes[a] == v) {
                    continue;
                }
                let key = key_of(f.iter().map(|&a| c.nodes[a]));
                if on_crack.contains(&key) {
                    continue;
                }
                match seen.get(&key) {
                    Some(&other) => {
                        let (a, b) = (find(&mut parent, r), find(&mut parent, other));
                        parent[a] = b;
                    }
                    None => {
                        seen.insert(key, r);
                    }
                }
            }
        }
        let mut copy_of_root: HashMap<usize, u32> = HashMap::new();
        let first = find(&mut parent, 0);
        for (r, &(e, a)) in ring.iter().enumerate() {
            let root = find(&mut parent, r);
            if root == first {
                continue;
            }
            let n = *copy_of_root.entry(root).or_insert_with(|| {
                added += 1;
                (mesh.nodes.len() + added - 1) as u32
            });
            moves.push((e, a, n));
        }
    }
    for _ in 0..added {
        mesh.nodes.push(Point::origin());
    }
    for (e, a, n) in moves {
        let c = &mut mesh.cells[e as usize];
        let old = c.nodes[a as usize];
        c.nodes[a as usize] = n;
        mesh.nodes[n as usize] = mesh.nodes[old as usize];
    }
    added
}
