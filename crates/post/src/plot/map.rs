//! Maps of a 2D node cloud: every node a square of its spacing coloured by a value, with a
//! colour bar, axes, optional region outlines, crack segments and heat-flux arrows.

use super::{
    axis_ticks, extent, plot_error, render, widen, Chart, ColourMap, DrawError, Figure, FONT,
};
use crate::error::Result;
use peritherm_core::math::{Point, Vector};
use peritherm_core::spatial::PointIndex;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Width of the colour-bar column, pixels.
const BAR: u32 = 150;
/// Height of the title strip, pixels.
const TITLE: u32 = 44;
/// Height of the note strip under a map with arrows, pixels.
const NOTE: u32 = 30;
/// Margin of the map chart, pixels.
const MARGIN: u32 = 12;
/// Height of the x-label area, pixels.
const XL: u32 = 55;
/// Width of the y-label area, pixels.
const YL: u32 = 90;

/// What to draw on a map; build with [`FieldMap::new`] and set the optional fields.
#[derive(Clone, Debug)]
pub struct FieldMap<'a> {
    /// Node positions (x and y are drawn), in `length_unit`.
    pub pos: &'a [Point],
    /// The value coloured at each node (°C for temperature, 0..1 for damage).
    pub value: &'a [f64],
    /// Node spacing Δ (side of each square), in `length_unit`.
    pub spacing: &'a [f64],
    /// Title above the map.
    pub title: String,
    /// Colour-bar label with its unit, e.g. "Temperature (°C)".
    pub quantity: String,
    /// Unit of the axes ("m" by default).
    pub length_unit: String,
    /// Colour map (diverging by default).
    pub colour_map: ColourMap,
    /// Value range of the colours (default: the values' own range).
    pub range: Option<(f64, f64)>,
    /// Crack segments, drawn as thick black lines.
    pub cracks: &'a [[Point; 2]],
    /// Region index of each node: the boundaries between regions are outlined.
    pub regions: Option<&'a [u32]>,
    /// Heat flux of each node (unit `flux_unit`): arrows on a coarse grid of nodes.
    pub flux: Option<&'a [Vector]>,
    /// Unit of the flux, for the note under the map ("W/m²" by default).
    pub flux_unit: String,
    /// Arrow grid cells along the longer side of the map (20 by default).
    pub arrows: usize,
    /// Isoline segments (e.g. a phase front, [`isoline`]), drawn as thin dark-red lines.
    pub isolines: &'a [[Point; 2]],
    /// Side of each node's square in spacings; None (the default): 1 on a lattice cloud,
    /// [`IRREGULAR_SQUARE`] when the nearest neighbours are not at distance Δ (mesh clouds),
    /// so that the squares leave no holes.
    pub square: Option<f64>,
}

/// Segments of the isoline `value = level` by marching squares over the lattice cells of a 2D
/// cloud: every square of four nodes at (x, y), (x + Δ, y), (x, y + Δ), (x + Δ, y + Δ) with
/// one spacing Δ, the crossing on each edge between a node at or below `level` and one above
/// it placed by linear interpolation (so a phase front at T_f bounds the liquid, whose nodes
/// alone lie above T_f). Cells that are not such squares (region interfaces, mesh clouds) are
/// skipped.
pub fn isoline(pos: &[Point], value: &[f64], spacing: &[f64], level: f64) -> Vec<[Point; 2]> {
    use std::collections::HashMap;
    // half-spacing units: cell-centred nodes sit at odd multiples of Δ/2, never on a rounding tie
    let key = |p: &Point, h: f64| {
        (
            (2.0 * p.x / h).round() as i64,
            (2.0 * p.y / h).round() as i64,
            h.to_bits(),
        )
    };
    let index: HashMap<(i64, i64, u64), usize> = pos
        .iter()
        .zip(spacing)
        .enumerate()
        .map(|(i, (p, &h))| (key(p, h), i))
        .collect();
    let mut out = Vec::new();
    for (i, (p, &h)) in pos.iter().zip(spacing).enumerate() {
        let (a, b, hb) = key(p, h);
        let corner = |da: i64, db: i64| index.get(&(a + da, b + db, hb)).copied();
        let (Some(i1), Some(i2), Some(i3)) = (corner(2, 0), corner(2, 2), corner(0, 2)) else {
            continue;
        };
        // corners counter-clockwise; the crossings on the edges whose ends straddle `level`
        let c = [i, i1, i2, i3];
        let mut cross = Vec::with_capacity(4);
        for e in 0..4 {
            let (u, v) = (c[e], c[(e + 1) % 4]);
            let (fu, fv) = (value[u] - level, value[v] - level);
            if (fu <= 0.0) != (fv <= 0.0) {
                let w = fu / (fu - fv);
                cross.push(pos[u] + (pos[v] - pos[u]) * w);
            }
        }
        for pair in cross.chunks_exact(2) {
            out.push([pair[0], pair[1]]);
        }
    }
    out
}

