//! `peritherm bench`: throughput of the explicit step against the machine's memory bandwidth.
//!
//! Measures, on this machine and with the same code the runs use: a STREAM-like triad
//! (a_i = b_i + s c_i) and a read-only pass on 1 and N threads, the bond updates per second of
//! one forward-Euler step on free plates (2D m = 3, 2D m = 6.5, 3D m = 3) through the CSR rows
//! and the stencils of K, each step after a read-only pass on the same threads (the machine may
//! be shared: both see the same load), the time of the neighbour search and of the assembly of
//! K, and the bytes held and streamed per bond. Every figure is the median of repeated
//! timings; nothing is estimated.

use crate::case::Case;
use crate::error::{Error, Result};
use crate::gather::{ColumnIndex, Precision, StepStorage};
use crate::horizons::Horizons;
use crate::model::{Geometry, Model};
use crate::operator::{directed_weights, Conductance};
use crate::run::run_model;
use crate::solve::explicit::{Explicit, ExplicitScheme};
use crate::solve::implicit::ImplicitStats;
use crate::solve::Integrator;
use rayon::ThreadPool;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Bytes streamed per bond update by the bandwidth-bound model: a u32 column and an f64 K_ij.
pub const BYTES_PER_BOND: f64 = 12.0;

/// What `peritherm bench` measures and how long it takes.
#[derive(Debug, Clone)]
pub struct BenchOptions {
    /// Small problems (about 10⁵ nodes) and few repetitions: a smoke run, not a measurement.
    pub quick: bool,
    /// Only the 2D m = 3 plate, with about this many nodes (e.g. 10⁷ for the memory check).
    pub nodes: Option<usize>,
    /// Threads of the parallel columns (the 1-thread column always runs too).
    pub threads: usize,
    /// Also run the explicit and implicit crack plate and thermal shock ([`CASES`], from the
    /// repository root) with their outputs in this directory, and time them.
    pub cases: Option<PathBuf>,
}

/// The explicit, fixed-step implicit and adaptive runs of the comparison in
/// docs/performance.md ("Time to solution, explicit against implicit").
pub const CASES: [&str; 6] = [
    "cases/dh_crack_plate_k1_m1.toml",
    "cases/dh_crack_plate_k1_m1_implicit.toml",
    "cases/dh_crack_plate_k1_m1_adaptive.toml",
    "cases/thermal_shock_k1_m1.toml",
    "cases/thermal_shock_k1_m1_implicit.toml",
    "cases/thermal_shock_k1_m1_adaptive.toml",
];

/// Time to solution of one case run by `peritherm bench --cases`.
#[derive(Debug, Clone)]
pub struct CaseRow {
    /// Case file.
    pub case: String,
    /// Integrator name.
    pub integrator: String,
    /// Steps taken.
    pub steps: u64,
    /// Time step, s.
    pub dt: f64,
    /// Set-up (model, implicit elimination and symbolic factorisation), s.
    pub setup: f64,
    /// Integration with output writing, the reference excluded, s.
    pub integration: f64,
    /// max |θ_PD − θ_reference| at each output time, (s, °C).
    pub errors: Vec<(f64, f64)>,
    /// For Euler runs that used stencils: their bytes over the CSR's 12 B per entry of K; else None.
    pub stencils: Option<f64>,
    /// Implicit runs: the solver's counts (tolerance, rejected steps, solves, factorisations).
    pub implicit: Option<ImplicitStats>,
}

/// One row of the step table.
#[derive(Debug, Clone)]
pub struct StepRow {
    /// Configuration name, e.g. "2D m = 3".
    pub name: String,
    /// Kernel: "CSR" (12 B streamed per bond), "stencils" ([`crate::stencil`]), "packed"
    /// ([`crate::packed`]), or either with K in f32.
    pub kernel: &'static str,
    /// Body nodes.
    pub nodes: usize,
    /// Stored pair conductances (bond updates per step).
    pub bonds: usize,
    /// Median time of one Euler step on 1 thread, s.
    pub step_1: f64,
    /// Median time of one Euler step on N threads, s.
    pub step_n: f64,
    /// Median read bandwidth on 1 thread measured between the steps, GB/s.
    pub read_1: f64,
    /// Median read bandwidth on N threads measured between the steps, GB/s.
    pub read_n: f64,
    /// Bytes held by the model's bond data per stored pair conductance, B.
    pub bytes_per_bond: f64,
    /// Bytes one step reads and writes per stored pair conductance ([`streamed_bytes`]), B.
    pub streamed_per_bond: f64,
    /// Bytes the kernel holds beside K (stencils, packed columns, f32 values) per stored pair
    /// conductance (0 for CSR), B.
    pub extra_bytes_per_bond: f64,
}

