//! The workspace's validation tests, as one test binary: each file of
//! `tests/` is a module of it (`Cargo.toml`: `autotests = false`). Built as
//! 24 binaries, each one compiled and optimised the whole generic pipeline
//! (`Simulation<2>`, `Simulation<3>`, the assembly, the solvers) again: 320
//! of the 1 110 CPU-seconds of a clean `cargo test --workspace --release`
//! (session 27). Run one file's tests with its module name as the filter:
//! `cargo test --release --test suite -- floating::`.

mod block_solver;
mod checkpoint;
mod contact;
mod convergence;
mod custom_materials;
mod determinism;
mod example_restart;
mod floating;
mod floating_3d;
mod hertz_3d;
mod hooks;
mod particle_management;
#[cfg(feature = "petsc")]
mod petsc;
mod picard_stop;
mod presets;
mod probes;
mod solid_dynamics;
mod stability_3d;
mod stability_degenerate;
mod stability_fluid;
mod stability_fsi;
mod stability_support;
mod stages;
mod three_d;
mod validation_dam_break;
mod validation_elastic_gate;
mod volume_correction;
mod water_at_rest_2d;
mod water_at_rest_3d;
