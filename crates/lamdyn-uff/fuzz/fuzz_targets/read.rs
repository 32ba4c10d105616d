//! Any byte string: the reader and the lister return Ok or an error, never panic; what reads
//! back writes (where a writer exists) and reads again.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = lamdyn_uff::list(data);
    for lenient_counts in [false, true] {
        if let Ok(file) = lamdyn_uff::read_with(data, lamdyn_uff::ReadOptions { lenient_counts }) {
            let writable: Vec<_> = file
                .datasets
                .into_iter()
                .map(|d| d.dataset)
                .filter(|d| !matches!(d, lamdyn_uff::Dataset::Elements(_) | lamdyn_uff::Dataset::TraceLine(_) | lamdyn_uff::Dataset::CoordinateSystems(_)))
                .collect();
            for enc in [lamdyn_uff::Encoding::Ascii, lamdyn_uff::Encoding::Binary { little_endian: false }] {
                if let Ok(bytes) = lamdyn_uff::write(&writable, enc) {
                    let _ = lamdyn_uff::read(bytes.as_slice());
                }
            }
        }
    }
});
