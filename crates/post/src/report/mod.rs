//! Measures that compare a run with a classical solution (theory §9), and the report
//! pages that show them ([`page`]).

pub mod page;

use crate::error::{Error, IoError, Result};
use peritherm_core::cloud::Cloud;
use peritherm_core::crack::Cutter;
use peritherm_core::math::Point;
use peritherm_core::spatial::PointIndex;
use peritherm_io::case::{ReferenceSource, ReferenceSpec};
use peritherm_io::output::{Comparison, Probe};
use peritherm_io::reference::covered_box;
use rayon::prelude::*;

/// The classical temperatures at the body nodes of `cloud` at time `t`, °C: the analytical
/// series evaluated there, or the reference table interpolated (linear least squares over its
/// nearest points, never across `cracks`; see [`field_difference`]). A table that does not
/// cover every node is an error naming it.
pub fn classical_at(
    cloud: &Cloud,
    source: &ReferenceSource,
    t: f64,
    cracks: &[Cutter],
) -> Result<Vec<f64>> {
    let values = classical_values(cloud, source, t, cracks)?;
    // a NaN or infinite reference would compare as an exact match (NaN > x is false)
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(values),
        Some(i) => {
            let p = cloud.pos[i];
            let (file, key) = match source {
                ReferenceSource::Table(table) => (table.path.clone(), format!("t = {t}")),
                _ => (Default::default(), "reference.solution".to_string()),
            };
            let message = format!(
                "the reference is {} at the node ({}, {}, {}) at t = {t} s; check its parameters",
                values[i], p.x, p.y, p.z
            );
            Err(match source {
                ReferenceSource::Table(_) => IoError::Case { file, key, message }.into(),
                _ => Error::model(key, message),
            })
        }
    }
}

/// [`classical_at`] before the check that every value is finite.
fn classical_values(
    cloud: &Cloud,
    source: &ReferenceSource,
    t: f64,
    cracks: &[Cutter],
) -> Result<Vec<f64>> {
    let nodes = &cloud.pos[..cloud.n_body];
    match source {
        ReferenceSource::Analytic(r) => Ok(r.eval_many(nodes, t)),
        ReferenceSource::Fem(_) => Err(Error::model(
            "reference.fem",
            "the FEM reference is solved (run::resolve_reference) before it is compared",
        )),
        ReferenceSource::Table(table) => {
            let bad = |message: String| {
                Error::Io(IoError::Case {
                    file: table.path.clone(),
                    key: format!("t = {t}"),
                    message,
                })
            };
            let snap = table
                .at(t)
                .ok_or_else(|| bad("no rows at this output time".into()))?;
            let (lo, hi) = covered_box(&snap.pos, cloud.dim);
            if let Some(p) = nodes
                .iter()
                .find(|p| (0..cloud.dim).any(|a| p[a] < lo[a] || p[a] > hi[a]))
            {
                return Err(bad(format!(
                    "does not cover the node at ({}, {}, {}) m: its points span ({}, {}, {}) to ({}, {}, {}) m",
                    p.x, p.y, p.z, lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
                )));
            }
            let index = PointIndex::new(&snap.pos);
            Ok(nodes
                .par_iter()
                .map(|x| interpolate(cloud.dim, &index, (&snap.pos, &snap.theta), x, cracks))
                .collect())
        }
    }
}

