//! The one validation path of `check` and `run`: the memory budget before anything is
//! allocated, the model, the semantic checks a valid-looking case can still fail, and the
//! plan of the time loop (step, step count, steppers). `check` stops here; `run` goes on.

use crate::bc::{FaceBc, NonFinite};
use crate::case::Case;
use crate::cloud::FACE_NAMES;
use crate::error::{CoreError, Error, Result};
use crate::limits::MAX_STEPS;
use crate::model::{Geometry, Model, Weights};
use crate::solve::exchange::{Collective, RankPlan, Reduce};
use crate::solve::implicit::{symmetric_over, Adaptive};
use crate::solve::{choose_dt, count_steps, Engine, Integrator, Schedule};
use crate::weights::store::Store;
use crate::weights_cache::WeightsCache;

/// Settings of a run that are not part of the case.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Memory a run may plan to use, bytes (None: a fraction of the machine's available).
    pub max_memory: Option<f64>,
    /// Where consistent weights are kept between runs (None: always computed).
    pub cache: Option<WeightsCache>,
}

impl Options {
    /// The weights store of a process that keeps new weights (`writes`) or only reads them.
    fn store(&self, writes: bool) -> Option<WeightsCache> {
        let cache = self.cache.as_ref()?;
        Some(if writes {
            cache.clone()
        } else {
            cache.reading()
        })
    }
}

/// The time loop a run will execute, validated.
pub struct Plan<'a> {
    /// The fixed step (adaptive: the first one, 0 when chosen from the tolerance), s.
    pub dt: f64,
    /// Adaptive step control of the implicit schemes.
    pub adaptive: Option<Adaptive>,
    /// Steps of a fixed-step run (0 when not known up front).
    pub total: u64,
    /// Whether the run is the steady solve at each output time (no steps).
    pub steady: bool,
    /// The stepper ([`Engine::new`]: explicit, enthalpy or implicit, set up).
    pub engine: Engine<'a>,
}

impl Plan<'_> {
    /// How the run steps: [`Plan::dt`], [`Plan::adaptive`], [`Plan::steady`].
    pub fn schedule(&self) -> Schedule {
        Schedule {
            dt: self.dt,
            adaptive: self.adaptive,
            steady: self.steady,
        }
    }
}

/// An error of any layer keyed to the case file: an unstable step to `time.dt`, a model
/// error's key to the file's key; every other error is returned as it is.
pub fn keyed(case: &Case, e: impl Into<Error>) -> Error {
    match e.into() {
        Error::Core(e @ CoreError::UnstableDt { .. }) => case.error("time.dt", e.to_string()),
        Error::Core(e) => case.keyed(e),
        Error::Io(e) => case.keyed(e),
        other => return other,
    }
    .into()
}

/// Checks the budget, builds the model and runs the semantic checks on it.
pub fn build(case: &Case, options: &Options) -> Result<Model> {
    build_keeping(case, options, true)
}

/// [`build`] as `peritherm check` does it: consistent weights are loaded from the cache when
/// it holds them and otherwise not solved (K stays uncorrected, the model's correction is
/// None), so that a check answers in the time of a set-up without them.
pub fn build_for_check(case: &Case, options: &Options) -> Result<Model> {
    build_as(case, options, true, Weights::StoredOnly)
}

/// [`build`], keeping newly computed weights in the cache only when `writes`.
fn build_keeping(case: &Case, options: &Options, writes: bool) -> Result<Model> {
    build_as(case, options, writes, Weights::Solve)
}

/// [`build`], keeping new weights only when `writes`, solving them as `weights` says.
fn build_as(case: &Case, options: &Options, writes: bool, weights: Weights) -> Result<Model> {
    case.budget
        .enforce(options.max_memory)
        .map_err(|message| case.error(&case.budget.key, message))?;
    let store = options.store(writes);
    let store = store.as_ref().map(|s| s as &dyn Store);
    // the semantic checks run before the consistent weights are solved
    Model::build_checked(&case.spec, (store, weights), |model| semantic(case, model))
        .map_err(|e| keyed(case, e))
}

