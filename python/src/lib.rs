//! `peritherm._peritherm`: the Python bindings of the peritherm library (PyO3). Cases,
//! models, time stepping through [`peritherm::simulation::Simulation`], fields as numpy
//! arrays (copies), and the CLI's `run`, `sweep` and `fem` as functions returning dicts. The
//! numerics are the library's; nothing here computes a temperature.

use numpy::{PyArray1, PyArray2};
use peritherm::case::Case;
use peritherm::error::IoError;
use peritherm::fem::{run_fem, FemOptions, Scheme};
use peritherm::history::output_index;
use peritherm::model::Model;
use peritherm::output::RunSummary;
use peritherm::simulation::{Simulation, Snapshot};
use peritherm::solve::Integrator;
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard, TryLockError};
use std::time::{Duration, Instant};

/// The library's error as a Python exception carrying its one-line message: a case, key or
/// model error (and a bad mesh, expression or step) is a `ValueError`, a file that cannot be
/// written an `OSError`, anything else (a failed solve, a non-finite state) a `RuntimeError`.
fn py_err(e: impl Into<peritherm::Error>) -> PyErr {
    use peritherm::error::{CoreError as C, IoError as I};
    let e = e.into();
    let msg = e.to_string().replace('\n', " ");
    match (e.core(), e.io()) {
        (Some(C::Model { .. } | C::Expr { .. } | C::UnstableDt { .. }), _)
        | (_, Some(I::Case { .. } | I::Mesh { .. })) => PyValueError::new_err(msg),
        (_, Some(I::Io { .. })) => PyOSError::new_err(msg),
        _ => PyRuntimeError::new_err(msg),
    }
}

/// Asks Python for pending signals at most every 50 ms (Ctrl-C raises KeyboardInterrupt);
/// called between chunks of steps with the GIL released, it attaches to check.
struct Signals {
    last: Instant,
    error: Option<PyErr>,
}

impl Signals {
    fn new() -> Self {
        Signals {
            last: Instant::now(),
            error: None,
        }
    }

    /// False once a signal handler raised (the error is kept for the caller).
    fn keep_going(&mut self) -> bool {
        if self.error.is_some() {
            return false;
        }
        if self.last.elapsed() < Duration::from_millis(50) {
            return true;
        }
        self.last = Instant::now();
        match Python::attach(|py| py.check_signals()) {
            Ok(()) => true,
            Err(e) => {
                self.error = Some(e);
                false
            }
        }
    }

    /// The signal's exception, if one was raised.
    fn into_result(self) -> PyResult<()> {
        match self.error {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// The payload a progress callback unwinds with when Ctrl-C interrupts a library run
/// (`run_case`, `fem`, `sweep`): the library's run loops take no stop request, so the binding
/// unwinds out of them (no panic message: `resume_unwind`), and the staged output directory
/// is removed as the unwinding drops it; `--out` stays as it was.
struct Interrupted;

/// Runs `f` (a library run) with the GIL released; `f` gets a closure to call between steps
/// that unwinds with [`Interrupted`] when a signal handler raised.
fn interruptible<T: Send>(
    py: Python<'_>,
    f: impl FnOnce(&mut dyn FnMut()) -> peritherm::Result<T> + Send,
) -> PyResult<T> {
    let mut signals = Signals::new();
    let result = py.detach(|| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let mut check = || {
                if !signals.keep_going() {
                    std::panic::resume_unwind(Box::new(Interrupted));
                }
            };
            f(&mut check)
        }))
    });
    match result {
        Ok(r) => r.map_err(py_err),
        Err(payload) if payload.is::<Interrupted>() => {
            signals.into_result()?;
            Err(PyRuntimeError::new_err("interrupted"))
        }
        Err(payload) => std::panic::resume_unwind(payload),
    }
}