/// Side of the squares, in spacings, on clouds that are not lattices.
pub const IRREGULAR_SQUARE: f64 = 1.6;

/// 1 if (almost) every node's nearest neighbour is at its spacing Δ (a lattice), else
/// [`IRREGULAR_SQUARE`].
fn square_side(pos: &[Point], spacing: &[f64]) -> f64 {
    let flat: Vec<Point> = pos.iter().map(|p| Point::new(p.x, p.y, 0.0)).collect();
    let index = PointIndex::new(&flat);
    let step = (flat.len() / 2000).max(1);
    let (mut lattice, mut seen) = (0usize, 0usize);
    for i in (0..flat.len()).step_by(step) {
        let Some(&(_, d)) = index.nearest(&flat[i], 2).get(1) else {
            continue;
        };
        seen += 1;
        if (d - spacing[i]).abs() <= 1e-6 * spacing[i] {
            lattice += 1;
        }
    }
    if seen == 0 || lattice as f64 >= 0.9 * seen as f64 {
        1.0
    } else {
        IRREGULAR_SQUARE
    }
}

impl<'a> FieldMap<'a> {
    /// A map of `value` at nodes `pos` with spacings `spacing`, no title, diverging colours.
    pub fn new(pos: &'a [Point], value: &'a [f64], spacing: &'a [f64]) -> Self {
        FieldMap {
            pos,
            value,
            spacing,
            title: String::new(),
            quantity: String::new(),
            length_unit: "m".into(),
            colour_map: ColourMap::Diverging,
            range: None,
            cracks: &[],
            isolines: &[],
            regions: None,
            flux: None,
            flux_unit: "W/m²".into(),
            arrows: 20,
            square: None,
        }
    }
}

/// Draws `map` into `<stem>.png` and `<stem>.svg`, with equal scales on both axes.
pub fn field_map(stem: &Path, map: &FieldMap) -> Result<()> {
    check_map(stem, map)?;
    let n = map.pos.len();
    let range = match map.range {
        Some((lo, hi)) if !(lo.is_finite() && hi.is_finite() && hi > lo) => {
            return Err(plot_error(
                stem,
                format!("colour range {lo}..{hi} is empty or not finite"),
            ))
        }
        Some(r) => r,
        None => {
            let (lo, hi) = extent(map.value.iter().copied());
            widen(lo, hi)
        }
    };
    if map.square.is_some_and(|c| !(c.is_finite() && c > 0.0)) {
        return Err(plot_error(stem, "the square size must be positive"));
    }
    let side = map
        .square
        .unwrap_or_else(|| square_side(map.pos, map.spacing));
    let r = |i: usize| map.spacing[i] / 2.0;
    let x = extent((0..n).flat_map(|i| [map.pos[i].x - r(i), map.pos[i].x + r(i)]));
    let y = extent((0..n).flat_map(|i| [map.pos[i].y - r(i), map.pos[i].y + r(i)]));
    // the plotting area aims at 760 px along the longer side, at least 240 px along the other
    let aspect = (y.1 - y.0) / (x.1 - x.0);
    let (pw, ph) = if aspect <= 1.0 {
        (760.0, (760.0 * aspect).max(240.0))
    } else {
        ((680.0 / aspect).max(240.0), 680.0)
    };
    let width = pw as u32 + YL + 2 * MARGIN + BAR;
    let note = if map.flux.is_some() { NOTE } else { 0 };
    let height = ph as u32 + TITLE + XL + 2 * MARGIN + note;
    let fig = MapFigure {
        map,
        range,
        x,
        y,
        size: (width, height),
        outlines: map
            .regions
            .map(|reg| outlines(map, reg))
            .unwrap_or_default(),
        side,
    };
    render(stem, &fig)
}