/// What a model built from valid keys can still get wrong: regions without nodes, nodes
/// without bonds (a horizon below the spacing), two nodes at one point (a duplicated mesh
/// element), and a stable step that vanishes.
pub fn semantic(case: &Case, model: &Model) -> Result<()> {
    regions_have_nodes(case, model)?;
    let (count, first) = lonely(model);
    no_lonely(model, count, first)?;
    duplicates(case, model)?;
    match first_non_finite(case, model) {
        Some(bad) => Err(bad.error(case)),
        None => Ok(()),
    }
}

/// Where an expression of the case is not finite: the time's index among [`check_times`], the
/// key's index among [`expression_keys`], and the place.
#[derive(Debug, Clone, Copy, PartialEq)]
struct BadExpression {
    time: usize,
    key: usize,
    found: NonFinite,
}

/// The times at which the boundary values and the source are checked before a run: t = 0 and
/// every output time, s.
fn check_times(case: &Case) -> Vec<f64> {
    let mut times = vec![0.0];
    times.extend(case.outputs.iter().copied());
    if case.outputs.is_empty() {
        times.push(case.end);
    }
    times
}

/// The key of every boundary set's expression (`boundary.NAME.value` or `.ambient`; `-` for
/// a set without one), then `source.value`.
fn expression_keys(case: &Case) -> Vec<String> {
    let names: Vec<String> = match &case.spec.geometry {
        Geometry::Box(_) => FACE_NAMES.iter().map(|s| s.to_string()).collect(),
        Geometry::Mesh(g) => g.set_names(),
    };
    let mut keys: Vec<String> = case
        .spec
        .faces
        .iter()
        .enumerate()
        .map(|(f, face)| {
            let name = names.get(f).map_or("-", |n| n.as_str());
            match face {
                FaceBc::Convection { .. } | FaceBc::LayerConvection { .. } => {
                    format!("boundary.{name}.ambient")
                }
                _ => format!("boundary.{name}.value"),
            }
        })
        .collect();
    keys.push("source.value".into());
    keys
}

impl BadExpression {
    /// The refusal, naming the key, the place and the time.
    fn error(&self, case: &Case) -> Error {
        let keys = expression_keys(case);
        let key = match self.found.face {
            Some(f) => keys[f].clone(),
            None => keys[keys.len() - 1].clone(),
        };
        let t = check_times(case)[self.time];
        let p = self.found.at;
        case.error(
            key,
            format!(
                "not finite ({}) at ({}, {}, {}) m, t = {t} s",
                self.found.value, p.x, p.y, p.z
            ),
        )
        .into()
    }
}

/// The first time, and there the first boundary set (then the source), at which an
/// expression is not finite where the run evaluates it.
fn first_non_finite(case: &Case, model: &Model) -> Option<BadExpression> {
    let n_keys = case.spec.faces.len();
    check_times(case).iter().enumerate().find_map(|(time, &t)| {
        let found = model.boundary.non_finite(&model.cloud, t)?;
        let key = found.face.unwrap_or(n_keys);
        Some(BadExpression { time, key, found })
    })
}

