//! `pfem-time`'s integration tests (closed forms, patch tests, locking,
//! the beam, rotating solids), as one test binary: each file of `tests/` is
//! a module of it (`Cargo.toml`: `autotests = false`), so that the
//! integrator is compiled once, not once per file. Run one file's tests
//! with its module name as the filter:
//! `cargo test --release -p pfem-time --test suite -- beam::`.

mod beam;
mod closed_forms;
mod common;
mod locking;
mod patch;
mod solid_rotation;
