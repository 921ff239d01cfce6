//! Mesh integrity: the defects that make a mesh count volume twice, fold over itself or name
//! one place twice, found before a cloud is built from it.
//!
//! A node cloud takes one node per element with the element's measure as its volume
//! ([`crate::cloud::mesh`]), so an element counted twice doubles a node's heat capacity without
//! a word. [`validate`] refuses, in this order:
//! - elements of zero measure, and quadrangles or hexahedra whose corners are out of order
//!   (tangled: not convex, or folded over themselves);
//! - two elements with the same nodes, in any dimension;
//! - a facet (end point, edge or face) shared by more than two body elements;
//! - two body elements that lie on the same side of the facet they share (one is inverted);
//! - a body element next to an unshared facet whose centre lies inside another body element
//!   (two meshes laid over each other, e.g. overlapping surfaces that were not fragmented).
//!
//! The orientation of an element is free (gmsh writes a plane surface clockwise when its curve
//! loop is clockwise): only the relation between neighbours counts. Not seen: overlaps that
//! leave every facet shared by two elements on opposite sides (a mesh that winds twice round a
//! hole) and slivers of overlap between meshes that do not touch a centre.
//!
//! Cost: O(n log n) in the number of elements n, with O(n) memory (about 60 B per facet and
//! 40 B per element, freed on return); the overlap search indexes only the centres of the
//! elements next to an unshared facet and every element looks for them within its own radius,
//! so a graded mesh does not widen the search.

use super::{contains, Element, ElementKind, Mesh, HEX_TETS};
use crate::math::{Point, Vector};
use crate::spatial::PointIndex;
use rayon::prelude::*;
use std::collections::HashMap;

/// Relative measure below which an element is degenerate: its measure over its longest edge
/// to the power of its dimension (round-off of file coordinates is about 1e-16).
const DEGENERATE: f64 = 1e-12;

/// A defect of a mesh; elements by their index in [`Mesh::elements`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Defect {
    /// An element whose nodes lie off the z = 0 plane (2D) or the x axis (1D): node index.
    OffPlane {
        /// The node's index in [`Mesh::nodes`].
        node: usize,
    },
    /// An element of zero measure (its corners on one point, line or plane).
    Degenerate {
        /// The element.
        element: usize,
    },
    /// A quadrangle or hexahedron that is not convex or folds over itself.
    Tangled {
        /// The element.
        element: usize,
    },
    /// Two elements with the same nodes.
    Duplicated {
        /// The earlier element.
        first: usize,
        /// The later one.
        second: usize,
    },
    /// A facet shared by more than two body elements.
    Crowded {
        /// Three of the elements that share it.
        elements: [usize; 3],
    },
    /// Two body elements on the same side of the facet they share.
    Folded {
        /// The earlier element.
        first: usize,
        /// The later one.
        second: usize,
    },
    /// A body element whose centre lies inside another body element.
    Overlapping {
        /// The element whose centre was tested.
        inner: usize,
        /// The element that contains that centre.
        outer: usize,
    },
}

/// The first defect of `mesh` (in the order of the module's list), or `Ok` when it has none.
pub fn validate(mesh: &Mesh) -> Result<(), Defect> {
    let dim = mesh.dim();
    if let Some(node) = mesh.off_plane(dim) {
        return Err(Defect::OffPlane { node });
    }
    let body: Vec<u32> = (0..mesh.elements.len())
        .filter(|&e| mesh.elements[e].kind.dim() == dim)
        .map(|e| e as u32)
        .collect();
    shapes(mesh)?;
    duplicated_sides(mesh, dim)?;
    let centres: Vec<Point> = body
        .par_iter()
        .map(|&e| centre(mesh, &mesh.elements[e as usize]))
        .collect();
    let open = shared_facets(mesh, &body, &centres)?;
    overlaps(mesh, &body, &centres, &open)
}

/// The mean of an element's corners (inside it when it is convex), file units.
fn centre(mesh: &Mesh, e: &Element) -> Point {
    let mut c = Vector::zeros();
    for &n in &e.nodes {
        c += mesh.nodes[n as usize].coords;
    }
    Point::from(c / e.nodes.len() as f64)
}