/// A Python value (dict, list, str, bool, int, float, numpy scalar or array) as TOML.
fn to_toml(v: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(toml::Value::Integer(v.extract()?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::map::Map::new();
        for (k, item) in d.iter() {
            let k: String = k.extract().map_err(|_| {
                PyValueError::new_err(format!("{key}: keys must be strings, got {k}"))
            })?;
            let sub = if key.is_empty() {
                k.clone()
            } else {
                format!("{key}.{k}")
            };
            if item.is_none() {
                continue; // None: the key is left out (its default applies)
            }
            t.insert(k, to_toml(&item, &sub)?);
        }
        return Ok(toml::Value::Table(t));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let mut a = Vec::new();
        for (i, item) in v.try_iter()?.enumerate() {
            a.push(to_toml(&item?, &format!("{key}.{i}"))?);
        }
        return Ok(toml::Value::Array(a));
    }
    if v.hasattr("tolist")? {
        // numpy arrays and scalars
        return to_toml(&v.call_method0("tolist")?, key);
    }
    Err(PyValueError::new_err(format!(
        "{key}: cannot be written as TOML (a {})",
        v.get_type().name()?
    )))
}

/// A parse error of the TOML made from a dict names a line of that text, which the user never
/// saw: name the dotted key written on that line instead (`region[1].spacing`).
fn keyed_by_line(e: IoError, text: &str) -> IoError {
    let IoError::Case { file, key, message } = e else {
        return e;
    };
    let Some(line) = key
        .strip_prefix("line ")
        .and_then(|n| n.parse::<usize>().ok())
    else {
        return IoError::Case { file, key, message };
    };
    let mut table = String::new();
    let mut counts: std::collections::HashMap<String, usize> = Default::default();
    let mut found = None;
    for (i, l) in text.lines().enumerate().take(line) {
        let l = l.trim();
        if let Some(h) = l.strip_prefix("[[").and_then(|h| h.strip_suffix("]]")) {
            let n = counts.entry(h.to_string()).or_insert(0);
            table = format!("{h}[{n}]");
            *n += 1;
        } else if let Some(h) = l.strip_prefix('[').and_then(|h| h.strip_suffix(']')) {
            // a sub-table of the last item of an array of tables: `[region.horizon]`
            table = match counts.keys().find(|a| h.starts_with(&format!("{a}."))) {
                Some(a) => format!("{a}[{}]{}", counts[a] - 1, &h[a.len()..]),
                None => h.to_string(),
            };
        }
        if i + 1 == line {
            found = Some(match l.split_once('=') {
                Some((k, _)) if !l.starts_with('[') => {
                    let k = k.trim().trim_matches('"');
                    if table.is_empty() {
                        k.to_string()
                    } else {
                        format!("{table}.{k}")
                    }
                }
                _ => table.clone(),
            });
        }
    }
    IoError::Case {
        file,
        key: found.filter(|k| !k.is_empty()).unwrap_or(key),
        message,
    }
}

/// A path argument: `str` or `os.PathLike`.
fn path_arg(p: &Bound<'_, PyAny>) -> PyResult<PathBuf> {
    p.extract::<PathBuf>()
}

/// A case file, parsed and validated (`peritherm check` without the model).
#[pyclass(name = "Case", module = "peritherm._peritherm", frozen)]
struct PyCase {
    case: Arc<Case>,
}

#[pymethods]
impl PyCase {
    /// Reads, parses and validates a case file (TOML); ValueError names the file and key.
    #[staticmethod]
    fn load(path: &Bound<'_, PyAny>) -> PyResult<Self> {
        let case = Case::load(&path_arg(path)?).map_err(py_err)?;
        Ok(PyCase {
            case: Arc::new(case),
        })
    }

    /// A case from TOML text; `path` names it in messages, and relative files (meshes,
    /// reference tables) are resolved beside it (default `<text>` in the working directory).
    #[staticmethod]
    #[pyo3(signature = (text, path = None))]
    fn from_toml(text: &str, path: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let path = match path {
            Some(p) => path_arg(p)?,
            None => PathBuf::from("<text>"),
        };
        let case = Case::parse(text, &path).map_err(py_err)?;
        Ok(PyCase {
            case: Arc::new(case),
        })
    }

    /// A case from a dict with the keys of a case file (nested dicts for tables, lists of
    /// dicts for `[[region]]`, None leaves a key out); `path` as in `from_toml` (default
    /// `<dict>`).
    #[staticmethod]
    #[pyo3(signature = (d, path = None))]
    fn from_dict(d: &Bound<'_, PyDict>, path: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let value = to_toml(d.as_any(), "")?;
        let text = toml::to_string(&value)
            .map_err(|e| PyValueError::new_err(format!("case dict: not TOML: {e}")))?;
        let path = match path {
            Some(p) => path_arg(p)?,
            None => PathBuf::from("<dict>"),
        };
        let case = Case::parse(&text, &path).map_err(|e| py_err(keyed_by_line(e, &text)))?;
        Ok(PyCase {
            case: Arc::new(case),
        })
    }

    /// Where the case came from.
    #[getter]
    fn path(&self) -> PathBuf {
        self.case.path.clone()
    }

    /// Title.
    #[getter]
    fn title(&self) -> String {
        self.case.title.clone()
    }

    /// End time, s.
    #[getter]
    fn end(&self) -> f64 {
        self.case.end
    }

    /// Output times, s.
    #[getter]
    fn outputs(&self) -> Vec<f64> {
        self.case.outputs.clone()
    }

    /// Integrator name (`euler`, `rk4`, `backward_euler`, `crank_nicolson`, `bdf2`, `steady`).
    #[getter]
    fn integrator(&self) -> &'static str {
        self.case.integrator.name()
    }

    /// The case's `time.dt`, s (None: chosen from the stability bound).
    #[getter]
    fn dt(&self) -> Option<f64> {
        self.case.dt
    }

    /// The case file's text as read (dict cases: the TOML written from the dict).
    #[getter]
    fn source(&self) -> String {
        self.case.source.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "Case({:?}, title={:?})",
            self.case.path.display().to_string(),
            self.case.title
        )
    }
}

