//! Helper of tools/uff/bench_vs_pyuff.py:
//! `uff_bench write PATH N_FRF LINES` writes N_FRF complex-double FRFs of LINES lines as binary
//! 58b; `uff_bench read PATH` reads the file and prints `seconds datasets checksum`.

use lamdyn_uff::d58::{Dof, Function58, Ordinate};
use lamdyn_uff::{Dataset, Encoding, ReadOptions, read_path, write};
use num_complex::Complex64;
use std::time::Instant;

fn frf(i: usize, lines: usize) -> Dataset {
    Dataset::Function(Box::new(Function58::complex_frf(
        &format!("FRF {i}"),
        i as i64 + 1,
        Dof {
            entity: "NONE".into(),
            node: i as i64 + 1,
            direction: 3,
        },
        Dof {
            entity: "NONE".into(),
            node: 100_000,
            direction: -3,
        },
        0.0,
        0.25,
        (0..lines)
            .map(|k| Complex64::from_polar(1.0 / (1.0 + k as f64), (i + k) as f64 * 0.01))
            .collect(),
    )))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    match args.get(1).map(String::as_str) {
        Some("write") => {
            let (n, lines): (usize, usize) = (
                args[3].parse().expect("N_FRF"),
                args[4].parse().expect("LINES"),
            );
            let sets: Vec<Dataset> = (0..n).map(|i| frf(i, lines)).collect();
            let bytes = write(
                &sets,
                Encoding::Binary {
                    little_endian: true,
                },
            )
            .expect("write");
            std::fs::write(&args[2], &bytes).expect("write file");
            println!("{} bytes", bytes.len());
        }
        Some("read") => {
            let t = Instant::now();
            let f =
                read_path(std::path::Path::new(&args[2]), ReadOptions::default()).expect("read");
            let secs = t.elapsed().as_secs_f64();
            let sum: f64 = f
                .functions()
                .map(|g| match &g.data {
                    Ordinate::Complex(v) => v.iter().map(|c| c.re).sum::<f64>(),
                    Ordinate::Real(v) => v.iter().sum(),
                })
                .sum();
            println!("{secs} {} {sum}", f.datasets.len());
        }
        _ => eprintln!("usage: uff_bench write PATH N_FRF LINES | read PATH"),
    }
}
