//! The plot module as a report writer meets it: every kind of plot writes a PNG of the right
//! size and an SVG with its labels, colours land where the values are, bad data is a typed
//! error; and `peritherm plot` on small 2D and 3D runs.

use crate::common::case::CaseToml;
use crate::common::cli::peritherm;
use peritherm::math::{Point, Vector};
use peritherm::plot::{
    convergence_plot, field_map, line_plot, ColourMap, FieldMap, Labels, Legend, Series, Style,
};
use peritherm::Error;
use std::path::Path;

/// Width and height from a PNG's IHDR chunk, after checking the signature.
fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "{}", path.display());
    assert_eq!(&b[12..16], b"IHDR");
    let be = |k: usize| u32::from_be_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
    (be(16), be(20))
}

/// Decoded RGB pixels of a PNG.
fn pixels(path: &Path) -> image::RgbImage {
    image::open(path).unwrap().to_rgb8()
}

/// Reads `<stem>.svg` after checking both files exist and are not empty.
fn outputs(stem: &Path) -> String {
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    assert!(std::fs::metadata(&svg).unwrap().len() > 1000);
    std::fs::read_to_string(svg).unwrap()
}

/// PD markers against reference lines at two times, and the error along the line.
#[test]
fn line_plot_writes_png_and_svg_with_labels() {
    let dir = tempfile::tempdir().unwrap();
    let xs: Vec<f64> = (0..=20).map(|i| i as f64 * 0.05).collect();
    let mut series = Vec::new();
    for (k, t) in [1.0f64, 2.0].iter().enumerate() {
        let exact: Vec<(f64, f64)> = xs.iter().map(|&x| (x, 100.0 * (-x / t).exp())).collect();
        let pd: Vec<(f64, f64)> = exact.iter().map(|&(x, y)| (x, y + 0.5)).collect();
        series.push(Series::new(format!("reference, t = {t} s"), exact).colour(k));
        series.push(
            Series::new(format!("PD, t = {t} s"), pd)
                .style(Style::Markers)
                .colour(k),
        );
    }
    series.push(Series::new("dashed", vec![(0.0, 10.0), (1.0, 20.0)]).style(Style::Dashed));
    series.push(Series::new("", vec![(0.0, 30.0), (1.0, 40.0)]).style(Style::LineMarkers));
    let stem = dir.path().join("probe");
    let labels = Labels::new("Probe line y = 0", "x (m)", "Temperature (°C)");
    line_plot(&stem, &labels, &series, Legend::UpperRight).unwrap();
    let svg = outputs(&stem);
    assert_eq!(png_size(&stem.with_extension("png")), (900, 600));
    for text in [
        "x (m)",
        "Temperature (°C)",
        "Probe line y = 0",
        "PD, t = 2 s",
    ] {
        assert!(svg.contains(text), "SVG lacks `{text}`");
    }
    // text is rasterised into the PNG: dark pixels left of the plotting area (the y labels)
    let img = pixels(&stem.with_extension("png"));
    let dark = (0..80)
        .flat_map(|x| (100..500).map(move |y| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x, y).0.iter().all(|&c| c < 100))
        .count();
    assert!(dark > 50, "{dark} dark pixels where the y labels are");
}

/// Two series on log–log axes: the rates come back and appear in the legend.
#[test]
fn convergence_plot_fits_and_labels_rates() {
    let dir = tempfile::tempdir().unwrap();
    let deltas = [1e-3, 5e-4, 2.5e-4, 1.25e-4];
    let a: Vec<(f64, f64)> = deltas.iter().map(|&d| (d, 3.0 * d * d)).collect();
    let b: Vec<(f64, f64)> = deltas.iter().map(|&d| (d, 0.2 * d.powf(1.07))).collect();
    let stem = dir.path().join("conv.delta");
    let labels = Labels::new("δ-convergence", "δ (m)", "eq 13 error (–)");
    let laws = convergence_plot(
        &stem,
        &labels,
        &[Series::new("m = 4", a), Series::new("m = 6.5", b).colour(1)],
        Legend::LowerRight,
    )
    .unwrap();
    assert!((laws[0].rate - 2.0).abs() < 1e-12 && (laws[1].rate - 1.07).abs() < 1e-12);
    let png = dir.path().join("conv.delta.png");
    assert_eq!(png_size(&png), (900, 600));
    let svg = std::fs::read_to_string(dir.path().join("conv.delta.svg")).unwrap();
    for text in [
        "δ (m)",
        "eq 13 error (–)",
        "m = 4 (rate 2.00)",
        "m = 6.5 (rate 1.07)",
    ] {
        assert!(svg.contains(text), "SVG lacks `{text}`");
    }
}