/// [`first_non_finite`] over the shares of `link`'s ranks: every rank gets the same answer
/// (the earliest time, then the first key, then the least position).
fn first_non_finite_over(
    case: &Case,
    model: &Model,
    link: &dyn Collective,
) -> Option<BadExpression> {
    let mine = first_non_finite(case, model);
    let code = |b: &BadExpression| (b.time * (case.spec.faces.len() + 1) + b.key) as f64;
    let least = link.reduce(mine.as_ref().map_or(f64::INFINITY, code), Reduce::Min);
    if !least.is_finite() {
        return None;
    }
    let mut ours = mine.filter(|b| code(b) == least);
    let mut found = NonFinite {
        face: None,
        at: crate::math::Point::origin(),
        value: f64::NAN,
    };
    for axis in 0..3 {
        let v = ours.as_ref().map_or(f64::INFINITY, |b| b.found.at[axis]);
        found.at[axis] = link.reduce(v, Reduce::Min);
        ours = ours.filter(|b| b.found.at[axis] == found.at[axis]);
    }
    // NaN, +inf, -inf as 0, 1, 2
    let kind = |v: f64| {
        if v.is_nan() {
            0.0
        } else if v > 0.0 {
            1.0
        } else {
            2.0
        }
    };
    let k = link.reduce(
        ours.as_ref().map_or(3.0, |b| kind(b.found.value)),
        Reduce::Min,
    );
    found.value = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][k as usize];
    let n_keys = case.spec.faces.len() + 1;
    let (time, key) = (least as usize / n_keys, least as usize % n_keys);
    found.face = (key < case.spec.faces.len()).then_some(key);
    Some(BadExpression { time, key, found })
}

/// Refuses a region without nodes (no element of the mesh's group, or no cell).
fn regions_have_nodes(case: &Case, model: &Model) -> Result<()> {
    let cloud = &model.cloud;
    let regions = match &case.spec.geometry {
        Geometry::Box(g) => g.regions.len(),
        Geometry::Mesh(g) => g.regions.len(),
    };
    let mut count = vec![0usize; regions];
    for &r in &cloud.region[..cloud.n_body] {
        if let Some(c) = count.get_mut(r as usize) {
            *c += 1;
        }
    }
    if let Some(r) = count.iter().position(|&c| c == 0) {
        return Err(Error::model(
            format!("region[{r}].name"),
            "the region has no nodes (no element of the mesh's group, or no cell)",
        ));
    }
    Ok(())
}

/// The body nodes of the model's rows without a bond: how many, and the first.
fn lonely(model: &Model) -> (usize, Option<usize>) {
    (model.bondless.len(), model.bondless.first().copied())
}

/// Refuses `count` body nodes without a bond, the first of them `first`.
fn no_lonely(model: &Model, count: usize, first: Option<usize>) -> Result<()> {
    let Some(i) = first else {
        return Ok(());
    };
    let cloud = &model.cloud;
    Err(Error::model(
        format!("region[{}].horizon", cloud.region[i]),
        format!(
            "{} of {} body nodes have no bond (first at ({}, {}, {}) m, spacing {:e} m, horizon {:e} m): the horizon must reach the neighbouring nodes",
            count,
            cloud.n_body,
            cloud.pos[i].x,
            cloud.pos[i].y,
            cloud.pos[i].z,
            cloud.spacing[i],
            cloud.horizon[i]
        ),
    ))
}

/// Whether `case` runs distributed with each rank building its share of the model
/// ([`Model::build_share`]): a shareable model stepped at a fixed step (explicit, implicit or
/// steady; adaptive runs step the whole model on every rank).
pub fn shares(case: &Case) -> bool {
    Model::shareable(&case.spec) && case.tolerance.is_none()
}