/// The stepping state of a [`PyModel`]: the simulation (borrowing the model and case that
/// the `PyModel` owns) and the outputs recorded by `run`.
struct State {
    sim: Simulation<'static>,
    recorded: Vec<Snapshot>,
}

/// The options of a run from Python: `max_memory` and the weights cache that
/// `$PERITHERM_CACHE` and `$PERITHERM_CACHE_SIZE` set, as for the command line.
fn run_options(max_memory: Option<f64>) -> peritherm::Result<peritherm::prepare::Options> {
    let cache = peritherm::weights_cache::WeightsCache::configured(None, None)
        .map_err(|message| peritherm::Error::model("environment", message))?;
    Ok(peritherm::prepare::Options { max_memory, cache })
}

/// A built model with its temperature, time and integrator.
#[pyclass(name = "Model", module = "peritherm._peritherm", frozen)]
struct PyModel {
    // declared first, so dropped first: it borrows `model` and `case`
    state: Mutex<State>,
    model: Arc<Model>,
    case: Arc<Case>,
}

impl PyModel {
    /// The model's directed neighbour lists, searched anew (the model does not keep them).
    fn horizons(&self) -> peritherm::horizons::Horizons {
        peritherm::horizons::Horizons::build(&self.model.cloud, &self.case.spec.kernel)
    }

    /// Builds the model of `case` as a run does (budget, model, semantic checks, plan).
    fn build(case: Arc<Case>, max_memory: Option<f64>) -> peritherm::Result<Self> {
        let options = run_options(max_memory)?;
        let model = Arc::new(peritherm::prepare::build(&case, &options)?);
        // SAFETY: the simulation borrows the model and the case, which live in Arcs owned
        // by this PyModel: their heap addresses never change, they are never mutated, and
        // `state` is dropped before them (field order). No reference to them escapes with
        // the 'static lifetime: the simulation is only reached through `state`.
        let (m, c): (&'static Model, &'static Case) =
            unsafe { (&*Arc::as_ptr(&model), &*Arc::as_ptr(&case)) };
        let sim = Simulation::new(c, m)?;
        Ok(PyModel {
            state: Mutex::new(State {
                sim,
                recorded: Vec::new(),
            }),
            model,
            case,
        })
    }

