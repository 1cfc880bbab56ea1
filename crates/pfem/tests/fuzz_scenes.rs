//! A fuzz campaign over scene files (issue 17): the bundled scenes with
//! one line mutated (a number replaced by a hostile value, the line deleted,
//! duplicated or garbled, the file cut there). Every mutant must load to a
//! typed error or to a scene that validates within a memory budget
//! (`Options::memory_budget`: the scene's estimate of its own size is
//! checked before anything is allocated; allocations are not counted) and
//! runs its first steps: no panic, no hang.
//! `cargo test --release -p pfem --test suite fuzz_scenes:: -- --nocapture`
//! Each campaign prints its seed; `PROPTEST_RNG_SEED=<seed>` replays it.

use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Mutex;

use pfem::core::{Const, Dim};
use pfem::geometry::{Delaunay2, Delaunay3, Tessellator};
use pfem::scene_file::{LoadedScene, SceneFile};
use pfem::time::StepParams;
use pfem::{Options, Scene, Simulation};
use proptest::test_runner::{Config, RngSeed, TestRunner};

/// A runner of `cases` cases whose seed is printed: `PROPTEST_RNG_SEED`'s
/// if set (proptest reads it), else one drawn from the clock.
fn runner(name: &str, cases: u32) -> TestRunner {
    let mut config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    if config.rng_seed == RngSeed::Random {
        let t = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos() as u64);
        config.rng_seed = RngSeed::Fixed(t ^ u64::from(std::process::id()));
    }
    println!(
        "{name}: seed {} (replay: PROPTEST_RNG_SEED={0})",
        config.rng_seed
    );
    TestRunner::new(config)
}

/// Memory budget of a fuzzed run (bytes): 200 MB.
const BUDGET: f64 = 2e8;
/// Mutants tried.
const CASES: u32 = 400;
/// Largest scene that is also stepped (particles, estimated).
const STEP_LIMIT: f64 = 3000.0;