/// Degenerate and tangled elements of every dimension from 1 on, first by index.
fn shapes(mesh: &Mesh) -> Result<(), Defect> {
    let bad = (0..mesh.elements.len())
        .into_par_iter()
        .find_map_first(|k| {
            let e = &mesh.elements[k];
            let p: Vec<Point> = e.nodes.iter().map(|&n| mesh.nodes[n as usize]).collect();
            shape_defect(e.kind, &p, k)
        });
    bad.map_or(Ok(()), Err)
}

/// The shape defect of element `k` of `kind` with corners `p`, if any.
fn shape_defect(kind: ElementKind, p: &[Point], k: usize) -> Option<Defect> {
    let d = kind.dim();
    if d == 0 {
        return None;
    }
    let longest = (0..p.len())
        .flat_map(|i| (0..i).map(move |j| (i, j)))
        .map(|(i, j)| (p[i] - p[j]).norm())
        .fold(0.0, f64::max);
    let scale = p.iter().map(|q| q.coords.amax()).fold(0.0, f64::max);
    let (measure, _) = super::measure_and_centroid(kind, p);
    // written so that a NaN coordinate counts as degenerate
    let sound = longest > 1e-14 * scale && measure > DEGENERATE * longest.powi(d as i32);
    if !sound {
        return Some(Defect::Degenerate { element: k });
    }
    let tangled = match kind {
        ElementKind::Quad => !quad_is_convex(p),
        ElementKind::Hex => !hex_is_untangled(p),
        _ => false,
    };
    tangled.then_some(Defect::Tangled { element: k })
}

/// True when the quadrangle's four corners turn the same way (a convex quadrangle; a
/// straight corner is accepted): every corner's turn agrees with the largest one.
fn quad_is_convex(p: &[Point]) -> bool {
    let turns: Vec<Vector> = (0..4)
        .map(|i| {
            let (a, b, c) = (p[(i + 3) % 4], p[i], p[(i + 1) % 4]);
            (b - a).cross(&(c - b))
        })
        .collect();
    let largest = turns
        .iter()
        .copied()
        .max_by(|x, y| x.norm_squared().total_cmp(&y.norm_squared()))
        .unwrap_or_default();
    turns
        .iter()
        .all(|t| t.dot(&largest) >= -DEGENERATE * largest.norm_squared())
}

/// True when the six tetrahedra of the hexahedron ([`HEX_TETS`]) have one orientation.
fn hex_is_untangled(p: &[Point]) -> bool {
    let v: Vec<f64> = HEX_TETS
        .iter()
        .map(|t| {
            let [a, b, c, d] = t.map(|i| p[i]);
            (b - a).cross(&(c - a)).dot(&(d - a))
        })
        .collect();
    let total: f64 = v.iter().map(|x| x.abs()).sum();
    let tol = DEGENERATE * total;
    v.iter().all(|&x| x >= -tol) || v.iter().all(|&x| x <= tol)
}

/// The nodes of an element or facet sorted, padded with `u32::MAX` (up to 8 nodes).
fn sorted_key(nodes: &[u32]) -> [u32; 8] {
    let mut k = [u32::MAX; 8];
    k[..nodes.len()].copy_from_slice(nodes);
    k.sort_unstable();
    k
}

/// Two elements below the body's dimension (boundary elements) with the same nodes.
fn duplicated_sides(mesh: &Mesh, dim: usize) -> Result<(), Defect> {
    let mut seen: HashMap<[u32; 8], usize> = HashMap::new();
    for (k, e) in mesh.elements.iter().enumerate() {
        let d = e.kind.dim();
        if d == 0 || d >= dim {
            continue;
        }
        if let Some(&first) = seen.get(&sorted_key(&e.nodes)) {
            return Err(Defect::Duplicated { first, second: k });
        }
        seen.insert(sorted_key(&e.nodes), k);
    }
    Ok(())
}

/// A facet of a body element: its sorted nodes (padded with `u32::MAX`), the element's
/// position in the body list and the facet's local number.
type FacetEntry = ([u32; 4], u32, u32);