    /// The state, or RuntimeError when another thread is stepping this model.
    fn state(&self) -> PyResult<MutexGuard<'_, State>> {
        match self.state.try_lock() {
            Ok(g) => Ok(g),
            Err(TryLockError::Poisoned(p)) => Ok(p.into_inner()),
            Err(TryLockError::WouldBlock) => Err(PyRuntimeError::new_err(
                "the model is being stepped in another thread",
            )),
        }
    }

    /// Steps with the GIL released, Ctrl-C checked between chunks of steps.
    fn stepping(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut State, &mut dyn FnMut(u64) -> bool) -> peritherm::Result<bool> + Send,
    ) -> PyResult<bool> {
        let mut guard = self.state()?;
        let state = &mut *guard;
        let mut signals = Signals::new();
        let done = py.detach(|| f(state, &mut |_| signals.keep_going()));
        let done = done.map_err(py_err)?;
        signals.into_result()?;
        Ok(done)
    }
}

/// n × 3 float64 array of points.
fn points<'py>(py: Python<'py>, p: impl Iterator<Item = [f64; 3]>) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = p.flat_map(|r| r.into_iter()).collect();
    let n = flat.len() / 3;
    let a = numpy::ndarray::Array2::from_shape_vec((n, 3), flat).expect("rows of three");
    numpy::IntoPyArray::into_pyarray(a, py)
}

/// One snapshot as a dict of numpy arrays.
fn snapshot_dict<'py>(py: Python<'py>, s: &Snapshot, nb: usize) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("time", s.time)?;
    d.set_item("temperature", PyArray1::from_slice(py, &s.theta[..nb]))?;
    d.set_item("flux", points(py, s.flux.iter().map(|q| [q.x, q.y, q.z])))?;
    d.set_item("damage", PyArray1::from_slice(py, &s.damage))?;
    d.set_item("energy", s.energy)?;
    Ok(d)
}

#[pymethods]
impl PyModel {
    /// Builds the model of a case (a `Case` or a path to a case file) as `peritherm run`
    /// does, at t = 0 s with the case's initial field. `max_memory`: bytes a model may plan
    /// to use (default: 80% of the available memory).
    #[staticmethod]
    #[pyo3(signature = (case, max_memory = None))]
    fn from_case(
        py: Python<'_>,
        case: &Bound<'_, PyAny>,
        max_memory: Option<f64>,
    ) -> PyResult<Self> {
        let case = match case.cast::<PyCase>() {
            Ok(c) => c.get().case.clone(),
            Err(_) => Arc::new(Case::load(&path_arg(case)?).map_err(py_err)?),
        };
        py.detach(|| PyModel::build(case, max_memory))
            .map_err(py_err)
    }

    /// The case the model was built from.
    #[getter]
    fn case(&self) -> PyCase {
        PyCase {
            case: self.case.clone(),
        }
    }

    /// Spatial dimension (1, 2 or 3).
    #[getter]
    fn dimension(&self) -> usize {
        self.model.cloud.dim
    }

    /// Number of body nodes; they come first in every per-node array.
    #[getter]
    fn n_body(&self) -> usize {
        self.model.cloud.n_body
    }

    /// Number of nodes, body and fictitious (boundary layers).
    #[getter]
    fn n_nodes(&self) -> usize {
        self.model.cloud.len()
    }

    /// Directed bonds (entries of `neighbor_indices`).
    #[getter]
    fn n_bonds(&self) -> usize {
        self.model.bonds
    }

