//! The limits that keep hostile input from crashing, hanging or exhausting the machine, in
//! one place. Each value is far above what any bundled case needs (stated per constant) and
//! far below what would take a machine down; a case beyond one is refused up front with the
//! count and the key to change (see `docs/robustness.md`).

/// Longest expression string, bytes. The longest bundled expression is under 100 bytes; 4096
/// bounds the parse tree to a depth the evaluator's recursion handles on any thread's stack.
pub const MAX_EXPR_LEN: usize = 4096;

/// Deepest expression tree (nested parentheses, signs, powers, calls and chained operators
/// each add a level). Bundled expressions are under 10 deep; at 256 the recursive evaluation
/// uses a few tens of kB of stack, within a worker thread's 2 MiB.
pub const MAX_EXPR_DEPTH: usize = 256;

/// Most time steps of a fixed-step run (explicit or implicit). The bundled cases take under
/// 10⁶; 10⁸ steps of even a 1 000-node model run for hours, so more is a mistake in
/// `time.dt` or `time.end` (or a material that makes the stable step vanish).
pub const MAX_STEPS: f64 = 1e8;

/// Most neighbours per node the horizon may imply (the lattice count of its ball, δ/Δ = m:
/// 2m in 1D, πm² in 2D, 4πm³/3 in 3D). The bundled cases have under 1 000 (m = 6 in 3D);
/// 20 000 allows m ≈ 80 in 2D and m ≈ 16 in 3D, beyond any convergence study.
pub const MAX_NEIGHBOURS: f64 = 2e4;

/// Most `[history]` points, and most extra probe lines (`reference.lines_x`, `lines_y`).
/// The bundled cases use at most four; each is a search over the body and a report plot.
pub const MAX_HISTORY_POINTS: usize = 100;

/// Most rows (samples × points) of a `[history]`, held in memory during the run. The bundled
/// laser case records 201; 10⁶ rows take about 50 MB.
pub const MAX_HISTORY_ROWS: f64 = 1e6;

/// Bytes of set-up and run memory per node (positions, spacings, volumes, state vectors, the
/// boundary's tables, the search structures and a mesh's elements): measured peaks less the
/// bonds' bytes left 160 B per node on the 10⁷-node lattice plate and 340 B on the
/// 10⁶-triangle square (its mesh held), B.
pub const BYTES_PER_NODE: f64 = 300.0;
/// Bytes per node that every rank of a distributed run holds whatever its share: the cloud
/// (positions, volumes, spacing, horizon, regions: about 70 B), the gathered temperature and
/// flux, the halo plan, B.
pub const SHARED_BYTES_PER_NODE: f64 = 200.0;

/// Bytes per directed bond that the explicit step holds beside K for `kernel.columns =
/// "packed"` (about 1.7 B on gmsh triangles, [`crate::packed`]), B.
pub const PACKED_BYTES_PER_BOND: f64 = 2.0;

/// Bytes per directed bond that the explicit step holds beside K for `kernel.precision =
/// "f32"` (the rounded K_ij), B.
pub const F32_BYTES_PER_BOND: f64 = 4.0;

/// Bytes per directed bond at the peak of the set-up: the search's column (4 B) while K's
/// column and value (12 B) are filled, and 2 B for the allocator's slack, B.
pub const BYTES_PER_BOND: f64 = 18.0;

/// Extra bytes per directed bond of a case with cracks or nodal flux relations: the stored
/// directed weights and cut factors, and what the damage reads (β V_j and the cracks' μ), B.
pub const CUT_BYTES_PER_BOND: f64 = 32.0;

/// Extra bytes per directed bond of the implicit integrators (the system matrix, its
/// elimination and the sparse factor's fill): the 256 B of the earlier estimate less its
/// explicit part, not remeasured, B.
pub const IMPLICIT_BYTES_PER_BOND: f64 = 192.0;

/// Extra bytes per directed bond and per node of the consistent weights' iterative solve on a
/// mesh cloud (K before the correction and at the trial step, the Newton and CG vectors, the
/// block-Jacobi blocks and the coarse level's modes): the unit cube of 36 447 tetrahedral
/// nodes and 7.1·10⁶ bonds peaked at 0.66 GB, B.
pub const CORRECTION_BYTES: (f64, f64) = (64.0, 3072.0);

/// Bytes per stored entry of the FEM reference's matrices (mass and stiffness in CSR, and the
/// sparse Cholesky factor's fill, taken as ten times the entries).
pub const FEM_BYTES_PER_ENTRY: f64 = 200.0;

/// Largest number of stored entries of the consistent weights' Newton matrix solved with one
/// sparse Cholesky factor (2D clouds; about 190 000 nodes at δ = 3Δ, ~16 GB at
/// [`CORRECTION_BYTES_PER_ENTRY`]). Beyond it, and in 3D, preconditioned CG, which needs
/// thousands of iterations per Newton step on large 2D meshes.
pub const MAX_DIRECT_ENTRIES: f64 = 1.6e8;

/// Bytes per stored entry of that Newton matrix at the correction's peak (the matrix, the
/// factor's fill and the solver's scratch): 5.9 GB measured for 5.8·10⁷ entries
/// (meshes/pipe_heating_fem.msh as one plane region, 70 524 nodes), rounded up.
pub const CORRECTION_BYTES_PER_ENTRY: f64 = 100.0;

/// Fraction of the machine's available memory a run may plan to use without `--max-memory`.
pub const MEMORY_FRACTION: f64 = 0.8;

/// True when `v` is at most `limit`; false for NaN (a count that cannot be computed is refused).
pub fn within(v: f64, limit: f64) -> bool {
    v.partial_cmp(&limit)
        .is_some_and(|o| o != std::cmp::Ordering::Greater)
}
