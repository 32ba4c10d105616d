//! Reading binary 58b FRFs: throughput of the reader on an in-memory file written by the writer
//! (the side-by-side comparison with pyuff on a ≥ 100 MB file is tools/uff/bench_vs_pyuff.py).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use lamdyn_uff::d58::{Dof, Function58};
use lamdyn_uff::{Dataset, Encoding, read, write};
use num_complex::Complex64;
use std::hint::black_box;

fn file(n_frf: usize, lines: usize) -> Vec<u8> {
    let sets: Vec<Dataset> = (0..n_frf)
        .map(|i| {
            Dataset::Function(Box::new(Function58::complex_frf(
                "bench",
                i as i64 + 1,
                Dof {
                    entity: "NONE".into(),
                    node: i as i64 + 1,
                    direction: 3,
                },
                Dof {
                    entity: "NONE".into(),
                    node: 1000,
                    direction: -3,
                },
                0.0,
                0.25,
                (0..lines)
                    .map(|k| Complex64::new(k as f64, -(k as f64)))
                    .collect(),
            )))
        })
        .collect();
    write(
        &sets,
        Encoding::Binary {
            little_endian: true,
        },
    )
    .expect("write")
}

fn bench(c: &mut Criterion) {
    let bytes = file(64, 16_384);
    let mut g = c.benchmark_group("read58b");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("64 FRFs x 16384 lines, complex double", |b| {
        b.iter(|| read(black_box(bytes.as_slice())).expect("read"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