    /// Node positions, m: float64 (n_nodes, 3), a copy.
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        points(py, self.model.cloud.pos.iter().map(|p| [p.x, p.y, p.z]))
    }

    /// Node volumes, m³ (per unit thickness or area as the case sets): float64 (n_nodes,).
    #[getter]
    fn volumes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.model.cloud.volume)
    }

    /// Node spacing Δ, m: float64 (n_nodes,).
    #[getter]
    fn spacing<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.model.cloud.spacing)
    }

    /// Horizon δ, m: float64 (n_nodes,).
    #[getter]
    fn horizon<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.model.cloud.horizon)
    }

    /// Region index (order of `[[region]]`): int32 (n_nodes,).
    #[getter]
    fn region<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i32>> {
        let r: Vec<i32> = self.model.cloud.region.iter().map(|&r| r as i32).collect();
        PyArray1::from_vec(py, r)
    }

    /// Neighbour lists (CSR) row offsets: int64 (rows + 1,); row i holds the bonds
    /// `neighbor_indices[offsets[i]:offsets[i+1]]` of node i (rows: every node with bonds,
    /// body first). The model keeps no neighbour lists once K is assembled: each call
    /// searches them again (about a second per 10⁶ nodes).
    #[getter]
    fn neighbor_offsets<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let o: Vec<i64> = self.horizons().offsets.iter().map(|&v| v as i64).collect();
        PyArray1::from_vec(py, o)
    }

    /// Neighbour lists (CSR) targets: int64 (n_bonds,), node indices into the per-node arrays
    /// (searched again on each call, as `neighbor_offsets`).
    #[getter]
    fn neighbor_indices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let t: Vec<i64> = self.horizons().targets.iter().map(|&v| v as i64).collect();
        PyArray1::from_vec(py, t)
    }

    /// Temperature of every node (body first), °C: float64 (n_nodes,), a copy. Setting it
    /// takes (n_body,) or (n_nodes,) values; the boundary then sets its nodes at the current
    /// time and the integrator restarts from this field.
    #[getter]
    fn get_temperature<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        Ok(PyArray1::from_slice(py, self.state()?.sim.theta()))
    }

    #[setter]
    fn set_temperature(&self, values: Vec<f64>) -> PyResult<()> {
        self.state()?.sim.set_theta(&values).map_err(py_err)
    }

    /// Simulated time, s.
    #[getter]
    fn time(&self) -> PyResult<f64> {
        Ok(self.state()?.sim.time())
    }

    /// Steps taken so far.
    #[getter]
    fn steps(&self) -> PyResult<u64> {
        Ok(self.state()?.sim.steps())
    }

    /// The run's fixed step, s (the case's time.dt, or 0.95 of the stable step).
    #[getter]
    fn dt(&self) -> PyResult<f64> {
        Ok(self.state()?.sim.dt())
    }

    /// Integrator name.
    #[getter]
    fn integrator(&self) -> &'static str {
        self.case.integrator.name()
    }

    /// Energy of the body now, J (as run.json's `energy`).
    fn energy(&self) -> PyResult<f64> {
        Ok(self.state()?.sim.energy())
    }

    /// Largest stable step of the case's explicit integrator (implicit cases: forward
    /// Euler's), s; run.json's `dt_stable`.
    fn stable_dt(&self) -> f64 {
        if self.case.integrator.is_implicit() {
            Integrator::Euler.stable_dt(&self.model)
        } else {
            self.case.integrator.stable_dt(&self.model)
        }
    }

    /// Heat flux per body node now, W/m²: float64 (n_body, 3).
    fn flux<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let q = self.state()?.sim.flux();
        Ok(points(py, q.iter().map(|q| [q.x, q.y, q.z])))
    }

    /// Damage φ per body node now (0 … 1): float64 (n_body,).
    fn damage<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        Ok(PyArray1::from_vec(py, self.state()?.sim.damage()))
    }

    /// Takes `n` steps of `dt` (GIL released; Ctrl-C raises KeyboardInterrupt between
    /// steps, the model then at the end of the last step taken).
    #[pyo3(signature = (n = 1))]
    fn step(&self, py: Python<'_>, n: u64) -> PyResult<()> {
        self.stepping(py, |s, keep| s.sim.step(n, keep))?;
        Ok(())
    }

    /// Advances to time `t` (s) with the steps `peritherm run` takes between two output
    /// times (GIL released, Ctrl-C as in `step`).
    fn advance_to(&self, py: Python<'_>, t: f64) -> PyResult<()> {
        self.stepping(py, |s, keep| s.sim.advance_to(t, keep))?;
        Ok(())
    }

    /// Advances through `outputs` (s; default: the case's output times after the current
    /// time, the steps also landing on its `[history]` sample times as a run's do) and returns, per output, a dict of `time`, `temperature` (n_body,), `flux`
    /// (n_body, 3), `damage` (n_body,) and `energy`; the outputs are also recorded for
    /// `write`. From t = 0 with the case's outputs this is `peritherm run` bit for bit.
    #[pyo3(signature = (outputs = None))]
    fn run<'py>(&self, py: Python<'py>, outputs: Option<Vec<f64>>) -> PyResult<Bound<'py, PyList>> {
        let mut guard = self.state()?;
        let state = &mut *guard;
        let t0 = state.sim.time();
        // by default the case's stops, as a run makes them: the outputs and the `[history]`
        // samples (the steps land on both), of which the outputs are returned
        let (stops, from_case) = match outputs {
            Some(o) => (o, false),
            None => (
                self.case.times().into_iter().filter(|&t| t > t0).collect(),
                true,
            ),
        };
        let mut signals = Signals::new();
        let result = py.detach(|| state.sim.run(&stops, |_| signals.keep_going()));
        let (mut snapshots, _) = result.map_err(py_err)?;
        if from_case {
            snapshots.retain(|s| output_index(&self.case.outputs, s.time).is_some());
        }
        let out = PyList::empty(py);
        for s in &snapshots {
            out.append(snapshot_dict(py, s, self.model.cloud.n_body)?)?;
        }
        state.recorded.extend(snapshots);
        signals.into_result()?;
        Ok(out)
    }

    /// Writes the outputs recorded by `run` (or, if none, the state now) into `out_dir`
    /// with `peritherm run`'s contract: `case.toml`, `field_<k>.csv` and `field_<k>.vtu` (with
    /// the case's reference and the comparison with it) and `run.json`, staged and swapped
    /// in whole. Returns run.json as a dict.
    fn write<'py>(
        &self,
        py: Python<'py>,
        out_dir: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let out = path_arg(out_dir)?;
        let mut guard = self.state()?;
        let state = &mut *guard;
        if state.recorded.is_empty() {
            let s = state.sim.snapshot();
            state.recorded.push(s);
        }
        let (case, model) = (&*self.case, &*self.model);
        let (recorded, steps, dt) = (&state.recorded, state.sim.steps(), state.sim.dt());
        let dt_stable = self.stable_dt();
        let summary = py
            .detach(|| write_recorded(case, model, &out, recorded, steps, dt, dt_stable))
            .map_err(py_err)?;
        summary_dict(py, &summary)
    }

    fn __repr__(&self) -> String {
        format!(
            "Model({:?}: {} body nodes, {} fictitious, {} bonds)",
            self.case.path.display().to_string(),
            self.model.cloud.n_body,
            self.model.cloud.n_fictitious(),
            self.model.bonds
        )
    }
}