/// Compares the body temperatures `theta` with the classical ones `classical` (at the body
/// nodes, from [`classical_at`]) at time `t`: over all nodes, along the probe line
/// y = `line_y` (Bobaru & Duangpanya 2012, eq. 13; nodes within half a spacing) and at the body
/// node nearest to the probe point, and the volume-weighted relative L2 error over all nodes. Nodes
/// within
/// `spec.exclude_tips` of a point of `tips` are left out.
pub fn compare(
    cloud: &Cloud,
    theta: &[f64],
    classical: &[f64],
    spec: &ReferenceSpec,
    t: f64,
    tips: &[Point],
) -> Comparison {
    let r = spec.exclude_tips;
    let skip = |i: usize| r > 0.0 && tips.iter().any(|c| (cloud.pos[i] - c).norm() < r);
    let line_y = spec.line_y;
    let n = cloud.n_body;
    let probe = spec.probe.and_then(|target| {
        let i = (0..n).min_by(|&a, &b| {
            let da = (cloud.pos[a] - target).norm();
            let db = (cloud.pos[b] - target).norm();
            da.total_cmp(&db)
        })?;
        let p = cloud.pos[i];
        Some(Probe {
            x: p.x,
            y: p.y,
            peridynamic: theta[i],
            classical: classical[i],
        })
    });
    let mut max_abs: f64 = 0.0;
    let (mut sq_rel, mut n_rel) = (0.0, 0usize);
    let (mut sq, mut cmax) = (0.0, 0.0f64);
    let (mut sq_vol, mut ref_vol) = (0.0, 0.0);
    let (mut num, mut den, mut n_line) = (0.0, 0.0, 0usize);
    let mut n_kept = 0usize;
    for i in 0..n {
        if skip(i) {
            continue;
        }
        n_kept += 1;
        let (c, p) = (classical[i], theta[i]);
        let d = c - p;
        max_abs = max_abs.max(d.abs());
        if c != 0.0 {
            sq_rel += (d / c) * (d / c);
            n_rel += 1;
        }
        sq += d * d;
        sq_vol += cloud.volume[i] * d * d;
        ref_vol += cloud.volume[i] * c * c;
        cmax = cmax.max(c.abs());
        let on_line = match line_y {
            Some(y) => (cloud.pos[i].y - y).abs() <= 0.5 * cloud.spacing[i] * (1.0 + 1e-9),
            None => true,
        };
        if on_line {
            num += d * d;
            den += c * c;
            n_line += 1;
        }
    }
    Comparison {
        time: t,
        max_abs_diff: max_abs,
        mean_sq_rel_diff: if n_rel > 0 {
            sq_rel / n_rel as f64
        } else {
            0.0
        },
        l2_rel_line: if den > 0.0 { (num / den).sqrt() } else { 0.0 },
        l2_rel_volume: if ref_vol > 0.0 {
            (sq_vol / ref_vol).sqrt()
        } else {
            0.0
        },
        epsilon: epsilon((sq / n_kept.max(1) as f64).sqrt(), cmax),
        line_nodes: n_line,
        probe,
    }
}

/// Difference between two node fields of the same body (e.g. a refined and a uniform run).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldDifference {
    /// max |θ_a − θ_b| over the nodes of A, °C.
    pub max_abs: f64,
    /// Mean |θ_a − θ_b| over the nodes of A, °C.
    pub mean_abs: f64,
    /// Node of A where the largest difference occurs, m.
    pub at: Point,
    /// Root mean square of θ_a − θ_b over the nodes of A compared, °C.
    pub rms: f64,
    /// max |θ_b| over the nodes of A compared (B interpolated there), °C.
    pub reference_max_abs: f64,
}

impl FieldDifference {
    /// PCS2022 (doi:10.1007/s42102-022-00092-3), eq. 27 with B as the
    /// reference: ε = rms(θ_b − θ_a) / max |θ_b| (0 when B is zero everywhere), dimensionless.
    pub fn epsilon(&self) -> f64 {
        epsilon(self.rms, self.reference_max_abs)
    }
}

/// PCS2022, eq. 27 from its two parts: ε = rms / max |T_ref| (0 when
/// the reference is zero everywhere), dimensionless.
pub fn epsilon(rms: f64, reference_max_abs: f64) -> f64 {
    if reference_max_abs > 0.0 {
        rms / reference_max_abs
    } else {
        0.0
    }
}

