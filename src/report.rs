//! Measures that compare a run with a classical solution (formulation §9).

use crate::case::ReferenceSpec;
use crate::cloud::Cloud;
use crate::math::Point;
use crate::output::{Comparison, Probe};

/// Compares the body temperatures with the case's reference at time `t`: over all nodes,
/// along the probe line y = `line_y` (seed 003 eq 13; nodes within half a spacing) and at the
/// body node nearest to `probe`.
pub fn compare(cloud: &Cloud, theta: &[f64], spec: &ReferenceSpec, t: f64) -> Comparison {
    let reference = &spec.solution;
    let line_y = spec.line_y;
    let n = cloud.n_body;
    let probe = spec.probe.as_ref().and_then(|c| {
        let target = Point::new(
            c.first().copied().unwrap_or(0.0),
            c.get(1).copied().unwrap_or(0.0),
            c.get(2).copied().unwrap_or(0.0),
        );
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
            classical: reference.eval(p.x, p.y, t),
        })
    });
    let points: Vec<(f64, f64)> = cloud.pos[..n].iter().map(|p| (p.x, p.y)).collect();
    let classical = reference.eval_many(&points, t);
    let mut max_abs: f64 = 0.0;
    let (mut sq_rel, mut n_rel) = (0.0, 0usize);
    let (mut sq, mut cmax) = (0.0, 0.0f64);
    let (mut num, mut den, mut n_line) = (0.0, 0.0, 0usize);
    for i in 0..n {
        let (c, p) = (classical[i], theta[i]);
        let d = c - p;
        max_abs = max_abs.max(d.abs());
        if c != 0.0 {
            sq_rel += (d / c) * (d / c);
            n_rel += 1;
        }
        sq += d * d;
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
        epsilon: if cmax > 0.0 {
            (sq / n as f64).sqrt() / cmax
        } else {
            0.0
        },
        line_nodes: n_line,
        probe,
    }
}