/// One rank's model and plan in a distributed run over `link`: its share of the model when
/// [`shares`] allows it (the budget per rank, the checks reduced over the ranks, the stable
/// bound of every rank's rows) and, for an implicit run, its system is symmetric over the
/// ranks; else the whole model with every rank's plan computed alike.
/// Every rank fails alike: what differs between ranks is reduced first.
pub fn build_rank(
    case: &Case,
    options: &Options,
    link: &dyn Collective,
) -> Result<(Model, RankPlan)> {
    if !shares(case) {
        return whole_rank(case, options, link);
    }
    case.budget
        .per_rank(link.size())
        .enforce(options.max_memory)
        .map_err(|message| case.error(&case.budget.key, message))?;
    let (mut model, partition) =
        Model::build_share(&case.spec, link.size(), link.rank()).map_err(|e| keyed(case, e))?;
    let (count, first) = lonely(&model);
    let count = link.reduce(count as f64, Reduce::Sum) as usize;
    let first = link.reduce(first.map_or(f64::INFINITY, |i| i as f64), Reduce::Min);
    let first = first.is_finite().then_some(first as usize);
    semantic_share(case, &model, count, first).map_err(|e| keyed(case, e))?;
    if let Some(bad) = first_non_finite_over(case, &model, link) {
        return Err(bad.error(case));
    }
    let lambda = link.reduce(model.lambda_max(), Reduce::Max);
    model.set_lambda_max(lambda);
    let implicit = case.integrator.is_implicit();
    if implicit && !symmetric_over(&model, link).map_err(|e| keyed(case, e))? {
        // distributed CG needs a symmetric system: every rank steps the whole model instead
        return whole_rank(case, options, link);
    }
    let plan = RankPlan::of_share(&model, partition, link);
    Ok((model, plan))
}

/// The whole model on this rank, with its plan computed as every rank computes it.
fn whole_rank(case: &Case, options: &Options, link: &dyn Collective) -> Result<(Model, RankPlan)> {
    // one writer per run: rank 0 keeps the weights, every rank may load them
    let model = build_keeping(case, options, link.rank() == 0)?;
    let plan = RankPlan::all(&model, link.size()).swap_remove(link.rank());
    Ok((model, plan))
}

/// [`semantic`] of a share, given the nodes without a bond over every rank.
fn semantic_share(case: &Case, model: &Model, count: usize, first: Option<usize>) -> Result<()> {
    regions_have_nodes(case, model)?;
    no_lonely(model, count, first)?;
    duplicates(case, model)
}

/// Refuses two body nodes at one point (a duplicated mesh element): their bond has zero
/// length and the stable step vanishes.
fn duplicates(case: &Case, model: &Model) -> Result<()> {
    let cloud = &model.cloud;
    let mut order: Vec<usize> = (0..cloud.n_body).collect();
    let key = |i: usize| [cloud.pos[i].x, cloud.pos[i].y, cloud.pos[i].z];
    order.sort_unstable_by(|&a, &b| {
        let (ka, kb) = (key(a), key(b));
        ka[0]
            .total_cmp(&kb[0])
            .then(ka[1].total_cmp(&kb[1]))
            .then(ka[2].total_cmp(&kb[2]))
    });
    for w in order.windows(2) {
        let d = (cloud.pos[w[0]] - cloud.pos[w[1]]).norm();
        if d <= 1e-9 * cloud.spacing[w[0]].min(cloud.spacing[w[1]]) {
            let p = cloud.pos[w[0]];
            let key = match case.spec.geometry {
                Geometry::Mesh(_) => "mesh.file".to_string(),
                Geometry::Box(_) => format!("region[{}]", cloud.region[w[0]]),
            };
            return Err(Error::model(
                key,
                format!(
                    "two nodes at ({}, {}, {}) m: a duplicated element (or overlapping regions)",
                    p.x, p.y, p.z
                ),
            ));
        }
    }
    Ok(())
}

