//! Runs that survive (issue 17): `pfem run --checkpoint-every` killed with
//! SIGKILL at random points and continued with `--restart` ends with the
//! same outputs, byte for byte, as the uninterrupted run — every VTU frame,
//! the `.pvd`, `probes.csv`, and the simulation section of the final
//! checkpoint (the 2D dam break and the elastic gate). Ctrl-C (SIGINT)
//! stops a run with status 130, a final checkpoint and a summary marked
//! interrupted.
//!
//! The kill times are drawn from a seed printed by the test (set
//! `PFEM_KILL_SEED` to replay one).
//! `cargo test --release -p pfem --test restart -- --nocapture`

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use pfem::checkpoint::SIMULATION;
use pfem::observe::read_checkpoint;

const PFEM: &str = env!("CARGO_BIN_EXE_pfem");

fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../../examples/scenes/{name}.toml"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pfem-restart-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// A small deterministic generator for the kill times.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn run_args(file: &Path, out: &Path, end: &str, every: &str) -> Vec<String> {
    vec![
        "run".into(),
        file.display().to_string(),
        "--out".into(),
        out.display().to_string(),
        "--end-time".into(),
        end.into(),
        "--checkpoint-every".into(),
        every.into(),
        "--quiet".into(),
        "--threads".into(),
        "1".into(),
    ]
}

/// Every output file of `dir` but the summary (wall times) and the
/// checkpoint (timers), by name.
fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != "summary.json" && n != "checkpoint.bin")
        .map(|n| {
            let b = std::fs::read(dir.join(&n)).unwrap();
            (n, b)
        })
        .collect();
    v.sort();
    v
}

