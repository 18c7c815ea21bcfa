//! PLY files (ascii, binary little- and big-endian): oriented point sets, query points and
//! triangle meshes, parsed and written with the `ply-rs-bw` crate.
//!
//! Around the crate this module adds: typed rows that accept any numeric PLY type for the
//! properties it reads, checks of the header (required properties, no list where a number is
//! expected, no property or element declared twice, which the crate would silently merge),
//! and one-line [`Error::Format`] messages naming the file, the line (ascii) and the element.
//!
//! The crate's ascii grammar accepts plain decimal numbers only (`-1.5`, `2e-3`): tokens such
//! as `nan`, `inf`, `.5` or `1.` are format errors. Binary payloads hold any bit pattern, so
//! non-finite values read from them are left for [`PointSet::validated`] /
//! [`Mesh::validated`].
//!
//! This file is long (about 1 250 lines, half of them tests) because the PLY grammar — header
//! checks, ASCII and both binary byte orders, every numeric type — is one concept, and its edge
//! cases are tested beside it.

use std::io::Write;
use std::path::Path;

use ply_rs_bw::parser::{ParseError, Parser, Reader};
use ply_rs_bw::ply::{
    Addable, ElementDef, Encoding, Header, Property, PropertyAccess, PropertyAccessResult,
    PropertyDef, PropertyType, ScalarType,
};
use ply_rs_bw::writer::Writer;

use crate::error::{Error, Result};
use crate::points::PointSet;

use super::mesh::{Mesh, check_writable};
use super::write_atomic_with;

/// How a PLY file written by neurosurf encodes its payload.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum PlyEncoding {
    /// Human-readable text; numbers in Rust's shortest round-trip decimal form (still
    /// bit-exact). Cannot hold non-finite values.
    Ascii,
    /// Little-endian binary: compact and fast.
    #[default]
    BinaryLittleEndian,
}

impl PlyEncoding {
    fn encoding(self) -> Encoding {
        match self {
            PlyEncoding::Ascii => Encoding::Ascii,
            PlyEncoding::BinaryLittleEndian => Encoding::BinaryLittleEndian,
        }
    }
}

/// The `vertex` properties this module reads and writes, by slot.
const VERTEX_SLOTS: [&str; 7] = ["x", "y", "z", "nx", "ny", "nz", "feature"];
const XYZ: &[&str] = &["x", "y", "z"];
const ORIENTED: &[&str] = &["x", "y", "z", "nx", "ny", "nz"];
/// Accepted names of the face index list, in order of preference.
const FACE_LISTS: [&str; 2] = ["vertex_indices", "vertex_index"];

/// One `vertex` row: the properties of [`VERTEX_SLOTS`] as `f64` (every PLY scalar type
/// converts exactly); other properties are ignored.
#[derive(Clone, Copy, Debug, Default)]
struct VertexRow([f64; 7]);

impl PropertyAccess for VertexRow {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let Some(slot) = VERTEX_SLOTS.iter().position(|&s| s == name) else {
            return PropertyAccessResult::Ignored;
        };
        match scalar_value(&property) {
            Some(v) => {
                self.0[slot] = v;
                PropertyAccessResult::Set
            }
            // Unreachable after `has_scalar` checked the header; the crate reports it anyway.
            None => PropertyAccessResult::UnsupportedType,
        }
    }
}

/// The value of a scalar property; `None` for lists.
fn scalar_value(property: &Property) -> Option<f64> {
    Some(match *property {
        Property::Char(v) => v.into(),
        Property::UChar(v) => v.into(),
        Property::Short(v) => v.into(),
        Property::UShort(v) => v.into(),
        Property::Int(v) => v.into(),
        Property::UInt(v) => v.into(),
        Property::Float(v) => v.into(),
        Property::Double(v) => v,
        _ => return None,
    })
}

/// One `face` row: the vertex index list under each name of [`FACE_LISTS`], any integer type.
#[derive(Clone, Debug, Default)]
struct FaceRow([Vec<i64>; 2]);

impl PropertyAccess for FaceRow {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let Some(k) = FACE_LISTS.iter().position(|&s| s == name) else {
            return PropertyAccessResult::Ignored;
        };
        let list: Vec<i64> = match property {
            Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
            // Unreachable after `face_list` checked the header.
            _ => return PropertyAccessResult::UnsupportedType,
        };
        self.0[k] = list;
        PropertyAccessResult::Set
    }
}

/// Rows of the elements this module does not use.
#[derive(Clone, Copy, Debug)]
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

/// The parts of a PLY file this module uses.
#[derive(Debug)]
struct PlyData {
    vertices: Vec<VertexRow>,
    faces: Vec<FaceRow>,
}

/// Reads and parses `path` with ply-rs-bw: the header, which `check` inspects before the
/// payload is read (so a missing property is named even when the payload is broken too), then
/// the rows of `vertex` and, when `read_faces`, of `face`; other elements are skipped.
fn read_ply(
    path: &Path,
    read_faces: bool,
    check: impl FnOnce(&Header) -> Result<()>,
) -> Result<PlyData> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let mut reader = Reader::new(&bytes[..]);
    let header = Parser::<Skip>::new()
        .read_header(&mut reader)
        .map_err(|e| header_error(path, &bytes, &e))?;
    // The reader now stands on the first payload line.
    check_unique_names(path, &bytes, reader.line().saturating_sub(1))?;
    check_counts(path, &bytes, &header)?;
    check(&header)?;
    let mut data = PlyData {
        vertices: Vec::new(),
        faces: Vec::new(),
    };
    for (name, element) in &header.elements {
        let start = reader.line();
        let context = |e: ParseError| payload_error(path, &bytes, &header, name, start, &e);
        match name.as_str() {
            "vertex" => {
                data.vertices = Parser::<VertexRow>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(context)?;
            }
            "face" if read_faces => {
                data.faces = Parser::<FaceRow>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(context)?;
            }
            _ => {
                Parser::<Skip>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(context)?;
            }
        }
    }
    Ok(data)
}

