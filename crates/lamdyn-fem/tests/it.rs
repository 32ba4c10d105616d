//! Cross-module tests of lamdyn-fem, one file per concern under `it/`.

// Matrix checks index two arrays with the same counters.
#![allow(clippy::needless_range_loop)]

mod it {
    mod common;
    mod convergence;
    mod element;
    mod mesh;
    mod modes;
    mod output;
}
