//! An independent classical reference for the Bobaru & Duangpanya 2012 Example 3 crack plate:
//! finite differences on a cell-centred grid, the crack as removed face conductances, solved by a
//! sparse Cholesky factorisation (faer). It shares no code with peritherm's solvers.

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::{MatMut, Side};

/// The plate: n × n cells on [−a, a]², the top face held at +θ_top and the bottom at −θ_top,
/// insulated sides, an insulated crack on y = 0 for |x| < c. Lengths in m, θ in °C.
pub struct CrackPlate {
    /// Cells per side.
    pub n: usize,
    /// Half width, m.
    pub a: f64,
    /// Crack half length, m.
    pub c: f64,
    /// Top temperature, °C (the bottom is held at its negative).
    pub theta_top: f64,
}

impl CrackPlate {
    /// Cell size, m.
    pub fn h(&self) -> f64 {
        2.0 * self.a / self.n as f64
    }

    /// Centre coordinate of cell column (or row) i, m.
    pub fn centre(&self, i: usize) -> f64 {
        -self.a + (i as f64 + 0.5) * self.h()
    }

    /// Temperature of the cell containing (x, y), °C, from a field returned by a solve.
    #[allow(dead_code)] // used by the `cases` target (cracks.rs), not by `convergence` (fem.rs)
    pub fn at(&self, field: &[f64], x: f64, y: f64) -> f64 {
        let cell = |v: f64| (((v + self.a) / self.h()).floor() as usize).min(self.n - 1);
        field[cell(y) * self.n + cell(x)]
    }

    /// Temperature at (x, y), °C, bilinear between the four nearest cell centres of a field
    /// returned by a solve; never across the crack (beside it, only the row on the point's
    /// side is used).
    #[allow(dead_code)] // used by the `cases` target (cracks.rs), not by `convergence` (fem.rs)
    pub fn interpolate(&self, field: &[f64], x: f64, y: f64) -> f64 {
        let n = self.n;
        let split = |v: f64| {
            let f = ((v + self.a) / self.h() - 0.5).clamp(0.0, (n - 1) as f64);
            let i = (f.floor() as usize).min(n - 2);
            (i, f - i as f64)
        };
        let ((i, tx), (j, mut ty)) = (split(x), split(y));
        let cut = |i: usize| self.centre(i).abs() < self.c;
        if j + 1 == n / 2 && (cut(i) || cut(i + 1)) {
            ty = if y < 0.0 { 0.0 } else { 1.0 };
        }
        let v = |i: usize, j: usize| field[j * n + i];
        (1.0 - ty) * ((1.0 - tx) * v(i, j) + tx * v(i + 1, j))
            + ty * ((1.0 - tx) * v(i, j + 1) + tx * v(i + 1, j + 1))
    }

    /// The 5-point operator (× k/h², i.e. in units of conductance) with `shift` added to
    /// the diagonal, and the right-hand side of the held faces (half-cell distance to a
    /// held face: conductance 2).
    fn system(&self, shift: f64) -> (SparseColMat<usize, f64>, Vec<f64>) {
        let n = self.n;
        let id = |i: usize, j: usize| j * n + i;
        let mut entries = Vec::with_capacity(5 * n * n);
        let mut b = vec![0.0; n * n];
        // conductance between (i, j) and (i, j + 1): zero across the crack
        let vertical = |i: usize, j: usize| {
            if j + 1 == n / 2 && self.centre(i).abs() < self.c {
                0.0
            } else {
                1.0
            }
        };
        for j in 0..n {
            for i in 0..n {
                let k = id(i, j);
                let mut diag = shift;
                let mut couple = |other: usize, g: f64| {
                    if g > 0.0 {
                        entries.push(Triplet::new(k, other, -g));
                        diag += g;
                    }
                };
                if i > 0 {
                    couple(id(i - 1, j), 1.0);
                }
                if i + 1 < n {
                    couple(id(i + 1, j), 1.0);
                }
                if j > 0 {
                    couple(id(i, j - 1), vertical(i, j - 1));
                }
                if j + 1 < n {
                    couple(id(i, j + 1), vertical(i, j));
                }
                if j == 0 {
                    diag += 2.0;
                    b[k] = -2.0 * self.theta_top;
                }
                if j + 1 == n {
                    diag += 2.0;
                    b[k] = 2.0 * self.theta_top;
                }
                entries.push(Triplet::new(k, k, diag));
            }
        }
        let m = SparseColMat::try_new_from_triplets(n * n, n * n, &entries)
            .expect("valid finite-difference matrix");
        (m, b)
    }

    /// The steady temperature, °C, cell by cell (row-major, row j at y = centre(j)).
    pub fn steady(&self) -> Vec<f64> {
        let (m, mut b) = self.system(0.0);
        let llt = m.sp_cholesky(Side::Lower).expect("SPD");
        let len = b.len();
        llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut b, len, 1));
        b
    }

    /// The temperature at `t_end` from θ0 = 0 by backward Euler steps of `dt` (diffusivity
    /// `alpha`, m²/s), °C. The time error at Δt = 1e-3 s is 0.03 °C on this plate (against
    /// Crank–Nicolson at 1e-4 s, measured with an independent scipy script).
    pub fn transient(&self, alpha: f64, dt: f64, t_end: f64) -> Vec<f64> {
        let h = self.h();
        let shift = h * h / (alpha * dt);
        let (m, b) = self.system(shift);
        let llt = m.sp_cholesky(Side::Lower).expect("SPD");
        let len = b.len();
        let mut theta = vec![0.0; len];
        for _ in 0..(t_end / dt).round() as usize {
            for (t, b) in theta.iter_mut().zip(&b) {
                *t = shift * *t + b;
            }
            llt.solve_in_place(MatMut::from_column_major_slice_mut(&mut theta, len, 1));
        }
        theta
    }
}
