//! The bundled examples continue a run stopped by `--max-wall-time` from
//! the checkpoint it wrote (`--restart`), as `pfem run` does: before
//! session 54 they wrote the checkpoint and could not read it.
//! `cargo build --release --examples && cargo test --release --test suite
//! -- example_restart::` (`cargo test` alone builds the examples first).

use std::path::PathBuf;
use std::process::Command;

/// The example binary `name`, built by `cargo test` beside this test
/// binary (`target/<profile>/examples/`).
fn example(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    let profile = exe
        .parent()
        .and_then(|deps| deps.parent())
        .expect("target/<profile>/deps");
    profile.join("examples").join(name)
}

fn run(args: &[&str]) -> std::process::Output {
    let bin = example("hydrostatic_2d");
    // (`cargo test` builds the examples; `cargo test --test suite` alone
    // does not.)
    assert!(
        bin.is_file(),
        "{} not built: `cargo build --release --examples` first",
        bin.display()
    );
    Command::new(bin)
        .args(args)
        .output()
        .expect("the example runs")
}

/// Stopped after its first steps and continued with `--restart`, the
/// hydrostatic example's `probes.csv` is the uninterrupted run's byte for
/// byte; a restart into another folder, and one with nothing left to run,
/// are refused with a message.
#[test]
fn an_example_stopped_by_its_wall_time_continues_from_its_checkpoint() {
    let base = std::env::temp_dir().join(format!("pfem_example_restart_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    let (cut, whole) = (base.join("cut"), base.join("whole"));
    let common = ["--quiet", "--no-vtu", "--end-time", "0.2"];
    let s = |p: &PathBuf| p.to_string_lossy().into_owned();
    let mut a: Vec<String> = common.iter().map(|s| s.to_string()).collect();
    a.extend(["--out".into(), s(&whole)]);
    let r = run(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    // A wall-time limit far below one step's cost stops it after its
    // first step.
    let mut a: Vec<String> = common.iter().map(|s| s.to_string()).collect();
    a.extend([
        "--out".into(),
        s(&cut),
        "--max-wall-time".into(),
        "1e-6".into(),
    ]);
    let r = run(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let err = String::from_utf8_lossy(&r.stderr).into_owned();
    assert_eq!(r.status.code(), Some(2), "{err}");
    let checkpoint = cut.join("checkpoint.bin");
    assert!(
        err.contains(&format!("--restart {}", checkpoint.display())),
        "{err}"
    );
    // Another folder is refused, and leaves the checkpoint's alone.
    let mut a: Vec<String> = common.iter().map(|s| s.to_string()).collect();
    a.extend([
        "--restart".into(),
        s(&checkpoint),
        "--out".into(),
        s(&base.join("elsewhere")),
    ]);
    let r = run(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let err = String::from_utf8_lossy(&r.stderr).into_owned();
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(err.contains("own folder"), "{err}");
    // Continued in its folder (no --out), it ends as the whole run.
    let mut a: Vec<String> = common.iter().map(|s| s.to_string()).collect();
    a.extend(["--restart".into(), s(&checkpoint)]);
    let r = run(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let err = String::from_utf8_lossy(&r.stderr).into_owned();
    assert!(r.status.success(), "{err}");
    assert!(err.contains("restarted from"), "{err}");
    let rows = |d: &PathBuf| std::fs::read_to_string(d.join("probes.csv")).unwrap();
    assert!(rows(&whole).lines().count() > 3);
    assert_eq!(rows(&cut), rows(&whole));
    // The finished restart wrote its final state into the checkpoint: a
    // second restart has nothing to run (it re-ran the end from the
    // stop's checkpoint and cut `probes.csv` back: session 54's review).
    let r = run(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let err = String::from_utf8_lossy(&r.stderr).into_owned();
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(err.contains("nothing to run"), "{err}");
    let _ = std::fs::remove_dir_all(&base);
}
