//! Independent explicit finite-difference solves of θ_t = α∇²θ from a uniform θ0: a box of
//! cells (2D or 3D, each face held at 0 or insulated) and a disc by radial finite volumes
//! (edge held at 0). They check the series of `crates/analytic` and share no peritherm code.

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

/// θ at the centres s_i = (i + ½)L/n of `n` cells of a slab [0, L], m, insulated at both
/// ends (mirrored ghosts), from θ = 0, heated by the rate `q(s, t)`, K/s, at `times`, s
/// (increasing): explicit Euler at 0.9 of its limit, steps shortened to land on each time.
/// Returns, per time, (s_i, θ_i) pairs.
pub fn slab_source_fd(
    n: usize,
    length: f64,
    alpha: f64,
    q: impl Fn(f64, f64) -> f64,
    times: &[f64],
) -> Vec<Vec<(f64, f64)>> {
    let h = length / n as f64;
    let s = |i: usize| (i as f64 + 0.5) * h;
    let limit = 0.5 * h * h / alpha;
    let mut theta = vec![0.0; n];
    let mut next = theta.clone();
    let mut t = 0.0;
    let mut out = Vec::new();
    for &to in times {
        let steps = ((to - t) / (0.9 * limit)).ceil() as usize;
        let dt = (to - t) / steps as f64;
        for _ in 0..steps {
            for i in 0..n {
                let lo = if i == 0 { theta[0] } else { theta[i - 1] };
                let hi = if i + 1 == n { theta[i] } else { theta[i + 1] };
                let lap = (lo - 2.0 * theta[i] + hi) / (h * h);
                next[i] = theta[i] + dt * (alpha * lap + q(s(i), t));
            }
            std::mem::swap(&mut theta, &mut next);
            t += dt;
        }
        t = to;
        out.push((0..n).map(|i| (s(i), theta[i])).collect());
    }
    out
}

/// θ at the cell centres of a rectangle [0, a] × [0, b], m, of `cells` = [nx, ny] cells at
/// `t_end`, s: the face x = 0 held at `held(t)` (ghost 2·held − θ), the other faces insulated
/// (mirrored ghosts), from `initial(x, y)` at the centres; explicit Euler at 0.9 of its
/// limit. Returns the centres (x fastest) with θ.
pub fn plate_held_left_fd(
    cells: [usize; 2],
    size: [f64; 2],
    alpha: f64,
    initial: impl Fn(f64, f64) -> f64,
    held: impl Fn(f64) -> f64,
    t_end: f64,
) -> Vec<([f64; 2], f64)> {
    let [nx, ny] = cells;
    let (hx, hy) = (size[0] / nx as f64, size[1] / ny as f64);
    let centre = |k: usize| [((k % nx) as f64 + 0.5) * hx, ((k / nx) as f64 + 0.5) * hy];
    let limit = 0.5 / (alpha * (1.0 / (hx * hx) + 1.0 / (hy * hy)));
    let steps = (t_end / (0.9 * limit)).ceil() as usize;
    let dt = t_end / steps as f64;
    let mut theta: Vec<f64> = (0..nx * ny)
        .map(|k| {
            let [x, y] = centre(k);
            initial(x, y)
        })
        .collect();
    let mut next = theta.clone();
    for s in 0..steps {
        let g = held(s as f64 * dt);
        for k in 0..nx * ny {
            let (i, j) = (k % nx, k / nx);
            let th = theta[k];
            let west = if i == 0 { 2.0 * g - th } else { theta[k - 1] };
            let east = if i + 1 == nx { th } else { theta[k + 1] };
            let south = if j == 0 { th } else { theta[k - nx] };
            let north = if j + 1 == ny { th } else { theta[k + nx] };
            let lap = (west - 2.0 * th + east) / (hx * hx) + (south - 2.0 * th + north) / (hy * hy);
            next[k] = th + alpha * dt * lap;
        }
        std::mem::swap(&mut theta, &mut next);
    }
    (0..nx * ny).map(|k| (centre(k), theta[k])).collect()
}