/// Compares field A with a reference field B: B is interpolated at each node of A by a
/// linear least-squares fit over B's 8 (3D: 12) nearest nodes that A's node sees without
/// crossing a crack (first-order exact: a linear field interpolates without error). Nodes of
/// A within `exclude.1` (m) of any point of `exclude.0` (e.g. crack tips) are left out.
pub fn field_difference(
    dim: usize,
    a: (&[Point], &[f64]),
    b: (&[Point], &[f64]),
    cracks: &[Cutter],
    exclude: (&[Point], f64),
) -> FieldDifference {
    let index = PointIndex::new(b.0);
    // (|θ_a − θ_b|, θ_b) per node of A, NaN where left out
    let per_node: Vec<(f64, f64)> =
        a.0.par_iter()
            .zip(a.1.par_iter())
            .map(|(x, &ta)| {
                if exclude.0.iter().any(|c| (x - c).norm() < exclude.1) {
                    return (f64::NAN, f64::NAN);
                }
                let tb = interpolate(dim, &index, b, x, cracks);
                ((ta - tb).abs(), tb)
            })
            .collect();
    let (imax, max_abs) = per_node
        .iter()
        .map(|p| p.0)
        .enumerate()
        .fold((0, 0.0), |m, (i, d)| if d > m.1 { (i, d) } else { m });
    let kept: Vec<(f64, f64)> = per_node.into_iter().filter(|d| !d.0.is_nan()).collect();
    let n = kept.len().max(1) as f64;
    FieldDifference {
        max_abs,
        mean_abs: kept.iter().map(|d| d.0).sum::<f64>() / n,
        at: a.0.get(imax).copied().unwrap_or_else(Point::origin),
        rms: (kept.iter().map(|d| d.0 * d.0).sum::<f64>() / n).sqrt(),
        reference_max_abs: kept.iter().map(|d| d.1.abs()).fold(0.0, f64::max),
    }
}

/// Value of field `b` at `x`: the linear least-squares fit over its 8 (3D: 12) nearest points
/// that `x` sees without crossing a crack.
fn interpolate(
    dim: usize,
    index: &PointIndex,
    b: (&[Point], &[f64]),
    x: &Point,
    cracks: &[Cutter],
) -> f64 {
    let k = if dim == 3 { 12 } else { 8 };
    let near: Vec<(usize, f64)> = index
        .nearest(x, 4 * k)
        .into_iter()
        .filter(|(j, _)| !cracks.iter().any(|c| c.cuts(x, &b.0[*j])))
        .take(k)
        .collect();
    fit_at(dim, x, &near, b)
}

/// Value at `x` of the weighted linear least-squares fit through the points `near` of `b`
/// (the nearest one's value when the fit is singular or there are too few points).
fn fit_at(dim: usize, x: &Point, near: &[(usize, f64)], b: (&[Point], &[f64])) -> f64 {
    let Some(&(j0, d0)) = near.first() else {
        return f64::NAN;
    };
    let h = near.last().map_or(1.0, |l| l.1.max(1e-300));
    if d0 <= 1e-9 * h {
        return b.1[j0];
    }
    let n = dim + 1;
    let mut ata = nalgebra::DMatrix::<f64>::zeros(n, n);
    let mut atb = nalgebra::DVector::<f64>::zeros(n);
    for &(j, d) in near {
        let w = 1.0 / (d / h + 0.1).powi(2);
        let dx = b.0[j] - x;
        let mut row = vec![1.0];
        row.extend((0..dim).map(|a| dx[a] / h));
        for r in 0..n {
            atb[r] += w * row[r] * b.1[j];
            for c in 0..n {
                ata[(r, c)] += w * row[r] * row[c];
            }
        }
    }
    if near.len() > n {
        if let Some(sol) = ata.cholesky().map(|c| c.solve(&atb)) {
            return sol[0];
        }
    }
    b.1[j0]
}

#[cfg(test)]
mod tests {
    use super::*;
    use peritherm_analytic::Reference;

