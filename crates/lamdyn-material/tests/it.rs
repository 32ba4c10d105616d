//! Cross-module tests of lamdyn-material, one file per module under `it/`.

mod it {
    mod causality;
    mod e756;
    mod homogenized;
    mod inverse;
    mod law;
    mod rku;
    mod sandwich;
    mod section;
    mod spec;
}
