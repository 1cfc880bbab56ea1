//! VTK XML unstructured grid (`.vtu`) writer.
//!
//! The file follows the VTK XML format, version 1.0, with a `UInt64` header:
//! points as `Float64` with three components (z = 0 in 2D), the cells as
//! `Int64` connectivity and offsets and `UInt8` types (triangle = 5 in 2D,
//! tetrahedron = 10 in 3D, vertex = 1 for isolated particles). Data arrays
//! are either ASCII or base64-encoded binary inline in the XML
//! ([`Encoding`]); both open in ParaView and in VTK's own readers
//! (`docs/check_vtu.py`).

use std::borrow::Cow;
use std::fmt::Write as _;
use std::path::Path;

use pfem_core::{Const, Dim, Point, Tensor, Vector};

use super::{base64, write_atomic, OutputError};

/// VTK cell type of a triangle.
const VTK_TRIANGLE: u8 = 5;
/// VTK cell type of a tetrahedron.
const VTK_TETRA: u8 = 10;
/// VTK cell type of a single vertex.
const VTK_VERTEX: u8 = 1;

/// How data arrays are stored inside the `.vtu` file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Encoding {
    /// Human-readable decimal text, shortest representation that reads back
    /// to the same `f64`. About three times larger than [`Encoding::Base64`].
    /// VTK's ASCII reader does not accept NaN or infinities, so a frame
    /// holding one is refused ([`FrameError::NonFiniteAscii`]).
    Ascii,
    /// Little-endian binary, base64-encoded inline (`format="binary"`), with
    /// a `UInt64` byte-count header per array. Exact, compact, NaN-safe.
    #[default]
    Base64,
}

