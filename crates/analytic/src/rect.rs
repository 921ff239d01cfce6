//! Rectangles and boxes: separable products of the unit slab series of each axis, the square
//! with all edges held (Bobaru & Duangpanya 2012, Example 1) and the rectangle, box or bar
//! with each face held or insulated ([`AxisEnds`](crate::AxisEnds)).

use crate::series::{axis_factor, slab};
use crate::Reference;

impl Reference {
    /// A [`Reference::SquareFixedEdges`] at x, y, t: the product of two slab series, °C.
    pub(crate) fn square_fixed_edges(&self, x: f64, y: f64, t: f64) -> f64 {
        let Reference::SquareFixedEdges {
            x0,
            y0,
            length: l,
            diffusivity: a,
            edge,
            initial,
        } = *self
        else {
            return f64::NAN;
        };
        edge + (initial - edge) * slab(x - x0, l, a, t) * slab(y - y0, l, a, t)
    }

    /// A [`Reference::BoxFixedFaces`] at (x, y, z), t: the product of the axes' unit factors,
    /// °C.
    pub(crate) fn box_fixed_faces(&self, x: f64, y: f64, z: f64, t: f64) -> f64 {
        let Reference::BoxFixedFaces {
            ref min,
            ref size,
            ref ends,
            diffusivity: a,
            edge,
            initial,
        } = *self
        else {
            return f64::NAN;
        };
        let u = (0..ends.len().min(3))
            .map(|k| axis_factor(ends[k], [x, y, z][k] - min[k], size[k], a, t));
        edge + (initial - edge) * u.product::<f64>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::AxisEnds;

    /// The square reproduces its initial and edge data (tolerance from truncation).
    #[test]
    fn square_meets_its_data() {
        let sq = Reference::SquareFixedEdges {
            x0: 0.0,
            y0: 0.0,
            length: 1.0,
            diffusivity: 1.14,
            edge: 0.0,
            initial: 40.0,
        };
        assert!((sq.eval(0.5, 0.5, 0.0, 1e-7) - 40.0).abs() < 1e-3);
        assert!(sq.eval(0.0, 0.3, 0.0, 0.01).abs() < 1e-12);
    }

    /// The box series meets its data: held faces at the edge value, a zero normal derivative
    /// at insulated faces (one-sided difference, h = 1e-6), the initial value inside at small
    /// t, an insulated axis contributing nothing, and the product of per-axis slab factors.
    #[test]
    fn box_series_meets_its_data() {
        let ends = vec![AxisEnds::FixedBoth, AxisEnds::FixedLow, AxisEnds::FixedHigh];
        let b = Reference::BoxFixedFaces {
            min: vec![1.0, -1.0, 0.0],
            size: vec![2.0, 1.0, 0.5],
            ends,
            diffusivity: 0.5,
            edge: -5.0,
            initial: 20.0,
        };
        let t = 0.02;
        for p in [
            [1.0, -0.5, 0.2],
            [3.0, -0.5, 0.2],
            [2.0, -1.0, 0.2],
            [2.0, -0.5, 0.5],
        ] {
            assert!((b.eval(p[0], p[1], p[2], t) + 5.0).abs() < 1e-9, "{p:?}");
        }
        let h = 1e-6;
        let dy = (b.eval(2.0, 0.0, 0.2, t) - b.eval(2.0, -h, 0.2, t)) / h;
        let dz = (b.eval(2.0, -0.5, h, t) - b.eval(2.0, -0.5, 0.0, t)) / h;
        assert!(dy.abs() < 1e-3 && dz.abs() < 1e-3, "{dy} {dz}");
        assert!((b.eval(2.0, -0.5, 0.25, 1e-9) - 20.0).abs() < 1e-6);
        let x_only = Reference::BoxFixedFaces {
            min: vec![1.0, -1.0],
            size: vec![2.0, 1.0],
            ends: vec![AxisEnds::FixedBoth, AxisEnds::Insulated],
            diffusivity: 0.5,
            edge: 0.0,
            initial: 1.0,
        };
        let bar = Reference::BarFixedEnds {
            x0: 1.0,
            length: 2.0,
            diffusivity: 0.5,
            left: 0.0,
            right: 0.0,
            initial: 1.0,
        };
        for x in [1.1, 1.7, 2.5] {
            let (u, v) = (x_only.eval(x, 7.0, 0.0, t), bar.eval(x, 0.0, 0.0, t));
            assert!((u - v).abs() < 1e-12, "{u} vs {v}");
        }
        assert_eq!(x_only.depends_on(), [true, false, false]);
        assert_eq!(b.depends_on(), [true, true, true]);
    }
}