/// The sorted nodes of a facet as one number, for a fast sort.
fn packed(k: &[u32; 4]) -> u128 {
    k.iter().fold(0u128, |acc, &n| (acc << 32) | n as u128)
}

/// Every facet of the body elements `body`, sorted by its nodes.
fn sorted_facets(mesh: &Mesh, body: &[u32]) -> Vec<FacetEntry> {
    let n: usize = body
        .iter()
        .map(|&e| mesh.elements[e as usize].kind.facets().len())
        .sum();
    let mut facets: Vec<FacetEntry> = Vec::with_capacity(n);
    for (b, &e) in body.iter().enumerate() {
        let el = &mesh.elements[e as usize];
        for (f, local) in el.kind.facets().iter().enumerate() {
            let mut key = [u32::MAX; 4];
            for (slot, &i) in key.iter_mut().zip(local.iter()) {
                *slot = el.nodes[i];
            }
            key.sort_unstable();
            facets.push((key, b as u32, f as u32));
        }
    }
    facets.par_sort_unstable_by_key(|f| packed(&f.0));
    facets
}

/// Checks the facets of the body elements `body` (with centres `centres`): none shared by more
/// than two elements, no two elements with the same nodes, no two on the same side of a
/// shared facet. Returns, by position in `body`, whether an element has a facet no other
/// element shares.
fn shared_facets(mesh: &Mesh, body: &[u32], centres: &[Point]) -> Result<Vec<bool>, Defect> {
    let facets = sorted_facets(mesh, body);
    let runs = facets.par_chunk_by(|a, b| a.0 == b.0);
    let found: Vec<(Option<u32>, Option<Defect>)> = runs
        .filter_map(|run| match run {
            [(_, b, _)] => Some((Some(*b), None)),
            [(key, a, _), (_, b, _)] => {
                let side = |x: u32| (body[x as usize], centres[x as usize]);
                pair_defect(mesh, key, side(*a), side(*b)).map(|d| (None, Some(d)))
            }
            _ => Some((None, Some(crowded(mesh, body, run)))),
        })
        .collect();
    // the defect of the smallest element indices, whatever the facets' order
    let defect = found
        .iter()
        .filter_map(|f| f.1.as_ref())
        .min_by_key(|d| order(d));
    if let Some(d) = defect {
        return Err(d.clone());
    }
    let mut open = vec![false; body.len()];
    for b in found.iter().filter_map(|f| f.0) {
        open[b as usize] = true;
    }
    Ok(open)
}

/// The element indices of a defect, for a deterministic choice among several.
fn order(d: &Defect) -> [usize; 3] {
    match *d {
        Defect::Duplicated { first, second } | Defect::Folded { first, second } => {
            [first, second, 0]
        }
        Defect::Crowded { elements } => elements,
        Defect::Overlapping { inner, outer } => [inner, outer, 0],
        Defect::Degenerate { element } | Defect::Tangled { element } => [element, 0, 0],
        Defect::OffPlane { node } => [node, 0, 0],
    }
}

/// The defect of body elements `a` and `b` (index into the mesh's elements, centre) sharing
/// the facet of nodes `key`, if any: both on one side of the facet, or the same nodes.
fn pair_defect(mesh: &Mesh, key: &[u32; 4], a: (u32, Point), b: (u32, Point)) -> Option<Defect> {
    let mut q = [Point::origin(); 4];
    let n = key.iter().take_while(|&&k| k != u32::MAX).count();
    for (slot, &k) in q.iter_mut().zip(&key[..n]) {
        *slot = mesh.nodes[k as usize];
    }
    if off_facet(&q[..n], &a.1).dot(&off_facet(&q[..n], &b.1)) < 0.0 {
        return None;
    }
    let (first, second) = (a.0.min(b.0) as usize, a.0.max(b.0) as usize);
    let same = sorted_key(&mesh.elements[first].nodes) == sorted_key(&mesh.elements[second].nodes);
    Some(match same {
        true => Defect::Duplicated { first, second },
        false => Defect::Folded { first, second },
    })
}

