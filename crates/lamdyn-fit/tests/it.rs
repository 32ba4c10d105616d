//! Integration tests of lamdyn-fit.

mod it {
    mod common;
    mod discretization;
    mod errors;
    mod misfit;
    mod recovery;
    mod sensors;
    mod supports;
    mod synthesis;
}