/// Set-up times of a plate, s.
#[derive(Debug, Clone)]
pub struct SetupRow {
    /// Configuration name.
    pub name: String,
    /// Body nodes.
    pub nodes: usize,
    /// Neighbour search ([`Horizons::build`]), s.
    pub search: f64,
    /// Directed weights ([`directed_weights`]), s.
    pub weights: f64,
    /// Assembly of K ([`Conductance::assemble`]), s.
    pub assembly: f64,
    /// The whole [`Model::build`] (cloud, search, weights, assembly, boundary), s.
    pub build: f64,
}

/// Everything `peritherm bench` measured.
#[derive(Debug, Clone)]
pub struct BenchReport {
    /// Threads of the parallel columns.
    pub threads: usize,
    /// Triad bandwidth on 1 thread, GB/s (24 bytes per element, STREAM's count).
    pub triad_1: f64,
    /// Triad bandwidth on N threads, GB/s.
    pub triad_n: f64,
    /// Read-only bandwidth on 1 thread, GB/s.
    pub read_1: f64,
    /// Read-only bandwidth on N threads, GB/s.
    pub read_n: f64,
    /// Explicit-step rows.
    pub steps: Vec<StepRow>,
    /// Set-up rows.
    pub setup: Vec<SetupRow>,
    /// Time-to-solution rows (with `--cases`).
    pub cases: Vec<CaseRow>,
    /// Peak resident set of the process at the end, bytes (Linux VmHWM; None elsewhere).
    pub peak_rss: Option<u64>,
    /// The plate's node count asked for with `--nodes` (None: the standard plates).
    pub nodes: Option<usize>,
}

/// Runs [`CASES`] into `out/<case name>/` and times them.
pub fn time_cases(out: &Path, mut say: impl FnMut(&str)) -> Result<Vec<CaseRow>> {
    let mut rows = Vec::new();
    for c in CASES {
        let path = Path::new(c);
        say(&format!("{c}: running"));
        let case = Case::load(path)?;
        let stem = path
            .file_stem()
            .map_or("case".into(), |s| s.to_string_lossy());
        let t_setup = Instant::now();
        let model = Model::build(&case.spec)?;
        let s = run_model(&case, &model, &out.join(stem.as_ref()), t_setup, |_, _| {})?;
        // what Explicit::new decides for this model (it builds the stencils again: a fraction
        // of a second against the run)
        let stencils = if case.integrator == Integrator::Euler {
            let st = Explicit::new(&model, ExplicitScheme::Euler);
            let csr = 12.0 * model.conductance.nnz() as f64;
            (st.stencil_bytes() > 0).then(|| st.stencil_bytes() as f64 / csr)
        } else {
            None
        };
        rows.push(CaseRow {
            case: c.to_string(),
            integrator: s.integrator.clone(),
            steps: s.steps,
            dt: s.dt,
            setup: s.setup_seconds,
            integration: s.wall_seconds,
            errors: s
                .reference
                .iter()
                .map(|r| (r.time, r.max_abs_diff))
                .collect(),
            stencils,
            implicit: s.implicit,
        });
    }
    Ok(rows)
}

fn pool(threads: usize) -> Result<ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::model("threads", e.to_string()))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The arrays of the bandwidth kernels: a STREAM-like triad a_i = b_i + s·c_i, and a
/// read-only pass summing b and c (the limit of a read-dominated loop such as the step).
pub struct Bandwidth {
    a: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
}

/// Elements per parallel task of the bandwidth kernels.
const BANDWIDTH_CHUNK: usize = 1 << 16;

