//! Validation of the analytic series a case names as its reference: every parameter finite,
//! every length, diffusivity and material constant a positive number, and the relations
//! between parameters each series needs. It names parameters by their serialised (case-file)
//! keys, so it lives in the IO layer (serde_json) rather than beside the series in
//! [`peritherm_analytic`].

use peritherm_analytic::Reference;

/// Checks a series' parameters before it is evaluated.
pub trait SeriesCheck {
    /// The parameters a series cannot be evaluated with, as a message (`None`: usable).
    fn check(&self) -> Option<String>;
}

impl SeriesCheck for Reference {
    fn check(&self) -> Option<String> {
        check_numbers(self).or_else(|| check_relations(self))
    }
}

/// The serialised keys of the parameters that must be normal positive numbers: lengths,
/// diffusivities and material constants.
fn must_be_positive(name: &str) -> bool {
    [
        "length",
        "diffusivity",
        "radius",
        "density",
        "latent_heat",
        "width",
        "heat_capacity",
        "depth",
        "duration",
        "shape",
    ]
    .iter()
    .any(|k| name.contains(k))
        || name.ends_with("conductivity")
        || name.ends_with("specific_heat")
        || name == "size"
}

/// Every parameter finite (non-finite numbers serialise as null), every length,
/// diffusivity and material constant a normal positive number.
fn check_numbers(r: &Reference) -> Option<String> {
    let value = serde_json::to_value(r).unwrap_or_default();
    for (name, v) in value.as_object().into_iter().flatten() {
        let numbers: Vec<Option<f64>> = match v {
            serde_json::Value::Array(a) if a.iter().any(|x| x.is_string()) => continue,
            serde_json::Value::Array(a) => a.iter().map(|x| x.as_f64()).collect(),
            serde_json::Value::String(_) => continue,
            x => vec![x.as_f64()],
        };
        if numbers.iter().any(|x| x.is_none_or(|x| !x.is_finite())) {
            return Some(format!("{name} must be finite, got {v}"));
        }
        if must_be_positive(name)
            && numbers
                .iter()
                .flatten()
                .any(|x| !(x.is_normal() && *x > 0.0))
        {
            return Some(format!("{name} must be > 0, got {v}"));
        }
    }
    None
}

/// The relations between parameters that a series needs (radii in order, one box entry per
/// axis, a reflectivity below 1, the split inside the plate).
fn check_relations(r: &Reference) -> Option<String> {
    match r {
        Reference::AnnulusSteady {
            inner_radius,
            outer_radius,
            ..
        } if outer_radius <= inner_radius => Some(format!(
            "outer_radius {outer_radius} must exceed inner_radius {inner_radius}"
        )),
        Reference::BoxFixedFaces {
            min,
            size,
            ends,
            diffusivity,
            ..
        } => {
            let d = min.len();
            if !(1..=3).contains(&d) || size.len() != d || ends.len() != d {
                return Some(format!(
                    "min, size and ends need one entry per axis (1 to 3), got {}, {} and {}",
                    d,
                    size.len(),
                    ends.len()
                ));
            }
            if size.iter().any(|l| !(l.is_finite() && *l > 0.0)) {
                return Some(format!("every size must be > 0, got {size:?}"));
            }
            positive("diffusivity", *diffusivity)
        }
        Reference::DiscFixedEdge {
            radius,
            diffusivity,
            ..
        } => positive("radius", *radius).or_else(|| positive("diffusivity", *diffusivity)),
        Reference::FilmLaserPulse { reflectivity, .. } if !(0.0..1.0).contains(reflectivity) => {
            Some(format!(
                "reflectivity must be in [0, 1), got {reflectivity}"
            ))
        }
        Reference::PlatePulseSplit {
            y0, width, split, ..
        } if !(*y0..=y0 + width).contains(split) => Some(format!(
            "split must lie in [y0, y0 + width] = [{y0}, {}], got {split}",
            y0 + width
        )),
        _ => None,
    }
}

/// "`name` must be > 0" unless `v` is a positive finite number.
fn positive(name: &str, v: f64) -> Option<String> {
    (!(v.is_finite() && v > 0.0)).then(|| format!("{name} must be > 0, got {v}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use peritherm_analytic::AxisEnds;

    /// Box and disc parameters that no series has are named.
    #[test]
    fn bad_series_parameters_are_named() {
        let b = Reference::BoxFixedFaces {
            min: vec![0.0, 0.0],
            size: vec![1.0],
            ends: vec![AxisEnds::FixedBoth, AxisEnds::FixedLow],
            diffusivity: 1.0,
            edge: 0.0,
            initial: 1.0,
        };
        assert!(b.check().unwrap().contains("one entry per axis"));
        let d = Reference::DiscFixedEdge {
            radius: -1.0,
            diffusivity: 1.0,
            edge: 0.0,
            initial: 1.0,
        };
        assert!(d.check().unwrap().contains("radius must be > 0"));
        let text = "kind = \"box_fixed_faces\"\nmin = [0.0]\nsize = [1.0]\nends = [\"fixed_low\"]\ndiffusivity = 1.0\nedge = 0.0\ninitial = 1.0\n";
        let r: Reference = toml::from_str(text).unwrap();
        assert_eq!(r.check(), None);
    }

    /// Issue 15: every series' lengths and diffusivities are validated, and every parameter
    /// must be finite (a length of 0 gave NaN, a diffusivity of −1 gave 3.5e169).
    #[test]
    fn every_series_parameter_is_validated() {
        let bar = |length: f64, diffusivity: f64, initial: f64| Reference::BarFixedEnds {
            x0: 0.0,
            length,
            diffusivity,
            left: 0.0,
            right: 0.0,
            initial,
        };
        assert_eq!(bar(1.0, 1.0, 1.0).check(), None);
        assert!(bar(0.0, 1.0, 1.0).check().unwrap().contains("length"));
        assert!(bar(1.0, -1.0, 1.0).check().unwrap().contains("diffusivity"));
        assert!(bar(1.0, 1e-320, 1.0)
            .check()
            .unwrap()
            .contains("diffusivity"));
        assert!(bar(1.0, 1.0, f64::NAN).check().unwrap().contains("initial"));
        let annulus = Reference::AnnulusSteady {
            inner_radius: 2.0,
            outer_radius: 1.0,
            inner: 0.0,
            outer: 1.0,
        };
        assert!(annulus.check().unwrap().contains("outer_radius"));
    }

    /// The laser series' data are accepted (the example that `analytic`'s laser test
    /// checks).
    #[test]
    fn laser_series_data_are_accepted() {
        assert_eq!(Reference::laser_film_example().check(), None);
    }

    /// A split outside the plate's width is named (the example of `analytic`'s split-plate
    /// test, its split moved).
    #[test]
    fn split_outside_the_plate_is_named() {
        let bad = Reference::split_plate_example(6.0, 0.5, 0.0);
        assert!(bad.check().unwrap().contains("split"));
    }
}
