//! CSV probes, atomic writes, `summary.json`, reference data and plots.

use std::path::PathBuf;

use pfem_io::output::{
    load_reference_csv, parse_reference_csv, plot_series_png, reference, write_atomic,
    write_summary, CsvProbe, OutputError, PlotSeries, PlotSpec, RunSummary, SeriesStyle,
};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pfem-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn csv_probe_is_readable_after_every_row() {
    let dir = temp_dir("csv");
    let path = dir.join("probe.csv");
    let mut probe = CsvProbe::create(&path, &["t", "front_x", "volume"]).unwrap();
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        "t,front_x,volume\n"
    );
    let rows = [
        [0.0, 0.146, 0.021_316],
        [1.0e-7, 0.146_000_000_1, f64::NAN],
        [0.3, 1.0 / 3.0, -2.5e20],
    ];
    for (k, row) in rows.iter().enumerate() {
        probe.row(row).unwrap();
        // No flush or drop needed: the row is in the file already.
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<_> = text.lines().collect();
        assert_eq!(lines.len(), k + 2);
        let parsed: Vec<f64> = lines[k + 1]
            .split(',')
            .map(|v| v.parse().unwrap())
            .collect();
        for (a, b) in parsed.iter().zip(row) {
            assert!(a == b || (a.is_nan() && b.is_nan()), "{a} vs {b}");
        }
    }
    let err = probe.row(&[1.0, 2.0]).unwrap_err();
    assert!(matches!(
        err,
        OutputError::RowLength {
            expected: 3,
            got: 2,
            ..
        }
    ));
    assert!(err.to_string().contains("probe.csv"));

    let err = CsvProbe::create(dir.join("bad.csv"), &["t", "x,y"]).unwrap_err();
    assert!(matches!(err, OutputError::ColumnName { ref name, .. } if name == "x,y"));
    // Session 27: a tab, no column at all, and a name given twice (a probe
    // named `t`) were accepted: blank rows, or two columns of one name of
    // which readers take the first.
    let err = CsvProbe::create(dir.join("bad.csv"), &["t", "a\tb"]).unwrap_err();
    assert!(matches!(err, OutputError::ColumnName { .. }), "{err}");
    let err = CsvProbe::create(dir.join("bad.csv"), &[]).unwrap_err();
    assert!(matches!(err, OutputError::ColumnName { .. }), "{err}");
    let err = CsvProbe::create(dir.join("bad.csv"), &["t", "x", "t"]).unwrap_err();
    assert!(
        matches!(err, OutputError::DuplicateColumn { ref name, .. } if name == "t"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn atomic_write_replaces_whole_and_leaves_no_temporary() {
    let dir = temp_dir("atomic");
    let path = dir.join("state.json");
    write_atomic(&path, b"first version, rather long").unwrap();
    write_atomic(&path, b"second").unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"second");
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["state.json"]);

    // A missing directory fails with the target path, and nothing is left.
    let missing = dir.join("no-such-dir").join("x.bin");
    let err = write_atomic(&missing, b"x").unwrap_err();
    assert!(matches!(&err, OutputError::Io { path, .. } if path == &missing));
    assert!(err.to_string().contains("no-such-dir"));

    // Many threads writing the same file never leave a mixed result.
    let shared = dir.join("shared.txt");
    std::thread::scope(|s| {
        for k in 0..8u8 {
            let shared = &shared;
            s.spawn(move || {
                let bytes = vec![b'a' + k; 100_000];
                for _ in 0..5 {
                    write_atomic(shared, &bytes).unwrap();
                }
            });
        }
    });
    let bytes = std::fs::read(&shared).unwrap();
    assert_eq!(bytes.len(), 100_000);
    assert!(bytes.iter().all(|&b| b == bytes[0]));
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        2,
        "no temporaries left"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn summary_json_round_trips() {
    let dir = temp_dir("summary");
    let path = dir.join("summary.json");
    let mut s = RunSummary {
        scene: "dam_break_2d".into(),
        dimension: 2,
        particles: 4321,
        steps: 1500,
        rejected_steps: 3,
        simulated_time: 0.6,
        fluid_volume_initial: 0.0322,
        fluid_volume_final: 0.0320,
        ..Default::default()
    };
    s.wall_time_s.insert("remesh".into(), 12.5);
    s.wall_time_s.insert("solve".into(), 40.25);
    s.volume_change_by_cause
        .insert("alpha_shape".into(), -1.5e-4);
    s.volume_change_by_cause
        .insert("particle_removal".into(), -5.0e-5);
    s.extra.insert("time_shift_s".into(), 0.02.into());
    s.extra.insert("note".into(), "coarse".into());
    s.extra.insert("nan_figure".into(), f64::NAN.into());
    write_summary(&path, &s).unwrap();

    let text = std::fs::read_to_string(&path).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["scene"], "dam_break_2d");
    assert_eq!(v["particles"], 4321);
    assert_eq!(v["steps"], 1500);
    assert_eq!(v["rejected_steps"], 3);
    assert_eq!(v["wall_time_s"]["remesh"], 12.5);
    assert_eq!(v["wall_time_s"]["solve"], 40.25);
    assert_eq!(v["fluid_volume_initial"], 0.0322);
    assert_eq!(v["volume_change_by_cause"]["alpha_shape"], -1.5e-4);
    assert_eq!(v["extra"]["note"], "coarse");
    assert!(v["extra"]["nan_figure"].is_null(), "NaN becomes null");

    s.extra.remove("nan_figure");
    write_summary(&path, &s).unwrap();
    let back: RunSummary = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    assert_eq!(back, s);
    assert!((s.relative_volume_change() - (-0.0002 / 0.0322)).abs() < 1e-12);
    // With an inflow's water, against the volume intended (session 44's
    // review: an inflow of more than 5 % read as an unresolved run); a
    // summary written before the field was recorded reads as none.
    let mut inflow = s.clone();
    inflow.fluid_volume_final = 0.0420;
    inflow.fluid_volume_intended = Some(0.0422);
    assert!((inflow.relative_volume_change() - (-0.0002 / 0.0422)).abs() < 1e-12);
    // An outflow that drained it all: no error (it read −100 %).
    let mut drained = s.clone();
    drained.fluid_volume_final = 0.0;
    drained.fluid_volume_intended = Some(0.0);
    assert_eq!(drained.relative_volume_change(), 0.0);
    let mut old: serde_json::Value = serde_json::to_value(&s).unwrap();
    old.as_object_mut().unwrap().remove("fluid_volume_intended");
    let old: RunSummary = serde_json::from_value(old).unwrap();
    assert_eq!(old.fluid_volume_intended, None);
    assert!((old.relative_volume_change() - (-0.0002 / 0.0322)).abs() < 1e-12);
    // A non-finite figure of the summary's own fields is written as null
    // and read back as NaN (session 39's review: reading failed).
    s.fluid_volume_final = f64::NAN;
    s.wall_time_s.insert("remesh".into(), f64::INFINITY);
    write_summary(&path, &s).unwrap();
    let back: RunSummary = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    assert!(back.fluid_volume_final.is_nan() && back.wall_time_s["remesh"].is_nan());
    assert_eq!(back.simulated_time, s.simulated_time);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn reference_files_match_embedded_copies() {
    let data = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/validation");
    let pairs = [
        (
            "martin_moyce_1952_n2_2_a2.25in_front.csv",
            reference::MARTIN_MOYCE_N2_2_A2_25IN_FRONT,
        ),
        (
            "martin_moyce_1952_n2_2_a1.125in_front.csv",
            reference::MARTIN_MOYCE_N2_2_A1_125IN_FRONT,
        ),
        (
            "martin_moyce_1952_n2_1_front.csv",
            reference::MARTIN_MOYCE_N2_1_FRONT,
        ),
        (
            "martin_moyce_1952_n2_1_height.csv",
            reference::MARTIN_MOYCE_N2_1_HEIGHT,
        ),
        (
            "antoci_2007_gate_experiment_ux.csv",
            reference::ANTOCI_2007_GATE_UX,
        ),
        (
            "antoci_2007_gate_experiment_uy.csv",
            reference::ANTOCI_2007_GATE_UY,
        ),
    ];
    for (file, embedded) in pairs {
        let loaded = load_reference_csv(data.join(file)).unwrap();
        assert_eq!(loaded, parse_reference_csv(embedded).unwrap(), "{file}");
    }
    let front = parse_reference_csv(reference::MARTIN_MOYCE_N2_1_FRONT).unwrap();
    assert_eq!(front[0], (0.43, 1.11));
    let ux = parse_reference_csv(reference::ANTOCI_2007_GATE_UX).unwrap();
    assert_eq!(ux[1], (0.04363, 0.012889));

    let err = load_reference_csv(data.join("no_such.csv")).unwrap_err();
    assert!(matches!(err, OutputError::Io { .. }));
    let dir = temp_dir("refcsv");
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "# x\nT,Z\n0.1,0.2\n0.2,oops\n").unwrap();
    let err = load_reference_csv(&bad).unwrap_err();
    assert!(matches!(&err, OutputError::Parse { source, .. } if source.line == 4));
    assert!(err.to_string().contains("bad.csv"));
    std::fs::remove_dir_all(&dir).ok();
}