impl Bandwidth {
    /// Three arrays of `len` f64, every page touched.
    pub fn new(len: usize) -> Bandwidth {
        use rayon::prelude::*;
        Bandwidth {
            a: vec![1.0; len],
            b: (0..len).into_par_iter().map(|i| i as f64).collect(),
            c: (0..len).into_par_iter().map(|i| 0.5 * i as f64).collect(),
        }
    }

    /// One triad pass on `pool`, s.
    pub fn triad(&mut self, pool: &ThreadPool) -> f64 {
        use rayon::prelude::*;
        let (a, b, c) = (&mut self.a, &self.b, &self.c);
        let s = 3.0;
        let t = Instant::now();
        pool.install(|| {
            a.par_chunks_mut(BANDWIDTH_CHUNK)
                .zip(b.par_chunks(BANDWIDTH_CHUNK))
                .zip(c.par_chunks(BANDWIDTH_CHUNK))
                .for_each(|((a, b), c)| {
                    for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
                        *a = b + s * c;
                    }
                })
        });
        let dt = t.elapsed().as_secs_f64();
        std::hint::black_box(&self.a);
        dt
    }

    /// One read-only pass on `pool` (Σ b_i + c_i, in eight independent partial sums so that
    /// the adds do not bound it), s.
    pub fn read(&self, pool: &ThreadPool) -> f64 {
        use rayon::prelude::*;
        let t = Instant::now();
        let sum: f64 = pool.install(|| {
            self.b
                .par_chunks(BANDWIDTH_CHUNK)
                .zip(self.c.par_chunks(BANDWIDTH_CHUNK))
                .map(|(b, c)| {
                    let mut acc = [0.0f64; 8];
                    for (b, c) in b.chunks_exact(8).zip(c.chunks_exact(8)) {
                        for k in 0..8 {
                            acc[k] += b[k] + c[k];
                        }
                    }
                    acc.iter().sum::<f64>()
                })
                .sum()
        });
        let dt = t.elapsed().as_secs_f64();
        std::hint::black_box(sum);
        dt
    }

    /// Bandwidth of a triad pass that took `seconds`, GB/s, counting 24 bytes per element as
    /// STREAM does.
    pub fn triad_gbs(&self, seconds: f64) -> f64 {
        24.0 * self.a.len() as f64 / seconds / 1e9
    }

    /// Bandwidth of a read pass that took `seconds`, GB/s (16 bytes read per element).
    pub fn read_gbs(&self, seconds: f64) -> f64 {
        16.0 * self.b.len() as f64 / seconds / 1e9
    }

    /// Median triad and read bandwidths of `reps` passes each on `pool`, GB/s.
    pub fn median_gbs(&mut self, pool: &ThreadPool, reps: usize) -> (f64, f64) {
        let t: Vec<f64> = (0..reps).map(|_| self.triad(pool)).collect();
        let r: Vec<f64> = (0..reps).map(|_| self.read(pool)).collect();
        (self.triad_gbs(median(t)), self.read_gbs(median(r)))
    }
}

/// A free (insulated) plate or cube of `cells` per side, unit conductivity and capacity, p = 1,
/// δ = m Δ: the configuration of the step table.
pub fn plate(dim: usize, cells: usize, m: f64) -> Result<Case> {
    let (min, max, n) = match dim {
        2 => ("[0.0, 0.0]", "[1.0, 1.0]", format!("[{cells}, {cells}]")),
        _ => (
            "[0.0, 0.0, 0.0]",
            "[1.0, 1.0, 1.0]",
            format!("[{cells}, {cells}, {cells}]"),
        ),
    };
    let text = format!(
        r#"
dimension = {dim}
[domain]
min = {min}
max = {max}
[[region]]
name = "plate"
cells = {n}
horizon = {{ factor = {m} }}
[material.m]
conductivity = 1.0
density = 1.0
specific_heat = 1.0
[kernel]
p = 1
[initial]
value = "sin(3*x)*cos(2*y) + z"
[time]
end = 1.0
integrator = "euler"
"#
    );
    Ok(Case::parse(&text, Path::new("bench.toml"))?)
}

