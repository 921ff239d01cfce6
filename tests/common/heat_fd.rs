//! Independent explicit finite-difference solves of θ_t = α∇²θ from a uniform θ0: a box of
//! cells (2D or 3D, each face held at 0 or insulated) and a disc by radial finite volumes
//! (edge held at 0). They check the series of `src/analytic.rs` and share no peritherm code.

/// A box [0, size_a] per axis split into `cells[a]` cells, each face held at 0 or insulated.
pub struct BoxFd {
    /// Cells per axis (2 or 3 axes).
    pub cells: Vec<usize>,
    /// Side lengths, m.
    pub size: Vec<f64>,
    /// Per axis: is the [low, high] face held at 0 (else insulated)?
    pub held: Vec<[bool; 2]>,
}

impl BoxFd {
    /// Cell width along axis `a`, m.
    pub fn h(&self, a: usize) -> f64 {
        self.size[a] / self.cells[a] as f64
    }

    /// Centre (x, y, z) of cell `k` (x fastest), m.
    pub fn centre(&self, k: usize) -> [f64; 3] {
        let mut p = [0.0; 3];
        let mut rest = k;
        for (a, &n) in self.cells.iter().enumerate() {
            p[a] = ((rest % n) as f64 + 0.5) * self.h(a);
            rest /= n;
        }
        p
    }

    /// θ at every cell centre at `t_end`, s (x fastest), from θ0 everywhere: the second
    /// difference with a mirrored ghost cell at each face (θ_ghost = −θ held, +θ insulated),
    /// explicit Euler at 0.9 of its stability limit, the last step shortened to land on t_end.
    pub fn solve(&self, alpha: f64, theta0: f64, t_end: f64) -> Vec<f64> {
        let d = self.cells.len();
        let total: usize = self.cells.iter().product();
        let stride: Vec<usize> = (0..d).map(|a| self.cells[..a].iter().product()).collect();
        let inv_h2: Vec<f64> = (0..d).map(|a| 1.0 / (self.h(a) * self.h(a))).collect();
        let limit = 0.5 / (alpha * inv_h2.iter().sum::<f64>());
        let steps = (t_end / (0.9 * limit)).ceil() as usize;
        let dt = t_end / steps as f64;
        let mut theta = vec![theta0; total];
        let mut next = theta.clone();
        for _ in 0..steps {
            for k in 0..total {
                let mut lap = 0.0;
                for a in 0..d {
                    let i = (k / stride[a]) % self.cells[a];
                    let ghost = |held: bool| if held { -theta[k] } else { theta[k] };
                    let lo = if i == 0 {
                        ghost(self.held[a][0])
                    } else {
                        theta[k - stride[a]]
                    };
                    let hi = if i + 1 == self.cells[a] {
                        ghost(self.held[a][1])
                    } else {
                        theta[k + stride[a]]
                    };
                    lap += (lo - 2.0 * theta[k] + hi) * inv_h2[a];
                }
                next[k] = theta[k] + alpha * dt * lap;
            }
            std::mem::swap(&mut theta, &mut next);
        }
        theta
    }
}

/// θ at the centres r_i = (i + ½)R/n of `n` rings of a disc of radius `radius`, m, at
/// `t_end`, s, from θ0, the edge held at 0: radial finite volumes (face fluxes r_(i±½)
/// (θ_(i±1) − θ_i)/h, a mirrored ghost at r = R), explicit Euler at 0.9 of its limit.
/// Returns (r_i, θ_i) pairs.
pub fn disc_fd(n: usize, radius: f64, alpha: f64, theta0: f64, t_end: f64) -> Vec<(f64, f64)> {
    let h = radius / n as f64;
    let r = |i: f64| (i + 0.5) * h;
    // Gershgorin: the eigenvalues of the operator are below twice its largest diagonal,
    // (r_(i+½) + r_(i−½))/(r_i h²) (with 2R for the outer face of the edge ring)
    let worst = (0..n)
        .map(|i| {
            let outer = if i + 1 == n {
                2.0 * radius
            } else {
                r(i as f64) + 0.5 * h
            };
            let inner = r(i as f64) - 0.5 * h;
            (outer + inner) / (r(i as f64) * h * h)
        })
        .fold(0.0, f64::max);
    let steps = (t_end / (0.9 / (alpha * worst))).ceil() as usize;
    let dt = t_end / steps as f64;
    let mut theta = vec![theta0; n];
    let mut next = theta.clone();
    for _ in 0..steps {
        for i in 0..n {
            let ri = r(i as f64);
            let inner = if i == 0 {
                0.0
            } else {
                (ri - 0.5 * h) * (theta[i - 1] - theta[i])
            };
            let outer = if i + 1 == n {
                radius * (-2.0 * theta[i])
            } else {
                (ri + 0.5 * h) * (theta[i + 1] - theta[i])
            };
            next[i] = theta[i] + alpha * dt * (inner + outer) / (ri * h * h);
        }
        std::mem::swap(&mut theta, &mut next);
    }
    (0..n).map(|i| (r(i as f64), theta[i])).collect()
}