/// The values of one data array, one entry per point or per cell.
///
/// Vectors and tensors are padded to 3D: a 2D vector `(x, y)` is written as
/// `(x, y, 0)`, a 2D tensor gets zero `z` rows and columns. In plane strain
/// the out-of-plane stress is *not* zero: write it as a separate scalar if it
/// matters.
#[derive(Clone, Copy, Debug)]
pub enum FieldData<'a, const D: usize> {
    /// Scalars, written as `Float64`.
    F64(&'a [f64]),
    /// Scalars, written as `Int32` (ids, counts).
    I32(&'a [i32]),
    /// Scalars, written as `UInt8` (flags, material kinds).
    U8(&'a [u8]),
    /// Vectors, written as `Float64` with 3 components.
    Vector(&'a [Vector<D>]),
    /// Full tensors, written as `Float64` with 9 components in row-major
    /// order `XX XY XZ YX YY YZ ZX ZY ZZ` (ParaView's "tensor").
    Tensor(&'a [Tensor<D>]),
    /// Symmetric tensors, written as `Float64` with 6 components in
    /// ParaView's order `XX YY ZZ XY YZ XZ`; only the upper triangle is
    /// read.
    SymTensor(&'a [Tensor<D>]),
}

impl<const D: usize> FieldData<'_, D> {
    /// Number of entries (points or cells) the array holds.
    pub fn len(&self) -> usize {
        match self {
            Self::F64(v) => v.len(),
            Self::I32(v) => v.len(),
            Self::U8(v) => v.len(),
            Self::Vector(v) => v.len(),
            Self::Tensor(v) | Self::SymTensor(v) => v.len(),
        }
    }

    /// Whether the array holds no entries.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of components written per entry (1, 3, 6 or 9).
    pub fn components(&self) -> usize {
        match self {
            Self::F64(_) | Self::I32(_) | Self::U8(_) => 1,
            Self::Vector(_) => 3,
            Self::Tensor(_) => 9,
            Self::SymTensor(_) => 6,
        }
    }
}

/// A named data array of a [`Frame`].
#[derive(Clone, Debug)]
pub struct Field<'a, const D: usize> {
    /// Array name as shown in ParaView.
    pub name: Cow<'a, str>,
    /// The values.
    pub data: FieldData<'a, D>,
}

impl<'a, const D: usize> Field<'a, D> {
    /// A `Float64` scalar field.
    pub fn scalar(name: impl Into<Cow<'a, str>>, values: &'a [f64]) -> Self {
        Self {
            name: name.into(),
            data: FieldData::F64(values),
        }
    }

    /// An `Int32` scalar field.
    pub fn int(name: impl Into<Cow<'a, str>>, values: &'a [i32]) -> Self {
        Self {
            name: name.into(),
            data: FieldData::I32(values),
        }
    }

    /// A `UInt8` scalar field (flags).
    pub fn flag(name: impl Into<Cow<'a, str>>, values: &'a [u8]) -> Self {
        Self {
            name: name.into(),
            data: FieldData::U8(values),
        }
    }

    /// A vector field, written with 3 components.
    pub fn vector(name: impl Into<Cow<'a, str>>, values: &'a [Vector<D>]) -> Self {
        Self {
            name: name.into(),
            data: FieldData::Vector(values),
        }
    }

    /// A full tensor field, written with 9 components.
    pub fn tensor(name: impl Into<Cow<'a, str>>, values: &'a [Tensor<D>]) -> Self {
        Self {
            name: name.into(),
            data: FieldData::Tensor(values),
        }
    }

    /// A symmetric tensor field, written with 6 components
    /// (`XX YY ZZ XY YZ XZ`).
    pub fn sym_tensor(name: impl Into<Cow<'a, str>>, values: &'a [Tensor<D>]) -> Self {
        Self {
            name: name.into(),
            data: FieldData::SymTensor(values),
        }
    }
}

/// One output frame: particles (the mesh nodes), the simplices joining
/// them, the isolated particles, and data on both.
///
/// The cells are simplices: triangles in 2D, tetrahedra in 3D, `D + 1`
/// point indices each, flat in `cells`. Particles that belong to no simplex
/// (free-flying drops) are invisible in ParaView unless they are cells too:
/// list them in `vertex_cells`, written as VTK vertex cells after the
/// simplices.
///
/// Point data arrays have one entry per point. Cell data arrays have one
/// entry per cell, simplices first then vertex cells; an array with one
/// entry per simplex only is accepted too and padded with zeros on the
/// vertex cells.
#[derive(Clone, Debug, Default)]
pub struct Frame<'a, const D: usize> {
    /// Point positions (m).
    pub points: &'a [Point<D>],
    /// Simplex connectivity, `D + 1` indices into `points` per simplex.
    pub cells: &'a [u32],
    /// Points written as single-vertex cells (isolated particles).
    pub vertex_cells: &'a [u32],
    /// Arrays with one entry per point.
    pub point_data: Vec<Field<'a, D>>,
    /// Arrays with one entry per cell (see the type's documentation).
    pub cell_data: Vec<Field<'a, D>>,
    /// Simulated time (s), written as the `TimeValue` field ParaView reads.
    pub time: Option<f64>,
}

/// Why a [`Frame`] cannot be written.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FrameError {
    /// `cells.len()` is not a multiple of the simplex size.
    #[error("cells has {len} indices, not a multiple of {nodes_per_cell} nodes per simplex")]
    CellsLength {
        /// Length of the connectivity slice.
        len: usize,
        /// Nodes per simplex (`D + 1`).
        nodes_per_cell: usize,
    },
    /// A cell refers to a point that does not exist.
    #[error("cell {cell} refers to point {index}, but there are {points} points")]
    CellIndex {
        /// Cell number (simplices first, then vertex cells).
        cell: usize,
        /// The offending point index.
        index: u32,
        /// Number of points in the frame.
        points: usize,
    },
    /// A data array has the wrong number of entries.
    #[error("{location} data {name:?} has {got} entries, expected {expected}")]
    FieldLength {
        /// `"point"` or `"cell"`.
        location: &'static str,
        /// Array name.
        name: String,
        /// Entries expected (for cell data: all cells; simplices only is
        /// also accepted).
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// A NaN or infinite value asked to be written as text: VTK's ASCII
    /// reader stops at it, so the file would not open. Binary encoding
    /// ([`Encoding::Base64`]) stores such values exactly.
    #[error(
        "{name:?} holds the non-finite value {value} at entry {entry}, which VTK's ASCII \
         reader cannot read; write binary (base64) frames to keep it"
    )]
    NonFiniteAscii {
        /// Array name (`"Points"`, `"TimeValue"` or a data array's).
        name: String,
        /// The entry (point or cell) holding it.
        entry: usize,
        /// The value.
        value: f64,
    },
}