/// Bytes held by the bond data of a model (K, and what the damage of cracks needs), B.
pub fn bond_bytes(model: &Model) -> usize {
    let k = &model.conductance;
    model.damage.as_ref().map_or(0, |d| d.bytes())
        + k.offsets.capacity() * 8
        + k.cols.capacity() * 4
        + k.vals.capacity() * 8
        + k.diag.capacity() * 8
}

/// Bytes per row that every kernel of the Euler step moves: θ_i read, the new θ_i written,
/// 1/(V_i ρc_i) read, the driven flag read, then the copy of the new θ back (read and write).
const ROW_BYTES: usize = 8 + 8 + 8 + 1 + 16;

/// A kernel of the step table: how the explicit step reads K.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepKernel {
    /// CSR rows: a u64 offset per row, a u32 column and an f64 K_ij per bond.
    Csr,
    /// Shared stencils (lattices).
    Stencils,
    /// Packed columns (about 1 B per bond) and f64 K_ij.
    Packed,
    /// CSR columns and K_ij rounded to f32.
    CsrF32,
    /// Packed columns and K_ij rounded to f32.
    PackedF32,
}

/// Every kernel of the step table, in its order.
pub const STEP_KERNELS: [StepKernel; 5] = [
    StepKernel::Csr,
    StepKernel::Stencils,
    StepKernel::Packed,
    StepKernel::CsrF32,
    StepKernel::PackedF32,
];

impl StepKernel {
    /// The name in the step table.
    pub fn name(self) -> &'static str {
        match self {
            StepKernel::Csr => "CSR",
            StepKernel::Stencils => "stencils",
            StepKernel::Packed => "packed",
            StepKernel::CsrF32 => "CSR, f32",
            StepKernel::PackedF32 => "packed, f32",
        }
    }

    /// The storage the explicit stepper is set to.
    fn storage(self) -> StepStorage {
        let (columns, precision) = match self {
            StepKernel::Csr | StepKernel::Stencils => (ColumnIndex::U32, Precision::F64),
            StepKernel::Packed => (ColumnIndex::Packed, Precision::F64),
            StepKernel::CsrF32 => (ColumnIndex::U32, Precision::F32),
            StepKernel::PackedF32 => (ColumnIndex::Packed, Precision::F32),
        };
        StepStorage { columns, precision }
    }
}

/// Bytes one forward-Euler step moves between memory and the cores, each array counted once
/// (the neighbours' θ_j are reused from cache in space-filling-curve order): the rows'
/// bytes (41 per row), and K as `kernel` reads it, which holds `held` bytes beside K. CSR: a
/// u64 offset per row, a u32 column and an f64 K_ij per bond; stencils: a u16 stencil index per
/// row and the stencils themselves; packed: the packed columns and K_ij; f32: 4 B per K_ij, B.
pub fn streamed_bytes(model: &Model, kernel: StepKernel, held: usize) -> f64 {
    let (rows, nnz) = (model.cloud.n_body, model.conductance.nnz());
    let k = match kernel {
        StepKernel::Csr => rows * 8 + nnz * BYTES_PER_BOND as usize,
        StepKernel::Stencils => rows * 2 + held,
        StepKernel::CsrF32 => rows * 8 + nnz * 8,
        // the f32 values are held beside K: the packed bytes are the rest
        StepKernel::Packed => held + nnz * 8,
        StepKernel::PackedF32 => held,
    };
    (rows * ROW_BYTES + k) as f64
}

