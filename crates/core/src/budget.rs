//! The size of a case before anything is allocated: nodes, fictitious nodes, bonds and bytes
//! estimated from the case (and, for a mesh, its elements), checked against the machine's
//! memory, and the neighbour count a horizon implies ([`crate::limits`]).

use crate::cloud::{BoxGeometry, HorizonRule};
use crate::error::Result;
use crate::kernel::PartialVolume;
use crate::limits::{
    BYTES_PER_BOND, BYTES_PER_NODE, CORRECTION_BYTES, CUT_BYTES_PER_BOND, F32_BYTES_PER_BOND,
    FEM_BYTES_PER_ENTRY, IMPLICIT_BYTES_PER_BOND, MAX_NEIGHBOURS, MEMORY_FRACTION,
    PACKED_BYTES_PER_BOND, SHARED_BYTES_PER_NODE,
};
use crate::machine::Memory;
use crate::model::{Geometry, ModelSpec};
use serde::Serialize;

/// Estimated size of a model, with the key that drives it.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Estimate {
    /// Body nodes.
    pub nodes: f64,
    /// Fictitious nodes of the boundary layers.
    pub fictitious: f64,
    /// Directed bonds.
    pub bonds: f64,
    /// Memory at the peak of set-up and run, bytes.
    pub bytes: f64,
    /// The case key whose value sets most of the size (e.g. `region[0].spacing`).
    pub key: String,
}

/// Formats bytes with a binary prefix, e.g. `1.5 GiB`.
pub fn human(bytes: f64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut v = bytes;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if u + 1 == units.len() && v >= 1024.0 {
        return format!("{bytes:.1e} B");
    }
    format!("{v:.1} {}", units[u])
}

/// Parses a memory size such as `8G`, `512M`, `2GiB` or `1e9` (bytes).
pub fn parse_bytes(s: &str) -> std::result::Result<f64, String> {
    let t = s.trim();
    let split = t
        .find(|c: char| c.is_ascii_alphabetic() && c != 'e' && c != 'E')
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a size (e.g. 8G, 512M, 1e9)"))?;
    let scale = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" | "kib" => 1024.0,
        "m" | "mb" | "mib" => 1024.0f64.powi(2),
        "g" | "gb" | "gib" => 1024.0f64.powi(3),
        "t" | "tb" | "tib" => 1024.0f64.powi(4),
        _ => return Err(format!("`{s}`: unknown unit (use K, M, G or T)")),
    };
    let bytes = v * scale;
    if bytes.is_finite() && bytes > 0.0 {
        Ok(bytes)
    } else {
        Err(format!("`{s}` is not a positive size"))
    }
}

/// Lattice nodes within a horizon of m spacings: 2m + 1 in 1D, π m² in 2D, 4π m³/3 in 3D.
pub fn ball(dim: usize, m: f64) -> f64 {
    match dim {
        1 => 2.0 * m + 1.0,
        2 => std::f64::consts::PI * m * m,
        _ => 4.0 / 3.0 * std::f64::consts::PI * m * m * m,
    }
}

/// Checks a horizon rule at spacing `dx` (m): the horizon reaches at least the next node
/// (δ ≥ Δ, else the nodes have no full bond) and implies at most [`MAX_NEIGHBOURS`].
pub fn check_horizon(dim: usize, dx: f64, rule: &HorizonRule) -> std::result::Result<(), String> {
    let delta = rule.horizon(dx);
    let m = delta / dx;
    if m < 1.0 - 1e-9 {
        return Err(format!(
            "δ = {delta:e} m is below the spacing Δ = {dx:e} m (δ/Δ = {m:.3}): the nodes would have no full bond; use δ ≥ Δ"
        ));
    }
    let n = ball(dim, m);
    if !crate::limits::within(n, MAX_NEIGHBOURS) {
        return Err(format!(
            "implies about {n:.3e} neighbours per node (δ/Δ = {m:.3e}); at most {MAX_NEIGHBOURS:e} are allowed"
        ));
    }
    Ok(())
}