fn scenes() -> Vec<(String, String)> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes");
    let mut v: Vec<(String, String)> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "toml"))
        .map(|e| {
            // The full path: a scene's STL file is found beside it.
            (
                e.path().display().to_string(),
                std::fs::read_to_string(e.path()).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

const HOSTILE: [&str; 14] = [
    "0", "-1", "1e-300", "5e-324", "1e300", "nan", "inf", "-inf", "1e9", "1e-9", "7", "1e-6",
    "-0.0", "\"x\"",
];

/// Replaces the first number of `line` by `value`.
fn replace_number(line: &str, value: &str) -> Option<String> {
    let bytes = line.as_bytes();
    let start = bytes
        .iter()
        .position(|c| c.is_ascii_digit() || *c == b'-')?;
    let end = bytes[start..]
        .iter()
        .position(|c| !(c.is_ascii_alphanumeric() || matches!(*c, b'.' | b'-' | b'+')))
        .map_or(line.len(), |e| start + e);
    Some(format!("{}{}{}", &line[..start], value, &line[end..]))
}

fn mutate(text: &str, line: usize, kind: usize, value: usize) -> String {
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let i = line % lines.len();
    match kind % 5 {
        0 => {
            if let Some(l) = replace_number(&lines[i], HOSTILE[value % HOSTILE.len()]) {
                lines[i] = l;
            }
        }
        1 => {
            lines.remove(i);
        }
        2 => {
            let l = lines[i].clone();
            lines.insert(i, l);
        }
        3 => lines[i] = "]] = {".into(),
        _ => lines.truncate(i),
    }
    lines.join("\n")
}

/// What a mutant did.
fn outcome<const D: usize>(scene: Scene<D>, tess: Box<dyn Tessellator<D>>) -> String
where
    Const<D>: Dim,
{
    let estimate = match scene.validate_within(BUDGET) {
        Ok(e) => e,
        Err(e) => return format!("scene error: {}", kind_of(&format!("{e:?}"))),
    };
    let options = Options {
        memory_budget: BUDGET,
        ..Options::default()
    };
    let mut sim = match Simulation::with_options(scene, tess, StepParams::default(), options) {
        Ok(s) => s,
        Err(e) => return format!("scene error: {}", kind_of(&format!("{e:?}"))),
    };
    if estimate.particles > STEP_LIMIT {
        return "built (not stepped: large)".into();
    }
    for _ in 0..2 {
        if sim.time() >= sim.end_time() {
            break;
        }
        if let Err(e) = sim.step() {
            return format!("run error: {}", kind_of(&format!("{e:?}")));
        }
    }
    "ran".into()
}

/// The variant name of an error's debug form.
fn kind_of(debug: &str) -> String {
    debug
        .split(|c: char| !c.is_alphanumeric())
        .find(|s| !s.is_empty())
        .unwrap_or("?")
        .to_string()
}

#[test]
fn mutated_scene_files_never_panic() {
    let all = scenes();
    let tally: Mutex<BTreeMap<String, usize>> = Mutex::new(BTreeMap::new());
    let mut runner = runner("mutated scene files", CASES);
    let inputs = (0usize..64, 0usize..400, 0usize..5, 0usize..64);
    runner
        .run(&inputs, |(file, line, kind, value)| {
            let (name, text) = &all[file % all.len()];
            let text = mutate(text, line, kind, value);
            let result = catch_unwind(AssertUnwindSafe(|| {
                match SceneFile::parse(&text, name).and_then(|f| f.build()) {
                    Err(e) => format!("file error: {}", kind_of(&format!("{e:?}"))),
                    Ok(LoadedScene::Two(s, _)) => outcome(s, Box::new(Delaunay2::default())),
                    Ok(LoadedScene::Three(s, _)) => outcome(s, Box::new(Delaunay3::default())),
                }
            }));
            let Ok(outcome) = result else {
                panic!("a panic on this mutant of {name}:\n{text}");
            };
            *tally.lock().unwrap().entry(outcome).or_default() += 1;
            Ok(())
        })
        .unwrap();
    println!("{CASES} mutants of {} scene files:", all.len());
    for (k, v) in tally.lock().unwrap().iter() {
        println!("{v:4}  {k}");
    }
}

/// The command line: random argument lists for `pfem check` and a bounded
/// `pfem run` on a bundled scene. Each ends with status 0, 1 or 2 (2: a run
/// stopped by its wall-clock cap; never a panic's 101, an abort's 134 or a
/// signal) within 60 s.
#[test]
fn random_command_lines_end_cleanly() {
    let bin = env!("CARGO_BIN_EXE_pfem");
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/scenes/dam_break_2d.toml");
    let out = std::env::temp_dir().join(format!("pfem-fuzz-cli-{}", std::process::id()));
    let words: [&[&str]; 12] = [
        &["--spacing", "1e-6", "0.01", "nan", "-1", "x"],
        &["--end-time", "0", "1e-3", "1e300", "inf"],
        &["--scheme", "newmark", "euler", "bossak", "rk4"],
        &["--solver", "direct", "cg", "lu", "magic"],
        &["--volume-correction", "0", "0.5", "7", "-1"],
        &["--memory-budget", "0.001", "1", "1e-30"],
        &["--threads", "0", "1", "2", "x"],
        &["--max-wall-time", "1", "0", "-5"],
        &["--picard-tol", "1e-6", "0", "1e300"],
        &["--bogus", "1"],
        &["-q"],
        &["--no-vtu"],
    ];
    let mut runner = runner("command lines", 48);
    let statuses: Mutex<BTreeMap<i32, usize>> = Mutex::new(BTreeMap::new());
    let picks = proptest::collection::vec((0usize..12, 0usize..8), 0..4);
    runner
        .run(&(proptest::bool::ANY, picks), |(run, picks)| {
            let mut args: Vec<String> = vec![
                if run { "run" } else { "check" }.into(),
                file.to_string_lossy().into_owned(),
            ];
            for (w, v) in picks {
                let opt = words[w];
                args.push(opt[0].into());
                if opt.len() > 1 {
                    args.push(opt[1 + v % (opt.len() - 1)].into());
                }
            }
            if run {
                // Bounded: a short end time, no frames, a wall-clock cap.
                args.extend(
                    [
                        "--end-time",
                        "0.002",
                        "--no-vtu",
                        "--quiet",
                        "--overwrite",
                        "--max-wall-time",
                        "20",
                        "--out",
                    ]
                    .map(String::from),
                );
                args.push(out.to_string_lossy().into_owned());
            }
            let mut child = std::process::Command::new(bin)
                .args(&args)
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .spawn()
                .unwrap();
            let start = std::time::Instant::now();
            let status = loop {
                if let Some(s) = child.try_wait().unwrap() {
                    break s;
                }
                if start.elapsed().as_secs() > 60 {
                    child.kill().ok();
                    panic!("`pfem {}` did not end within 60 s", args.join(" "));
                }
                std::thread::sleep(std::time::Duration::from_millis(20));
            };
            let code = status.code().unwrap_or(-1);
            // 2: stopped by the wall-clock cap before the end time.
            assert!(
                (0..=2).contains(&code),
                "`pfem {}` ended with {status}",
                args.join(" ")
            );
            *statuses.lock().unwrap().entry(code).or_default() += 1;
            Ok(())
        })
        .unwrap();
    println!(
        "48 command lines: exit status counts {:?}",
        statuses.lock().unwrap()
    );
    std::fs::remove_dir_all(&out).ok();
}

/// Found by `mutated_scene_files_never_panic` (2 December 2026): the
/// hydrostatic tank with `max_dt = 1e300` took a first step of 10³⁰⁰ s,
/// whose `Δt K` overflowed the pressure matrix to infinity, and faer's
/// Cholesky panicked on it (an index of −1). A step whose system is not
/// finite is now an error the step control answers, never a panic.
#[test]
fn an_enormous_time_step_is_an_error_or_a_run_never_a_panic() {
    let (name, text) = scenes()
        .into_iter()
        .find(|(n, _)| n.ends_with("hydrostatic_2d.toml"))
        .unwrap();
    let text = text.replace("max_dt = 5e-3", "max_dt = 1e300");
    assert!(text.contains("1e300"), "the scene's max_dt line changed");
    let result = catch_unwind(AssertUnwindSafe(|| {
        match SceneFile::parse(&text, &name).and_then(|f| f.build()) {
            Err(e) => format!("file error: {}", kind_of(&format!("{e:?}"))),
            Ok(LoadedScene::Two(s, _)) => outcome(s, Box::new(Delaunay2::default())),
            Ok(LoadedScene::Three(s, _)) => outcome(s, Box::new(Delaunay3::default())),
        }
    }));
    let outcome = result.expect("a panic");
    println!("max_dt = 1e300: {outcome}");
}