/// Euler steps of `model` on `pool` in three blocks of `reps / 3`, each block after two read
/// passes on the same pool and one discarded step (so that steps and reads see the same load
/// from elsewhere, and no timed step pays for evicting the read's arrays), reading K as
/// `kernel` does: median step, s, median read bandwidth, GB/s, and the bytes held beside K
/// (None for stencils on a cloud whose rows do not repeat).
pub fn time_step(
    pool: &ThreadPool,
    model: &Model,
    reps: usize,
    kernel: StepKernel,
    bandwidth: &Bandwidth,
) -> (f64, f64, Option<usize>) {
    let dt = 0.5 * Integrator::Euler.stable_dt(model);
    let mut theta = model.theta0.clone();
    let mut st = pool.install(|| Explicit::new(model, ExplicitScheme::Euler));
    let stencils = kernel == StepKernel::Stencils;
    let used = pool.install(|| {
        st.set_storage(kernel.storage());
        st.set_stencils(stencils) == stencils
    });
    let mut steps = Vec::with_capacity(reps);
    let mut passes = Vec::new();
    let per_block = reps.div_ceil(3).max(1);
    for _ in 0..3 {
        passes.push(bandwidth.read(pool));
        passes.push(bandwidth.read(pool));
        pool.install(|| st.step(&mut theta, 0.0, dt)); // not timed
        for _ in 0..per_block {
            let t = Instant::now();
            pool.install(|| st.step(&mut theta, 0.0, dt));
            steps.push(t.elapsed().as_secs_f64());
        }
    }
    std::hint::black_box(&theta);
    (
        median(steps),
        bandwidth.read_gbs(median(passes)),
        used.then(|| st.stencil_bytes() + st.storage_bytes()),
    )
}

/// Times the neighbour search, the directed weights and the assembly of a case's model, s.
pub fn time_setup(pool: &ThreadPool, case: &Case) -> Result<[f64; 3]> {
    let Geometry::Box(g) = &case.spec.geometry else {
        return Err(Error::model("bench", "set-up timing needs a box geometry"));
    };
    pool.install(|| {
        let cloud = g.generate(0, 0.0)?;
        let t = Instant::now();
        let horizons = Horizons::build(&cloud, &case.spec.kernel);
        let search = t.elapsed().as_secs_f64();
        let k: Vec<f64> = vec![case.spec.materials[0].conductivity; cloud.len()];
        let t = Instant::now();
        let w = directed_weights(
            &cloud,
            &horizons,
            &case.spec.kernel,
            &k,
            case.spec.bond_rule,
        );
        let weights = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let kk = Conductance::assemble(&cloud, &horizons, &w);
        let assembly = t.elapsed().as_secs_f64();
        std::hint::black_box(&kk);
        Ok([search, weights, assembly])
    })
}

/// Peak resident set size of this process, bytes (Linux `VmHWM`), if known.
pub fn peak_rss() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Runs the benchmark; `say` receives progress lines.
pub fn run(opts: &BenchOptions, mut say: impl FnMut(&str)) -> Result<BenchReport> {
    let bench = Bench {
        p1: pool(1)?,
        pn: pool(opts.threads)?,
        triad_len: if opts.quick { 1 << 22 } else { 1 << 26 },
        step_reps: if opts.quick { 5 } else { 21 },
    };
    let reps = if opts.quick { 5 } else { 15 };
    say(&format!(
        "triad and read, {} MB per array",
        (bench.triad_len * 8) >> 20
    ));
    let mut bandwidth = Bandwidth::new(bench.triad_len);
    let (triad_1, read_1) = bandwidth.median_gbs(&bench.p1, reps);
    let (triad_n, read_n) = bandwidth.median_gbs(&bench.pn, reps);
    // made again beside each model, so that it does not add to the build's peak memory
    drop(bandwidth);
    let mut steps = Vec::new();
    let mut setup = Vec::new();
    for (name, dim, cells, m) in plate_configs(opts) {
        let case = plate(dim, cells, m)?;
        if setup.is_empty() {
            say(&format!("{name}: set-up"));
            let repeats = if opts.quick || opts.nodes.is_some() {
                1
            } else {
                3
            };
            setup.push(bench.setup_row(&name, &case, repeats)?);
        }
        say(&format!("{name}: build"));
        let model = bench.pn.install(|| Model::build(&case.spec))?;
        say(&format!(
            "{name}: {} nodes, {} bonds: steps",
            model.cloud.n_body,
            model.conductance.nnz()
        ));
        steps.extend(bench.step_rows(&name, &model, &mut say));
    }
    if opts.nodes.is_none() {
        steps.extend(mesh_steps(opts, &bench, &mut say)?);
    }
    let cases = match &opts.cases {
        Some(dir) => time_cases(dir, &mut say)?,
        None => Vec::new(),
    };
    Ok(BenchReport {
        cases,
        threads: opts.threads,
        triad_1,
        triad_n,
        read_1,
        read_n,
        steps,
        setup,
        peak_rss: peak_rss(),
        nodes: opts.nodes,
    })
}