    /// PCS2022, eq. 27 by its definition: a field off the reference by
    /// the same d at every node has rms d, so ε = d / max |T_ref| whatever the field; a difference
    /// at one node of N gives rms d/√N. Both for `compare` (classical references) and
    /// `field_difference` (runs: a linear reference field is interpolated exactly). Tolerance:
    /// round-off.
    #[test]
    fn epsilon_is_rms_over_reference_maximum() {
        let n = 11;
        let pos: Vec<Point> = (0..n)
            .map(|i| Point::new(0.1 * i as f64, 0.0, 0.0))
            .collect();
        let cloud = Cloud {
            dim: 1,
            tau: 1.0,
            pos: pos.clone(),
            volume: vec![0.1; n],
            spacing: vec![0.1; n],
            horizon: vec![0.3; n],
            material: vec![0; n],
            region: vec![0; n],
            n_body: n,
            ..Default::default()
        };
        let spec = ReferenceSpec {
            source: ReferenceSource::Analytic(Reference::AnnulusSteady {
                inner_radius: 1.0,
                outer_radius: 2.0,
                inner: 0.0,
                outer: 0.0,
            }),
            line_y: None,
            line_x: None,
            lines_x: Vec::new(),
            lines_y: Vec::new(),
            exclude_tips: 0.0,
            probe: None,
        };
        // reference 300 + 200 x: max |T_ref| = 500 at x = 1
        let reference: Vec<f64> = pos.iter().map(|p| 300.0 + 200.0 * p.x).collect();
        let d = 2.5;
        let shifted: Vec<f64> = reference.iter().map(|t| t + d).collect();
        let c = compare(&cloud, &shifted, &reference, &spec, 1.0, &[]);
        assert!((c.epsilon - d / 500.0).abs() < 1e-15, "{}", c.epsilon);
        let mut one = reference.clone();
        one[3] -= d;
        let c = compare(&cloud, &one, &reference, &spec, 1.0, &[]);
        let want = d / (n as f64).sqrt() / 500.0;
        assert!((c.epsilon - want).abs() < 1e-15, "{} vs {want}", c.epsilon);
        // a negative reference: the maximum is of |T_ref|
        let negative: Vec<f64> = reference.iter().map(|t| -t).collect();
        let moved: Vec<f64> = negative.iter().map(|t| t - d).collect();
        let c = compare(&cloud, &moved, &negative, &spec, 1.0, &[]);
        assert!((c.epsilon - d / 500.0).abs() < 1e-15);
        // field to field: B is the reference, interpolated at A's nodes
        let f = field_difference(1, (&pos, &shifted), (&pos, &reference), &[], (&[], 0.0));
        assert!((f.rms - d).abs() < 1e-12, "{}", f.rms);
        assert!((f.reference_max_abs - 500.0).abs() < 1e-12);
        assert!((f.epsilon() - d / 500.0).abs() < 1e-14);
        assert_eq!(epsilon(1.0, 0.0), 0.0);
    }

    /// The relative L2 error weighs each node by its volume: one node of volume 3 and three
    /// of volume 1, all off by the same fraction f, give f; an error on the heavy node alone
    /// counts √3 times one on a light node alone.
    #[test]
    fn relative_l2_is_volume_weighted() {
        let pos: Vec<Point> = (0..4).map(|i| Point::new(i as f64, 0.0, 0.0)).collect();
        let cloud = Cloud {
            dim: 1,
            tau: 1.0,
            pos,
            volume: vec![3.0, 1.0, 1.0, 1.0],
            spacing: vec![1.0; 4],
            horizon: vec![3.0; 4],
            material: vec![0; 4],
            region: vec![0; 4],
            n_body: 4,
            ..Default::default()
        };
        let spec = ReferenceSpec {
            source: ReferenceSource::Analytic(Reference::AnnulusSteady {
                inner_radius: 1.0,
                outer_radius: 2.0,
                inner: 0.0,
                outer: 0.0,
            }),
            line_y: None,
            line_x: None,
            lines_x: Vec::new(),
            lines_y: Vec::new(),
            exclude_tips: 0.0,
            probe: None,
        };
        let reference = vec![2.0, 5.0, -1.0, 4.0];
        let scaled: Vec<f64> = reference.iter().map(|t| t * 1.02).collect();
        let c = compare(&cloud, &scaled, &reference, &spec, 1.0, &[]);
        assert!(
            (c.l2_rel_volume - 0.02).abs() < 1e-14,
            "{}",
            c.l2_rel_volume
        );
        let norm = (3.0f64 * 4.0 + 25.0 + 1.0 + 16.0).sqrt();
        let mut heavy = reference.clone();
        heavy[0] += 0.1;
        let mut light = reference.clone();
        light[1] += 0.1;
        let h = compare(&cloud, &heavy, &reference, &spec, 1.0, &[]).l2_rel_volume;
        let l = compare(&cloud, &light, &reference, &spec, 1.0, &[]).l2_rel_volume;
        assert!((h - 0.1 * 3f64.sqrt() / norm).abs() < 1e-14, "{h}");
        assert!((l - 0.1 / norm).abs() < 1e-14, "{l}");
    }
}