/// Encodes `frame` as the bytes of a `.vtu` file.
///
/// This is the allocation-owning half of [`write_vtu`], for callers that
/// send the bytes elsewhere (a socket, an archive).
pub fn encode_vtu<const D: usize>(
    frame: &Frame<'_, D>,
    encoding: Encoding,
) -> Result<Vec<u8>, FrameError>
where
    Const<D>: Dim,
{
    encode_vtu_dyn(&erase(frame), encoding)
}

/// [`encode_vtu`] with the frame's time replaced by `time`.
pub(crate) fn encode_vtu_at<const D: usize>(
    frame: &Frame<'_, D>,
    encoding: Encoding,
    time: Option<f64>,
) -> Result<Vec<u8>, FrameError>
where
    Const<D>: Dim,
{
    let mut grid = erase(frame);
    grid.time = time;
    encode_vtu_dyn(&grid, encoding)
}

/// Writes `frame` to `path` as a VTK XML unstructured grid, atomically
/// (see [`write_atomic`]).
pub fn write_vtu<const D: usize>(
    path: impl AsRef<Path>,
    frame: &Frame<'_, D>,
    encoding: Encoding,
) -> Result<(), OutputError>
where
    Const<D>: Dim,
{
    let path = path.as_ref();
    let bytes = encode_vtu(frame, encoding).map_err(|source| OutputError::InvalidFrame {
        path: path.to_path_buf(),
        source,
    })?;
    write_atomic(path, &bytes)
}

// ---------------------------------------------------------------------------
// Dimension-erased body: one compiled copy serves 2D and 3D.

/// The values of one array seen through an accessor.
enum Values<'a> {
    /// `get(entry, component)` for `component < ncomp`.
    F64 {
        ncomp: usize,
        get: Box<dyn Fn(usize, usize) -> f64 + 'a>,
    },
    I32(&'a [i32]),
    U8(&'a [u8]),
}

/// A named array of `len` entries.
struct Array<'a> {
    name: &'a str,
    len: usize,
    values: Values<'a>,
}

/// A frame with the dimension turned into a value.
struct Grid<'a> {
    nodes_per_cell: usize,
    simplex_type: u8,
    points: Array<'a>,
    cells: &'a [u32],
    vertex_cells: &'a [u32],
    point_data: Vec<Array<'a>>,
    cell_data: Vec<Array<'a>>,
    time: Option<f64>,
}

/// Components of a symmetric tensor in ParaView's order.
const SYM_COMPONENTS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)];

fn erase_field<'b, const D: usize>(f: &'b Field<'_, D>) -> Array<'b>
where
    Const<D>: Dim,
{
    let values = match f.data {
        FieldData::F64(v) => Values::F64 {
            ncomp: 1,
            get: Box::new(move |i, _| v[i]),
        },
        FieldData::I32(v) => Values::I32(v),
        FieldData::U8(v) => Values::U8(v),
        FieldData::Vector(v) => Values::F64 {
            ncomp: 3,
            get: Box::new(move |i, k| if k < D { v[i][k] } else { 0.0 }),
        },
        FieldData::Tensor(v) => Values::F64 {
            ncomp: 9,
            get: Box::new(move |i, k| {
                let (r, c) = (k / 3, k % 3);
                if r < D && c < D {
                    v[i][(r, c)]
                } else {
                    0.0
                }
            }),
        },
        FieldData::SymTensor(v) => Values::F64 {
            ncomp: 6,
            get: Box::new(move |i, k| {
                let (r, c) = SYM_COMPONENTS[k];
                if c < D {
                    v[i][(r, c)]
                } else {
                    0.0
                }
            }),
        },
    };
    Array {
        name: &f.name,
        len: f.data.len(),
        values,
    }
}

fn erase<'b, const D: usize>(frame: &'b Frame<'_, D>) -> Grid<'b>
where
    Const<D>: Dim,
{
    let points = frame.points;
    Grid {
        nodes_per_cell: <Const<D> as Dim>::NV,
        simplex_type: if D == 2 { VTK_TRIANGLE } else { VTK_TETRA },
        points: Array {
            name: "Points",
            len: points.len(),
            values: Values::F64 {
                ncomp: 3,
                get: Box::new(move |i, k| if k < D { points[i][k] } else { 0.0 }),
            },
        },
        cells: frame.cells,
        vertex_cells: frame.vertex_cells,
        point_data: frame.point_data.iter().map(erase_field).collect(),
        cell_data: frame.cell_data.iter().map(erase_field).collect(),
        time: frame.time,
    }
}

