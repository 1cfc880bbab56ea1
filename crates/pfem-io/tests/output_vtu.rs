//! The `.vtu` and `.pvd` writers, read back with an independent XML parser
//! (roxmltree) and an independent base64 decoder.

use std::path::{Path, PathBuf};

use base64::Engine as _;
use pfem_core::{Point, Tensor, Vector};
use pfem_io::output::{write_vtu, Encoding, Field, Frame, OutputError, PvdWriter, VtuSeries};

/// A fresh, empty directory under the system temp dir.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pfem-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// One `<DataArray>` decoded to `f64`s (integers are exact in `f64`).
#[derive(Debug)]
struct Array {
    vtk_type: String,
    components: usize,
    values: Vec<f64>,
}

fn decode(node: roxmltree::Node<'_, '_>) -> Array {
    assert_eq!(node.tag_name().name(), "DataArray");
    let vtk_type = node.attribute("type").unwrap().to_owned();
    let components = node
        .attribute("NumberOfComponents")
        .map_or(1, |c| c.parse().unwrap());
    let text = node.text().unwrap_or("").trim();
    let values = match node.attribute("format").unwrap() {
        "ascii" => text
            .split_whitespace()
            .map(|v| v.parse::<f64>().unwrap())
            .collect(),
        "binary" => {
            let bytes = base64::engine::general_purpose::STANDARD
                .decode(text)
                .unwrap();
            let n = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
            let data = &bytes[8..];
            assert_eq!(n, data.len(), "header byte count");
            match vtk_type.as_str() {
                "Float64" => data
                    .chunks_exact(8)
                    .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                    .collect(),
                "Int64" => data
                    .chunks_exact(8)
                    .map(|c| i64::from_le_bytes(c.try_into().unwrap()) as f64)
                    .collect(),
                "Int32" => data
                    .chunks_exact(4)
                    .map(|c| f64::from(i32::from_le_bytes(c.try_into().unwrap())))
                    .collect(),
                "UInt8" => data.iter().map(|&b| f64::from(b)).collect(),
                t => panic!("unexpected type {t}"),
            }
        }
        f => panic!("unexpected format {f}"),
    };
    Array {
        vtk_type,
        components,
        values,
    }
}

/// The parsed parts of a `.vtu` file.
struct Vtu {
    n_points: usize,
    n_cells: usize,
    time: Option<f64>,
    points: Array,
    connectivity: Array,
    offsets: Array,
    types: Array,
    point_data: Vec<(String, Array)>,
    cell_data: Vec<(String, Array)>,
}

fn child<'a, 'i>(node: roxmltree::Node<'a, 'i>, name: &str) -> roxmltree::Node<'a, 'i> {
    node.children()
        .find(|n| n.has_tag_name(name))
        .unwrap_or_else(|| panic!("no <{name}> in <{}>", node.tag_name().name()))
}

fn named_arrays(node: roxmltree::Node<'_, '_>) -> Vec<(String, Array)> {
    node.children()
        .filter(|n| n.has_tag_name("DataArray"))
        .map(|n| (n.attribute("Name").unwrap().to_owned(), decode(n)))
        .collect()
}

fn read_vtu(path: &Path) -> Vtu {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "VTKFile");
    assert_eq!(root.attribute("type"), Some("UnstructuredGrid"));
    assert_eq!(root.attribute("byte_order"), Some("LittleEndian"));
    assert_eq!(root.attribute("header_type"), Some("UInt64"));
    let grid = child(root, "UnstructuredGrid");
    let time = grid
        .children()
        .find(|n| n.has_tag_name("FieldData"))
        .map(|fd| {
            let (name, a) = named_arrays(fd).pop().unwrap();
            assert_eq!(name, "TimeValue");
            a.values[0]
        });
    let pieces: Vec<_> = grid
        .children()
        .filter(|n| n.has_tag_name("Piece"))
        .collect();
    assert_eq!(pieces.len(), 1);
    let piece = pieces[0];
    let cells = child(piece, "Cells");
    let cell_arrays = named_arrays(cells);
    let take = |name: &str| -> Array {
        let (_, a) = cell_arrays.iter().find(|(n, _)| n == name).unwrap();
        Array {
            vtk_type: a.vtk_type.clone(),
            components: a.components,
            values: a.values.clone(),
        }
    };
    Vtu {
        n_points: piece.attribute("NumberOfPoints").unwrap().parse().unwrap(),
        n_cells: piece.attribute("NumberOfCells").unwrap().parse().unwrap(),
        time,
        points: decode(child(child(piece, "Points"), "DataArray")),
        connectivity: take("connectivity"),
        offsets: take("offsets"),
        types: take("types"),
        point_data: named_arrays(child(piece, "PointData")),
        cell_data: named_arrays(child(piece, "CellData")),
    }
}

