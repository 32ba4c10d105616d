//! Times the stabilization diagram (LSCF poles at orders 2..=60 step 2 and their
//! classification) on a CSV FRF set: `lscf_timing CHANNELS FRF LO_HZ HI_HZ REPEATS [vectors]`.
//! Prints the median wall time in seconds (used by tools/ema/bench_vs_sdypy.py).

use lamdyn_ema::lscf::{LscfSettings, lscf};
use lamdyn_ema::stabilization::{StabilityCriteria, diagram};
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let read = |p: &str| std::fs::read_to_string(p).expect("read");
    let (r, f) = lamdyn_frf::csv::parse_channels(&a[1], &read(&a[1])).expect("channels");
    let set = lamdyn_frf::csv::parse_frf(&a[2], &read(&a[2]), r, f).expect("frf");
    let band = [a[3].parse().expect("lo"), a[4].parse().expect("hi")];
    let repeats: usize = a[5].parse().expect("repeats");
    // Optional 6th argument `vectors`: mode vectors and the vector criterion as well.
    let mode_vectors = a.get(6).is_some_and(|v| v == "vectors");
    let curves: Vec<&[num_complex::Complex64]> = (0..set.responses().len())
        .map(|i| set.curve(i, 0))
        .collect();
    let mut times: Vec<f64> = (0..repeats)
        .map(|_| {
            let t = Instant::now();
            let orders = lscf(
                set.freqs_hz(),
                &curves,
                &LscfSettings {
                    mode_vectors,
                    ..LscfSettings::new(band, (2, 60, 2))
                },
            )
            .expect("lscf");
            let d = diagram(&orders, &StabilityCriteria::default());
            assert!(!d.is_empty());
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    println!("{}", times[times.len() / 2]);
}