fn validate(g: &Grid<'_>) -> Result<(), FrameError> {
    let nv = g.nodes_per_cell;
    if !g.cells.len().is_multiple_of(nv) {
        return Err(FrameError::CellsLength {
            len: g.cells.len(),
            nodes_per_cell: nv,
        });
    }
    let n_points = g.points.len;
    let n_simplices = g.cells.len() / nv;
    let n_cells = n_simplices + g.vertex_cells.len();
    let bad = g
        .cells
        .iter()
        .enumerate()
        .map(|(j, &i)| (j / nv, i))
        .chain(
            g.vertex_cells
                .iter()
                .enumerate()
                .map(|(j, &i)| (n_simplices + j, i)),
        )
        .find(|&(_, i)| i as usize >= n_points);
    if let Some((cell, index)) = bad {
        return Err(FrameError::CellIndex {
            cell,
            index,
            points: n_points,
        });
    }
    for a in &g.point_data {
        if a.len != n_points {
            return Err(FrameError::FieldLength {
                location: "point",
                name: a.name.to_owned(),
                expected: n_points,
                got: a.len,
            });
        }
    }
    for a in &g.cell_data {
        if a.len != n_cells && a.len != n_simplices {
            return Err(FrameError::FieldLength {
                location: "cell",
                name: a.name.to_owned(),
                expected: n_cells,
                got: a.len,
            });
        }
    }
    Ok(())
}

/// The first non-finite value of a floating-point array, for ASCII frames.
fn non_finite(a: &Array<'_>) -> Option<FrameError> {
    let Values::F64 { ncomp, get } = &a.values else {
        return None;
    };
    (0..a.len).find_map(|i| {
        (0..*ncomp)
            .map(|k| get(i, k))
            .find(|v| !v.is_finite())
            .map(|value| FrameError::NonFiniteAscii {
                name: a.name.to_owned(),
                entry: i,
                value,
            })
    })
}

fn encode_vtu_dyn(g: &Grid<'_>, encoding: Encoding) -> Result<Vec<u8>, FrameError> {
    validate(g)?;
    if encoding == Encoding::Ascii {
        if let Some(value) = g.time.filter(|t| !t.is_finite()) {
            return Err(FrameError::NonFiniteAscii {
                name: "TimeValue".into(),
                entry: 0,
                value,
            });
        }
        let arrays = std::iter::once(&g.points)
            .chain(&g.point_data)
            .chain(&g.cell_data);
        if let Some(e) = arrays.filter_map(non_finite).next() {
            return Err(e);
        }
    }
    let nv = g.nodes_per_cell;
    let n_points = g.points.len;
    let n_simplices = g.cells.len() / nv;
    let n_cells = n_simplices + g.vertex_cells.len();

    let mut w = XmlWriter {
        out: String::with_capacity(64 * (n_points + n_cells) + 1024),
        encoding,
        bytes: Vec::new(),
    };
    w.out.push_str(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" \
         byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n",
    );
    if let Some(t) = g.time {
        w.out.push_str("    <FieldData>\n");
        w.data_array(Some("TimeValue"), 1, Some(1), std::iter::once(t));
        w.out.push_str("    </FieldData>\n");
    }
    let _ = writeln!(
        w.out,
        "    <Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">"
    );

    w.out.push_str("      <PointData>\n");
    for a in &g.point_data {
        w.array(a, 0);
    }
    w.out.push_str("      </PointData>\n      <CellData>\n");
    for a in &g.cell_data {
        w.array(a, n_cells - a.len);
    }
    w.out.push_str("      </CellData>\n      <Points>\n");
    w.array(&g.points, 0);
    w.out.push_str("      </Points>\n      <Cells>\n");
    let connectivity = g.cells.iter().chain(g.vertex_cells).map(|&i| i64::from(i));
    w.data_array(Some("connectivity"), 1, None, connectivity);
    let n_simplex_nodes = (nv * n_simplices) as i64;
    let offsets = (1..=n_simplices as i64)
        .map(|c| c * nv as i64)
        .chain((1..=g.vertex_cells.len() as i64).map(|c| n_simplex_nodes + c));
    w.data_array(Some("offsets"), 1, None, offsets);
    let types = std::iter::repeat_n(g.simplex_type, n_simplices)
        .chain(std::iter::repeat_n(VTK_VERTEX, g.vertex_cells.len()));
    w.data_array(Some("types"), 1, None, types);
    w.out
        .push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    Ok(w.out.into_bytes())
}