fn find<'a>(arrays: &'a [(String, Array)], name: &str) -> &'a Array {
    &arrays.iter().find(|(n, _)| n == name).unwrap().1
}

/// Two triangles of a unit square, plus one isolated particle.
fn check_2d(encoding: Encoding, dir: &Path) {
    let points = [
        Point::<2>::new(0.0, 0.0),
        Point::<2>::new(1.0, 0.0),
        Point::<2>::new(1.0, 1.0),
        Point::<2>::new(0.0, 1.0),
        Point::<2>::new(0.3, 2.5e-7),
    ];
    let cells = [0, 1, 2, 0, 2, 3];
    let pressure = [1.0, -2.5, 1.0 / 3.0, 1e300, 7.0e-12];
    let velocity: Vec<_> = (0..5)
        .map(|i| Vector::<2>::new(i as f64, -0.1 * i as f64))
        .collect();
    let stress: Vec<_> = (0..5)
        .map(|i| Tensor::<2>::new(1.0 + i as f64, 0.5, 0.5, -2.0))
        .collect();
    let ids = [10, -3, 7, 0, 2_000_000_000];
    let free = [0u8, 0, 1, 1, 1];
    let material = [1i32, 2];
    let area = [0.5, 0.5, 0.0];
    let frame = Frame {
        points: &points,
        cells: &cells,
        vertex_cells: &[4],
        point_data: vec![
            Field::scalar("pressure", &pressure),
            Field::vector("velocity", &velocity),
            Field::sym_tensor("stress", &stress),
            Field::tensor("stress_full", &stress),
            Field::int("id", &ids),
            Field::flag("free_surface & <boundary>", &free),
        ],
        // `material` covers the simplices only: padded with 0 for the vertex.
        cell_data: vec![
            Field::int("material", &material),
            Field::scalar("area", &area),
        ],
        time: Some(0.125),
    };
    let path = dir.join(format!("frame2d_{encoding:?}.vtu"));
    write_vtu(&path, &frame, encoding).unwrap();
    let v = read_vtu(&path);

    assert_eq!((v.n_points, v.n_cells), (5, 3));
    assert_eq!(v.time, Some(0.125));
    assert_eq!(v.points.vtk_type, "Float64");
    assert_eq!(v.points.components, 3);
    let expected_points: Vec<f64> = points.iter().flat_map(|p| [p.x, p.y, 0.0]).collect();
    assert_eq!(v.points.values, expected_points);
    assert_eq!(v.connectivity.values, [0., 1., 2., 0., 2., 3., 4.]);
    assert_eq!(v.offsets.values, [3., 6., 7.]);
    assert_eq!(v.types.vtk_type, "UInt8");
    assert_eq!(v.types.values, [5., 5., 1.]);

    let p = find(&v.point_data, "pressure");
    assert_eq!((p.vtk_type.as_str(), p.components), ("Float64", 1));
    assert_eq!(p.values, pressure, "f64 round-trips exactly");
    let u = find(&v.point_data, "velocity");
    assert_eq!(u.components, 3);
    assert_eq!(u.values.len(), 15);
    assert_eq!(&u.values[6..9], &[2.0, -0.2, 0.0]);
    let s = find(&v.point_data, "stress");
    assert_eq!(s.components, 6);
    // XX YY ZZ XY YZ XZ
    assert_eq!(&s.values[6..12], &[2.0, -2.0, 0.0, 0.5, 0.0, 0.0]);
    let s9 = find(&v.point_data, "stress_full");
    assert_eq!(s9.components, 9);
    assert_eq!(
        &s9.values[9..18],
        &[2.0, 0.5, 0.0, 0.5, -2.0, 0.0, 0.0, 0.0, 0.0]
    );
    let id = find(&v.point_data, "id");
    assert_eq!(id.vtk_type, "Int32");
    assert_eq!(id.values, ids.map(f64::from));
    let flag = find(&v.point_data, "free_surface & <boundary>");
    assert_eq!(flag.vtk_type, "UInt8");
    assert_eq!(flag.values, [0., 0., 1., 1., 1.]);

    let m = find(&v.cell_data, "material");
    assert_eq!(m.values, [1., 2., 0.]);
    assert_eq!(find(&v.cell_data, "area").values, area);
}

