//! The EMA's least-squares factorisation: `lamdyn_ema::thin_qr::ThinQr` against faer's
//! `Mat::qr` (both sequential), each factorising and applying Qᵀ to nine curves, on the shapes
//! the EMA meets: a block of the residues' TSQR (2048 lines, four poles), the refinement's basis
//! (5057 lines, four poles), the check's projected pole columns, and the check's fixed LSCF
//! roots (54 columns, four panels of `ThinQr`).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::householder::{
    apply_block_householder_sequence_transpose_on_the_left_in_place_scratch,
    apply_block_householder_sequence_transpose_on_the_left_in_place_with_conj,
};
use faer::linalg::solvers::Qr;
use faer::{Conj, Mat, Par};
use lamdyn_ema::thin_qr::ThinQr;
use std::hint::black_box;

/// A rows × cols matrix of partial-fraction-like columns (smooth, distinct, unit scale).
fn basis(rows: usize, cols: usize) -> Mat<f64> {
    Mat::from_fn(rows, cols, |i, j| {
        let x = i as f64 / rows as f64;
        let k = (j + 1) as f64;
        1.0 / (1.0 + (40.0 * (x - k / (cols as f64 + 1.0))).powi(2)) + 0.1 * (k * x).sin()
    })
}

/// `m` ← Qᵀ m by faer's blocked Householder sequence (what the EMA used before `ThinQr`).
fn faer_transpose_q(qr: &Qr<f64>, m: &mut Mat<f64>) {
    let (basis, factor) = (qr.Q_basis(), qr.Q_coeff());
    let scratch = apply_block_householder_sequence_transpose_on_the_left_in_place_scratch::<f64>(
        basis.nrows(),
        factor.nrows(),
        m.ncols(),
    );
    apply_block_householder_sequence_transpose_on_the_left_in_place_with_conj(
        basis,
        factor,
        Conj::No,
        m.as_mut(),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(scratch)),
    );
}

fn factorise(c: &mut Criterion) {
    faer::set_global_parallelism(Par::Seq);
    let mut group = c.benchmark_group("thin_qr");
    for (rows, cols) in [(4096, 10), (10114, 10), (10061, 8), (10114, 54)] {
        let a = basis(rows, cols);
        let b = basis(rows, 9);
        let id = format!("{rows}x{cols}");
        group.bench_with_input(BenchmarkId::new("lamdyn ThinQr", &id), &a, |bench, a| {
            bench.iter(|| {
                let qr = ThinQr::new(black_box(a));
                let mut qtb = b.clone();
                qr.apply_transpose_q(&mut qtb);
                black_box((qr.r(), qtb))
            })
        });
        group.bench_with_input(BenchmarkId::new("faer Mat::qr", &id), &a, |bench, a| {
            bench.iter(|| {
                let qr = black_box(a).qr();
                let mut qtb = b.clone();
                faer_transpose_q(&qr, &mut qtb);
                black_box((qr.thin_R().to_owned(), qtb))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, factorise);
criterion_main!(benches);
