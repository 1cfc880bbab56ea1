//! The `pfem` crate's integration tests, as one test binary: each file of
//! `tests/` is a module of it (`Cargo.toml`: `autotests = false`), so that
//! the generic pipeline is compiled once, not once per file. Run one
//! file's tests with its module name as the filter:
//! `cargo test --release -p pfem --test suite -- scene_file::`. The
//! kill-and-restart test is a binary of its own (`tests/restart.rs`): it
//! times a run and kills copies of it at fractions of that time, which
//! other tests' load in the same process would skew.

mod fuzz_scenes;
mod geometry_inputs;
mod robust_inputs;
mod scene_file;