/// Estimates the size of a model of `spec`; `size_keys[r]` names what sets region r's
/// spacing (e.g. `region[0].cells`, or `mesh.file`), `implicit` adds the matrix factor.
pub fn estimate(spec: &ModelSpec, size_keys: &[String], implicit: bool) -> Result<Estimate> {
    let band = match spec.kernel.partial_volume {
        PartialVolume::AllOrNothing => 0.0,
        PartialVolume::Algorithm1 => 0.5,
    };
    let layered: Vec<bool> = spec.faces.iter().map(|f| f.needs_layer()).collect();
    let mut correction = 0.0;
    // (body nodes, fictitious nodes, bonds) per region
    let per_region: Vec<(f64, f64, f64)> = match &spec.geometry {
        Geometry::Box(g) => box_regions(g, &layered, band),
        Geometry::Mesh(g) => {
            let cloud = g.generate(&[], 0.0)?;
            let dim = cloud.dim;
            let mut out = vec![(0.0, 0.0, 0.0); g.regions.len()];
            let facets = match &cloud.sides {
                crate::cloud::Sides::Mesh(m) => m.boundary.facets.len() as f64,
                _ => 0.0,
            };
            let mut m_max: f64 = 0.0;
            for i in 0..cloud.n_body {
                let m = cloud.horizon[i] / cloud.spacing[i] + band;
                m_max = m_max.max(m);
                if !crate::limits::within(ball(dim, m), MAX_NEIGHBOURS) {
                    return Err(crate::Error::model(
                        format!("region[{}].horizon", cloud.region[i]),
                        format!(
                            "implies about {:.3e} neighbours per node (δ/Δ = {m:.3e}); at most {MAX_NEIGHBOURS:e} are allowed",
                            ball(dim, m)
                        ),
                    ));
                }
                let r = &mut out[cloud.region[i] as usize];
                r.0 += 1.0;
                r.2 += ball(dim, m);
            }
            if let Some(r) = out.iter().position(|c| c.0 == 0.0) {
                return Err(crate::Error::model(
                    format!("region[{r}].name"),
                    "the mesh's group of this region has no elements",
                ));
            }
            // mirrored layers: about one node per boundary facet and spacing of reach
            if layered.iter().any(|&l| l) {
                if let Some(r) = out.first_mut() {
                    r.1 = facets * (m_max + 1.0);
                    r.2 += r.1 * ball(dim, m_max + 1.0);
                }
            }
            correction = correction_bytes(spec, dim, &out);
            out
        }
    };
    let (mut nodes, mut fictitious, mut bonds) = (0.0, 0.0, 0.0);
    let mut biggest = (0, 0.0);
    for (r, &(n, f, b)) in per_region.iter().enumerate() {
        nodes += n;
        fictitious += f;
        bonds += b;
        let bytes = (n + f) * BYTES_PER_NODE + b * BYTES_PER_BOND;
        if bytes > biggest.1 {
            biggest = (r, bytes);
        }
    }
    let mut per_bond = BYTES_PER_BOND;
    if implicit {
        per_bond += IMPLICIT_BYTES_PER_BOND;
    }
    let relation = spec
        .faces
        .iter()
        .any(|f| matches!(f, crate::bc::FaceBc::RelationFlux { .. }));
    if !spec.cracks.is_empty() || relation {
        per_bond += CUT_BYTES_PER_BOND;
    }
    per_bond += step_bytes_per_bond(spec.step);
    Ok(Estimate {
        nodes,
        fictitious,
        bonds,
        bytes: (nodes + fictitious) * BYTES_PER_NODE + bonds * per_bond + correction,
        key: size_keys
            .get(biggest.0)
            .cloned()
            .unwrap_or_else(|| "region".into()),
    })
}

/// Bytes of the consistent weights' solve on a mesh cloud (every node takes part): the
/// direct factor of [`crate::weights::estimate`] (2D, at most
/// [`crate::limits::MAX_DIRECT_ENTRIES`] entries at
/// [`crate::limits::CORRECTION_BYTES_PER_ENTRY`]) and the iterative solve's
/// [`CORRECTION_BYTES`] per bond and node; 0 without a correction.
fn correction_bytes(spec: &ModelSpec, dim: usize, per_region: &[(f64, f64, f64)]) -> f64 {
    if spec.symmetry.is_symmetric() {
        return 0.0;
    }
    let nodes: f64 = per_region.iter().map(|r| r.0 + r.1).sum();
    let pairs: f64 = per_region.iter().map(|r| r.2).sum();
    let factor = crate::weights::estimate(dim, spec.consistency, nodes, pairs).bytes;
    if spec.consistency == crate::weights::Order::None {
        return factor;
    }
    factor + pairs * CORRECTION_BYTES.0 + nodes * CORRECTION_BYTES.1
}

/// Per box region: body nodes, fictitious nodes of the layers on its faces that carry one,
/// and bonds (all as f64: a hostile case's counts overflow integers).
fn box_regions(g: &BoxGeometry, layered: &[bool], band: f64) -> Vec<(f64, f64, f64)> {
    let max_spacing = g.regions.iter().map(|r| r.spacing()).fold(0.0, f64::max);
    let max_horizon = g
        .regions
        .iter()
        .map(|r| r.horizon.horizon(r.spacing()))
        .fold(0.0, f64::max);
    let layer = max_horizon + band * max_spacing;
    let scale = (0..g.dim).map(|a| g.max[a] - g.min[a]).fold(0.0, f64::max);
    let eps = 1e-9 * scale;
    g.regions
        .iter()
        .map(|reg| {
            let h = reg.spacing();
            let ext = (layer / h).ceil().max(0.0);
            let (mut body, mut with) = (1.0, 1.0);
            for a in 0..g.dim {
                let n = reg.cells[a] as f64 + if g.boundary_placement { 1.0 } else { 0.0 };
                let lo = layered.get(2 * a).copied().unwrap_or(false)
                    && (reg.min[a] - g.min[a]).abs() < eps;
                let hi = layered.get(2 * a + 1).copied().unwrap_or(false)
                    && (reg.max[a] - g.max[a]).abs() < eps;
                body *= n;
                with *= n + ext * (lo as u8 + hi as u8) as f64;
            }
            let m = reg.horizon.horizon(h) / h + band;
            (body, with - body, with * ball(g.dim, m))
        })
        .collect()
}