/// Writes the comparison plot; the PNG is left in the temp dir for a look.
#[test]
fn plot_renders_png_with_text() {
    let dir = std::env::temp_dir().join("pfem-test-plot");
    std::fs::create_dir_all(&dir).unwrap();
    let measured = parse_reference_csv(reference::MARTIN_MOYCE_N2_2_A2_25IN_FRONT).unwrap();
    let measured_small = parse_reference_csv(reference::MARTIN_MOYCE_N2_2_A1_125IN_FRONT).unwrap();
    let simulated: Vec<(f64, f64)> = (0..=60)
        .map(|i| {
            let t = 0.125 * f64::from(i);
            (t, 1.0 + 0.2 * t.powf(1.55))
        })
        .collect();
    let spec = PlotSpec {
        title: "Dam break (n² = 2): surge front".into(),
        x_label: "T = t·√(2g/a)".into(),
        y_label: "Z = x/a".into(),
        series: vec![
            PlotSeries::line("pfem (synthetic)", &simulated),
            PlotSeries::markers("Martin & Moyce 1952, a = 2.25 in", &measured),
            PlotSeries {
                label: "Martin & Moyce 1952, a = 1.125 in".into(),
                points: &measured_small,
                style: SeriesStyle::LineAndMarkers,
            },
        ],
        ..Default::default()
    };
    let path = dir.join(format!("front-{}.png", std::process::id()));
    plot_series_png(&path, &spec).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");

    // Decode and check the image is not blank: white background, some
    // coloured pixels from each series colour.
    let decoder = png::Decoder::new(std::io::Cursor::new(&bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut rgb = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut rgb).unwrap();
    assert_eq!((info.width, info.height), (800, 600));
    let px: Vec<&[u8]> = rgb.chunks_exact(3).collect();
    let count = |c: [u8; 3]| px.iter().filter(|p| **p == c).count();
    assert!(count([255, 255, 255]) > 300_000, "mostly white");
    assert!(count([31, 119, 180]) > 200, "line series drawn");
    assert!(count([255, 127, 14]) > 200, "markers drawn");
    assert!(count([0, 0, 0]) > 500, "axes and text drawn");

    let err = plot_series_png(
        dir.join("tiny.png"),
        &PlotSpec {
            width: 10,
            ..Default::default()
        },
    );
    assert!(matches!(err, Err(OutputError::Plot { .. })));
}

/// `CsvProbe::resume` keeps the first bytes a checkpoint counts, drops the
/// rest (rows written after it), ends a kept row cut before its line end,
/// and appends after them.
#[test]
fn a_csv_probe_resumes_after_the_rows_it_keeps() {
    let dir = temp_dir("csv-resume");
    let path = dir.join("probes.csv");
    std::fs::write(&path, "t,a\n0.0,1.0\n0.5,2.0\n1.0,3.0\n").unwrap();
    let keep = "t,a\n0.0,1.0\n".len() as u64;
    let mut probe = CsvProbe::resume(&path, &["t", "a"], keep).unwrap();
    probe.row(&[0.25, 4.0]).unwrap();
    probe.sync().unwrap();
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        "t,a\n0.0,1.0\n0.25,4.0\n"
    );
    // Cut before the line end of its last kept row.
    let mut probe = CsvProbe::resume(&path, &["t", "a"], keep - 1).unwrap();
    probe.row(&[0.5, 5.0]).unwrap();
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        "t,a\n0.0,1.0\n0.5,5.0\n"
    );
    assert!(CsvProbe::resume(dir.join("none.csv"), &["t"], 0).is_err());
    std::fs::remove_dir_all(&dir).ok();
}
