//! Compiles `src/shim.c` against PETSc when the `petsc` feature is on.
//!
//! PETSc is found through `PETSC_DIR` (and `PETSC_ARCH`, as PETSc's own
//! makefiles do) or else pkg-config's `PETSc`; its MPI through
//! pkg-config's `ompi` or `mpich`, or else `mpicc -showme`.
//! Without the feature this does nothing.

use std::path::PathBuf;
use std::process::Command;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=src/shim.c");
    println!("cargo:rerun-if-env-changed=PETSC_DIR");
    println!("cargo:rerun-if-env-changed=PETSC_ARCH");
    if std::env::var_os("CARGO_FEATURE_PETSC").is_none() {
        return;
    }
    build();
}

#[cfg(feature = "petsc")]
fn build() {
    let (mut includes, mut libdirs, mut libs) = petsc();
    let (mi, ml, mlibs) = mpi();
    includes.extend(mi);
    libdirs.extend(ml);
    libs.extend(mlibs);
    let mut cc = cc::Build::new();
    cc.file("src/shim.c").warnings(false);
    for i in &includes {
        cc.include(i);
    }
    cc.compile("pfem_petsc_shim");
    for d in &libdirs {
        println!("cargo:rustc-link-search=native={}", d.display());
        // So that tests and examples find the library without LD_LIBRARY_PATH.
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", d.display());
    }
    for l in &libs {
        println!("cargo:rustc-link-lib={l}");
    }
}

#[cfg(not(feature = "petsc"))]
fn build() {}

/// Include directories, library directories and libraries of PETSc.
#[allow(dead_code)]
fn petsc() -> (Vec<PathBuf>, Vec<PathBuf>, Vec<String>) {
    if let Some(dir) = std::env::var_os("PETSC_DIR") {
        let dir = PathBuf::from(dir);
        let arch = std::env::var_os("PETSC_ARCH").map(|a| dir.join(a));
        let mut inc = vec![dir.join("include")];
        let mut lib = vec![dir.join("lib")];
        if let Some(a) = arch {
            inc.push(a.join("include"));
            lib.insert(0, a.join("lib"));
        }
        let name = if lib.iter().any(|d| d.join("libpetsc_real.so").exists()) {
            "petsc_real"
        } else {
            "petsc"
        };
        return (inc, lib, vec![name.into()]);
    }
    for module in ["PETSc", "petsc"] {
        if let Some(out) = run("pkg-config", &["--cflags", "--libs", module]) {
            return split_flags(&out);
        }
    }
    panic!(
        "the `petsc` feature needs PETSc: set PETSC_DIR (and PETSC_ARCH), or install it where \
         pkg-config finds `PETSc` (Debian: apt-get install libpetsc-real-dev)"
    );
}

/// Include directories, library directories and libraries of the MPI
/// that PETSc's headers include and PETSc's library calls.
#[allow(dead_code)]
fn mpi() -> (Vec<PathBuf>, Vec<PathBuf>, Vec<String>) {
    for module in ["ompi", "mpich", "mpi"] {
        if let Some(out) = run("pkg-config", &["--cflags", "--libs", module]) {
            return split_flags(&out);
        }
    }
    let inc = run("mpicc", &["-showme:incdirs"]).unwrap_or_default();
    let libdirs = run("mpicc", &["-showme:libdirs"]).unwrap_or_default();
    let libs = run("mpicc", &["-showme:libs"]).unwrap_or_default();
    (
        inc.split_whitespace().map(PathBuf::from).collect(),
        libdirs.split_whitespace().map(PathBuf::from).collect(),
        libs.split_whitespace().map(String::from).collect(),
    )
}

/// `-I`, `-L` and `-l` flags of a pkg-config answer.
#[allow(dead_code)]
fn split_flags(out: &str) -> (Vec<PathBuf>, Vec<PathBuf>, Vec<String>) {
    let (mut inc, mut lib, mut libs) = (vec![], vec![], vec![]);
    for tok in out.split_whitespace() {
        if let Some(p) = tok.strip_prefix("-I") {
            inc.push(PathBuf::from(p));
        } else if let Some(p) = tok.strip_prefix("-L") {
            lib.push(PathBuf::from(p));
        } else if let Some(l) = tok.strip_prefix("-l") {
            libs.push(l.to_string());
        }
    }
    (inc, lib, libs)
}

#[allow(dead_code)]
fn run(cmd: &str, args: &[&str]) -> Option<String> {
    let out = Command::new(cmd).args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}