#[test]
fn vtu_2d_round_trips_base64() {
    let dir = temp_dir("vtu2d-b64");
    check_2d(Encoding::Base64, &dir);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn vtu_2d_round_trips_ascii() {
    let dir = temp_dir("vtu2d-ascii");
    check_2d(Encoding::Ascii, &dir);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn vtu_3d_round_trips() {
    let dir = temp_dir("vtu3d");
    // Two tetrahedra sharing a face, and two isolated particles.
    let points = [
        Point::<3>::new(0.0, 0.0, 0.0),
        Point::<3>::new(1.0, 0.0, 0.0),
        Point::<3>::new(0.0, 1.0, 0.0),
        Point::<3>::new(0.0, 0.0, 1.0),
        Point::<3>::new(1.0, 1.0, 1.0),
        Point::<3>::new(5.0, 5.0, 5.0),
        Point::<3>::new(-5.0, 5.0, 5.0),
    ];
    let cells = [0, 1, 2, 3, 1, 2, 3, 4];
    let velocity: Vec<_> = (0..7)
        .map(|i| Vector::<3>::new(i as f64, 2.0 * i as f64, -(i as f64)))
        .collect();
    let stress: Vec<_> = (0..7)
        .map(|i| Tensor::<3>::new(1.0, 4.0, 6.0, 4.0, 2.0, 5.0, 6.0, 5.0, 3.0 + i as f64))
        .collect();
    let volume = [1.0 / 6.0, 1.0 / 3.0, 0.0, 0.0];
    for encoding in [Encoding::Base64, Encoding::Ascii] {
        let frame = Frame {
            points: &points,
            cells: &cells,
            vertex_cells: &[5, 6],
            point_data: vec![
                Field::vector("velocity", &velocity),
                Field::sym_tensor("stress", &stress),
            ],
            cell_data: vec![Field::scalar("volume", &volume)],
            time: None,
        };
        let path = dir.join(format!("frame3d_{encoding:?}.vtu"));
        write_vtu(&path, &frame, encoding).unwrap();
        let v = read_vtu(&path);
        assert_eq!((v.n_points, v.n_cells), (7, 4));
        assert_eq!(v.time, None);
        let expected: Vec<f64> = points.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
        assert_eq!(v.points.values, expected);
        assert_eq!(v.connectivity.vtk_type, "Int64");
        assert_eq!(
            v.connectivity.values,
            [0., 1., 2., 3., 1., 2., 3., 4., 5., 6.]
        );
        assert_eq!(v.offsets.values, [4., 8., 9., 10.]);
        assert_eq!(v.types.values, [10., 10., 1., 1.]);
        assert_eq!(
            &find(&v.point_data, "velocity").values[9..12],
            &[3.0, 6.0, -3.0]
        );
        assert_eq!(
            &find(&v.point_data, "stress").values[6..12],
            &[1.0, 2.0, 4.0, 4.0, 5.0, 6.0]
        );
        assert_eq!(find(&v.cell_data, "volume").values, volume);
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn invalid_frame_names_the_file_and_writes_nothing() {
    let dir = temp_dir("vtu-invalid");
    let points = [Point::<2>::zeros(); 3];
    let short = [1.0; 2];
    let frame = Frame {
        points: &points,
        cells: &[0, 1, 2],
        point_data: vec![Field::scalar("p", &short)],
        ..Default::default()
    };
    let path = dir.join("bad.vtu");
    let err = write_vtu(&path, &frame, Encoding::Base64).unwrap_err();
    assert!(matches!(&err, OutputError::InvalidFrame { path: p, .. } if p == &path));
    assert!(err.to_string().contains("bad.vtu"), "{err}");
    assert!(!path.exists());
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "no temporary left"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn series_writes_frames_then_a_valid_pvd() {
    let dir = temp_dir("series").join("nested/out");
    let points = [
        Point::<2>::new(0.0, 0.0),
        Point::<2>::new(1.0, 0.0),
        Point::<2>::new(0.0, 1.0),
    ];
    let mut series = VtuSeries::create(&dir, "dam", Encoding::Base64).unwrap();
    assert!(series.is_empty());
    // An empty collection is valid XML already.
    let doc_text = std::fs::read_to_string(series.pvd_path()).unwrap();
    roxmltree::Document::parse(&doc_text).unwrap();

    for (k, t) in [0.0, 0.05, 1e-7].into_iter().enumerate() {
        let frame = Frame {
            points: &points,
            cells: &[0, 1, 2],
            ..Default::default()
        };
        let file = series.write_frame(t, &frame).unwrap();
        assert_eq!(file, dir.join(format!("dam_{k:06}.vtu")));
        assert_eq!(read_vtu(&file).time, Some(t));

        // After every frame the collection parses and lists every frame.
        let text = std::fs::read_to_string(dir.join("dam.pvd")).unwrap();
        let doc = roxmltree::Document::parse(&text).unwrap();
        let root = doc.root_element();
        assert_eq!(root.attribute("type"), Some("Collection"));
        let sets: Vec<_> = child(root, "Collection")
            .children()
            .filter(|n| n.has_tag_name("DataSet"))
            .collect();
        assert_eq!(sets.len(), k + 1);
        let last = sets[k];
        assert_eq!(
            last.attribute("timestep").unwrap().parse::<f64>().unwrap(),
            t
        );
        let listed = last.attribute("file").unwrap();
        assert_eq!(listed, format!("dam_{k:06}.vtu"), "relative to the .pvd");
        assert!(dir.join(listed).exists());
    }
    assert_eq!(series.len(), 3);
    std::fs::remove_dir_all(dir.parent().unwrap().parent().unwrap()).ok();
}

#[test]
fn pvd_writer_escapes_and_fails_with_the_path() {
    let dir = temp_dir("pvd");
    let mut pvd = PvdWriter::create(dir.join("x.pvd")).unwrap();
    pvd.push(1.5, "a&b/\"c\".vtu").unwrap();
    let text = std::fs::read_to_string(pvd.path()).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let set = doc
        .descendants()
        .find(|n| n.has_tag_name("DataSet"))
        .unwrap();
    assert_eq!(set.attribute("file"), Some("a&b/\"c\".vtu"));

    let missing = dir.join("no/such/dir/y.pvd");
    let err = PvdWriter::create(&missing).unwrap_err();
    assert!(matches!(&err, OutputError::Io { path, .. } if path == &missing));
    std::fs::remove_dir_all(&dir).ok();
}

/// Leaves a 2D and a 3D frame plus a series in `PFEM_VTU_SAMPLE_DIR` (or
/// the system's temporary folder), for `docs/check_vtu.py` to open with
/// VTK itself. Ignored (it writes files for another program to check):
/// `PFEM_VTU_SAMPLE_DIR=/tmp/vtu cargo test -p pfem-io --test output_vtu
/// write_samples -- --ignored`, then `python3 docs/check_vtu.py
/// /tmp/vtu/*.vtu /tmp/vtu/series3d.pvd`.
#[test]
#[ignore = "writes sample files for docs/check_vtu.py (VTK); see its doc comment"]
fn write_samples_for_vtk_when_asked() {
    let dir = std::env::var_os("PFEM_VTU_SAMPLE_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("pfem-vtu-samples"));
    std::fs::create_dir_all(&dir).unwrap();
    check_2d(Encoding::Base64, &dir);
    check_2d(Encoding::Ascii, &dir);
    let points = [
        Point::<3>::new(0.0, 0.0, 0.0),
        Point::<3>::new(1.0, 0.0, 0.0),
        Point::<3>::new(0.0, 1.0, 0.0),
        Point::<3>::new(0.0, 0.0, 1.0),
        Point::<3>::new(2.0, 2.0, 2.0),
    ];
    let velocity = [Vector::<3>::new(1.0, 2.0, 3.0); 5];
    let stress = [Tensor::<3>::identity(); 5];
    let mut series = VtuSeries::create(&dir, "series3d", Encoding::Base64).unwrap();
    for t in [0.0, 0.1] {
        let frame = Frame {
            points: &points,
            cells: &[0, 1, 2, 3],
            vertex_cells: &[4],
            point_data: vec![
                Field::vector("velocity", &velocity),
                Field::sym_tensor("stress", &stress),
                Field::tensor("stress9", &stress),
            ],
            cell_data: vec![Field::scalar("volume", &[1.0 / 6.0, 0.0])],
            time: None,
        };
        series.write_frame(t, &frame).unwrap();
    }
}

/// The standard outputs' frames carry each particle's displacement from
/// where it entered, and in 2D the out-of-plane stress `σ_zz` of plane
/// strain: a clamped elastic block sagging under gravity, read back.
#[test]
fn standard_frames_carry_displacement_and_out_of_plane_stress() {
    use pfem_constitutive::Hypoelastic;
    use pfem_driver::Simulation;
    use pfem_io::StandardOutput;
    use pfem_scene::{Geometry, RunSettings, Scene};
    let h = 0.1;
    let (young, poisson) = (1e6, 0.3); // plane strain: σ_zz ≠ 0
    let scene = Scene::<2>::new("block")
        .gravity(Vector::<2>::new(0.0, -9.81))
        .settings(RunSettings {
            end_time: 0.02,
            max_dt: 5e-3,
            output_interval: Some(0.02),
            ..Default::default()
        })
        .solid(
            "block",
            Box::new(Hypoelastic::new(1000.0, young, poisson).unwrap()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(1.0, 0.3),
            },
            h,
            Some((Point::<2>::new(-0.01, -0.01), Point::<2>::new(0.01, 0.31))),
        );
    let mut sim = Simulation::new(
        scene,
        Box::new(pfem_geometry::Delaunay2::default()),
        pfem_time::StepParams::default(),
    )
    .unwrap();
    let dir = temp_dir("standard-frames");
    std::fs::remove_dir_all(&dir).unwrap();
    let mut out = StandardOutput::new(&dir, true, Vec::new(), true);
    sim.run(&mut [&mut out]).unwrap();
    let last = dir.join("block_000001.vtu");
    let v = read_vtu(&last);
    let d = find(&v.point_data, "displacement");
    assert_eq!(d.components, 3);
    for i in 0..v.n_points {
        let x = sim.particles().x()[i] - sim.initial_position(i);
        assert_eq!(d.values[3 * i], x[0]);
        assert_eq!(d.values[3 * i + 1], x[1]);
    }
    // The free end sags.
    let min_dy = (0..v.n_points)
        .map(|i| d.values[3 * i + 1])
        .fold(f64::INFINITY, f64::min);
    assert!(min_dy < 0.0, "{min_dy}");
    // σ_zz is the solids' out-of-plane stress history, cell by cell.
    let zz = find(&v.cell_data, "stress_zz");
    assert_eq!(zz.values.len(), v.n_cells);
    let hist = sim.elements().solid_history();
    let mut biggest: f64 = 0.0;
    for e in 0..v.n_cells {
        assert_eq!(zz.values[e], hist[e].stress_zz, "cell {e}");
        biggest = biggest.max(zz.values[e].abs());
    }
    assert!(biggest > 0.0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A flying drop (a fluid particle in no element) is a vertex cell whose
/// `material` is its own fluid's: until session 42 every cell array was
/// padded with 0 on vertex cells, and material 0 was the solid's here.
#[test]
fn a_flying_drop_shows_its_own_material() {
    use pfem_constitutive::{Hypoelastic, Newtonian};
    use pfem_driver::Simulation;
    use pfem_io::StandardOutput;
    use pfem_scene::{Geometry, RunSettings, Scene};
    let h = 0.1;
    let scene = Scene::<2>::new("drop")
        .gravity(Vector::<2>::new(0.0, -9.81))
        .settings(RunSettings {
            end_time: 0.01,
            max_dt: 5e-3,
            output_interval: Some(0.01),
            ..Default::default()
        })
        .solid(
            "block",
            Box::new(Hypoelastic::new(1000.0, 1e6, 0.3).unwrap()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 0.0),
                max: Point::<2>::new(1.0, 0.3),
            },
            h,
            Some((Point::<2>::new(-0.01, -0.01), Point::<2>::new(0.01, 0.31))),
        )
        .fluid(
            "drop",
            Box::new(Newtonian::water()),
            Geometry::Particles(vec![Point::<2>::new(3.0, 1.0)]),
            h,
        );
    let mut sim = Simulation::new(
        scene,
        Box::new(pfem_geometry::Delaunay2::default()),
        pfem_time::StepParams::default(),
    )
    .unwrap();
    let drop = sim.particles().len() - 1;
    let fluid_material = sim.particles().material()[drop];
    assert_ne!(fluid_material, 0, "the block's material is 0");
    let dir = temp_dir("flying-drop");
    std::fs::remove_dir_all(&dir).unwrap();
    let mut out = StandardOutput::new(&dir, true, Vec::new(), true);
    sim.run(&mut [&mut out]).unwrap();
    let v = read_vtu(&dir.join("drop_000001.vtu"));
    let n_simplices = sim.elements().len();
    assert_eq!(v.n_cells, n_simplices + 1, "one vertex cell");
    let material = find(&v.cell_data, "material");
    assert_eq!(material.values.len(), v.n_cells);
    assert_eq!(material.values[n_simplices], f64::from(fluid_material));
    let tags = find(&v.point_data, "boundary_tag");
    assert_eq!(tags.values[drop], 4.0, "isolated");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scene without fluid (a free block over a floor): its particles touch
/// no fluid, tag 5. Until session 48 the tags were left at 0, "interior",
/// a fluid particle's.
#[test]
fn a_scene_without_fluid_tags_its_particles_dry() {
    use pfem_constitutive::Hypoelastic;
    use pfem_driver::Simulation;
    use pfem_io::StandardOutput;
    use pfem_scene::{Geometry, RunSettings, Scene, WallMotion};
    let h = 0.01;
    let scene = Scene::<2>::new("block")
        .gravity(Vector::<2>::new(0.0, -9.81))
        .settings(RunSettings {
            end_time: 0.004,
            max_dt: 2e-3,
            output_interval: Some(0.004),
            ..Default::default()
        })
        .wall(
            "floor",
            Geometry::Box {
                min: Point::<2>::new(-0.1, -h),
                max: Point::<2>::new(0.3, 0.0),
            },
            h,
            WallMotion::Fixed,
        )
        .solid(
            "block",
            Box::new(Hypoelastic::new(1000.0, 1e7, 0.3).unwrap()),
            Geometry::Box {
                min: Point::<2>::new(0.0, 1.5 * h),
                max: Point::<2>::new(0.1, 1.5 * h + 0.05),
            },
            h,
            None,
        );
    let mut sim = Simulation::new(
        scene,
        Box::new(pfem_geometry::Delaunay2::default()),
        pfem_time::StepParams::default(),
    )
    .unwrap();
    let dir = temp_dir("dry-tags");
    std::fs::remove_dir_all(&dir).unwrap();
    let mut out = StandardOutput::new(&dir, true, Vec::new(), true);
    sim.run(&mut [&mut out]).unwrap();
    let v = read_vtu(&dir.join("block_000001.vtu"));
    let tags = find(&v.point_data, "boundary_tag");
    assert_eq!(tags.values.len(), sim.particles().len());
    assert!(tags.values.iter().all(|&t| t == 5.0), "{:?}", tags.values);
    let _ = std::fs::remove_dir_all(&dir);
}