/// Checks that `map` has something to draw: one finite value, position and positive spacing
/// per node, regions and flux (when given) for every node, finite crack ends.
fn check_map(stem: &Path, map: &FieldMap) -> Result<()> {
    let n = map.pos.len();
    if n == 0 {
        return Err(plot_error(stem, "no nodes to draw"));
    }
    if map.value.len() != n || map.spacing.len() != n {
        return Err(plot_error(
            stem,
            format!(
                "{n} positions but {} values and {} spacings",
                map.value.len(),
                map.spacing.len()
            ),
        ));
    }
    if map.regions.is_some_and(|r| r.len() != n) || map.flux.is_some_and(|f| f.len() != n) {
        return Err(plot_error(
            stem,
            format!("regions or flux not given for all {n} nodes"),
        ));
    }
    for i in 0..n {
        let (p, v, h) = (map.pos[i], map.value[i], map.spacing[i]);
        if !(p.x.is_finite() && p.y.is_finite() && v.is_finite() && h.is_finite() && h > 0.0) {
            return Err(plot_error(
                stem,
                format!(
                    "node {i}: position ({}, {}), value {v}, spacing {h}: not finite or spacing not positive",
                    p.x, p.y
                ),
            ));
        }
        if map
            .flux
            .is_some_and(|f| !(f[i].x.is_finite() && f[i].y.is_finite()))
        {
            return Err(plot_error(stem, format!("node {i}: flux is not finite")));
        }
    }
    if map
        .cracks
        .iter()
        .flatten()
        .any(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        return Err(plot_error(stem, "a crack segment has a non-finite end"));
    }
    Ok(())
}

/// Edges of node squares that face a node of another region (region boundaries).
fn outlines(map: &FieldMap, region: &[u32]) -> Vec<[(f64, f64); 2]> {
    let flat: Vec<Point> = map.pos.iter().map(|p| Point::new(p.x, p.y, 0.0)).collect();
    let index = PointIndex::new(&flat);
    let mut out = Vec::new();
    for (i, p) in flat.iter().enumerate() {
        let h = map.spacing[i];
        for (dx, dy) in [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)] {
            let probe = Point::new(p.x + 0.75 * h * dx, p.y + 0.75 * h * dy, 0.0);
            let Some(&(j, d)) = index.nearest(&probe, 1).first() else {
                continue;
            };
            if j != i && region[j] != region[i] && d <= h {
                let (cx, cy) = (p.x + 0.5 * h * dx, p.y + 0.5 * h * dy);
                let (ex, ey) = (0.5 * h * dy.abs(), 0.5 * h * dx.abs());
                out.push([(cx - ex, cy - ey), (cx + ex, cy + ey)]);
            }
        }
    }
    out
}