/// The gmsh square the step table times beside the plates: [`MESH_CASE`] on level 4 (quick:
/// level 3), without consistent weights.
pub fn mesh_case(quick: bool) -> Result<Case> {
    let level = if quick { 3 } else { 4 };
    let set: Vec<crate::sweep::Vary> = [
        format!("mesh.file=\"../../meshes/scale_square_L{level}.msh\""),
        "kernel.consistency=\"none\"".to_string(),
    ]
    .iter()
    .map(|v| v.parse().map_err(|e: String| Error::model("bench", e)))
    .collect::<Result<_>>()?;
    crate::sweep::load_with(Path::new(MESH_CASE), &set)
}

/// The unit square of gmsh default triangles (from the repository root).
pub const MESH_CASE: &str = "cases/large/scale_square.toml";

/// The step rows of [`mesh_case`]; none, with a note, outside the repository.
fn mesh_steps(
    opts: &BenchOptions,
    bench: &Bench,
    say: &mut impl FnMut(&str),
) -> Result<Vec<StepRow>> {
    if !Path::new(MESH_CASE).exists() {
        say(&format!(
            "{MESH_CASE} not found (run from the repository root): no mesh rows"
        ));
        return Ok(Vec::new());
    }
    let name = "2D gmsh m = 3";
    say(&format!("{name}: reading the mesh and building"));
    let case = mesh_case(opts.quick)?;
    let model = bench.pn.install(|| Model::build(&case.spec))?;
    say(&format!(
        "{name}: {} nodes, {} bonds: steps",
        model.cloud.n_body,
        model.conductance.nnz()
    ));
    Ok(bench.step_rows(name, &model, say))
}

/// The plates the benchmark times: (name, dimension, cells per side, m = δ/Δ).
fn plate_configs(opts: &BenchOptions) -> Vec<(String, usize, usize, f64)> {
    match opts.nodes {
        Some(n) => {
            let c = (n as f64).sqrt().round().max(4.0) as usize;
            vec![("2D m = 3".into(), 2, c, 3.0)]
        }
        None if opts.quick => vec![
            ("2D m = 3".into(), 2, 300, 3.0),
            ("2D m = 6.5".into(), 2, 300, 6.5),
            ("3D m = 3".into(), 3, 45, 3.0),
        ],
        None => vec![
            ("2D m = 3".into(), 2, 1000, 3.0),
            ("2D m = 6.5".into(), 2, 1000, 6.5),
            ("3D m = 3".into(), 3, 100, 3.0),
        ],
    }
}

/// The thread pools and sizes of one benchmark run.
struct Bench {
    /// One worker thread.
    p1: ThreadPool,
    /// All the threads asked for.
    pn: ThreadPool,
    /// Length of each bandwidth-kernel array (doubles).
    triad_len: usize,
    /// Repetitions of each timed step.
    step_reps: usize,
}

impl Bench {
    /// The set-up timings of `case` (medians of `repeats`) and the time of its whole model
    /// build, all threads.
    fn setup_row(&self, name: &str, case: &Case, repeats: usize) -> Result<SetupRow> {
        let mut s = Vec::new();
        let mut w = Vec::new();
        let mut a = Vec::new();
        for _ in 0..repeats {
            let [x, y, z] = time_setup(&self.pn, case)?;
            s.push(x);
            w.push(y);
            a.push(z);
        }
        let t = Instant::now();
        let model = self.pn.install(|| Model::build(&case.spec))?;
        let build = t.elapsed().as_secs_f64();
        let row = SetupRow {
            name: name.to_string(),
            nodes: model.cloud.n_body,
            search: median(s),
            weights: median(w),
            assembly: median(a),
            build,
        };
        drop(model);
        Ok(row)
    }