/// `Model.write`: the recorded outputs through the library's writer, staged like a run.
fn write_recorded(
    case: &Case,
    model: &Model,
    out: &Path,
    recorded: &[Snapshot],
    steps: u64,
    dt: f64,
    dt_stable: f64,
) -> peritherm::Result<RunSummary> {
    let name = case.path.display().to_string();
    peritherm::staging::write_into(out, &name, |dir| {
        let origin = peritherm::provenance::write_copy(dir, case)?;
        let started = Instant::now();
        let mut writer = peritherm::run::OutputWriter::new(case, model, dir)?;
        for (k, s) in recorded.iter().enumerate() {
            writer.write_with_flux(k, s.time, &s.theta, &s.flux, s.energy)?;
        }
        let summary = RunSummary {
            status: "complete".into(),
            title: case.title.clone(),
            case: name.clone(),
            solver: "peridynamics".into(),
            nodes: model.cloud.n_body,
            fictitious_nodes: model.cloud.n_fictitious(),
            bonds: model.bonds,
            pairs: model.conductance.nnz(),
            steps,
            dt: if dt.is_finite() { dt } else { 0.0 },
            dt_stable,
            integrator: case.integrator.name().into(),
            output_times: recorded.iter().map(|s| s.time).collect(),
            fields: writer.fields,
            initial_energy: model.energy(&model.theta0),
            energy: writer.energy,
            setup_seconds: 0.0,
            wall_seconds: started.elapsed().as_secs_f64(),
            reference_seconds: writer.reference_seconds,
            threads: rayon::current_num_threads(),
            consistency: model.correction,
            reference: writer.comparisons,
            implicit: None,
            history: None,
            settings: case.settings.clone(),
            origin: Some(origin),
            ranks: None,
            step_storage: None,
        };
        summary.write(dir)?;
        Ok(summary)
    })
}

