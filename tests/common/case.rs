//! A case file written from Rust: the blocks every test case repeats (dimension, domain,
//! regions, material, initial field, time) as builder methods, and whatever else the test is
//! about (boundary faces, kernel, cracks, sources, references) as TOML sections appended
//! verbatim. Tests about the TOML text itself (hostile input, key errors) keep their text.
//!
//! ```ignore
//! let model = CaseToml::new(2)
//!     .domain("[0.0, 0.0]", "[1.0, 0.5]")
//!     .region("plate", "spacing = 0.025", 3.0)
//!     .material("m", 2.0, 4.0, 0.5)
//!     .section("[boundary.x_min]\ntype = \"temperature\"\nvalue = 1.0")
//!     .initial("x")
//!     .model("plate.toml");
//! ```
// Each test target uses a different subset of the builder's methods.
#![allow(dead_code)]

use peritherm::case::Case;
use peritherm::model::Model;
use std::fmt::Write as _;
use std::path::Path;

/// The text of a case file, built block by block; [`CaseToml::text`] writes it.
#[derive(Clone, Debug)]
pub struct CaseToml {
    /// Top-level keys (`dimension`, `symmetry`, `title`), which precede every table.
    root: Vec<String>,
    /// `[domain]` keys, if any.
    domain: Vec<String>,
    /// `[mesh]` keys, if any.
    mesh: Vec<String>,
    /// `[[region]]` tables, each its lines.
    regions: Vec<Vec<String>>,
    /// `[material.<name>]` tables, each its lines.
    materials: Vec<Vec<String>>,
    /// Further tables, verbatim, in the order given.
    sections: Vec<String>,
    /// The `[initial]` value, as TOML.
    initial: Option<String>,
    /// `[time]` keys after `end`.
    time: Vec<String>,
    /// `time.end`, s.
    end: f64,
}

impl CaseToml {
    /// A case of the given dimension ending at t = 1 s, with nothing else yet.
    pub fn new(dimension: usize) -> Self {
        CaseToml {
            root: vec![format!("dimension = {dimension}")],
            domain: Vec::new(),
            mesh: Vec::new(),
            regions: Vec::new(),
            materials: Vec::new(),
            sections: Vec::new(),
            initial: None,
            time: Vec::new(),
            end: 1.0,
        }
    }

    /// A further top-level key, e.g. `symmetry = "axisymmetric"`.
    pub fn key(mut self, line: &str) -> Self {
        self.root.push(line.to_string());
        self
    }

    /// `[domain]` with its corners, TOML arrays such as `"[0.0, 0.0]"`.
    pub fn domain(mut self, min: &str, max: &str) -> Self {
        self.domain.push(format!("min = {min}"));
        self.domain.push(format!("max = {max}"));
        self
    }

    /// A further `[domain]` key, e.g. `thickness = 0.1`.
    pub fn domain_key(mut self, line: &str) -> Self {
        self.domain.push(line.to_string());
        self
    }

    /// `[mesh]` reading `file` (relative to the case's path).
    pub fn mesh(mut self, file: &str) -> Self {
        self.mesh.push(format!("file = \"{file}\""));
        self
    }

    /// A further `[mesh]` key, e.g. `thickness = 1e-4`.
    pub fn mesh_key(mut self, line: &str) -> Self {
        self.mesh.push(line.to_string());
        self
    }

    /// A `[[region]]` called `name` with its resolution (`"spacing = 0.05"`,
    /// `"cells = [20, 10]"`, or `""` on a mesh) and δ = `factor` × Δ.
    pub fn region(mut self, name: &str, resolution: &str, factor: f64) -> Self {
        let mut lines = vec![format!("name = \"{name}\"")];
        if !resolution.is_empty() {
            lines.push(resolution.to_string());
        }
        lines.push(format!("horizon = {{ factor = {factor:?} }}"));
        self.regions.push(lines);
        self
    }

    /// A further key of the last region, e.g. `max = [0.8, 1.0]`.
    pub fn region_key(mut self, line: &str) -> Self {
        self.regions
            .last_mut()
            .expect("a region first")
            .push(line.to_string());
        self
    }

    /// A `[material.<name>]`: conductivity W/(m K), density kg/m³, specific heat J/(kg K).
    pub fn material(
        mut self,
        name: &str,
        conductivity: f64,
        density: f64,
        specific_heat: f64,
    ) -> Self {
        self.materials.push(vec![
            format!("[material.{name}]"),
            format!("conductivity = {conductivity:?}"),
            format!("density = {density:?}"),
            format!("specific_heat = {specific_heat:?}"),
        ]);
        self
    }

    /// Further tables, verbatim: faces, `[kernel]`, `[[crack]]`, `[source]`, ...
    pub fn section(mut self, text: &str) -> Self {
        self.sections.push(text.trim_matches('\n').to_string());
        self
    }

    /// `[initial]` given by an expression of x, y, z.
    pub fn initial(mut self, expr: &str) -> Self {
        self.initial = Some(format!("\"{expr}\""));
        self
    }

    /// `[initial]` given by a number.
    pub fn initial_value(mut self, value: f64) -> Self {
        self.initial = Some(format!("{value:?}"));
        self
    }

    /// `time.end`, s.
    pub fn end(mut self, end: f64) -> Self {
        self.end = end;
        self
    }

    /// A further `[time]` key, e.g. `integrator = "euler"`.
    pub fn time_key(mut self, line: &str) -> Self {
        self.time.push(line.to_string());
        self
    }

    /// The case file's text.
    pub fn text(&self) -> String {
        let mut t = String::new();
        for l in &self.root {
            writeln!(t, "{l}").unwrap();
        }
        if !self.domain.is_empty() {
            writeln!(t, "[domain]\n{}", self.domain.join("\n")).unwrap();
        }
        if !self.mesh.is_empty() {
            writeln!(t, "[mesh]\n{}", self.mesh.join("\n")).unwrap();
        }
        for r in &self.regions {
            writeln!(t, "[[region]]\n{}", r.join("\n")).unwrap();
        }
        for m in &self.materials {
            writeln!(t, "{}", m.join("\n")).unwrap();
        }
        for s in &self.sections {
            writeln!(t, "{s}").unwrap();
        }
        if let Some(v) = &self.initial {
            writeln!(t, "[initial]\nvalue = {v}").unwrap();
        }
        writeln!(t, "[time]\nend = {:?}", self.end).unwrap();
        for l in &self.time {
            writeln!(t, "{l}").unwrap();
        }
        t
    }

    /// The case, parsed as if read from `path` (relative paths in it resolve from there).
    pub fn case(&self, path: impl AsRef<Path>) -> Case {
        let path = path.as_ref();
        Case::parse(&self.text(), path)
            .unwrap_or_else(|e| panic!("{e}\n{}:\n{}", path.display(), self.text()))
    }

    /// The model of [`CaseToml::case`].
    pub fn model(&self, path: impl AsRef<Path>) -> Model {
        Model::build(&self.case(path).spec).unwrap()
    }
}