/// The part of `c − q[0]` normal to the facet with corners `q` in any order (a point, an edge
/// in a plane or a face in space, whose first three corners span its plane).
fn off_facet(q: &[Point], c: &Point) -> Vector {
    let u = c - q[0];
    match q.len() {
        1 => u,
        2 => {
            let t = (q[1] - q[0]).normalize();
            u - t * u.dot(&t)
        }
        _ => {
            let normal = (q[1] - q[0]).cross(&(q[2] - q[0]));
            normal * u.dot(&normal)
        }
    }
}

/// The defect of three or more body elements on one facet (`run`: facets of one key).
fn crowded(mesh: &Mesh, body: &[u32], run: &[([u32; 4], u32, u32)]) -> Defect {
    let mut elements: Vec<usize> = run.iter().map(|r| body[r.1 as usize] as usize).collect();
    elements.sort_unstable();
    for (i, &a) in elements.iter().enumerate() {
        for &b in &elements[i + 1..] {
            if sorted_key(&mesh.elements[a].nodes) == sorted_key(&mesh.elements[b].nodes) {
                return Defect::Duplicated {
                    first: a,
                    second: b,
                };
            }
        }
    }
    Defect::Crowded {
        elements: [elements[0], elements[1], elements[2]],
    }
}

/// A body element next to an unshared facet (`open`) whose centre (`centres`) lies inside
/// another body element, first by element index. The tested centres are few (the elements
/// next to the boundary, O(n^((d−1)/d))), so they are indexed and every element looks for
/// the tested centres within its own radius.
fn overlaps(mesh: &Mesh, body: &[u32], centres: &[Point], open: &[bool]) -> Result<(), Defect> {
    let tested: Vec<usize> = (0..body.len()).filter(|&b| open[b]).collect();
    let points: Vec<Point> = tested.iter().map(|&b| centres[b]).collect();
    let index = PointIndex::new(&points);
    let (tested, points) = (&tested, &points);
    let hits: Vec<(usize, usize)> = (0..body.len())
        .into_par_iter()
        .flat_map_iter(|o| {
            let e = &mesh.elements[body[o] as usize];
            let corners = mesh.corners(e);
            let radius = corners
                .iter()
                .map(|p| (p - centres[o]).norm())
                .fold(0.0, f64::max);
            let near = index.within(&centres[o], radius);
            near.into_iter().filter_map(move |t| {
                let b = tested[t];
                (b != o && contains(e.kind, &corners, &points[t]))
                    .then_some((body[b] as usize, body[o] as usize))
            })
        })
        .collect();
    match hits.into_iter().min() {
        Some((inner, outer)) => Err(Defect::Overlapping { inner, outer }),
        None => Ok(()),
    }
}

impl Defect {
    /// One line describing the defect; `tag` gives an element's tag in the file and `node` a
    /// node's, `mesh` the places (file units).
    pub fn describe(
        &self,
        mesh: &Mesh,
        tag: &dyn Fn(usize) -> u64,
        node: &dyn Fn(usize) -> u64,
    ) -> String {
        let dim = mesh.dim();
        let at = |e: usize| {
            let c = centre(mesh, &mesh.elements[e]);
            format!("({}, {}, {})", c.x, c.y, c.z)
        };
        let element_dim = |e: usize| mesh.elements[e].kind.dim();
        let one = |e: usize| {
            let kind = kind_name(mesh.elements[e].kind);
            format!("element {} ({kind} at {})", tag(e), at(e))
        };
        let pair = |a: usize, b: usize| {
            let kinds = kinds_name(mesh.elements[a].kind);
            format!("elements {} and {} ({kinds} at {})", tag(a), tag(b), at(a))
        };
        let (measure, facet) = (measure_name(dim), facet_name(dim));
        const REGENERATE: &str = "regenerate the mesh with gmsh";
        match *self {
            Defect::OffPlane { node: n } => {
                let p = mesh.nodes[n];
                let place = if dim == 2 { "z = 0 plane" } else { "x axis" };
                let (tag, (x, y, z)) = (node(n), (p.x, p.y, p.z));
                format!(
                    "node {tag} at ({x}, {y}, {z}) is off the {place}: a {dim}D mesh lies in it"
                )
            }
            Defect::Degenerate { element: e } => format!(
                "{} has zero {}: its corners lie on one {}; {REGENERATE}",
                one(e),
                measure_name(element_dim(e)),
                ["point", "point", "line", "plane"][element_dim(e)]
            ),
            Defect::Tangled { element: e } => format!(
                "{} is tangled: its corners are not in gmsh's order (it is not convex or folds \
                 over itself); {REGENERATE}",
                one(e)
            ),
            Defect::Duplicated { first, second } => format!(
                "{} have the same nodes, so their {} would be counted twice: remove one, or \
                 {REGENERATE}",
                pair(first, second),
                measure_name(element_dim(first))
            ),
            Defect::Crowded {
                elements: [a, b, c],
            } => format!(
                "elements {}, {} and {} share one {facet} near {}: overlapping elements would \
                 count the {measure} twice; {REGENERATE}",
                tag(a),
                tag(b),
                tag(c),
                at(a)
            ),
            Defect::Folded { first, second } => format!(
                "{} lie on the same side of the {facet} they share: one is inverted and they \
                 overlap; {REGENERATE}",
                pair(first, second)
            ),
            Defect::Overlapping { inner, outer } => format!(
                "{} lies inside element {}: overlapping {} would count the {measure} twice; make \
                 them one conforming mesh (e.g. BooleanFragments in the .geo) and mesh again",
                one(inner),
                tag(outer),
                ["points", "lines", "surfaces", "volumes"][dim]
            ),
        }
    }
}