/// Validates and sets up the time loop of `case` on `model`.
pub fn plan<'a>(case: &Case, model: &'a Model) -> Result<Plan<'a>> {
    let adaptive = case.tolerance.map(|tolerance| Adaptive {
        tolerance,
        first: case.dt,
        max: case.dt_max,
    });
    let dt = match adaptive {
        Some(_) => case.dt.unwrap_or(0.0),
        None => choose_dt(model, case.integrator, case.dt).map_err(|e| keyed(case, e))?,
    };
    let fixed = case.integrator != Integrator::Steady && adaptive.is_none();
    let total = if fixed {
        let end = case.outputs.last().copied().unwrap_or(case.end);
        let why = match case.dt {
            Some(_) => format!("time.dt = {dt:e} s"),
            None => format!(
                "the stable step {dt:e} s of {} (set by the materials and the spacing)",
                case.integrator.name()
            ),
        };
        let key = if case.dt.is_some() {
            "time.dt"
        } else {
            "time.end"
        };
        within_budget(case, end / dt, end, key, &why)?;
        let total = count_steps(0.0, &case.times(), dt);
        within_budget(case, total as f64, end, key, &why)?;
        total
    } else {
        0
    };
    if let Some(a) = &adaptive {
        adaptive_within_budget(case, a)?;
    }
    // the stepper's set-up (implicit: elimination, symbolic factorisation) is part of the plan
    let engine =
        Engine::new(model, case.integrator, adaptive.is_some()).map_err(|e| keyed(case, e))?;
    if let (Engine::Implicit(implicit), Integrator::Steady) = (&engine, case.integrator) {
        implicit.level_fixed().map_err(|e| keyed(case, e))?;
    }
    Ok(Plan {
        dt,
        adaptive,
        total,
        steady: case.integrator == Integrator::Steady,
        engine,
    })
}

/// Refuses `steps` steps to reach `end` (s) with `why` beyond [`MAX_STEPS`], keyed at `key`.
fn within_budget(case: &Case, steps: f64, end: f64, key: &str, why: &str) -> Result<()> {
    if crate::limits::within(steps, MAX_STEPS) {
        return Ok(());
    }
    Err(case
        .error(
            key,
            format!(
                "{steps:.3e} steps to reach {end} s with {why}; at most {MAX_STEPS:e} are allowed"
            ),
        )
        .into())
}

/// Refuses an adaptive run whose largest step (`time.dt_max`, else a tenth of the span) needs
/// more than [`MAX_STEPS`] steps to the last output; a run that falls below it is stopped at
/// that many steps ([`crate::solve::implicit`]).
fn adaptive_within_budget(case: &Case, a: &Adaptive) -> Result<()> {
    let end = case.outputs.last().copied().unwrap_or(case.end);
    match a.max {
        Some(top) => within_budget(
            case,
            end / top,
            end,
            "time.dt_max",
            &format!("steps of at most time.dt_max = {top:e} s"),
        ),
        None => Ok(()),
    }
}

/// The key that most likely made the state non-finite at node `node` by time `t`: a source or
/// a boundary value that is non-finite or huge there, else the step.
pub fn likely_cause(case: &Case, model: &Model, node: usize, t: f64) -> String {
    let p = model.cloud.pos[node];
    let bad = |e: &crate::expr::Expr| {
        [0.0, t].iter().any(|&s| {
            let v = e.eval(p.x, p.y, p.z, s);
            !v.is_finite() || v.abs() > 1e100
        })
    };
    if case.spec.source.as_ref().is_some_and(bad) {
        return "source.value".into();
    }
    let names: Vec<String> = match &case.spec.geometry {
        Geometry::Box(_) => FACE_NAMES.iter().map(|s| s.to_string()).collect(),
        Geometry::Mesh(g) => g.set_names(),
    };
    for (f, face) in case.spec.faces.iter().enumerate() {
        let (e, k) = match face {
            FaceBc::NodalTemperature { value, .. }
            | FaceBc::LayerTemperature { value, .. }
            | FaceBc::LayerFlux { value }
            | FaceBc::RelationFlux { value } => (value, "value"),
            FaceBc::Convection { ambient, .. } | FaceBc::LayerConvection { ambient, .. } => {
                (ambient, "ambient")
            }
            _ => continue,
        };
        if bad(e) {
            let name = names.get(f).cloned().unwrap_or_else(|| "-".into());
            return format!("boundary.{name}.{k}");
        }
    }
    match (&case.spec.source, case.dt) {
        (_, Some(_)) => "time.dt".into(),
        (Some(_), None) => "source.value".into(),
        (None, None) => "time.dt".into(),
    }
}