    /// The explicit step of `model` timed on one and on all threads with each kernel of
    /// [`STEP_KERNELS`] (stencils when rows repeat), each beside a read-only pass.
    fn step_rows(&self, name: &str, model: &Model, say: &mut impl FnMut(&str)) -> Vec<StepRow> {
        let nnz = model.conductance.nnz() as f64;
        let bandwidth = Bandwidth::new(self.triad_len);
        let mut rows = Vec::new();
        let reps = self.step_reps;
        for kernel in STEP_KERNELS {
            let (step_1, read_1, used) = time_step(&self.p1, model, reps, kernel, &bandwidth);
            let Some(held) = used else {
                say(&format!("{name}: no stencils (rows do not repeat)"));
                continue;
            };
            let (step_n, read_n, _) = time_step(&self.pn, model, reps, kernel, &bandwidth);
            rows.push(StepRow {
                name: name.to_string(),
                kernel: kernel.name(),
                nodes: model.cloud.n_body,
                bonds: model.conductance.nnz(),
                step_1,
                step_n,
                read_1,
                read_n,
                bytes_per_bond: bond_bytes(model) as f64 / nnz,
                streamed_per_bond: streamed_bytes(model, kernel, held) / nnz,
                extra_bytes_per_bond: held as f64 / nnz,
            });
        }
        rows
    }
}

impl BenchReport {
    /// The report as Markdown tables.
    pub fn markdown(&self) -> String {
        let mut s = self.bandwidth_table();
        s += &self.step_table();
        s += &self.setup_table();
        if !self.cases.is_empty() {
            s += &self.cases_table();
        }
        if let Some(b) = self.peak_rss {
            s += &format!("\nPeak resident set: {:.2} GB\n", b as f64 / 1e9);
        }
        s
    }

    /// The tables as figure files (`bench_bandwidth`, `bench_step`, `bench_setup` and, with
    /// `--cases`, `bench_cases`), measured by `command`. With `--nodes N` the one plate's
    /// `bench_step_<N>`, `bench_setup_<N>` and `bench_memory_<N>` (N as 1e7): the read pass beside
    /// a model of that size is disturbed, so no bandwidth table.
    pub fn figures(&self, command: &str) -> Vec<peritherm_post::figures::Figures> {
        use peritherm_post::figures::from_markdown;
        let mut tables = match self.nodes {
            None => vec![
                ("bench_bandwidth", self.bandwidth_table()),
                ("bench_step", self.step_table()),
                ("bench_setup", self.setup_table()),
            ],
            Some(_) => vec![
                ("bench_step", self.step_table()),
                ("bench_setup", self.setup_table()),
                ("bench_memory", self.memory_table()),
            ],
        };
        if !self.cases.is_empty() {
            tables.push(("bench_cases", self.cases_table()));
        }
        let suffix = self.nodes.map_or(String::new(), |n| format!("_{n:.0e}"));
        let provenance = crate::figures::provenance(self.threads);
        let figure = |(name, table): (&str, String)| {
            from_markdown(
                &format!("{name}{suffix}"),
                command,
                provenance.clone(),
                &table,
            )
        };
        tables.into_iter().map(figure).collect()
    }

    /// The process's peak resident set as a table of one row.
    fn memory_table(&self) -> String {
        let peak = self
            .peak_rss
            .map_or("-".into(), |b| format!("{:.1}", b as f64 / 1e9));
        format!("| process | peak resident set (GB) |\n|---|---|\n| `peritherm bench` | {peak} |\n")
    }

    /// The bond updates per second that a bandwidth of `gbs` GB/s allows at
    /// [`BYTES_PER_BOND`].
    fn bond_limit(gbs: f64) -> f64 {
        gbs * 1e9 / BYTES_PER_BOND
    }

    /// The memory bandwidth table (triad and read-only pass on one and all threads).
    fn bandwidth_table(&self) -> String {
        let n = self.threads;
        let lim = Self::bond_limit;
        let mut s = String::new();
        s += "| memory bandwidth | 1 thread | ";
        s += &format!("{n} threads |\n|---|---|---|\n");
        s += &format!(
            "| STREAM-like triad, GB/s | {:.1} | {:.1} |\n| read-only, GB/s | {:.1} | {:.1} |\n| bond-update limit at {BYTES_PER_BOND} B/bond read, 10⁹/s | {:.2} | {:.2} |\n\n",
            self.triad_1,
            self.triad_n,
            self.read_1,
            self.read_n,
            lim(self.read_1) / 1e9,
            lim(self.read_n) / 1e9
        );
        s
    }