/// A hot node is drawn red and a cold one blue, where they are; the damage map uses the
/// sequential ramp; axes, colour-bar label and arrows' note are in the SVG.
#[test]
fn field_map_colours_nodes_where_they_are() {
    let dir = tempfile::tempdir().unwrap();
    let pos = [Point::new(0.0, 0.0, 0.0), Point::new(1.0, 0.0, 0.0)];
    let theta = [100.0, 0.0];
    let spacing = [1.0, 1.0];
    let flux = [Vector::new(-5.0, 0.0, 0.0), Vector::new(-5.0, 0.0, 0.0)];
    let cracks = [[Point::new(0.5, -0.5, 0.0), Point::new(0.5, 0.5, 0.0)]];
    let regions = [0, 1];
    let mut map = FieldMap::new(&pos, &theta, &spacing);
    map.title = "two nodes".into();
    map.quantity = "Temperature (°C)".into();
    map.cracks = &cracks;
    map.regions = Some(&regions);
    map.flux = Some(&flux);
    let stem = dir.path().join("map");
    field_map(&stem, &map).unwrap();
    let svg = outputs(&stem);
    for text in [
        "x (m)",
        "y (m)",
        "Temperature (°C)",
        "two nodes",
        "max 100",
        "W/m²",
    ] {
        assert!(svg.contains(text), "SVG lacks `{text}`");
    }
    let img = pixels(&stem.with_extension("png"));
    assert_eq!(img.dimensions(), png_size(&stem.with_extension("png")));
    // mean column of the exactly hot and exactly cold pixels
    let where_is = |c: [u8; 3]| {
        let xs: Vec<u32> = img
            .enumerate_pixels()
            .filter(|(_, _, p)| p.0 == c)
            .map(|(x, _, _)| x)
            .collect();
        (
            xs.len(),
            xs.iter().map(|&x| x as f64).sum::<f64>() / xs.len().max(1) as f64,
        )
    };
    let (hot, hot_x) = where_is([190, 30, 40]);
    let (cold, cold_x) = where_is([40, 70, 200]);
    assert!(
        hot > 20_000 && cold > 20_000,
        "{hot} red and {cold} blue pixels"
    );
    assert!(
        hot_x + 200.0 < cold_x,
        "red at x ≈ {hot_x} px, blue at {cold_x} px"
    );

    let damage = [0.0, 1.0];
    let mut map = FieldMap::new(&pos, &damage, &spacing);
    map.colour_map = ColourMap::Sequential;
    map.range = Some((0.0, 1.0));
    map.quantity = "Damage (–)".into();
    let stem = dir.path().join("damage");
    field_map(&stem, &map).unwrap();
    assert!(outputs(&stem).contains("Damage (–)"));
    let img = pixels(&stem.with_extension("png"));
    let count = |c: [u8; 3]| img.pixels().filter(|p| p.0 == c).count();
    assert!(count([255, 255, 204]) > 20_000 && count([128, 0, 38]) > 20_000);
}

/// Empty series, NaN values, zero-size ranges and mismatched lengths are typed errors.
#[test]
fn bad_input_is_a_typed_error() {
    let dir = tempfile::tempdir().unwrap();
    let stem = dir.path().join("bad");
    let labels = Labels::new("t", "x", "y");
    let is_plot = |r: peritherm::Result<()>| match r {
        Err(Error::Plot { message, .. }) => message,
        other => panic!("expected a plot error, got {other:?}"),
    };
    let line = |s: &[Series]| line_plot(&stem, &labels, s, Legend::None);
    let conv = |s: &[Series]| convergence_plot(&stem, &labels, s, Legend::None).map(|_| ());
    assert!(is_plot(line(&[])).contains("no series"));
    assert!(is_plot(line(&[Series::new("a", vec![])])).contains("no points"));
    let nan = Series::new("a", vec![(0.0, 1.0), (1.0, f64::NAN)]);
    assert!(is_plot(line(std::slice::from_ref(&nan))).contains("not finite"));
    let flat = Series::new("a", vec![(2.0, 1.0), (2.0, 3.0)]);
    assert!(is_plot(line(std::slice::from_ref(&flat))).contains("zero size"));
    assert!(is_plot(conv(&[flat])).contains("same"));
    let nan = Series::new("a", vec![(1.0, 1.0), (2.0, f64::NAN)]);
    assert!(is_plot(conv(&[nan])).contains("not finite"));
    let neg = Series::new("a", vec![(1.0, -1.0), (2.0, 3.0)]);
    assert!(is_plot(conv(&[neg])).contains("positive"));
    let single = Series::new("a", vec![(1.0, 1.0)]);
    assert!(is_plot(conv(&[single])).contains("two points"));

    let pos = [Point::new(0.0, 0.0, 0.0), Point::new(1.0, 0.0, 0.0)];
    let ok = [1.0, 2.0];
    let map = |v: &[f64], h: &[f64], range| {
        let mut m = FieldMap::new(&pos, v, h);
        m.range = range;
        field_map(&stem, &m)
    };
    assert!(is_plot(field_map(&stem, &FieldMap::new(&[], &[], &[]))).contains("no nodes"));
    assert!(is_plot(map(&[1.0], &ok, None)).contains("values"));
    assert!(is_plot(map(&[1.0, f64::NAN], &ok, None)).contains("not finite"));
    assert!(is_plot(map(&ok, &[1.0, 0.0], None)).contains("spacing"));
    assert!(is_plot(map(&ok, &ok, Some((5.0, 5.0)))).contains("colour range"));
    // a uniform field is not an error: the colour range is widened around the value
    map(&[3.0, 3.0], &ok, None).unwrap();
    // a file that cannot be written is a plot error too
    let nowhere = dir.path().join("missing").join("plot");
    let good = [Series::new("a", vec![(0.0, 1.0), (1.0, 2.0)])];
    assert!(is_plot(line_plot(&nowhere, &labels, &good, Legend::None)).contains("png"));
}

