//! Set-up of a free 2D plate with m = 3 (p = 1): the neighbour search (bucket grid and k-d
//! tree), the directed weights with the assembly of K, and the stencils of K. Throughput is
//! in nodes per second; 300 × 300 nodes keep the bench short (`peritherm bench` times 10⁶).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use peritherm::bench::plate;
use peritherm::horizons::Horizons;
use peritherm::model::{Geometry, Model};
use peritherm::operator::{directed_weights, Conductance};
use peritherm::stencil::Stencils;

fn setup(c: &mut Criterion) {
    let cells: usize = std::env::var("PERITHERM_BENCH_CELLS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(300);
    let case = plate(2, cells, 3.0).expect("the bench plate is valid");
    let Geometry::Box(geo) = &case.spec.geometry else {
        unreachable!("the bench plate is a box")
    };
    let cloud = geo.generate(0, 0.0).expect("the bench plate generates");
    let kernel = case.spec.kernel;
    let mut g = c.benchmark_group("setup_2d_m3");
    g.sample_size(10);
    g.throughput(Throughput::Elements(cloud.len() as u64));
    g.bench_function(format!("search_grid_{}_nodes", cloud.len()), |b| {
        b.iter(|| Horizons::build_with(&cloud, &kernel, true))
    });
    g.bench_function(format!("search_kdtree_{}_nodes", cloud.len()), |b| {
        b.iter(|| Horizons::build_with(&cloud, &kernel, false))
    });
    let horizons = Horizons::build(&cloud, &kernel);
    let k = vec![case.spec.materials[0].conductivity; cloud.len()];
    g.bench_function(format!("weights_assembly_{}_nodes", cloud.len()), |b| {
        b.iter(|| {
            let w = directed_weights(&cloud, &horizons, &kernel, &k, case.spec.bond_rule);
            Conductance::assemble(&cloud, &horizons, &w)
        })
    });
    let model = Model::build(&case.spec).expect("the bench plate builds");
    g.bench_function(format!("stencils_{}_nodes", cloud.len()), |b| {
        b.iter(|| Stencils::build(&model.conductance))
    });
    g.bench_function(format!("model_build_{}_nodes", cloud.len()), |b| {
        b.iter(|| Model::build(&case.spec))
    });
    g.finish();
}

criterion_group!(benches, setup);
criterion_main!(benches);