/// A run summary (run.json) as a dict.
fn summary_dict<'py>(py: Python<'py>, s: &RunSummary) -> PyResult<Bound<'py, PyAny>> {
    let json = serde_json::to_string(s).expect("plain data serialises");
    py.import("json")?.call_method1("loads", (json,))
}

/// `peritherm run CASE --out OUT`: runs the case (a path or a `Case`) with the library's
/// `run_case_with` and returns run.json as a dict (its `reference` list holds the comparison
/// measures per output time). GIL released; Ctrl-C raises KeyboardInterrupt and leaves `out`
/// as it was.
#[pyfunction]
#[pyo3(signature = (case, out, max_memory = None))]
fn run_case<'py>(
    py: Python<'py>,
    case: &Bound<'py, PyAny>,
    out: &Bound<'py, PyAny>,
    max_memory: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let case = match case.cast::<PyCase>() {
        Ok(c) => c.get().case.clone(),
        Err(_) => Arc::new(Case::load(&path_arg(case)?).map_err(py_err)?),
    };
    let out = path_arg(out)?;
    let options = run_options(max_memory).map_err(py_err)?;
    let summary = interruptible(py, |check| {
        peritherm::run::run_case_with(&case, &out, &options, |_, _| check())
    })?;
    summary_dict(py, &summary)
}

/// `peritherm fem CASE --out OUT`: the built-in FEM solve of a case (`scheme`:
/// "crank-nicolson", "backward-euler" or "steady"; `h` element size, m; `dt` step, s);
/// returns run.json as a dict. GIL released; Ctrl-C as in `run_case`.
#[pyfunction]
#[pyo3(signature = (case, out, h = None, scheme = "crank-nicolson", dt = None))]
fn fem<'py>(
    py: Python<'py>,
    case: &Bound<'py, PyAny>,
    out: &Bound<'py, PyAny>,
    h: Option<f64>,
    scheme: &str,
    dt: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let case = match case.cast::<PyCase>() {
        Ok(c) => c.get().case.clone(),
        Err(_) => Arc::new(Case::load(&path_arg(case)?).map_err(py_err)?),
    };
    let scheme = Scheme::from_name(scheme).ok_or_else(|| {
        let names: Vec<&str> = Scheme::ALL.iter().map(|s| s.name()).collect();
        PyValueError::new_err(format!(
            "scheme: `{scheme}` is not one of {}",
            names.join(", ")
        ))
    })?;
    let out = path_arg(out)?;
    let opts = FemOptions {
        h,
        scheme,
        dt,
        mesh: None,
    };
    let summary = interruptible(py, |check| run_fem(&case, &out, &opts, |_, _| check()))?;
    summary_dict(py, &summary)
}