/// A steel plate 1 × 0.5 of two regions, held at 100 °C on the left: in 2D (thickness 0.1)
/// with a crack, to t = 200 s; in 3D (0.2 thick), uncracked, to t = 1 s.
fn small(dim: usize) -> String {
    let corners = |x: f64, y: f64| {
        if dim == 2 {
            format!("[{x:?}, {y:?}]")
        } else {
            format!("[{x:?}, {y:?}, {:?}]", if y > 0.0 { 0.2 } else { 0.0 })
        }
    };
    let mut c = CaseToml::new(dim).domain(&corners(0.0, 0.0), &corners(1.0, 0.5));
    if dim == 2 {
        c = c.domain_key("thickness = 0.1");
    }
    c = c
        .region("left", "spacing = 0.05", 3.0)
        .region_key(&format!("min = {}", corners(0.0, 0.0)))
        .region_key(&format!("max = {}", corners(0.5, 0.5)))
        .region("right", "spacing = 0.05", 3.0)
        .region_key(&format!("min = {}", corners(0.5, 0.0)))
        .region_key(&format!("max = {}", corners(1.0, 0.5)))
        .material("steel", 50.0, 7850.0, 420.0);
    if dim == 2 {
        c = c.section("[[crack]]\npoints = [[0.3, 0.25], [0.7, 0.25]]");
    }
    c = c.section("[boundary.x_min]\ntype = \"temperature\"\nmethod = \"mirror\"\nvalue = 100.0");
    if dim == 2 {
        c = c.end(200.0).time_key("outputs = [100.0, 200.0]");
    }
    c.text()
}

/// `peritherm plot` on a cracked 2D run writes temperature and damage maps per output; on a
/// 3D run it points at the VTK files.
#[test]
fn cli_plot_writes_maps_and_refuses_3d() {
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("small.toml");
    std::fs::write(&case, small(2)).unwrap();
    let out = dir.path().join("out");
    let o = peritherm(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = peritherm(&["plot", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for k in 1..=2 {
        for kind in ["map", "damage"] {
            let stem = out.join(format!("{kind}_{k}"));
            let svg = outputs(&stem);
            assert!(svg.contains("x (m)"));
        }
        let svg = std::fs::read_to_string(out.join(format!("map_{k}.svg"))).unwrap();
        assert!(svg.contains("Temperature (°C)") && svg.contains("Arrows: heat flux"));
    }

    let case3 = dir.path().join("cube.toml");
    std::fs::write(&case3, small(3)).unwrap();
    let out3 = dir.path().join("out3");
    let o = peritherm(&[
        "run",
        case3.to_str().unwrap(),
        "--out",
        out3.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = peritherm(&["plot", out3.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("2D") && err.contains(".vtu"), "{err}");
}

/// The isoline of a field that is linear on each cell is exact: for θ = 3x + y on a
/// cell-centred lattice, every segment of θ = 1.7 has both ends on the line 3x + y = 1.7
/// (1e-12: interpolation round-off), and the segments join up to the line's length across
/// the lattice's convex hull (marching squares covers every cell the line crosses).
#[test]
fn isoline_of_a_linear_field_lies_on_the_line() {
    use peritherm::plot::isoline;
    let h = 0.05;
    let mut pos = Vec::new();
    for j in 0..20 {
        for i in 0..20 {
            pos.push(Point::new((i as f64 + 0.5) * h, (j as f64 + 0.5) * h, 0.0));
        }
    }
    let value: Vec<f64> = pos.iter().map(|p| 3.0 * p.x + p.y).collect();
    let spacing = vec![h; pos.len()];
    let segs = isoline(&pos, &value, &spacing, 1.7);
    assert!(!segs.is_empty());
    let mut length = 0.0;
    for s in &segs {
        for p in s {
            assert!((3.0 * p.x + p.y - 1.7).abs() < 1e-12);
        }
        length += (s[1] - s[0]).norm();
    }
    // the line crosses y ∈ [0.025, 0.975] between the outer node rows: Δy = 0.95, Δx = Δy/3
    let expected = 0.95 * (1.0f64 + 1.0 / 9.0).sqrt();
    assert!((length - expected).abs() < 1e-9, "{length} vs {expected}");
}