/// Heat-flux arrows: one node per cell of a coarse grid (the nearest to the cell's centre),
/// length proportional to |q| (the longest 0.8 of a cell); returns the arrows as polylines
/// and the largest |q| among the sampled nodes.
fn arrows(
    map: &FieldMap,
    flux: &[Vector],
    x: (f64, f64),
    y: (f64, f64),
) -> (Vec<Vec<(f64, f64)>>, f64) {
    let (w, h) = (x.1 - x.0, y.1 - y.0);
    let cell = w.max(h) / map.arrows.max(1) as f64;
    let nx = (w / cell).ceil() as usize;
    // per grid cell, the node nearest to the cell's centre
    let mut best: std::collections::HashMap<usize, (usize, f64)> = Default::default();
    for (i, p) in map.pos.iter().enumerate() {
        let a = (((p.x - x.0) / cell).floor().max(0.0) as usize).min(nx.max(1) - 1);
        let b = ((p.y - y.0) / cell).floor().max(0.0) as usize;
        let (cx, cy) = (x.0 + (a as f64 + 0.5) * cell, y.0 + (b as f64 + 0.5) * cell);
        let d = (p.x - cx).hypot(p.y - cy);
        let e = best.entry(b * nx + a).or_insert((i, d));
        if d < e.1 {
            *e = (i, d);
        }
    }
    let mut picked: Vec<usize> = best.values().map(|&(i, _)| i).collect();
    picked.sort_unstable();
    let q = |i: usize| (flux[i].x * flux[i].x + flux[i].y * flux[i].y).sqrt();
    let qmax = picked.iter().map(|&i| q(i)).fold(0.0, f64::max);
    if qmax <= 0.0 {
        return (Vec::new(), 0.0);
    }
    let mut out = Vec::new();
    for i in picked {
        let s = q(i) / qmax;
        if s < 0.03 {
            continue;
        }
        let (ux, uy) = (flux[i].x / q(i), flux[i].y / q(i));
        let len = 0.8 * cell * s;
        let p = map.pos[i];
        let (tx, ty) = (p.x + 0.5 * len * ux, p.y + 0.5 * len * uy);
        out.push(vec![(p.x - 0.5 * len * ux, p.y - 0.5 * len * uy), (tx, ty)]);
        let head = 0.25 * cell * s.sqrt().max(0.4);
        let (c, sn) = (0.45f64.cos(), 0.45f64.sin());
        let back = |sx: f64| {
            let (bx, by) = (-ux * c - sx * uy * sn, -uy * c + sx * ux * sn);
            (tx + head * bx, ty + head * by)
        };
        out.push(vec![back(1.0), (tx, ty), back(-1.0)]);
    }
    (out, qmax)
}

/// A map ready to draw.
struct MapFigure<'a> {
    map: &'a FieldMap<'a>,
    range: (f64, f64),
    x: (f64, f64),
    y: (f64, f64),
    size: (u32, u32),
    outlines: Vec<[(f64, f64); 2]>,
    side: f64,
}