/// A scalar type VTK knows.
trait VtkScalar: Copy {
    const TYPE: &'static str;
    fn push_le(self, bytes: &mut Vec<u8>);
    fn push_ascii(self, out: &mut String);
}

impl VtkScalar for f64 {
    const TYPE: &'static str = "Float64";
    fn push_le(self, bytes: &mut Vec<u8>) {
        bytes.extend_from_slice(&self.to_le_bytes());
    }
    fn push_ascii(self, out: &mut String) {
        // `{:?}` is the shortest text that reads back to the same value and
        // switches to exponent notation for very small and large numbers.
        let _ = write!(out, "{self:?}");
    }
}

impl VtkScalar for i64 {
    const TYPE: &'static str = "Int64";
    fn push_le(self, bytes: &mut Vec<u8>) {
        bytes.extend_from_slice(&self.to_le_bytes());
    }
    fn push_ascii(self, out: &mut String) {
        let _ = write!(out, "{self}");
    }
}

impl VtkScalar for i32 {
    const TYPE: &'static str = "Int32";
    fn push_le(self, bytes: &mut Vec<u8>) {
        bytes.extend_from_slice(&self.to_le_bytes());
    }
    fn push_ascii(self, out: &mut String) {
        let _ = write!(out, "{self}");
    }
}

impl VtkScalar for u8 {
    const TYPE: &'static str = "UInt8";
    fn push_le(self, bytes: &mut Vec<u8>) {
        bytes.push(self);
    }
    fn push_ascii(self, out: &mut String) {
        let _ = write!(out, "{self}");
    }
}

struct XmlWriter {
    out: String,
    encoding: Encoding,
    /// Scratch buffer for binary arrays.
    bytes: Vec<u8>,
}

impl XmlWriter {
    /// Writes `a`, followed by `pad` zero entries.
    fn array(&mut self, a: &Array<'_>, pad: usize) {
        let name = Some(a.name);
        match &a.values {
            Values::F64 { ncomp, get } => {
                let ncomp = *ncomp;
                let values = (0..a.len * ncomp)
                    .map(|j| get(j / ncomp, j % ncomp))
                    .chain(std::iter::repeat_n(0.0, pad * ncomp));
                self.data_array(name, ncomp, None, values);
            }
            Values::I32(v) => {
                let values = v.iter().copied().chain(std::iter::repeat_n(0, pad));
                self.data_array(name, 1, None, values);
            }
            Values::U8(v) => {
                let values = v.iter().copied().chain(std::iter::repeat_n(0, pad));
                self.data_array(name, 1, None, values);
            }
        }
    }

    /// Writes one `<DataArray>` element; `tuples` adds `NumberOfTuples`
    /// (needed in `<FieldData>`).
    fn data_array<T: VtkScalar>(
        &mut self,
        name: Option<&str>,
        ncomp: usize,
        tuples: Option<usize>,
        values: impl Iterator<Item = T>,
    ) {
        let out = &mut self.out;
        let _ = write!(out, "        <DataArray type=\"{}\"", T::TYPE);
        if let Some(name) = name {
            out.push_str(" Name=\"");
            escape_xml_into(name, out);
            out.push('"');
        }
        if ncomp != 1 {
            let _ = write!(out, " NumberOfComponents=\"{ncomp}\"");
        }
        if let Some(n) = tuples {
            let _ = write!(out, " NumberOfTuples=\"{n}\"");
        }
        match self.encoding {
            Encoding::Ascii => {
                out.push_str(" format=\"ascii\">\n");
                let per_line = if ncomp > 1 { ncomp } else { 8 };
                for (j, x) in values.enumerate() {
                    if j % per_line == 0 {
                        out.push_str("          ");
                    } else {
                        out.push(' ');
                    }
                    x.push_ascii(out);
                    if j % per_line == per_line - 1 {
                        out.push('\n');
                    }
                }
                if !out.ends_with('\n') {
                    out.push('\n');
                }
                out.push_str("        </DataArray>\n");
            }
            Encoding::Base64 => {
                out.push_str(" format=\"binary\">\n          ");
                // Header (byte count, UInt64) and data form one base64
                // stream, as VTK writes uncompressed inline data.
                let bytes = &mut self.bytes;
                bytes.clear();
                bytes.extend_from_slice(&[0; 8]);
                for x in values {
                    x.push_le(bytes);
                }
                let n = (bytes.len() - 8) as u64;
                bytes[..8].copy_from_slice(&n.to_le_bytes());
                base64::encode_into(bytes, out);
                out.push_str("\n        </DataArray>\n");
            }
        }
    }
}

