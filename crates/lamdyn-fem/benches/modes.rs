//! The 20 lowest free-free modes of the paper's flat plate (0.923 × 0.8632 × 0.00385 m) on
//! n × n MITC4 meshes: assembly, and the whole solve (factorization, Lanczos, Sturm check).
//! Sizes are in benches/sizes.toml. The side-by-side comparison with CalculiX, with peak memory,
//! is tools/bench/modes_vs_calculix.py.
//!
//! `cargo bench -p lamdyn-fem --bench modes`

use criterion::{Criterion, criterion_group, criterion_main};
use lamdyn_fem::assembly::Assembly;
use lamdyn_fem::eigen::{ModalParams, Silent, solve_modes};
use lamdyn_fem::element::ShellMaterial;
use lamdyn_fem::mesh::structured::RectangleSpec;
use std::time::Duration;

const GLASS: ShellMaterial = ShellMaterial {
    young_pa: 67.45e9,
    poisson: 0.22,
    density_kg_m3: 2702.0,
    thickness_m: 0.00385,
};

fn sizes() -> Vec<usize> {
    let text = include_str!("sizes.toml");
    text.lines()
        .find_map(|l| l.strip_prefix("plate_elements_per_side = "))
        .map(|v| {
            v.trim_matches(['[', ']', ' '])
                .split(',')
                .filter_map(|s| s.trim().parse().ok())
                .collect()
        })
        .unwrap_or_else(|| vec![20, 40])
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("modes");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    for n in sizes() {
        let mesh = RectangleSpec::flat(0.923, 0.8632, n, n)
            .build()
            .expect("mesh");
        group.bench_function(format!("assembly/plate/n_{n:04}"), |b| {
            b.iter(|| Assembly::new(&mesh, &GLASS, &[]).expect("assembly"))
        });
        let asm = Assembly::new(&mesh, &GLASS, &[]).expect("assembly");
        group.bench_function(format!("solve20/plate/n_{n:04}"), |b| {
            b.iter(|| solve_modes(&asm, &ModalParams::lowest(20), &Silent).expect("modes"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