/// Bytes of one rank that builds its share of a model ([`crate::model::Model::build_share`]):
/// [`BYTES_PER_NODE`] per row and [`BYTES_PER_BOND`] per bond of its share, plus
/// [`SHARED_BYTES_PER_NODE`] for each of the `all_nodes` nodes of the cloud, B.
pub fn share_bytes(rows: f64, bonds: f64, all_nodes: f64) -> f64 {
    rows * BYTES_PER_NODE + bonds * BYTES_PER_BOND + all_nodes * SHARED_BYTES_PER_NODE
}

impl Estimate {
    /// Refuses when the estimate exceeds `limit` bytes, or, without one, the fraction
    /// [`MEMORY_FRACTION`] of the machine's available memory; the message states the
    /// estimate, the machine's memory and the key to change.
    pub fn enforce(&self, limit: Option<f64>) -> std::result::Result<(), String> {
        let machine = Memory::of_machine();
        let allowed = match (limit, machine.available) {
            (Some(l), _) => l,
            (None, Some(a)) => MEMORY_FRACTION * a,
            (None, None) => return Ok(()),
        };
        if self.bytes <= allowed {
            return Ok(());
        }
        let have = match (machine.available, machine.total) {
            (Some(a), Some(t)) => format!("{} available of {}", human(a), human(t)),
            _ => "unknown".into(),
        };
        let limit_text = match limit {
            Some(l) => format!("--max-memory {}", human(l)),
            None => format!("{:.0}% of the available memory", 100.0 * MEMORY_FRACTION),
        };
        Err(format!(
            "needs about {} ({:.3e} nodes, {:.3e} fictitious, {:.3e} bonds), above {limit_text} (machine: {have}); coarsen this or pass --max-memory",
            human(self.bytes),
            self.nodes,
            self.fictitious,
            self.bonds
        ))
    }

    /// The estimate for one of `ranks` ranks that each build their share of the model
    /// ([`share_bytes`] of an even share).
    pub fn per_rank(&self, ranks: usize) -> Estimate {
        let (nodes, r) = (self.nodes + self.fictitious, ranks.max(1) as f64);
        Estimate {
            bytes: share_bytes(nodes / r, self.bonds / r, nodes),
            ..self.clone()
        }
    }

    /// One line for `check`: the estimate.
    pub fn line(&self) -> String {
        let machine = Memory::of_machine();
        format!(
            "estimate: {:.3e} nodes, {:.3e} fictitious, {:.3e} bonds, {} (machine: {} available)",
            self.nodes,
            self.fictitious,
            self.bonds,
            human(self.bytes),
            machine
                .available
                .map(human)
                .unwrap_or_else(|| "unknown".into())
        )
    }
}

/// Estimated memory of the FEM reference on a structured box mesh of element size `h` (m)
/// over the extents `size` (m): nodes and bytes.
pub fn fem_box(size: &[f64], h: f64) -> (f64, f64) {
    let dim = size.len();
    let nodes: f64 = size.iter().map(|l| (l / h).ceil() + 1.0).product();
    let entries = nodes * 3f64.powi(dim as i32);
    (
        nodes,
        nodes * BYTES_PER_NODE + entries * FEM_BYTES_PER_ENTRY,
    )
}

/// What the explicit step holds beside K per directed bond for `storage`, B.
fn step_bytes_per_bond(storage: crate::gather::StepStorage) -> f64 {
    use crate::gather::{ColumnIndex, Precision};
    let packed = match storage.columns {
        ColumnIndex::U32 => 0.0,
        ColumnIndex::Packed => PACKED_BYTES_PER_BOND,
    };
    let rounded = match storage.precision {
        Precision::F64 => 0.0,
        Precision::F32 => F32_BYTES_PER_BOND,
    };
    packed + rounded
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_units() {
        assert_eq!(parse_bytes("1k").unwrap(), 1024.0);
        assert_eq!(parse_bytes("2G").unwrap(), 2.0 * 1024f64.powi(3));
        assert_eq!(parse_bytes("1e9").unwrap(), 1e9);
        for bad in ["", "-1G", "x", "1Q", "nan"] {
            assert!(parse_bytes(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn horizons_below_the_spacing_or_absurdly_wide_are_refused() {
        assert!(check_horizon(2, 0.05, &HorizonRule::Factor(3.0)).is_ok());
        assert!(check_horizon(2, 0.05, &HorizonRule::Factor(0.5)).is_err());
        assert!(check_horizon(2, 0.05, &HorizonRule::Factor(1e4)).is_err());
        assert!(check_horizon(3, 0.05, &HorizonRule::Factor(2f64.powi(32))).is_err());
        assert!(check_horizon(2, 0.05, &HorizonRule::Radius(2f64.powi(32))).is_err());
        // NaN counts are refused, not waved through by a false comparison
        assert!(check_horizon(2, 0.05, &HorizonRule::Radius(f64::INFINITY)).is_err());
    }
}