impl Figure for MapFigure<'_> {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawError>
    where
        DB::ErrorType: 'static,
    {
        let map = self.map;
        let w = self.size.0;
        let body = root.titled(&map.title, (FONT, 26))?;
        let (body, note) = if map.flux.is_some() {
            let (b, n) = body.split_vertically(body.dim_in_pixel().1 - NOTE);
            (b, Some(n))
        } else {
            (body, None)
        };
        let (main, bar) = body.split_horizontally(w - BAR);
        // equal scales: widen the shorter data range to the plotting area's aspect
        let build = |x: (f64, f64), y: (f64, f64)| {
            ChartBuilder::on(&main)
                .margin(MARGIN)
                .x_label_area_size(XL)
                .y_label_area_size(YL)
                .build_cartesian_2d(x.0..x.1, y.0..y.1)
        };
        let (pw, ph) = build(self.x, self.y)?.plotting_area().dim_in_pixel();
        let (dx, dy) = (self.x.1 - self.x.0, self.y.1 - self.y.0);
        let per_px = (dx / pw.max(1) as f64).max(dy / ph.max(1) as f64);
        let (cx, cy) = (0.5 * (self.x.0 + self.x.1), 0.5 * (self.y.0 + self.y.1));
        let (hx, hy) = (0.5 * per_px * pw as f64, 0.5 * per_px * ph as f64);
        let (xr, yr) = ((cx - hx, cx + hx), (cy - hy, cy + hy));
        let mut chart = build(xr, yr)?;
        self.draw_squares(&mut chart, per_px)?;
        let grey = RGBColor(70, 70, 70).stroke_width(1);
        chart.draw_series(
            self.outlines
                .iter()
                .map(|s| PathElement::new(s.to_vec(), grey)),
        )?;
        draw_cracks(&mut chart, map.cracks, per_px)?;
        let front = RGBColor(150, 0, 20).stroke_width(2);
        chart.draw_series(
            map.isolines
                .iter()
                .map(|s| PathElement::new(vec![(s[0].x, s[0].y), (s[1].x, s[1].y)], front)),
        )?;
        let mut longest = 0.0;
        if let Some(flux) = map.flux {
            let (lines, qmax) = arrows(map, flux, self.x, self.y);
            longest = qmax;
            let ink = RGBColor(15, 15, 15).stroke_width(2);
            chart.draw_series(lines.into_iter().map(|l| PathElement::new(l, ink)))?;
        }
        draw_axes(&mut chart, &map.length_unit, xr, yr)?;
        let (_, main_y) = chart.plotting_area().get_pixel_range();
        self.draw_colour_bar(&bar, main_y)?;
        if let Some(note) = note {
            let text = if longest > 0.0 {
                format!(
                    "Arrows: heat flux on a coarse grid of nodes, longest |q| = {} {}",
                    super::sci(longest),
                    map.flux_unit
                )
            } else {
                "No arrows: the heat flux is zero at the sampled nodes".to_string()
            };
            let style = TextStyle::from((FONT, 17).into_font()).color(&BLACK);
            note.draw(&Text::new(text, (YL as i32 + MARGIN as i32, 2), style))?;
        }
        Ok(())
    }
}

impl MapFigure<'_> {
    /// The node squares in their colours; `per_px` is the data length of one pixel.
    fn draw_squares<DB: DrawingBackend>(
        &self,
        chart: &mut Chart<DB>,
        per_px: f64,
    ) -> std::result::Result<(), DrawError>
    where
        DB::ErrorType: 'static,
    {
        let map = self.map;
        let (lo, hi) = self.range;
        let pad = 0.5 * per_px; // half a pixel of overlap hides seams between squares
        chart.draw_series((0..map.pos.len()).map(|i| {
            let (p, r) = (map.pos[i], 0.5 * self.side * map.spacing[i] + pad);
            // larger squares than Δ (irregular clouds) stay inside the cloud's box
            let (bx, by) = (self.x, self.y);
            Rectangle::new(
                [
                    ((p.x - r).max(bx.0), (p.y - r).max(by.0)),
                    ((p.x + r).min(bx.1), (p.y + r).min(by.1)),
                ],
                map.colour_map.colour(map.value[i], lo, hi).filled(),
            )
        }))?;
        Ok(())
    }

    /// The colour bar in `bar`, as tall as the map (pixel rows `main_y`) less room for the
    /// min and max labels.
    fn draw_colour_bar<DB: DrawingBackend>(
        &self,
        bar: &DrawingArea<DB, Shift>,
        main_y: std::ops::Range<i32>,
    ) -> std::result::Result<(), DrawError>
    where
        DB::ErrorType: 'static,
    {
        let map = self.map;
        let (lo, hi) = self.range;
        let bar_y = bar.get_pixel_range().1;
        let top = (main_y.start - bar_y.start + 24).max(0) as u32;
        let bottom = (bar_y.end - main_y.end + 24).max(0) as u32;
        let mut cb = ChartBuilder::on(bar)
            .margin_top(top)
            .margin_bottom(bottom)
            .margin_left(14)
            .margin_right(6)
            .right_y_label_area_size(92)
            .build_cartesian_2d(0.0..1.0, lo..hi)?;
        const STRIPS: usize = 200;
        cb.draw_series((0..STRIPS).map(|k| {
            let a = lo + (hi - lo) * k as f64 / STRIPS as f64;
            let b = lo + (hi - lo) * (k + 1) as f64 / STRIPS as f64;
            let c = map.colour_map.colour(0.5 * (a + b), lo, hi);
            Rectangle::new([(0.0, a), (1.0, b)], c.filled())
        }))?;
        cb.draw_series(std::iter::once(Rectangle::new(
            [(0.0, lo), (1.0, hi)],
            BLACK.stroke_width(1),
        )))?;
        let fb = axis_ticks((lo, hi));
        cb.configure_mesh()
            .set_all_tick_mark_size(5)
            .disable_x_axis()
            .disable_mesh()
            .y_labels(8)
            .y_desc(&map.quantity)
            .label_style((FONT, 17))
            .axis_desc_style((FONT, 19))
            .y_label_formatter(&fb)
            .draw()?;
        let (px, py) = cb.plotting_area().get_pixel_range();
        let base = bar.get_base_pixel();
        let style = TextStyle::from((FONT, 17).into_font()).color(&BLACK);
        let x0 = px.start - base.0 - 8;
        bar.draw(&Text::new(
            format!("max {}", short(hi)),
            (x0, py.start - base.1 - 20),
            style.clone(),
        ))?;
        bar.draw(&Text::new(
            format!("min {}", short(lo)),
            (x0, py.end - base.1 + 6),
            style,
        ))?;
        Ok(())
    }
}