/// Rejects an element that declares more rows than the file can hold: in binary each row
/// takes at least its scalars and list counts, in ASCII a line. Without it a header such as
/// `element junk 5555555555555550` with no properties makes the payload reader loop for ages
/// over rows of nothing.
fn check_counts(path: &Path, bytes: &[u8], header: &Header) -> Result<()> {
    let lines = bytes.iter().filter(|&&b| b == b'\n').count() + 1;
    for (name, element) in &header.elements {
        let row_bytes: usize = element
            .properties
            .values()
            .map(|p| match &p.data_type {
                PropertyType::Scalar(t) | PropertyType::List(t, _) => scalar_bytes(t),
            })
            .sum();
        let fits = match header.encoding {
            Encoding::Ascii => element.count <= lines,
            _ => {
                row_bytes > 0
                    && element
                        .count
                        .checked_mul(row_bytes)
                        .is_some_and(|b| b <= bytes.len())
            }
        };
        if element.count > 0 && !fits {
            return Err(Error::format(
                path,
                format!(
                    "element '{name}' declares {} rows, more than the file's {} bytes can hold; \
                     correct the count in its header",
                    element.count,
                    bytes.len()
                ),
            ));
        }
    }
    Ok(())
}

/// Bytes of one binary `ty`.
fn scalar_bytes(ty: &ScalarType) -> usize {
    match ty {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// Rejects an element, or a property within one element, declared twice: ply-rs-bw keys its
/// header by name and would silently keep one of them, misreading the payload.
///
/// Only scans names: the crate has already accepted the `header_lines` lines.
fn check_unique_names(path: &Path, bytes: &[u8], header_lines: usize) -> Result<()> {
    let mut elements: Vec<(String, Vec<String>)> = Vec::new();
    for (i, line) in bytes.split(|&b| b == b'\n').take(header_lines).enumerate() {
        let line = String::from_utf8_lossy(line);
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        let err = |what: String| Error::format(path, format!("line {}: {what}", i + 1));
        match words[..] {
            ["element", name, ..] => {
                if elements.iter().any(|(e, _)| e == name) {
                    return Err(err(format!("element '{name}' is declared twice")));
                }
                elements.push((name.to_string(), Vec::new()));
            }
            ["property", .., name] => {
                if let Some((element, properties)) = elements.last_mut() {
                    if properties.iter().any(|p| p == name) {
                        return Err(err(format!(
                            "property '{name}' of element '{element}' is declared twice"
                        )));
                    }
                    properties.push(name.to_string());
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// A ply-rs-bw error as one line: the crate nests messages as `…\n\tString: '<line>'\n\tError:
/// …`; the echoed input is dropped (callers quote the line themselves), as are the parser
/// generator's internals, and Rust's number-parsing errors are put in words.
fn crate_message(e: &ParseError) -> String {
    let text = e.to_string();
    let text = match e.line() {
        Some(n) => text
            .strip_prefix(&format!("Line {n}: "))
            .unwrap_or(&text)
            .to_string(),
        None => text,
    };
    let mut parts: Vec<String> = Vec::new();
    let mut in_echo = false;
    for raw in text.lines() {
        let part = raw.trim();
        if in_echo {
            // The echoed line ended with a newline: its closing quote is on its own line.
            in_echo = !part.ends_with('\'');
            continue;
        }
        if let Some(echo) = part.strip_prefix("String:") {
            let echo = echo.trim();
            in_echo = echo == "'" || !echo.ends_with('\'');
            continue;
        }
        let part = part.strip_prefix("Error:").unwrap_or(part).trim();
        let part = part.strip_prefix("Value:").unwrap_or(part).trim();
        // PEG details: a dump of the tokens it expected.
        let part = part.split(": expected").next().unwrap_or(part);
        let part = part.trim_end_matches([',', ' ', '.']);
        let part = if part.starts_with("ParseIntError") {
            if part.contains("Overflow") {
                "out of range for its type"
            } else {
                "not an integer of its type"
            }
        } else if part.starts_with("ParseFloatError") {
            "not a number"
        } else if part.ends_with("but found nothing") {
            "fewer values than the header declares"
        } else {
            part
        };
        if part.is_empty()
            || part.starts_with("ParseError {")
            || matches!(
                part,
                "Couldn't read element line" | "Couldn't parse element line" | "Parse error"
            )
        {
            continue;
        }
        parts.push(part.to_string());
    }
    let mut message = parts.join(": ");
    if let Some(first) = message.get(..1) {
        let lower = first.to_ascii_lowercase();
        message.replace_range(..1, &lower);
    }
    if message.is_empty() {
        message = "malformed PLY file".into();
    }
    message
}

/// Line `n` (1-based) of the file, without its line break.
fn file_line(bytes: &[u8], n: usize) -> String {
    let line = bytes
        .split(|&b| b == b'\n')
        .nth(n.saturating_sub(1))
        .unwrap_or_default();
    String::from_utf8_lossy(line).trim_end().to_string()
}

/// `line` shortened for a message.
fn shorten(line: &str) -> String {
    let line = line.trim();
    if line.chars().count() > 80 {
        format!("{}…", line.chars().take(80).collect::<String>())
    } else {
        line.to_string()
    }
}

/// A format error for a ply-rs-bw error in the header: `line N: {message}: '<the line>'` when
/// the crate knows the line.
fn header_error(path: &Path, bytes: &[u8], e: &ParseError) -> Error {
    let message = crate_message(e);
    let Some(n) = e.line() else {
        return Error::format(path, message);
    };
    let line = shorten(&file_line(bytes, n));
    if line.is_empty() {
        Error::format(path, format!("line {n}: {message}"))
    } else {
        Error::format(path, format!("line {n}: {message}: '{line}'"))
    }
}

/// A format error for a ply-rs-bw error in the payload of `element`, whose rows start at line
/// `start`. Ascii: `line N: element 'E' ROW: {message} in '<the line>'`; binary: the element
/// and the message (the crate's line number means nothing in a binary payload).
fn payload_error(
    path: &Path,
    bytes: &[u8],
    header: &Header,
    element: &str,
    start: usize,
    e: &ParseError,
) -> Error {
    let mut message = crate_message(e);
    let line = match e.line() {
        Some(n) if header.encoding == Encoding::Ascii => n,
        _ => {
            return Error::format(
                path,
                if message.contains(&format!("element '{element}'")) {
                    message
                } else {
                    format!("element '{element}': {message}")
                },
            );
        }
    };
    let text = file_line(bytes, line);
    // A data line the number grammar rejects: "error at 1:COLUMN". Name the token there.
    if let Some(column) = message
        .strip_prefix("error at 1:")
        .and_then(|c| c.parse::<usize>().ok())
    {
        let chars: Vec<char> = text.chars().collect();
        let mut at = column.saturating_sub(1).min(chars.len());
        // The error may point just past the token (`1.`).
        if at > 0 && chars.get(at).is_none_or(|c| c.is_whitespace()) {
            at -= 1;
        }
        let from = chars[..at]
            .iter()
            .rposition(|c| c.is_whitespace())
            .map_or(0, |k| k + 1);
        let to = chars[at..]
            .iter()
            .position(|c| c.is_whitespace())
            .map_or(chars.len(), |k| at + k);
        let token: String = chars[from..to].iter().collect();
        message = format!("'{token}' is not a number");
    }
    let row = line.saturating_sub(start);
    let context = if message.contains(&format!("element '{element}'")) {
        String::new()
    } else {
        format!("element '{element}' {row}: ")
    };
    let text = shorten(&text);
    if text.is_empty() {
        Error::format(path, format!("line {line}: {context}{message}"))
    } else {
        Error::format(path, format!("line {line}: {context}{message} in '{text}'"))
    }
}

/// The definition of `name`, or a format error naming it.
fn element<'h>(path: &Path, header: &'h Header, name: &str) -> Result<&'h ElementDef> {
    header.elements.get(name).ok_or_else(|| {
        Error::format(
            path,
            if name == "face" {
                NO_FACE_ELEMENT.to_string()
            } else {
                format!("the PLY header has no '{name}' element")
            },
        )
    })
}

/// The error text of a PLY file read as a mesh that has no faces at all.
pub(crate) const NO_FACE_ELEMENT: &str = "the PLY header has no 'face' element";

/// Whether `element` declares `property`; a format error if it is declared as a list.
fn has_scalar(path: &Path, element: &ElementDef, property: &str) -> Result<bool> {
    match element.properties.get(property).map(|p| &p.data_type) {
        None => Ok(false),
        Some(PropertyType::Scalar(_)) => Ok(true),
        Some(PropertyType::List(..)) => Err(Error::format(
            path,
            format!(
                "PLY property '{property}' of element '{}' is a list, expected a number",
                element.name
            ),
        )),
    }
}

/// Requires the `vertex` element to declare every scalar in `properties`.
fn require_vertex_scalars(path: &Path, header: &Header, properties: &[&str]) -> Result<()> {
    let vertex = element(path, header, "vertex")?;
    for &property in properties {
        if !has_scalar(path, vertex, property)? {
            return Err(Error::format(
                path,
                format!("PLY element 'vertex' has no '{property}' property"),
            ));
        }
    }
    Ok(())
}

fn is_integer(ty: &ScalarType) -> bool {
    !matches!(ty, ScalarType::Float | ScalarType::Double)
}

/// Which of [`FACE_LISTS`] the `face` element declares (the first one present); a format
/// error unless it is a list of integers.
fn face_list(path: &Path, header: &Header) -> Result<usize> {
    let face = element(path, header, "face")?;
    let (k, property) = FACE_LISTS
        .iter()
        .enumerate()
        .find_map(|(k, name)| face.properties.get(*name).map(|p| (k, p)))
        .ok_or_else(|| {
            Error::format(
                path,
                "PLY element 'face' has no 'vertex_indices' (or 'vertex_index') property",
            )
        })?;
    match &property.data_type {
        PropertyType::List(_, item) if is_integer(item) => Ok(k),
        PropertyType::List(_, item) => Err(Error::format(
            path,
            format!(
                "PLY property '{}' of element 'face' must list integers, not {item:?}",
                property.name
            ),
        )),
        PropertyType::Scalar(_) => Err(Error::format(
            path,
            format!(
                "PLY property '{}' of element 'face' must be a list",
                property.name
            ),
        )),
    }
}

/// Reads an oriented point set from a PLY file (ascii or binary of either byte order).
///
/// The `vertex` element must have numeric properties `x y z nx ny nz` of any PLY type; an
/// optional numeric `feature` property (integer valued) becomes [`PointSet::features`].
/// Other elements and properties are ignored. The result is not validated: non-finite values
/// (possible in binary files) and zero normals are left for [`PointSet::validated`].
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; [`Error::Format`] for a malformed header or
/// payload (naming the line, or the element), a missing or duplicated property (named), or a
/// `feature` value that is not a non-negative 32-bit integer.
pub fn read_points(path: &Path) -> Result<PointSet> {
    let mut with_feature = false;
    let data = read_ply(path, false, |header| {
        require_vertex_scalars(path, header, ORIENTED)?;
        with_feature = has_scalar(path, element(path, header, "vertex")?, "feature")?;
        Ok(())
    })?;
    let features = if with_feature {
        let mut features = Vec::with_capacity(data.vertices.len());
        for (i, row) in data.vertices.iter().enumerate() {
            let f = row.0[6];
            if !(f >= 0.0 && f <= f64::from(u32::MAX) && f.fract() == 0.0) {
                return Err(Error::format(
                    path,
                    format!("vertex {i}: feature {f} is not a non-negative 32-bit integer"),
                ));
            }
            features.push(f as u32);
        }
        Some(features)
    } else {
        None
    };
    Ok(PointSet {
        positions: data
            .vertices
            .iter()
            .map(|r| [r.0[0], r.0[1], r.0[2]])
            .collect(),
        normals: data
            .vertices
            .iter()
            .map(|r| [r.0[3], r.0[4], r.0[5]])
            .collect(),
        features,
    })
}

/// Reads the `x y z` of every vertex of a PLY file (other properties are ignored).
pub(crate) fn read_ply_positions(path: &Path) -> Result<Vec<[f64; 3]>> {
    let data = read_ply(path, false, |header| {
        require_vertex_scalars(path, header, XYZ)
    })?;
    Ok(data
        .vertices
        .iter()
        .map(|r| [r.0[0], r.0[1], r.0[2]])
        .collect())
}

/// Reads a polygon mesh from PLY: `vertex` with `x y z`, `face` with an integer list
/// `vertex_indices` (or `vertex_index`); polygons are fan-triangulated. Not validated.
pub(crate) fn read_ply_mesh(path: &Path) -> Result<Mesh> {
    let mut list = 0;
    let data = read_ply(path, true, |header| {
        require_vertex_scalars(path, header, XYZ)?;
        list = face_list(path, header)?;
        Ok(())
    })?;
    let positions = data
        .vertices
        .iter()
        .map(|r| [r.0[0], r.0[1], r.0[2]])
        .collect();
    let mut triangles = Vec::with_capacity(data.faces.len());
    for (i, face) in data.faces.iter().enumerate() {
        let indices = &face.0[list];
        if indices.len() < 3 {
            return Err(Error::format(
                path,
                format!(
                    "face {i} has {} vertices, at least 3 are needed",
                    indices.len()
                ),
            ));
        }
        let index = |v: i64| {
            u32::try_from(v).map_err(|_| {
                Error::format(path, format!("face {i} has an invalid vertex index {v}"))
            })
        };
        let first = index(indices[0])?;
        for k in 1..indices.len() - 1 {
            triangles.push([first, index(indices[k])?, index(indices[k + 1])?]);
        }
    }
    Ok(Mesh {
        positions,
        triangles,
    })
}

/// A vertex row to write: `double` properties named by the first six [`VERTEX_SLOTS`] and an
/// `int feature`.
#[derive(Clone, Copy, Debug, Default)]
struct VertexOut {
    values: [f64; 6],
    feature: i32,
}

impl PropertyAccess for VertexOut {
    fn new() -> Self {
        Self::default()
    }

    fn get_double(&self, name: &str) -> Option<f64> {
        ORIENTED
            .iter()
            .position(|&s| s == name)
            .map(|k| self.values[k])
    }

    fn get_int(&self, name: &str) -> Option<i32> {
        (name == "feature").then_some(self.feature)
    }
}

/// A triangle to write as `list uchar int vertex_indices`.
#[derive(Clone, Copy, Debug, Default)]
struct TriangleOut([i32; 3]);

impl PropertyAccess for TriangleOut {
    fn new() -> Self {
        Self::default()
    }

    fn get_list_int(&self, name: &str) -> Option<&[i32]> {
        (name == FACE_LISTS[0]).then_some(&self.0[..])
    }
}

/// An element definition for the writer.
fn element_def(name: &str, count: usize, properties: &[(&str, PropertyType)]) -> ElementDef {
    let mut def = ElementDef::new(name.to_string());
    def.count = count;
    for (property, ty) in properties {
        def.properties
            .add(PropertyDef::new(property.to_string(), ty.clone()));
    }
    def
}

/// Writes the header for `elements`.
fn write_header(
    w: &mut dyn Write,
    encoding: PlyEncoding,
    elements: &[&ElementDef],
) -> std::io::Result<()> {
    let mut header = Header::new();
    header.encoding = encoding.encoding();
    header.comments.push("written by neurosurf".into());
    for element in elements {
        header.elements.add((*element).clone());
    }
    Writer::<Skip>::new().write_header(&mut &mut *w, &header)?;
    Ok(())
}

/// Writes one row of `def` with ply-rs-bw.
fn write_row<E: PropertyAccess>(
    w: &mut dyn Write,
    encoding: PlyEncoding,
    row: &E,
    def: &ElementDef,
) -> std::io::Result<()> {
    let writer = Writer::<E>::new();
    let mut out = &mut *w;
    match encoding {
        PlyEncoding::Ascii => writer.write_ascii_element(&mut out, row, def)?,
        PlyEncoding::BinaryLittleEndian => {
            writer.write_little_endian_element(&mut out, row, def)?
        }
    };
    Ok(())
}

/// Ascii PLY (as ply-rs-bw reads it) holds finite numbers only.
fn check_ascii_finite<'a>(
    encoding: PlyEncoding,
    what: &str,
    rows: impl Iterator<Item = &'a [f64; 3]>,
) -> Result<()> {
    if encoding != PlyEncoding::Ascii {
        return Ok(());
    }
    match rows
        .enumerate()
        .find(|(_, v)| v.iter().any(|c| !c.is_finite()))
    {
        Some((i, v)) => Err(Error::invalid(format!(
            "{what} {i} has a non-finite value {v:?}, which ascii PLY cannot hold \
             (write binary PLY instead)"
        ))),
        None => Ok(()),
    }
}

const DOUBLE: PropertyType = PropertyType::Scalar(ScalarType::Double);

/// Writes an oriented point set as PLY, atomically: a `vertex` element with `double`
/// properties `x y z nx ny nz` and, when [`PointSet::features`] is set, an `int feature`.
/// Values are written bit-exactly in both encodings.
///
/// # Errors
/// [`Error::InvalidInput`] when the normal or feature counts differ from the point count, a
/// feature exceeds `i32::MAX`, or (ascii only) a value is not finite; [`Error::Io`] when
/// writing fails.
pub fn write_points_ply(path: &Path, points: &PointSet, encoding: PlyEncoding) -> Result<()> {
    let n = points.positions.len();
    if points.normals.len() != n {
        return Err(Error::invalid(format!(
            "{n} positions but {} normals",
            points.normals.len()
        )));
    }
    let features: Option<Vec<i32>> = match &points.features {
        None => None,
        Some(f) if f.len() != n => {
            return Err(Error::invalid(format!(
                "{n} positions but {} feature labels",
                f.len()
            )));
        }
        Some(f) => Some(
            f.iter()
                .map(|&v| {
                    i32::try_from(v)
                        .map_err(|_| Error::invalid(format!("feature label {v} is too large")))
                })
                .collect::<Result<_>>()?,
        ),
    };
    check_ascii_finite(encoding, "point", points.positions.iter())?;
    check_ascii_finite(encoding, "normal", points.normals.iter())?;
    let mut properties: Vec<(&str, PropertyType)> =
        ORIENTED.iter().map(|&name| (name, DOUBLE)).collect();
    if features.is_some() {
        properties.push(("feature", PropertyType::Scalar(ScalarType::Int)));
    }
    let vertex = element_def("vertex", n, &properties);
    write_atomic_with(path, |w| {
        write_header(w, encoding, &[&vertex])?;
        for i in 0..n {
            let [x, y, z] = points.positions[i];
            let [nx, ny, nz] = points.normals[i];
            let row = VertexOut {
                values: [x, y, z, nx, ny, nz],
                feature: features.as_ref().map_or(0, |f| f[i]),
            };
            write_row(w, encoding, &row, &vertex)?;
        }
        Ok(())
    })
}

/// Writes a triangle mesh as PLY, atomically: a `vertex` element with `double x y z` (and
/// `nx ny nz` when `normals` is given, one per vertex) and a `face` element with
/// `list uchar int vertex_indices`.
///
/// # Errors
/// [`Error::InvalidInput`] when the normal count differs from the vertex count, an index is
/// out of range or exceeds `i32::MAX`, or (ascii only) a value is not finite; [`Error::Io`]
/// when writing fails.
pub fn write_mesh_ply(
    path: &Path,
    mesh: &Mesh,
    normals: Option<&[[f64; 3]]>,
    encoding: PlyEncoding,
) -> Result<()> {
    check_writable(mesh, normals)?;
    if mesh.positions.len() > i32::MAX as usize {
        return Err(Error::invalid("too many vertices for a PLY int index"));
    }
    check_ascii_finite(encoding, "vertex", mesh.positions.iter())?;
    check_ascii_finite(encoding, "normal", normals.unwrap_or_default().iter())?;
    let count = if normals.is_some() { 6 } else { 3 };
    let properties: Vec<(&str, PropertyType)> = ORIENTED[..count]
        .iter()
        .map(|&name| (name, DOUBLE))
        .collect();
    let vertex = element_def("vertex", mesh.positions.len(), &properties);
    let face = element_def(
        "face",
        mesh.triangles.len(),
        &[(
            FACE_LISTS[0],
            PropertyType::List(ScalarType::UChar, ScalarType::Int),
        )],
    );
    write_atomic_with(path, |w| {
        write_header(w, encoding, &[&vertex, &face])?;
        for (i, p) in mesh.positions.iter().enumerate() {
            let n = normals.map_or([0.0; 3], |n| n[i]);
            let row = VertexOut {
                values: [p[0], p[1], p[2], n[0], n[1], n[2]],
                feature: 0,
            };
            write_row(w, encoding, &row, &vertex)?;
        }
        for t in &mesh.triangles {
            // In range: checked against the vertex count above.
            write_row(w, encoding, &TriangleOut(t.map(|v| v as i32)), &face)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sample_points(features: bool) -> PointSet {
        let n = 50;
        let positions = (0..n)
            .map(|i| {
                let t = i as f64 * 0.37;
                [t.sin() * 1e-7, t.cos() / 3.0, (t * 1e30).tan()]
            })
            .collect();
        let normals = (0..n)
            .map(|i| {
                let t = i as f64 * 1.1;
                [t.cos(), t.sin(), -0.0]
            })
            .collect();
        PointSet {
            positions,
            normals,
            features: features.then(|| (0..n as u32).map(|i| i % 3).collect()),
        }
    }

    fn bits(p: &PointSet) -> Vec<u64> {
        p.positions
            .iter()
            .chain(&p.normals)
            .flatten()
            .map(|v| v.to_bits())
            .collect()
    }

    #[test]
    fn point_round_trips_are_bit_exact() {
        let dir = tempfile::tempdir().unwrap();
        for encoding in [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian] {
            for features in [false, true] {
                let points = sample_points(features);
                let path = dir.path().join(format!("{encoding:?}-{features}.ply"));
                write_points_ply(&path, &points, encoding).unwrap();
                let back = read_points(&path).unwrap();
                assert_eq!(bits(&back), bits(&points), "{encoding:?} {features}");
                assert_eq!(back.features, points.features);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn any_non_nan_doubles_round_trip(
            values in prop::collection::vec(
                prop::num::f64::ANY.prop_filter("not NaN", |v| !v.is_nan()),
                6..60,
            ),
            labels in prop::option::of(prop::collection::vec(0u32..=i32::MAX as u32, 10)),
        ) {
            let n = values.len() / 6;
            let chunk = |k: usize| [values[6 * k], values[6 * k + 1], values[6 * k + 2]];
            let points = PointSet {
                positions: (0..n).map(chunk).collect(),
                normals: (0..n).map(|k| [values[6 * k + 3], values[6 * k + 4], values[6 * k + 5]]).collect(),
                features: labels.map(|l| (0..n).map(|k| l[k % l.len()]).collect()),
            };
            let finite = values[..6 * n].iter().all(|v| v.is_finite());
            let dir = tempfile::tempdir().unwrap();
            for encoding in [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian] {
                let path = dir.path().join("p.ply");
                let written = write_points_ply(&path, &points, encoding);
                if encoding == PlyEncoding::Ascii && !finite {
                    // Ascii PLY cannot hold infinities: refused, nothing written.
                    prop_assert!(matches!(written, Err(Error::InvalidInput(_))));
                    prop_assert!(!path.exists());
                    continue;
                }
                written.unwrap();
                let back = read_points(&path).unwrap();
                prop_assert_eq!(bits(&back), bits(&points));
                prop_assert_eq!(&back.features, &points.features);
                std::fs::remove_file(&path).unwrap();
            }
        }
    }

    #[test]
    fn writer_rejects_inconsistent_point_sets() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.ply");
        let mut points = sample_points(true);
        points.normals.pop();
        assert!(matches!(
            write_points_ply(&path, &points, PlyEncoding::Ascii),
            Err(Error::InvalidInput(_))
        ));
        let mut points = sample_points(true);
        points.features.as_mut().unwrap()[3] = u32::MAX;
        assert!(matches!(
            write_points_ply(&path, &points, PlyEncoding::Ascii),
            Err(Error::InvalidInput(_))
        ));
        let mut points = sample_points(false);
        points.normals[7][2] = f64::INFINITY;
        let e = write_points_ply(&path, &points, PlyEncoding::Ascii).unwrap_err();
        assert!(e.to_string().contains("normal 7"), "{e}");
        assert!(!path.exists());
        // Binary holds it.
        write_points_ply(&path, &points, PlyEncoding::BinaryLittleEndian).unwrap();
        assert_eq!(read_points(&path).unwrap().normals[7][2], f64::INFINITY);
    }

    #[test]
    fn writes_the_expected_header() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("h.ply");
        let points = PointSet {
            positions: vec![[0.5, -1.0, 1e-300]],
            normals: vec![[0.0, 0.0, 1.0]],
            features: Some(vec![4]),
        };
        write_points_ply(&path, &points, PlyEncoding::Ascii).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let expected = "ply\nformat ascii 1.0\ncomment written by neurosurf\nelement vertex 1\n\
            property double x\nproperty double y\nproperty double z\nproperty double nx\n\
            property double ny\nproperty double nz\nproperty int feature\nend_header\n0.5 -1 ";
        assert!(text.starts_with(expected), "{text}");
        assert!(text.ends_with(" 0 0 1 4\n"), "{text}");
    }

    fn write(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    }

    fn format_message(e: Error) -> String {
        match e {
            Error::Format { message, .. } => message,
            other => panic!("expected a format error, got {other:?}"),
        }
    }

    #[test]
    fn reads_float_properties_and_uchar_features() {
        let dir = tempfile::tempdir().unwrap();
        let ascii = "ply\nformat ascii 1.0\ncomment hand made\nelement vertex 2\n\
            property float x\nproperty float y\nproperty float z\nproperty uchar red\n\
            property float nx\nproperty float ny\nproperty float nz\nproperty uchar feature\n\
            element face 0\nproperty list uchar int vertex_indices\nend_header\n\
            0.5 -1 2e1 255 0 0 1 2\n1.25 0 0 7 1 0 0 0\n";
        let path = write(&dir, "a.ply", ascii.as_bytes());
        let p = read_points(&path).unwrap();
        assert_eq!(p.positions, vec![[0.5, -1.0, 20.0], [1.25, 0.0, 0.0]]);
        assert_eq!(p.normals, vec![[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]);
        assert_eq!(p.features, Some(vec![2, 0]));

        // The same in big-endian binary with mixed types: double x, short y, int z.
        let mut bin = b"ply\nformat binary_big_endian 1.0\nelement vertex 2\n\
            property double x\nproperty short y\nproperty int z\nproperty float nx\n\
            property float ny\nproperty float nz\nproperty uchar feature\nend_header\n"
            .to_vec();
        for (x, y, z, n, f) in [
            (0.5f64, -1i16, 20i32, [0f32, 0.0, 1.0], 2u8),
            (1.25, 0, 0, [1.0, 0.0, 0.0], 0),
        ] {
            bin.extend(x.to_be_bytes());
            bin.extend(y.to_be_bytes());
            bin.extend(z.to_be_bytes());
            for c in n {
                bin.extend(c.to_be_bytes());
            }
            bin.push(f);
        }
        let path = write(&dir, "b.ply", &bin);
        assert_eq!(read_points(&path).unwrap(), p);
    }

    #[test]
    fn non_finite_binary_values_are_left_for_validation() {
        let dir = tempfile::tempdir().unwrap();
        let mut points = sample_points(false);
        points.positions[4][1] = f64::NAN;
        let path = dir.path().join("nan.ply");
        write_points_ply(&path, &points, PlyEncoding::BinaryLittleEndian).unwrap();
        let back = read_points(&path).unwrap();
        assert!(back.positions[4][1].is_nan());
        let e = back.validated().unwrap_err();
        let e = e.to_string();
        assert!(e.contains("point 4") && e.contains("non-finite"), "{e}");
    }

    /// An ascii point-set header with the given vertex properties (all `float`).
    fn ascii_header(count: usize, properties: &[&str]) -> String {
        let mut h = format!("ply\nformat ascii 1.0\nelement vertex {count}\n");
        for p in properties {
            h += &format!("property float {p}\n");
        }
        h + "end_header\n"
    }

    const ORIENTED_FEATURE: [&str; 7] = VERTEX_SLOTS;

    #[test]
    fn malformed_files_are_format_errors() {
        let dir = tempfile::tempdir().unwrap();
        let good = dir.path().join("good.ply");
        write_points_ply(&good, &sample_points(true), PlyEncoding::BinaryLittleEndian).unwrap();
        let bytes = std::fs::read(&good).unwrap();
        let oriented = ascii_header(2, ORIENTED);
        let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
            (
                "truncated binary",
                bytes[..bytes.len() - 30].to_vec(),
                &["element 'vertex'", "end of file", "expected 50, got 49"],
            ),
            (
                "missing nx",
                (ascii_header(1, &["x", "y", "z", "ny", "nz"]) + "0 0 0 0 1\n").into_bytes(),
                &["'vertex'", "no 'nx' property"],
            ),
            (
                "garbage header",
                b"ply\nformat ascii 1.0\nelement vertex 1\nthis is not a header\n".to_vec(),
                &["line 4", "'this is not a header'"],
            ),
            ("not PLY", b"OFF\n3 1 0\n".to_vec(), &["line 1", "magic", "'OFF'"]),
            (
                "more rows than bytes",
                b"ply\nformat binary_little_endian 1.0\nelement junk 5555555555555550\n\
                  element vertex 0\nproperty float x\nend_header\n"
                    .to_vec(),
                &["element 'junk'", "5555555555555550 rows", "correct the count"],
            ),
            (
                "more rows than lines",
                (ascii_header(1_000_000, ORIENTED) + "0 0 0 0 0 1\n").into_bytes(),
                &["element 'vertex'", "1000000 rows"],
            ),
            ("empty", Vec::new(), &["end of file", "magic"]),
            (
                "no end_header",
                b"ply\nformat ascii 1.0\nelement vertex 0\n".to_vec(),
                &["line 4", "end_header"],
            ),
            (
                "no format",
                b"ply\nelement vertex 0\nend_header\n".to_vec(),
                &["format"],
            ),
            (
                "bad format",
                b"ply\nformat binary 1.0\nend_header\n".to_vec(),
                &["line 2", "'format binary 1.0'"],
            ),
            (
                "bad type",
                b"ply\nformat ascii 1.0\nelement vertex 0\nproperty real x\nend_header\n".to_vec(),
                &["line 4", "'property real x'"],
            ),
            (
                "property first",
                b"ply\nformat ascii 1.0\nproperty float x\nend_header\n".to_vec(),
                &["line 3", "without preceding element"],
            ),
            (
                "duplicate property",
                (ascii_header(0, &["x", "y", "z", "nx", "ny", "nz", "y"])).into_bytes(),
                &["line 10", "'y'", "twice"],
            ),
            (
                "duplicate element",
                (ascii_header(0, ORIENTED) + "element vertex 0\nend_header\n")
                    .replacen("end_header\n", "", 1)
                    .into_bytes(),
                &["line 10", "element 'vertex'", "twice"],
            ),
            (
                "bad number",
                (oriented.clone() + "0 0 0 0 0 1\n0 0 zero 0 0 1\n").into_bytes(),
                &[
                    "line 12",
                    "element 'vertex' 1",
                    "'zero' is not a number",
                    "'0 0 zero 0 0 1'",
                ],
            ),
            (
                "short line",
                (oriented.clone() + "0 0 0 0 0 1\n0 0 0 0 1\n").into_bytes(),
                &[
                    "line 12",
                    "element 'vertex' 1",
                    "fewer values",
                    "'0 0 0 0 1'",
                ],
            ),
            (
                "missing rows",
                (oriented.clone() + "0 0 0 0 0 1\n").into_bytes(),
                &["line 12", "end of file", "expected 2, got 1"],
            ),
            (
                "blank row",
                (oriented.clone() + "0 0 0 0 0 1\n\n0 0 0 0 0 1\n").into_bytes(),
                &["line 12", "element 'vertex' 1"],
            ),
            (
                "no vertex element",
                b"ply\nformat ascii 1.0\nelement point 0\nproperty float x\nend_header\n".to_vec(),
                &["no 'vertex' element"],
            ),
            (
                "list x",
                b"ply\nformat ascii 1.0\nelement vertex 0\nproperty list uchar float x\nend_header\n"
                    .to_vec(),
                &["'x'", "list"],
            ),
            (
                "fractional feature",
                (ascii_header(1, &ORIENTED_FEATURE) + "0 0 0 0 0 1 1.5\n").into_bytes(),
                &["vertex 0", "feature 1.5"],
            ),
            (
                "negative feature",
                (ascii_header(1, &ORIENTED_FEATURE) + "0 0 0 0 0 1 -1\n").into_bytes(),
                &["vertex 0", "feature -1"],
            ),
            (
                "uchar out of range",
                b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                  property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
                  property uchar feature\nend_header\n0 0 0 0 0 1 256\n"
                    .to_vec(),
                &["line 12", "'256'", "out of range"],
            ),
        ];
        for (name, content, needles) in cases {
            let path = write(&dir, "case.ply", &content);
            let e = format_message(read_points(&path).unwrap_err());
            assert!(!e.contains('\n') && !e.contains('\t'), "{name}: {e}");
            for needle in needles {
                assert!(e.contains(needle), "{name}: {e}");
            }
        }
        // Positions alone are enough for query points.
        let path = write(
            &dir,
            "xyz.ply",
            (ascii_header(1, &["x", "y", "z", "ny", "nz"]) + "0 0 0 0 1\n").as_bytes(),
        );
        assert_eq!(read_ply_positions(&path).unwrap(), vec![[0.0; 3]]);

        let e = read_points(&dir.path().join("missing.ply")).unwrap_err();
        assert!(matches!(e, Error::Io { .. }), "{e}");
    }

    #[test]
    fn ascii_takes_plain_decimals_and_crlf() {
        let dir = tempfile::tempdir().unwrap();
        let text = ascii_header(3, ORIENTED).replace('\n', "\r\n")
            + "0.5 -2 +3e-1 0 0 1\r\n  -0 1E2 7 1 0 0 \r\n1 2 3 0 1 0";
        let path = write(&dir, "crlf.ply", text.as_bytes());
        let p = read_points(&path).unwrap();
        assert_eq!(p.positions[0], [0.5, -2.0, f64::from(0.3f32)]);
        assert_eq!(p.positions[1], [0.0, 100.0, 7.0]);
        assert_eq!(p.positions[2], [1.0, 2.0, 3.0]);
        // ply-rs-bw's ascii grammar has no `nan`, `inf`, `.5` or `1.`: a format error naming
        // the line, not a silent value.
        for (row, token) in [(0, "nan"), (1, "inf"), (2, ".5"), (1, "1.")] {
            let mut rows = ["0 0 0 0 0 1"; 3];
            let bad = format!("0 {token} 0 0 0 1");
            rows[row] = &bad;
            let text = ascii_header(3, ORIENTED) + &rows.join("\n");
            let path = write(&dir, "bad.ply", text.as_bytes());
            let e = format_message(read_points(&path).unwrap_err());
            let line = format!("line {}", 11 + row);
            let what = format!("'{token}' is not a number");
            assert!(
                e.contains(&line) && e.contains(&what) && e.contains(&bad),
                "{token}: {e}"
            );
        }
        // No newline after `end_header`, no vertices.
        let path = write(
            &dir,
            "empty.ply",
            ascii_header(0, XYZ).trim_end().as_bytes(),
        );
        assert!(read_ply_positions(&path).unwrap().is_empty());
    }

    #[test]
    fn reads_polygon_meshes() {
        let dir = tempfile::tempdir().unwrap();
        // A unit square as one quad (vertex_index, uint list) plus a triangle.
        let text = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n\
            property float z\nelement face 2\nproperty uchar flags\nproperty list uchar uint vertex_index\n\
            end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n0 4 0 1 2 3\n1 3 0 1 4\n";
        let path = write(&dir, "quad.ply", text.as_bytes());
        let mesh = read_ply_mesh(&path).unwrap();
        assert_eq!(mesh.positions.len(), 5);
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]]);

        // Every integer list type, both byte orders, `vertex_indices` preferred.
        for (ty, size) in [("char", 1), ("ushort", 2), ("int", 4)] {
            let mut bin = format!(
                "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n\
                 property double y\nproperty double z\nelement face 1\n\
                 property list uchar {ty} vertex_index\nproperty list uchar {ty} vertex_indices\n\
                 end_header\n"
            )
            .into_bytes();
            for v in [0.0f64, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
                bin.extend(v.to_be_bytes());
            }
            for list in [[0u8, 0, 0], [2, 1, 0]] {
                bin.push(3);
                for i in list {
                    bin.extend(std::iter::repeat_n(0, size - 1));
                    bin.push(i);
                }
            }
            let path = write(&dir, "bin.ply", &bin);
            let mesh = read_ply_mesh(&path).unwrap();
            assert_eq!(mesh.positions[1], [1.0, 0.0, 0.0], "{ty}");
            assert_eq!(mesh.triangles, vec![[2, 1, 0]], "{ty}");
        }

        let no_faces = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
            property float z\nend_header\n0 0 0\n";
        let path = write(&dir, "nofaces.ply", no_faces.as_bytes());
        let e = format_message(read_ply_mesh(&path).unwrap_err());
        assert!(e.contains("'face'"), "{e}");

        let bad_list = text.replace(
            "list uchar uint vertex_index",
            "list uchar float vertex_indices",
        );
        let path = write(&dir, "floatlist.ply", bad_list.as_bytes());
        let e = format_message(read_ply_mesh(&path).unwrap_err());
        assert!(e.contains("vertex_indices"), "{e}");

        let wrong_name = text.replace("vertex_index", "corners");
        let path = write(&dir, "corners.ply", wrong_name.as_bytes());
        let e = format_message(read_ply_mesh(&path).unwrap_err());
        assert!(e.contains("vertex_indices"), "{e}");

        let short = text.replace("1 3 0 1 4", "1 2 0 1");
        let path = write(&dir, "short.ply", short.as_bytes());
        let e = format_message(read_ply_mesh(&path).unwrap_err());
        assert!(e.contains("face 1"), "{e}");

        let truncated = text.replace("1 3 0 1 4", "1 3 0 1");
        let path = write(&dir, "truncated.ply", truncated.as_bytes());
        let e = format_message(read_ply_mesh(&path).unwrap_err());
        assert!(
            e.contains("line 17") && e.contains("element 'face' 1"),
            "{e}"
        );

        let out_of_range = text.replace("1 3 0 1 4", "1 3 0 1 9");
        let path = write(&dir, "range.ply", out_of_range.as_bytes());
        let e = format_message(crate::io::read_mesh(&path).unwrap_err());
        assert!(e.contains("vertex 9"), "{e}");

        let negative = text
            .replace("uint vertex_index", "int vertex_index")
            .replace("1 3 0 1 4", "1 3 0 1 -4");
        let path = write(&dir, "negative.ply", negative.as_bytes());
        let e = format_message(read_ply_mesh(&path).unwrap_err());
        assert!(e.contains("-4"), "{e}");
    }

    #[test]
    fn ascii_mesh_with_normals_round_trips() {
        let dir = tempfile::tempdir().unwrap();
        let mesh = crate::io::mesh::tests::unit_cube();
        let normals: Vec<[f64; 3]> = mesh.positions.iter().map(|p| p.map(|c| c - 0.5)).collect();
        let path = dir.path().join("cube.ply");
        write_mesh_ply(&path, &mesh, Some(&normals), PlyEncoding::Ascii).unwrap();
        assert_eq!(crate::io::read_mesh(&path).unwrap(), mesh);
        let p = read_points(&path).unwrap();
        assert_eq!(p.normals, normals);
        assert_eq!(p.features, None);
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.contains("\nproperty list uchar int vertex_indices\n"),
            "{text}"
        );
        assert!(text.ends_with("\n3 1 3 7\n3 1 7 5\n"), "{text}");
    }
}