    /// The explicit step table: one row per plate and kernel.
    fn step_table(&self) -> String {
        let n = self.threads;
        let mut s = format!(
            "| explicit Euler step | kernel | nodes | bonds | step, 1 thread | step, {n} threads | speed-up | bond updates/s, 1 / {n} threads | read alongside, 1 / {n} threads | B held per bond (+ beside K) | B streamed per bond | of the read limit, 1 / {n} threads |\n"
        );
        s += "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        for r in &self.steps {
            let (r1, rn) = (r.bonds as f64 / r.step_1, r.bonds as f64 / r.step_n);
            // the bandwidth the step used over the read-only pass's
            let of_read = |rate: f64, gbs: f64| 100.0 * rate * r.streamed_per_bond / (gbs * 1e9);
            s += &format!(
                "| {} | {} | {} | {} | {:.2} ms | {:.2} ms | {:.2}× | {:.2} / {:.2} × 10⁹ | {:.1} / {:.1} GB/s | {:.1} (+ {:.2}) | {:.2} | {:.0} / {:.0} % |\n",
                r.name,
                r.kernel,
                r.nodes,
                r.bonds,
                r.step_1 * 1e3,
                r.step_n * 1e3,
                r.step_1 / r.step_n,
                r1 / 1e9,
                rn / 1e9,
                r.read_1,
                r.read_n,
                r.bytes_per_bond,
                r.extra_bytes_per_bond,
                r.streamed_per_bond,
                of_read(r1, r.read_1),
                of_read(rn, r.read_n),
            );
        }
        s
    }

    /// The set-up table: search, weights, assembly and the whole build.
    fn setup_table(&self) -> String {
        let mut s = String::from("\n| set-up | nodes | neighbour search | directed weights | assembly of K | search + weights + assembly | whole Model::build |\n|---|---|---|---|---|---|---|\n");
        for r in &self.setup {
            s += &format!(
                "| {} | {} | {:.2} s | {:.2} s | {:.2} s | {:.2} s | {:.2} s |\n",
                r.name,
                r.nodes,
                r.search,
                r.weights,
                r.assembly,
                r.search + r.weights + r.assembly,
                r.build
            );
        }
        s
    }

    /// The table of the timed cases (`--cases`).
    fn cases_table(&self) -> String {
        let mut s = String::from("\n| case | integrator | K as | Δt (s) | steps (rejected) | solves (by CG) | factorisations | set-up (s) | integration (s) | total (s) | max abs PD − reference (°C) at each output |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
        for r in &self.cases {
            let errors: Vec<String> = r
                .errors
                .iter()
                .map(|(t, e)| format!("{e:.3e} at {t} s"))
                .collect();
            // an adaptive run states its tolerance, a fixed-step one its Δt
            let adaptive = r.implicit.filter(|i| i.tolerance > 0.0);
            let kas = match (r.integrator.as_str(), r.stencils) {
                ("euler", Some(f)) => format!("stencils ({:.1} % of the CSR bytes)", 100.0 * f),
                ("euler", None) => "CSR".to_string(),
                _ if adaptive.is_some() => "factorised or CG".to_string(),
                _ => "factorised".to_string(),
            };
            let (dt, rejected) = match adaptive {
                Some(i) => (
                    format!("adaptive, tol {:e} K", i.tolerance),
                    format!(" ({})", i.rejected),
                ),
                None => (format!("{:.3e}", r.dt), String::new()),
            };
            let (solves, factorisations) = match r.implicit {
                Some(i) => (
                    format!("{} ({})", i.solves, i.cg_solves),
                    i.factorisations.to_string(),
                ),
                None => ("-".into(), "-".into()),
            };
            s += &format!(
                "| `{}` | {} | {} | {dt} | {}{rejected} | {solves} | {factorisations} | {:.2} | {:.2} | {:.2} | {} |\n",
                r.case,
                r.integrator,
                kas,
                r.steps,
                r.setup,
                r.integration,
                r.setup + r.integration,
                errors.join(", ")
            );
        }
        s
    }
}
