//! Measures that compare a run with a classical solution (formulation §9).

use crate::analytic::Reference;
use crate::cloud::Cloud;
use crate::output::Comparison;

/// Compares the body temperatures with `reference` at time `t`; `line_y` selects the
/// probe line of seed 003 eq 13 (nodes within half a spacing of y = line_y).
pub fn compare(
    cloud: &Cloud,
    theta: &[f64],
    reference: &Reference,
    line_y: Option<f64>,
    t: f64,
) -> Comparison {
    let n = cloud.n_body;
    let classical: Vec<f64> = (0..n)
        .map(|i| reference.eval(cloud.pos[i].x, cloud.pos[i].y, t))
        .collect();
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
    }
}
