//! Colour maps of field values.

use plotters::style::RGBColor;

/// How values are turned into colours on a map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ColourMap {
    /// Blue (lowest) through white (middle) to red (highest): temperatures.
    #[default]
    Diverging,
    /// Pale yellow (lowest) through orange to dark red (highest): damage and other
    /// one-sided quantities.
    Sequential,
}

impl ColourMap {
    /// Colour of `v` on the range `lo..hi` (clamped to it; the middle colour if `hi <= lo`).
    pub fn colour(self, v: f64, lo: f64, hi: f64) -> RGBColor {
        let s = if hi > lo && v.is_finite() {
            ((v - lo) / (hi - lo)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let stops: &[(u8, u8, u8)] = match self {
            ColourMap::Diverging => &[(40, 70, 200), (255, 255, 255), (190, 30, 40)],
            ColourMap::Sequential => &[
                (255, 255, 204),
                (254, 217, 118),
                (253, 141, 60),
                (227, 26, 28),
                (128, 0, 38),
            ],
        };
        let n = stops.len() - 1;
        let x = s * n as f64;
        let k = (x.floor() as usize).min(n - 1);
        let t = x - k as f64;
        let (a, b) = (stops[k], stops[k + 1]);
        let mix = |p: u8, q: u8| (p as f64 + (q as f64 - p as f64) * t).round() as u8;
        RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
    }
}

#[cfg(test)]
mod tests {
    use super::ColourMap;
    use plotters::style::RGBColor;

    /// The ends and the middle of both ramps.
    #[test]
    fn ramp_ends() {
        let d = ColourMap::Diverging;
        assert_eq!(d.colour(-1.0, -1.0, 1.0), RGBColor(40, 70, 200));
        assert_eq!(d.colour(0.0, -1.0, 1.0), RGBColor(255, 255, 255));
        assert_eq!(d.colour(5.0, -1.0, 1.0), RGBColor(190, 30, 40));
        assert_eq!(d.colour(f64::NAN, -1.0, 1.0), RGBColor(255, 255, 255));
        let s = ColourMap::Sequential;
        assert_eq!(s.colour(0.0, 0.0, 1.0), RGBColor(255, 255, 204));
        assert_eq!(s.colour(0.5, 0.0, 1.0), RGBColor(253, 141, 60));
        assert_eq!(s.colour(1.0, 0.0, 1.0), RGBColor(128, 0, 38));
    }
}