/// Appends `s` to `out` with the five XML special characters escaped, and
/// the characters XML 1.0 forbids even as references (the controls below
/// U+0020 but tab, line feed and carriage return; U+FFFE and U+FFFF)
/// replaced by U+FFFD.
pub(crate) fn escape_xml_into(s: &str, out: &mut String) {
    for c in s.chars() {
        match c {
            c if c < ' ' && !matches!(c, '\t' | '\n' | '\r') => out.push('\u{FFFD}'),
            '\u{FFFE}' | '\u{FFFF}' => out.push('\u{FFFD}'),
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Control characters XML 1.0 forbids are replaced: a name holding one
    /// made a file no XML reader opens.
    #[test]
    fn names_with_control_characters_stay_well_formed_xml() {
        let mut out = String::new();
        escape_xml_into("a\u{1}b\tc<&\u{FFFF}", &mut out);
        assert_eq!(out, "a\u{FFFD}b\tc&lt;&amp;\u{FFFD}");
    }

    /// A NaN written as text made a file ParaView could not open; it is
    /// refused in ASCII and kept exactly in binary.
    #[test]
    fn ascii_refuses_non_finite_values_binary_keeps_them() {
        let points = [Point::<2>::zeros(); 3];
        let p = [1.0, f64::NAN, 2.0];
        let frame = Frame {
            points: &points,
            cells: &[0, 1, 2],
            point_data: vec![Field {
                name: "pressure".into(),
                data: FieldData::F64(&p),
            }],
            ..Default::default()
        };
        match encode_vtu(&frame, Encoding::Ascii).unwrap_err() {
            FrameError::NonFiniteAscii { name, entry, value } => {
                assert_eq!((name.as_str(), entry), ("pressure", 1));
                assert!(value.is_nan());
            }
            e => panic!("unexpected error {e}"),
        }
        assert!(encode_vtu(&frame, Encoding::Base64).is_ok());
        let mut bad = points;
        bad[2][1] = f64::INFINITY;
        let frame = Frame {
            points: &bad,
            cells: &[0, 1, 2],
            ..Default::default()
        };
        assert!(matches!(
            encode_vtu(&frame, Encoding::Ascii),
            Err(FrameError::NonFiniteAscii { entry: 2, .. })
        ));
    }

    #[test]
    fn rejects_out_of_range_index() {
        let points = [Point::<2>::zeros(); 3];
        let frame = Frame {
            points: &points,
            cells: &[0, 1, 3],
            ..Default::default()
        };
        assert_eq!(
            encode_vtu(&frame, Encoding::Ascii).unwrap_err(),
            FrameError::CellIndex {
                cell: 0,
                index: 3,
                points: 3
            }
        );
    }

    #[test]
    fn rejects_ragged_cells_and_short_fields() {
        let points = [Point::<3>::zeros(); 4];
        let frame = Frame {
            points: &points,
            cells: &[0, 1, 2],
            ..Default::default()
        };
        assert!(matches!(
            encode_vtu(&frame, Encoding::Base64),
            Err(FrameError::CellsLength {
                len: 3,
                nodes_per_cell: 4
            })
        ));
        let p = [1.0; 3];
        let frame = Frame {
            points: &points,
            cells: &[0, 1, 2, 3],
            point_data: vec![Field::scalar("p", &p)],
            ..Default::default()
        };
        assert!(matches!(
            encode_vtu(&frame, Encoding::Base64),
            Err(FrameError::FieldLength {
                location: "point",
                expected: 4,
                got: 3,
                ..
            })
        ));
    }

    #[test]
    fn escapes_names() {
        let mut s = String::new();
        escape_xml_into("a<b&\"c\"", &mut s);
        assert_eq!(s, "a&lt;b&amp;&quot;c&quot;");
    }
}