/// Cracks as filled bands 4 px wide (thick plotters lines leave pinholes); `per_px` is the
/// data length of one pixel.
fn draw_cracks<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    cracks: &[[Point; 2]],
    per_px: f64,
) -> std::result::Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    chart.draw_series(cracks.iter().filter_map(|c| {
        let (dx, dy) = (c[1].x - c[0].x, c[1].y - c[0].y);
        let len = dx.hypot(dy);
        (len > 0.0).then(|| {
            let (nx, ny) = (-dy / len * 2.0 * per_px, dx / len * 2.0 * per_px);
            let (tx, ty) = (dx / len * per_px, dy / len * per_px);
            let (a, b) = ((c[0].x - tx, c[0].y - ty), (c[1].x + tx, c[1].y + ty));
            Polygon::new(
                vec![
                    (a.0 + nx, a.1 + ny),
                    (b.0 + nx, b.1 + ny),
                    (b.0 - nx, b.1 - ny),
                    (a.0 - nx, a.1 - ny),
                ],
                BLACK.filled(),
            )
        })
    }))?;
    Ok(())
}

/// The x and y axes over the ranges `xr` and `yr`, labelled in `unit`.
fn draw_axes<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    unit: &str,
    xr: (f64, f64),
    yr: (f64, f64),
) -> std::result::Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let (fx, fy) = (axis_ticks(xr), axis_ticks(yr));
    chart
        .configure_mesh()
        .set_all_tick_mark_size(5)
        .disable_mesh()
        .x_desc(format!("x ({unit})"))
        .y_desc(format!("y ({unit})"))
        .label_style((FONT, 18))
        .axis_desc_style((FONT, 20))
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .draw()?;
    Ok(())
}

/// A value in four significant digits, without trailing zeros.
fn short(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 {
        "0".into()
    } else if (1e-2..1e5).contains(&a) {
        let d = (3 - a.log10().floor() as i32).clamp(0, 5) as usize;
        let s = format!("{v:.d$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        super::sci(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Squares of Δ on a lattice, larger on a jittered cloud.
    #[test]
    fn square_side_follows_the_cloud() {
        let lattice: Vec<Point> = (0..100)
            .map(|k| Point::new((k % 10) as f64 * 0.1, (k / 10) as f64 * 0.1, 0.0))
            .collect();
        let h = vec![0.1; 100];
        assert_eq!(square_side(&lattice, &h), 1.0);
        let jittered: Vec<Point> = lattice
            .iter()
            .enumerate()
            .map(|(k, p)| Point::new(p.x + 0.013 * ((k * 7 % 5) as f64 - 2.0), p.y, 0.0))
            .collect();
        assert_eq!(square_side(&jittered, &h), IRREGULAR_SQUARE);
    }
}
