//! Bond updates per second of one forward-Euler step on free plates (p = 1): 2D m = 3,
//! 2D m = 6.5 and 3D m = 3, through the plain CSR rows and through the stencils of K.
//! Throughput is reported in stored pair conductances (bond updates) per second. The sizes
//! (about 10⁵ nodes) keep the bench short; `peritherm bench` measures 10⁶ nodes against the
//! machine's memory bandwidth.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use peritherm::bench::plate;
use peritherm::model::Model;
use peritherm::solve::explicit::{Explicit, ExplicitScheme, Integrator};

fn explicit_step(c: &mut Criterion) {
    let scale: f64 = std::env::var("PERITHERM_BENCH_SCALE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0);
    let side = |n: f64| (n * scale).round() as usize;
    let mut g = c.benchmark_group("explicit_step");
    g.sample_size(20);
    for (name, dim, cells, m) in [
        ("2d_m3", 2, side(300.0), 3.0),
        ("2d_m6.5", 2, side(200.0), 6.5),
        ("3d_m3", 3, side(40.0), 3.0),
    ] {
        let case = plate(dim, cells, m).expect("the bench plate is valid");
        let model = Model::build(&case.spec).expect("the bench plate builds");
        let dt = Integrator::Euler.stable_dt(&model) * 0.5;
        g.throughput(Throughput::Elements(model.conductance.nnz() as u64));
        for (kernel, on) in [("csr", false), ("stencils", true)] {
            let mut theta = model.theta0.clone();
            let mut st = Explicit::new(&model, ExplicitScheme::Euler);
            if st.set_stencils(on) != on {
                continue;
            }
            g.bench_function(
                format!("euler_{name}_{kernel}_{}_nodes", model.cloud.n_body),
                |b| b.iter(|| st.step(&mut theta, 0.0, dt)),
            );
        }
        if name == "2d_m3" {
            let mut out = vec![0.0; model.cloud.n_body];
            g.bench_function(
                format!("bond_sum_{name}_{}_nodes", model.cloud.n_body),
                |b| b.iter(|| model.conductance.apply(&model.theta0, &mut out)),
            );
        }
    }
    g.finish();
}

criterion_group!(benches, explicit_step);
criterion_main!(benches);
