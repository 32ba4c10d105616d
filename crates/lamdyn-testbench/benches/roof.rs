//! The built-in `roof` virtual test (`lamdyn simulate --example roof`): 18 × 18 × 3 C3D20
//! elements (972 elements, 5263 nodes, 15 789 dofs), reduced basis of 40 modes at two core
//! moduli with core-sensitivity and residual vectors (162 vectors), 9 × 9 triaxial sensors
//! (243 FRFs), 320 lines, five hits of 2085 samples at 512 Hz.
//!
//! - `roof/build`: mesh, assembly, supports, two shift-invert Lanczos runs, basis, projection;
//! - `roof/frfs`: the 243 accelerance FRFs at 320 lines from the reduced model;
//! - `roof/hits`: five hammer hits as time signals (1042 synthesis lines, inverse FFTs);
//! - `roof/direct_line`: the peer route, one line by sparse complex LU of the full model (the
//!   symbolic analysis done once): × 320 for the FRFs a direct solver would need.
//!
//! `cargo bench -p lamdyn-testbench --bench roof`

use criterion::{Criterion, criterion_group, criterion_main};
use lamdyn_layered::reduced::DirectSolver;
use lamdyn_testbench::description::Description;
use lamdyn_testbench::impact::hammer_load;
use std::f64::consts::PI;
use std::time::Duration;

fn bench(c: &mut Criterion) {
    let desc = Description::roof();
    let bench = desc.build(&mut |_| {}).expect("the roof builds");
    eprintln!(
        "roof: {} elements, {} nodes, {} dofs, basis {} vectors, {} threads",
        bench.mesh.elements.len(),
        bench.mesh.nodes.len(),
        bench.dofs(),
        bench.model.size(),
        rayon::current_num_threads()
    );
    let mut group = c.benchmark_group("roof");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    group.bench_function("build", |b| {
        b.iter(|| desc.build(&mut |_| {}).expect("the roof builds"))
    });
    group.bench_function("frfs", |b| b.iter(|| bench.frfs().expect("FRFs")));
    group.bench_function("hits", |b| b.iter(|| bench.hit_records().expect("hits")));
    let direct = DirectSolver::new(&bench.system, &bench.core_layers).expect("direct solver");
    let load = hammer_load(&bench.mesh, &bench.test).expect("load");
    let w = 2.0 * PI * 40.0;
    group.bench_function("direct_line", |b| {
        b.iter(|| {
            direct
                .response(&load, w, bench.core_scale(w), &[0])
                .expect("direct solve")
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
