//! Bond updates per second of one explicit step: 2D plate, δ = 3Δ (m = 3), 10⁶ nodes.
//! Throughput is reported in stored pair conductances (bond updates) per second.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use peritherm::case::Case;
use peritherm::model::Model;
use peritherm::solve::explicit::{Explicit, Integrator};
use std::path::Path;

fn plate(cells: usize) -> Model {
    let text = format!(
        r#"
dimension = 2
[domain]
min = [0.0, 0.0]
max = [1.0, 1.0]
[[region]]
name = "plate"
cells = [{cells}, {cells}]
horizon = {{ factor = 3.0 }}
[material.m]
conductivity = 1.0
density = 1.0
specific_heat = 1.0
[kernel]
p = 1
[initial]
value = "sin(3*x)*cos(2*y)"
[time]
end = 1.0
integrator = "euler"
"#
    );
    Model::build(&Case::parse(&text, Path::new("bench.toml")).unwrap().spec).unwrap()
}

fn explicit_step(c: &mut Criterion) {
    let cells: usize = std::env::var("PERITHERM_BENCH_CELLS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1000);
    let model = plate(cells);
    let dt = Integrator::Euler.stable_dt(&model) * 0.5;
    let mut g = c.benchmark_group("explicit_step");
    g.sample_size(20);
    g.throughput(Throughput::Elements(model.conductance.nnz() as u64));
    let mut theta = model.theta0.clone();
    let mut st = Explicit::new(&model, Integrator::Euler);
    g.bench_function(format!("euler_2d_m3_{}_nodes", model.cloud.n_body), |b| {
        b.iter(|| st.step(&mut theta, 0.0, dt))
    });
    let mut out = vec![0.0; model.cloud.n_body];
    g.bench_function(
        format!("bond_sum_2d_m3_{}_nodes", model.cloud.n_body),
        |b| b.iter(|| model.conductance.apply(&model.theta0, &mut out)),
    );
    g.finish();
}

criterion_group!(benches, explicit_step);
criterion_main!(benches);