/// `peritherm sweep CASE... --vary KEY=V1,V2 --out OUT [--against RUN | --against-first]
/// [--exclude-tips R]`:
/// the same variants, runs, comparisons, plots, sweep.csv and sweep.md. Returns a dict:
/// `rows` (one dict per variant and output time, the columns of sweep.csv), `table` (the
/// Markdown the CLI prints, with the fitted rates and plot links), `csv` (sweep.csv's text).
/// GIL released; Ctrl-C is honoured between variants.
#[pyfunction]
#[pyo3(signature = (cases, out, vary = Vec::new(), against = None, against_first = false, exclude_tips = 0.0))]
fn sweep<'py>(
    py: Python<'py>,
    cases: Vec<PathBuf>,
    out: PathBuf,
    vary: Vec<String>,
    against: Option<PathBuf>,
    against_first: bool,
    exclude_tips: f64,
) -> PyResult<Bound<'py, PyDict>> {
    use peritherm::sweep::{self, Against, Vary};
    if cases.is_empty() {
        return Err(PyValueError::new_err("cases: give at least one case file"));
    }
    if against.is_some() && against_first {
        return Err(PyValueError::new_err(
            "against, against_first: give one of them",
        ));
    }
    let against = Against::chosen(against, against_first);
    if !(exclude_tips.is_finite() && exclude_tips >= 0.0) {
        return Err(PyValueError::new_err(format!(
            "exclude_tips: must be a distance >= 0 m, got {exclude_tips}"
        )));
    }
    let vary: Vec<Vary> = vary
        .iter()
        .map(|v| {
            v.parse::<Vary>()
                .map_err(|e| PyValueError::new_err(format!("vary: {e}")))
        })
        .collect::<PyResult<_>>()?;
    let (variants, against) = sweep::study(&cases, &vary, against).map_err(py_err)?;
    let (rows, table, csv) = interruptible(py, |check| {
        let options = run_options(None)?;
        let rows = sweep::run(&variants, &out, &against, exclude_tips, &options, |_, _| {
            check()
        })?;
        let (table, csv) = sweep::write_study(&variants, &rows, &out, &against)?;
        Ok((rows, table, csv))
    })?;
    let d = PyDict::new(py);
    let list = PyList::empty(py);
    for r in &rows {
        let row = PyDict::new(py);
        row.set_item("label", &r.label)?;
        let settings = PyDict::new(py);
        for (k, v) in &r.settings {
            settings.set_item(k, v)?;
        }
        row.set_item("settings", settings)?;
        row.set_item("nodes", r.nodes)?;
        row.set_item("bonds", r.bonds)?;
        row.set_item("steps", r.steps)?;
        row.set_item("wall_seconds", r.wall_seconds)?;
        row.set_item("delta_min", r.delta_min)?;
        row.set_item("ratio", r.ratio)?;
        row.set_item("h_mean", r.h_mean)?;
        row.set_item("time", r.time)?;
        row.set_item("max_abs", r.max_abs)?;
        row.set_item("mean_abs", r.mean_abs)?;
        row.set_item("eq13", r.eq13)?;
        row.set_item("epsilon", r.epsilon)?;
        row.set_item("l2_rel", r.l2_rel)?;
        row.set_item("against", &r.against)?;
        list.append(row)?;
    }
    d.set_item("rows", list)?;
    d.set_item("table", table)?;
    d.set_item("csv", csv)?;
    Ok(d)
}

/// Version of the peritherm library the module was built with.
const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The native module.
#[pymodule]
fn _peritherm(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyCase>()?;
    m.add_class::<PyModel>()?;
    m.add_function(wrap_pyfunction!(run_case, m)?)?;
    m.add_function(wrap_pyfunction!(fem, m)?)?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add("__version__", VERSION)?;
    Ok(())
}
