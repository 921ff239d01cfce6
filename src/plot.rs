//! Temperature maps of 2D runs as PNG images (plotters): every node a square of its spacing,
//! coloured blue (coldest) through white to red (hottest), with the cracks drawn in black.

use crate::error::{Error, Result};
use crate::math::Point;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::path::Path;

/// Width and height of a map in pixels.
const SIZE: u32 = 800;

/// Blue–white–red colour of `v` in `lo..hi`.
fn colour(v: f64, lo: f64, hi: f64) -> RGBColor {
    let s = if hi > lo {
        ((v - lo) / (hi - lo)).clamp(0.0, 1.0)
    } else {
        0.5
    };
    let ramp = |a: f64, b: f64, t: f64| (a + (b - a) * t).round() as u8;
    if s < 0.5 {
        let t = s / 0.5;
        RGBColor(
            ramp(40.0, 255.0, t),
            ramp(70.0, 255.0, t),
            ramp(200.0, 255.0, t),
        )
    } else {
        let t = (s - 0.5) / 0.5;
        RGBColor(
            ramp(255.0, 190.0, t),
            ramp(255.0, 30.0, t),
            ramp(255.0, 40.0, t),
        )
    }
}

/// Draws the map of one field to `path` (PNG): nodes at `pos` with spacings `spacing`,
/// temperatures coloured over `range`, and `cracks` as black segments.
pub fn temperature_map(
    path: &Path,
    pos: &[Point],
    theta: &[f64],
    spacing: &[f64],
    range: (f64, f64),
    cracks: &[[Point; 2]],
) -> Result<()> {
    let fail = |e: String| Error::Io {
        path: path.to_path_buf(),
        error: std::io::Error::other(e),
    };
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (p, h) in pos.iter().zip(spacing) {
        x0 = x0.min(p.x - h / 2.0);
        x1 = x1.max(p.x + h / 2.0);
        y0 = y0.min(p.y - h / 2.0);
        y1 = y1.max(p.y + h / 2.0);
    }
    let aspect = (y1 - y0) / (x1 - x0);
    let (w, h) = if aspect <= 1.0 {
        (SIZE, ((SIZE as f64 * aspect).round() as u32).max(1))
    } else {
        (((SIZE as f64 / aspect).round() as u32).max(1), SIZE)
    };
    let root = BitMapBackend::new(path, (w, h)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(e.to_string()))?;
    let area = root.apply_coord_spec(Cartesian2d::<RangedCoordf64, RangedCoordf64>::new(
        x0..x1,
        y1..y0,
        (0..w as i32, 0..h as i32),
    ));
    for ((p, t), d) in pos.iter().zip(theta).zip(spacing) {
        let r = d / 2.0;
        area.draw(&Rectangle::new(
            [(p.x - r, p.y - r), (p.x + r, p.y + r)],
            colour(*t, range.0, range.1).filled(),
        ))
        .map_err(|e| fail(e.to_string()))?;
    }
    for c in cracks {
        area.draw(&PathElement::new(
            vec![(c[0].x, c[0].y), (c[1].x, c[1].y)],
            BLACK.stroke_width(3),
        ))
        .map_err(|e| fail(e.to_string()))?;
    }
    root.present().map_err(|e| fail(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::colour;

    /// The ends and the middle of the colour ramp.
    #[test]
    fn ramp_ends() {
        assert_eq!(
            colour(-1.0, -1.0, 1.0),
            plotters::style::RGBColor(40, 70, 200)
        );
        assert_eq!(
            colour(0.0, -1.0, 1.0),
            plotters::style::RGBColor(255, 255, 255)
        );
        assert_eq!(
            colour(5.0, -1.0, 1.0),
            plotters::style::RGBColor(190, 30, 40)
        );
    }
}