/// The plural of an element shape's name.
fn kinds_name(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Point => "points",
        ElementKind::Line => "lines",
        ElementKind::Triangle => "triangles",
        ElementKind::Quad => "quadrangles",
        ElementKind::Tet => "tetrahedra",
        ElementKind::Hex => "hexahedra",
    }
}

/// The name of an element shape, as gmsh calls it.
fn kind_name(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Point => "point",
        ElementKind::Line => "line",
        ElementKind::Triangle => "triangle",
        ElementKind::Quad => "quadrangle",
        ElementKind::Tet => "tetrahedron",
        ElementKind::Hex => "hexahedron",
    }
}

/// Length, area or volume, by dimension.
fn measure_name(dim: usize) -> &'static str {
    ["size", "length", "area", "volume"][dim.min(3)]
}

/// End point, edge or face: a facet of a body of dimension `dim`.
fn facet_name(dim: usize) -> &'static str {
    ["point", "end point", "edge", "face"][dim.min(3)]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn element(kind: ElementKind, nodes: &[u32]) -> Element {
        Element {
            kind,
            nodes: nodes.to_vec(),
            groups: [0].into(),
        }
    }

    /// The unit square cut into n × n squares of two triangles each, every triangle turning
    /// counter-clockwise, nodes numbered from `first` and shifted by (`dx`, `dy`).
    fn triangles(n: u32, first: u32, dx: f64, dy: f64) -> (Vec<Point>, Vec<Element>) {
        let h = 1.0 / n as f64;
        let nodes = (0..=n)
            .flat_map(|j| {
                (0..=n).map(move |i| Point::new(dx + i as f64 * h, dy + j as f64 * h, 0.0))
            })
            .collect();
        let at = |i: u32, j: u32| first + j * (n + 1) + i;
        let mut elements = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                elements.push(element(ElementKind::Triangle, &[a, b, c]));
                elements.push(element(ElementKind::Triangle, &[a, c, d]));
            }
        }
        (nodes, elements)
    }

    fn square(n: u32) -> Mesh {
        let (nodes, elements) = triangles(n, 0, 0.0, 0.0);
        Mesh {
            nodes,
            elements,
            groups: [].into(),
        }
    }

    fn unit_cube() -> Vec<Point> {
        [
            [0., 0., 0.],
            [1., 0., 0.],
            [1., 1., 0.],
            [0., 1., 0.],
            [0., 0., 1.],
            [1., 0., 1.],
            [1., 1., 1.],
            [0., 1., 1.],
        ]
        .iter()
        .map(|p| Point::new(p[0], p[1], p[2]))
        .collect()
    }

    fn mesh(nodes: Vec<Point>, elements: Vec<Element>) -> Mesh {
        Mesh {
            nodes,
            elements,
            groups: [].into(),
        }
    }

    #[test]
    fn a_conforming_mesh_of_any_orientation_passes() {
        let mut m = square(6);
        assert_eq!(validate(&m), Ok(()));
        // gmsh writes a clockwise curve loop's surface clockwise; mixed orientations are legal
        for e in m.elements.iter_mut().step_by(3) {
            e.nodes.reverse();
        }
        assert_eq!(validate(&m), Ok(()));
        for e in &mut m.elements {
            e.nodes.reverse();
        }
        assert_eq!(validate(&m), Ok(()));
    }

    #[test]
    fn boundary_elements_and_a_hanging_node_interface_pass() {
        // left square of two triangles, right square of four with a node at (1, 0.5)
        let p = |x: f64, y: f64| Point::new(x, y, 0.0);
        let nodes = vec![
            p(0., 0.),
            p(1., 0.),
            p(1., 1.),
            p(0., 1.),
            p(2., 0.),
            p(2., 1.),
            p(1., 0.5),
        ];
        let t = |n: &[u32]| element(ElementKind::Triangle, n);
        let mut elements = vec![t(&[0, 1, 2]), t(&[0, 2, 3])];
        elements.extend([t(&[1, 4, 6]), t(&[4, 5, 6]), t(&[5, 2, 6])]);
        elements.push(element(ElementKind::Line, &[0, 1]));
        elements.push(element(ElementKind::Line, &[1, 4]));
        elements.push(element(ElementKind::Point, &[0]));
        assert_eq!(validate(&mesh(nodes, elements)), Ok(()));
    }

    #[test]
    fn a_duplicated_element_is_refused() {
        let mut m = square(4);
        let copy = m.elements[5].clone();
        m.elements.push(copy);
        let last = m.elements.len() - 1;
        assert_eq!(
            validate(&m),
            Err(Defect::Duplicated {
                first: 5,
                second: last
            })
        );
        // the same nodes in another order are the same element
        m.elements[last].nodes.rotate_left(1);
        assert_eq!(
            validate(&m),
            Err(Defect::Duplicated {
                first: 5,
                second: last
            })
        );
    }

    #[test]
    fn a_duplicated_boundary_line_is_refused() {
        let mut m = square(2);
        m.elements.push(element(ElementKind::Line, &[0, 1]));
        m.elements.push(element(ElementKind::Line, &[1, 0]));
        let n = m.elements.len();
        assert_eq!(
            validate(&m),
            Err(Defect::Duplicated {
                first: n - 2,
                second: n - 1
            })
        );
    }

    #[test]
    fn a_copy_with_its_own_nodes_laid_over_the_mesh_is_refused() {
        let mut m = square(4);
        let (nodes, elements) = triangles(2, m.nodes.len() as u32, 0.3, 0.2);
        let first_copy = m.elements.len();
        m.nodes.extend(nodes);
        m.elements.extend(elements);
        match validate(&m) {
            Err(Defect::Overlapping { inner, outer }) => {
                // one of the pair is in the copy, the other in the square
                assert!(
                    (inner < first_copy) != (outer < first_copy),
                    "{inner} {outer}"
                );
            }
            other => panic!("expected an overlap, got {other:?}"),
        }
    }

    #[test]
    fn overlapping_lines_are_refused() {
        let nodes = [0.0, 1.0, 0.5, 1.5]
            .map(|x| Point::new(x, 0.0, 0.0))
            .to_vec();
        let lines = vec![
            element(ElementKind::Line, &[0, 1]),
            element(ElementKind::Line, &[2, 3]),
        ];
        assert_eq!(
            validate(&mesh(nodes, lines)),
            Err(Defect::Overlapping { inner: 0, outer: 1 })
        );
    }

    #[test]
    fn an_inverted_neighbour_is_refused() {
        // both triangles above their shared edge 0–1
        let p = |x: f64, y: f64| Point::new(x, y, 0.0);
        let nodes = vec![p(0., 0.), p(1., 0.), p(0.2, 1.), p(0.8, 0.5)];
        let t = |n: &[u32]| element(ElementKind::Triangle, n);
        let m = mesh(nodes, vec![t(&[0, 1, 2]), t(&[1, 0, 3])]);
        assert_eq!(
            validate(&m),
            Err(Defect::Folded {
                first: 0,
                second: 1
            })
        );
    }

    #[test]
    fn an_interior_node_pulled_across_an_edge_is_refused() {
        let mut m = square(4);
        // node (2, 2) of the 5 × 5 grid moved past its neighbours' far edge
        m.nodes[12].x += 0.3;
        assert!(
            matches!(validate(&m), Err(Defect::Folded { .. })),
            "{:?}",
            validate(&m)
        );
    }

    #[test]
    fn an_edge_shared_by_three_triangles_is_refused() {
        let p = |x: f64, y: f64| Point::new(x, y, 0.0);
        let nodes = vec![p(0., 0.), p(1., 0.), p(0.5, 1.), p(0.5, -1.), p(0.5, 2.)];
        let t = |n: &[u32]| element(ElementKind::Triangle, n);
        let m = mesh(nodes, vec![t(&[0, 1, 2]), t(&[1, 0, 3]), t(&[0, 1, 4])]);
        assert_eq!(
            validate(&m),
            Err(Defect::Crowded {
                elements: [0, 1, 2]
            })
        );
    }

    #[test]
    fn elements_of_zero_measure_are_refused() {
        let mut m = square(2);
        m.nodes.push(Point::new(0.5, 0.0, 0.0));
        m.elements.push(element(ElementKind::Triangle, &[0, 1, 9]));
        let k = m.elements.len() - 1;
        assert_eq!(validate(&m), Err(Defect::Degenerate { element: k }));
        m.elements[k] = element(ElementKind::Line, &[3, 3]);
        assert_eq!(validate(&m), Err(Defect::Degenerate { element: k }));
    }

    #[test]
    fn a_bow_tie_quadrangle_is_refused() {
        let p = |x: f64, y: f64| Point::new(x, y, 0.0);
        let nodes = vec![p(0., 0.), p(1., 0.), p(1., 1.), p(0., 1.)];
        let good = mesh(
            nodes.clone(),
            vec![element(ElementKind::Quad, &[0, 1, 2, 3])],
        );
        assert_eq!(validate(&good), Ok(()));
        let bad = mesh(nodes, vec![element(ElementKind::Quad, &[0, 1, 3, 2])]);
        assert_eq!(validate(&bad), Err(Defect::Tangled { element: 0 }));
    }

    #[test]
    fn hexahedra_and_tetrahedra_of_a_cube() {
        let cube = unit_cube();
        let hex = |n: &[u32]| mesh(cube.clone(), vec![element(ElementKind::Hex, n)]);
        assert_eq!(validate(&hex(&[0, 1, 2, 3, 4, 5, 6, 7])), Ok(()));
        assert_eq!(
            validate(&hex(&[4, 5, 6, 7, 0, 1, 2, 3])),
            Ok(()),
            "mirrored"
        );
        assert_eq!(
            validate(&hex(&[0, 1, 2, 3, 4, 5, 7, 6])),
            Err(Defect::Tangled { element: 0 })
        );
        // the cube's six tetrahedra are conforming; a seventh over them overlaps
        let tets: Vec<Element> = HEX_TETS
            .iter()
            .map(|t| element(ElementKind::Tet, &t.map(|i| i as u32)))
            .collect();
        assert_eq!(validate(&mesh(cube.clone(), tets.clone())), Ok(()));
        let mut more = tets;
        more.push(element(ElementKind::Tet, &[0, 1, 3, 4]));
        assert!(validate(&mesh(cube, more)).is_err());
    }

    #[test]
    fn a_2d_mesh_off_its_plane_is_refused() {
        let mut m = square(2);
        m.nodes[4].z = 0.1;
        assert_eq!(validate(&m), Err(Defect::OffPlane { node: 4 }));
    }

    #[test]
    fn the_description_names_the_file_tags() {
        let mut m = square(2);
        m.elements.push(m.elements[1].clone());
        let d = validate(&m).unwrap_err();
        let line = d.describe(&m, &|e| 100 + e as u64, &|n| n as u64 + 1);
        assert!(
            line.starts_with("elements 101 and 108 (triangles at"),
            "{line}"
        );
        assert!(!line.contains('\n'));
    }
}
