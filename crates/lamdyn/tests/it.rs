//! Integration tests of the `lamdyn` CLI, run in-process through `lamdyn::run` (and through the
//! real binary where process behaviour matters).

mod it {
    mod common;
    mod core;
    mod e756;
    mod ema;
    mod fit;
    mod laminate;
    mod modes;
    mod robustness;
    mod run;
    mod safety;
    mod simulate;
    mod uff;
}