/// Runs `name` whole, then again killed `kills` times at random wall times
/// within the whole run's duration and continued from its last checkpoint
/// each time; compares the outputs.
fn kill_and_restart(name: &str, end: &str, every: &str, kills: usize, rng: &mut Lcg) {
    let file = scene(name);
    let whole = tmp(&format!("{name}-whole"));
    let t0 = Instant::now();
    let st = Command::new(PFEM)
        .args(run_args(&file, &whole, end, every))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert!(st.success(), "{name}: the uninterrupted run failed");
    let duration = t0.elapsed().as_secs_f64();

    let cut = tmp(&format!("{name}-killed"));
    let mut restarts = 0;
    let mut kills_done = 0;
    loop {
        let ck = cut.join("checkpoint.bin");
        let mut args = run_args(&file, &cut, end, every);
        if ck.exists() {
            args.push("--restart".into());
            args.push(ck.display().to_string());
            restarts += 1;
        } else {
            // Killed before its first checkpoint: start again.
            args.push("--overwrite".into());
        }
        let mut child = Command::new(PFEM)
            .args(&args)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        if kills_done == kills {
            let st = child.wait().unwrap();
            assert!(st.success(), "{name}: the last restart failed");
            break;
        }
        let at = (0.1 + 0.3 * rng.next()) * duration;
        let deadline = Instant::now() + Duration::from_secs_f64(at);
        let mut finished = false;
        while Instant::now() < deadline {
            if child.try_wait().unwrap().is_some() {
                finished = true;
                break;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        if finished {
            break;
        }
        child.kill().unwrap(); // SIGKILL
        child.wait().unwrap();
        kills_done += 1;
        let t = read_checkpoint(&ck)
            .ok()
            .and_then(|_| Some(std::fs::metadata(&ck).ok()?.len()));
        println!(
            "{name}: killed after {at:.2} s of {duration:.2} s; checkpoint {}",
            match t {
                Some(b) => format!("of {b} bytes is whole"),
                None => "absent".into(),
            }
        );
    }
    println!("{name}: {kills_done} kills, {restarts} restarts");
    assert!(restarts >= 1, "{name}: no kill came after a checkpoint");
    let (a, b) = (outputs(&whole), outputs(&cut));
    assert_eq!(
        a.iter().map(|x| &x.0).collect::<Vec<_>>(),
        b.iter().map(|x| &x.0).collect::<Vec<_>>(),
        "{name}: not the same files"
    );
    for ((n, x), (_, y)) in a.iter().zip(&b) {
        assert!(x == y, "{name}: {n} differs from the uninterrupted run's");
    }
    let sa = read_checkpoint(whole.join("checkpoint.bin")).unwrap();
    let sb = read_checkpoint(cut.join("checkpoint.bin")).unwrap();
    assert!(
        sa.section(SIMULATION) == sb.section(SIMULATION),
        "{name}: final states differ"
    );
    println!("{name}: {} files and the final state identical", a.len());
    let _ = std::fs::remove_dir_all(&whole);
    let _ = std::fs::remove_dir_all(&cut);
}

fn seed() -> u64 {
    std::env::var("PFEM_KILL_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .unwrap()
                .as_nanos() as u64
        })
}

#[test]
fn a_dam_break_killed_at_random_points_restarts_to_the_same_result() {
    let s = seed();
    println!("PFEM_KILL_SEED={s}");
    kill_and_restart("dam_break_2d", "0.12", "0.005", 3, &mut Lcg(s));
}

#[test]
fn an_elastic_gate_killed_at_random_points_restarts_to_the_same_result() {
    let s = seed();
    println!("PFEM_KILL_SEED={s}");
    kill_and_restart("elastic_gate_2d", "0.04", "0.004", 3, &mut Lcg(s ^ 0x5eed));
}

#[cfg(unix)]
#[test]
fn ctrl_c_writes_a_checkpoint_and_an_interrupted_summary() {
    let out = tmp("sigint");
    let file = scene("dam_break_2d");
    let mut child = Command::new(PFEM)
        .args([
            "run",
            &file.display().to_string(),
            "--out",
            &out.display().to_string(),
            "--end-time",
            "1.0",
            "--quiet",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for the first frame, then SIGINT.
    let t0 = Instant::now();
    while !out.join("dam_break_2d.pvd").exists() && t0.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(500));
    let st = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(st.success());
    let st = child.wait().unwrap();
    assert_eq!(st.code(), Some(130), "exit status of an interrupted run");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["extra"]["status"], "interrupted");
    let t = summary["simulated_time"].as_f64().unwrap();
    assert!(t > 0.0 && t < 1.0, "stopped at {t} s");
    let ck = read_checkpoint(out.join("checkpoint.bin")).unwrap();
    assert!(ck.section(SIMULATION).is_some());
    let _ = std::fs::remove_dir_all(&out);
}

/// A restart continues in its checkpoint's folder by default, and refuses a
/// folder that does not hold the frames its checkpoint lists (session 39's
/// review: given another folder, it deleted that folder's frames numbered
/// from the checkpoint's count on and rewrote its `.pvd`); a run stopped by
/// `--max-wall-time` ends with status 2 and says how to go on.
#[test]
fn a_restart_keeps_to_its_own_folder_and_a_wall_clock_stop_says_so() {
    let (dam, still) = (scene("dam_break_2d"), scene("hydrostatic_2d"));
    let (a, b) = (tmp("own-a"), tmp("own-b"));
    let run = |file: &Path, out: &Path, extra: &[&str]| {
        let mut args = run_args(file, out, "0.04", "0.02");
        args.extend(extra.iter().map(|s| s.to_string()));
        Command::new(PFEM).args(&args).output().unwrap()
    };
    // Another scene's run in A, the dam break in B.
    assert!(run(&still, &a, &[]).status.success());
    assert!(run(&dam, &b, &[]).status.success());
    let files_a = outputs(&a);
    let ck_b = b.join("checkpoint.bin").display().to_string();
    let restart_with = |out: Option<&Path>, extra: &[&str]| {
        let mut args = vec![
            "run".to_string(),
            dam.display().to_string(),
            "--end-time".into(),
            "0.06".into(),
            "--quiet".into(),
            "--restart".into(),
            ck_b.clone(),
        ];
        if let Some(o) = out {
            args.extend(["--out".to_string(), o.display().to_string()]);
        }
        args.extend(extra.iter().map(|s| s.to_string()));
        Command::new(PFEM).args(&args).output().unwrap()
    };
    let restart = |out: Option<&Path>| restart_with(out, &[]);
    // B's checkpoint into A's folder: refused, A untouched. With
    // `--no-vtu` too (the review of session 45: the checkpoint then lists
    // no frame to miss, and A's probes, summary and checkpoint were
    // replaced by the restart's).
    for extra in [&[][..], &["--no-vtu"][..]] {
        let o = restart_with(Some(&a), extra);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {err}");
        assert!(
            err.contains("not the checkpoint's and is not empty"),
            "{extra:?}: {err}"
        );
        assert_eq!(outputs(&a), files_a, "{extra:?}: A's files changed");
    }
    // A run without frames (E), continued into a new folder (D): its probe
    // rows are E's folder's, copied (a checkpoint holds their count and
    // hash, not the rows: session 46), and the same as E's own restart's.
    let (d, e) = (tmp("own-d"), tmp("own-e"));
    assert!(run(&dam, &e, &["--no-vtu"]).status.success());
    let ck_e = e.join("checkpoint.bin").display().to_string();
    let go_on = |out: Option<&Path>| {
        let mut args = vec!["run".to_string(), dam.display().to_string()];
        args.extend(["--end-time", "0.06", "--quiet", "--no-vtu", "--restart"].map(String::from));
        args.push(ck_e.clone());
        if let Some(o) = out {
            args.extend(["--out".to_string(), o.display().to_string()]);
        }
        Command::new(PFEM).args(&args).output().unwrap()
    };
    for out in [Some(d.as_path()), None] {
        let o = go_on(out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let rows = |dir: &Path| std::fs::read_to_string(dir.join("probes.csv")).unwrap();
    assert_eq!(rows(&d), rows(&e), "the restart into a new folder");
    assert!(rows(&e).lines().count() > 20);
    // B (with frames) into a new folder is refused, and leaves it empty.
    let f = tmp("own-f");
    let o = restart(Some(&f));
    assert_eq!(o.status.code(), Some(1));
    assert!(std::fs::read_dir(&f).map_or(true, |mut d| d.next().is_none()));
    // Without --out, B's checkpoint continues in B's folder.
    let o = restart(None);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(b.join("summary.json")).unwrap()).unwrap();
    assert!((summary["simulated_time"].as_f64().unwrap() - 0.06).abs() < 1e-9);
    // Its wall time is the whole run's, as its stages' are (before session
    // 49, the last invocation's alone: below the sum of the stages).
    let wall = &summary["wall_time_s"];
    let stages: f64 = ["remesh", "assemble", "solve", "update", "hooks", "output"]
        .iter()
        .map(|k| wall[*k].as_f64().unwrap())
        .sum();
    let total = wall["total"].as_f64().unwrap();
    assert!(
        total >= stages,
        "total {total} s below its stages' {stages} s"
    );
    // B's checkpoint (t = 0.04 s) to an end time before it: nothing to
    // run, said, and its summary as it was (before session 49:
    // "finished", the summary rewritten from a fresh remeshing's volume).
    let before = std::fs::read(b.join("summary.json")).unwrap();
    let o = Command::new(PFEM)
        .args([
            "run",
            &dam.display().to_string(),
            "--end-time",
            "0.03",
            "--quiet",
            "--restart",
            &ck_b,
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("nothing to run"), "{err}");
    assert_eq!(std::fs::read(b.join("summary.json")).unwrap(), before);
    // B's checkpoint through a link in another folder L: a refused
    // restart (another scene) leaves L's files (before session 49 it
    // continued in the link's folder and, refused, emptied it).
    let l = tmp("own-l");
    std::fs::create_dir_all(&l).unwrap();
    std::fs::write(l.join("notes.txt"), "mine").unwrap();
    #[cfg(unix)]
    {
        let link = l.join("ck.bin");
        std::os::unix::fs::symlink(b.join("checkpoint.bin"), &link).unwrap();
        let o = Command::new(PFEM)
            .args(["run", &still.display().to_string(), "--quiet", "--restart"])
            .arg(&link)
            .output()
            .unwrap();
        assert_eq!(
            o.status.code(),
            Some(1),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert_eq!(
            std::fs::read_to_string(l.join("notes.txt")).unwrap(),
            "mine"
        );
        assert!(link.exists(), "the link was removed");
        let mut names: Vec<String> = std::fs::read_dir(&l)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["ck.bin", "notes.txt"]);
    }
    let _ = std::fs::remove_dir_all(&l);
    // A run with frames (G), continued without (`--no-vtu`), then with
    // frames again: the frames listed before are carried on by the
    // checkpoints of the part without (before session 49 that part's
    // checkpoint listed none and said "no frames", and the third part was
    // refused for good).
    let g = tmp("own-g");
    assert!(run(&dam, &g, &[]).status.success());
    let ck_g = g.join("checkpoint.bin").display().to_string();
    let go = |end: &str, extra: &[&str]| {
        let mut args = vec!["run".to_string(), dam.display().to_string()];
        args.extend(
            [
                "--end-time",
                end,
                "--checkpoint-every",
                "0.02",
                "--quiet",
                "--restart",
            ]
            .map(String::from),
        );
        args.push(ck_g.clone());
        args.extend(extra.iter().map(|s| s.to_string()));
        Command::new(PFEM).args(&args).output().unwrap()
    };
    let listed = || {
        std::fs::read_to_string(g.join("dam_break_2d.pvd"))
            .unwrap()
            .matches("<DataSet")
            .count()
    };
    let first = listed();
    let o = go("0.06", &["--no-vtu"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(listed(), first);
    let o = go("0.08", &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        listed() > first,
        "{} frames listed, {first} before",
        listed()
    );
    let _ = std::fs::remove_dir_all(&g);
    // A wall-clock limit shorter than a step: status 2, the hint printed.
    let c = tmp("own-c");
    let o = run(&dam, &c, &["--max-wall-time", "1e-6"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("wall-clock limit") && err.contains("--restart"),
        "{err}"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(c.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["extra"]["status"], "stopped");
    for dir in [a, b, c, d, e, f] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// A restart under an edited scene file is refused, naming what differs
/// (the checkpoint keeps the file's text): a review of session 55 moved a
/// point probe (its column changed meaning mid-file, 984.66 → 1 471.59 Pa
/// between two rows), changed the gravity (ignored: the checkpoint's ran
/// on) and scaled a force table (applied), all accepted. The end time and
/// the frames' interval may change; a `--spacing` the run did not have is
/// named as the spacing.
#[test]
fn a_restart_under_an_edited_scene_file_is_refused_by_what_differs() {
    let dir = tmp("edited");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(scene("loaded_cantilever_2d")).unwrap();
    let file = dir.join("beam.toml");
    std::fs::write(&file, &text).unwrap();
    let out = dir.join("out");
    let ran = Command::new(PFEM)
        .args(run_args(&file, &out, "0.02", "0.01"))
        .output()
        .unwrap();
    assert!(ran.status.success(), "{ran:?}");
    let checkpoint = out.join("checkpoint.bin");
    let restart = |edited: &str, extra: &[&str]| {
        std::fs::write(&file, edited).unwrap();
        let copy = dir.join("copy");
        let _ = std::fs::remove_dir_all(&copy);
        std::fs::create_dir_all(&copy).unwrap();
        for e in std::fs::read_dir(&out).unwrap().flatten() {
            std::fs::copy(e.path(), copy.join(e.file_name())).unwrap();
        }
        let mut args = run_args(&file, &copy, "0.03", "0.01");
        args.extend([
            "--restart".into(),
            copy.join("checkpoint.bin").display().to_string(),
        ]);
        args.extend(extra.iter().map(|s| s.to_string()));
        Command::new(PFEM).args(args).output().unwrap()
    };
    let _ = &checkpoint;
    for (edit, key) in [
        (
            text.replace(
                "[0.2, 0.0, -2000.0], [1.0, 0.0, -2000.0]",
                "[0.2, 0.0, -20000.0], [1.0, 0.0, -20000.0]",
            ),
            "[[force]]",
        ),
        (
            text.replace("point = [0.5, 0.0]", "point = [0.4, 0.0]"),
            "probes",
        ),
        (
            text.replace("dimension = 2\n", "dimension = 2\ngravity = [0.0, -9.81]\n"),
            "gravity",
        ),
        (text.replace("young = 2e9", "young = 2.1e9"), "body `beam`"),
    ] {
        assert_ne!(edit, text, "the edit for {key} applies");
        let r = restart(&edit, &[]);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success(), "{key}: accepted");
        assert!(
            err.contains("the scene file differs") && err.contains(key),
            "{key}: {err}"
        );
    }
    // Another `--spacing` than the run's: named as the option (it read
    // "the scene file differs … in spacing, body `beam`").
    let r = restart(&text, &["--spacing", "0.00625"]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("its run was given none, this one --spacing 0.00625"),
        "{err}"
    );
    // Comments, the end time and the frames' interval: accepted.
    let edit = format!(
        "# a comment\n{}",
        text.replace("end_time = 0.6", "end_time = 0.9")
            .replace("output_interval = 0.02", "output_interval = 0.01")
    );
    for edited in [text.as_str(), edit.as_str()] {
        let r = restart(edited, &[]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A restarted run's summary is its own: the stop's, left in the folder,
/// outlived a kill of the continued run (a review of session 55:
/// "stopped" at 0.030 s beside probe rows to 0.071 s). Whenever the
/// continued run is killed, the folder's summary (if any) is not behind
/// its probe rows.
#[test]
fn a_killed_restart_leaves_no_summary_behind_its_rows() {
    let dir = tmp("stale-summary");
    let file = scene("dam_break_2d");
    let out = dir.join("out");
    let mut args = run_args(&file, &out, "0.01", "0.005");
    args.extend(["--spacing".into(), "0.005715".into()]);
    let ran = Command::new(PFEM).args(&args).output().unwrap();
    assert!(ran.status.success(), "{ran:?}");
    let summary = out.join("summary.json");
    assert!(summary.is_file());
    let mut args = run_args(&file, &out, "5.0", "1.0");
    args.extend([
        "--spacing".into(),
        "0.005715".into(),
        "--restart".into(),
        out.join("checkpoint.bin").display().to_string(),
    ]);
    let mut child = Command::new(PFEM)
        .args(&args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Killed once it has written rows past the checkpoint's.
    let rows = |p: &Path| std::fs::read_to_string(p).map_or(0, |t| t.lines().count());
    let before = rows(&out.join("probes.csv"));
    let deadline = Instant::now() + Duration::from_secs(60);
    while rows(&out.join("probes.csv")) < before + 5 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(
        rows(&out.join("probes.csv")) >= before + 5,
        "no rows were written"
    );
    if let Ok(text) = std::fs::read_to_string(&summary) {
        let last_row: f64 = std::fs::read_to_string(out.join("probes.csv"))
            .unwrap()
            .lines()
            .last()
            .and_then(|l| l.split(',').next())
            .and_then(|t| t.parse().ok())
            .unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let t = v["simulated_time"].as_f64().unwrap();
        assert!(t >= last_row, "summary at {t} s, rows to {last_row} s");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
