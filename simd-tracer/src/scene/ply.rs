//! Stanford PLY meshes, read into a [`MeshData`].
//!
//! The format is Greg Turk's "The PLY Polygon File Format" (Stanford, 1994),
//! the specification every exporter follows: a text header that declares
//! elements, their record counts and their properties, then the records.
//!
//! ```text
//! ply
//! format binary_little_endian 1.0          ascii 1.0, binary_little_endian 1.0 or binary_big_endian 1.0
//! comment written by …                     comment and obj_info lines are ignored
//! element vertex 8                         an element: its name and record count
//! property float x                         a scalar property: type and name
//! property float y
//! property float z
//! element face 6
//! property list uchar int vertex_indices   a list: count type, item type, name
//! end_header
//! …                                        the records, element by element, in header order
//! ```
//!
//! Scalar types are `char uchar short ushort int uint float double` or
//! their sized names `int8 uint8 int16 uint16 int32 uint32 float32 float64`.
//! ASCII data holds one record per line (values separated by whitespace,
//! blank lines skipped); binary data packs the records back to back in the
//! declared types and byte order. Header lines may end in `\r\n`.
//!
//! What is read:
//!
//! * `vertex`: `x y z` (required); `nx ny nz`, shading normals (optional,
//!   kept as stored even if zero length: the scene decides); texture
//!   coordinates `u v`, `s t`, `texture_u texture_v` or
//!   `texture_s texture_t` (the first pair present, in that order). Any
//!   scalar type; values are rounded to `f32`.
//! * `face`: the list `vertex_indices` (or `vertex_index`), with any integer
//!   count and item types. Triangles are kept in their order and polygons
//!   are fan-triangulated from their first vertex (`0 1 2 3` gives `0 1 2`
//!   and `0 2 3`), so PLY's counter-clockwise front face is kept.
//! * Every other element (edges, materials, triangle strips, …) and every
//!   other property is skipped, lists included, wherever it is in the file.
//!   Records are counted from 0 in messages, like the vertex indices.
//!
//! What is refused, with one line naming the culprit (never a panic, never
//! a silently shortened mesh): a first line other than `ply`; a format other
//! than the three above; a malformed or unknown header line; a missing
//! `end_header`; a missing `vertex` or `face` element or `x`, `y`, `z`
//! property; half of a normal or texture coordinate set; a file that ends
//! inside a record (`file ends in vertex 12 of 100`); anything but
//! whitespace after the last value of an ASCII line or after the last
//! record; a polygon with fewer than 3 vertices; a negative or out-of-range
//! vertex index (naming the face); a NaN or infinite value (also a `double`
//! beyond the `f32` range) in a property that is read.
//!
//! Why the counts are checked first: they size every allocation, so a
//! vertex or face count above [`MAX_MESH_ELEMENTS`] is refused from the
//! header, and so is a header whose counts need more data than the file
//! holds: a binary record is at least its scalars and list counts, an ASCII
//! value at least two bytes (a digit and a separator). A lying header thus
//! costs at most a small multiple of the file's own size. List counts are
//! never allocated: lists are read item by item, and each item must be in
//! the file.

use crate::scene::mesh::{MAX_MESH_ELEMENTS, MeshData, MeshFileError};
use glam::{Vec2, Vec3};
use std::collections::HashSet;

/// An integer property type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum IntType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
}

impl IntType {
    /// Bytes of one binary value.
    fn size_bytes(self) -> u64 {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 => 4,
        }
    }

    /// The smallest and largest value.
    fn range(self) -> (i64, i64) {
        match self {
            Self::I8 => (i8::MIN.into(), i8::MAX.into()),
            Self::U8 => (0, u8::MAX.into()),
            Self::I16 => (i16::MIN.into(), i16::MAX.into()),
            Self::U16 => (0, u16::MAX.into()),
            Self::I32 => (i32::MIN.into(), i32::MAX.into()),
            Self::U32 => (0, u32::MAX.into()),
        }
    }
}

/// A scalar property type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    Int(IntType),
    F32,
    F64,
}

impl Scalar {
    /// The type of a header name, under either of its names.
    fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::Int(IntType::I8),
            "uchar" | "uint8" => Self::Int(IntType::U8),
            "short" | "int16" => Self::Int(IntType::I16),
            "ushort" | "uint16" => Self::Int(IntType::U16),
            "int" | "int32" => Self::Int(IntType::I32),
            "uint" | "uint32" => Self::Int(IntType::U32),
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    /// Bytes of one binary value.
    fn size_bytes(self) -> u64 {
        match self {
            Self::Int(t) => t.size_bytes(),
            Self::F32 => 4,
            Self::F64 => 8,
        }
    }
}

/// A property: a scalar, or a list (its count, then that many items).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List { count: IntType, item: Scalar },
}

/// A property declared in the header.
#[derive(Debug, Clone, PartialEq)]
struct Property {
    name: String,
    kind: Kind,
}

/// An element declared in the header.
#[derive(Debug, Clone, PartialEq)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
}

impl Element {
    /// The fewest bytes a record can take: binary, its scalars and list
    /// counts; ASCII, two bytes per value (a digit and a separator; a list
    /// has at least its count).
    fn min_record_bytes(&self, encoding: Encoding) -> u64 {
        let properties = self.properties.iter();
        match encoding {
            Encoding::Ascii => 2 * self.properties.len() as u64,
            Encoding::Binary { .. } => properties
                .map(|p| match p.kind {
                    Kind::Scalar(t) => t.size_bytes(),
                    Kind::List { count, .. } => count.size_bytes(),
                })
                .sum(),
        }
    }

    /// The index and type of the scalar property `name`, if there is one.
    fn scalar(&self, name: &str) -> Result<Option<(usize, Scalar)>, MeshFileError> {
        match self
            .properties
            .iter()
            .enumerate()
            .find(|(_, p)| p.name == name)
        {
            None => Ok(None),
            Some((i, p)) => match p.kind {
                Kind::Scalar(t) => Ok(Some((i, t))),
                Kind::List { .. } => Err(MeshFileError(format!(
                    "property `{name}` of element `{}` is a list, expected a scalar",
                    self.name
                ))),
            },
        }
    }

    /// The scalar properties `names`: all of them, none of them (`None`),
    /// or an error naming the missing half of the set.
    fn scalar_set<const N: usize>(
        &self,
        names: [&str; N],
    ) -> Result<Option<[(usize, Scalar); N]>, MeshFileError> {
        let mut found = [None; N];
        for (slot, name) in found.iter_mut().zip(names) {
            *slot = self.scalar(name)?;
        }
        if found.iter().all(Option::is_none) {
            return Ok(None);
        }
        let mut set = [(0, Scalar::F32); N];
        for ((entry, slot), name) in set.iter_mut().zip(found).zip(names) {
            *entry = slot.ok_or_else(|| {
                MeshFileError(format!(
                    "element `{}` has only part of `{}`: no `{name}`",
                    self.name,
                    names.join(" ")
                ))
            })?;
        }
        Ok(Some(set))
    }
}

/// How the records are encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Ascii,
    Binary { big_endian: bool },
}

/// A parsed header.
#[derive(Debug, Clone, PartialEq)]
struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the first record.
    data_start: usize,
    /// Lines up to and including `end_header` (ASCII line numbers go on).
    lines: usize,
}

fn header_error(line: usize, message: impl core::fmt::Display) -> MeshFileError {
    MeshFileError(format!("PLY header line {line}: {message}"))
}

/// The first line and the rest of `bytes` (the line without its `\n`).
fn split_line(bytes: &[u8]) -> (&[u8], &[u8]) {
    match bytes.iter().position(|&b| b == b'\n') {
        Some(i) => (
            bytes.get(..i).unwrap_or_default(),
            bytes.get(i + 1..).unwrap_or_default(),
        ),
        None => (bytes, &[]),
    }
}

fn parse_header(bytes: &[u8]) -> Result<Header, MeshFileError> {
    let (first, mut rest) = split_line(bytes);
    if first.strip_suffix(b"\r").unwrap_or(first).trim_ascii_end() != b"ply" {
        return Err(MeshFileError::new(
            "not a PLY file (the first line is not `ply`)",
        ));
    }
    let mut line_number = 1;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    // Names seen, to refuse repeats in time linear in the header's size:
    // element names, and (element index, property name).
    let mut element_names = HashSet::new();
    let mut property_names = HashSet::new();
    loop {
        if rest.is_empty() {
            return Err(MeshFileError::new(
                "PLY header without `end_header` (the file ends in the header)",
            ));
        }
        let (line, next) = split_line(rest);
        rest = next;
        line_number += 1;
        // Comments are free text, in whatever encoding the exporter used.
        let first_word = line.split(u8::is_ascii_whitespace).find(|w| !w.is_empty());
        if matches!(first_word, Some(b"comment" | b"obj_info")) {
            continue;
        }
        let text = std::str::from_utf8(line)
            .map_err(|_| header_error(line_number, "not text (is `end_header` missing?)"))?;
        let mut words = text.split_ascii_whitespace();
        let keyword = words.next();
        let words: Vec<&str> = words.collect();
        match (keyword, words.as_slice()) {
            (None, _) => {}
            (Some("end_header"), []) => break,
            (Some("format"), [name, version]) => {
                if encoding.is_some() {
                    return Err(header_error(line_number, "a second `format` line"));
                }
                encoding = Some(match *name {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Binary { big_endian: false },
                    "binary_big_endian" => Encoding::Binary { big_endian: true },
                    other => {
                        return Err(header_error(
                            line_number,
                            format!(
                                "unknown format `{other}` (ascii, binary_little_endian or binary_big_endian)"
                            ),
                        ));
                    }
                });
                if *version != "1.0" {
                    return Err(header_error(
                        line_number,
                        format!("PLY version `{version}` is not supported (1.0 is)"),
                    ));
                }
            }
            (Some("element"), [name, count]) => {
                let count: u64 = count.parse().map_err(|_| {
                    header_error(
                        line_number,
                        format!("element count `{count}` is not a non-negative integer"),
                    )
                })?;
                if !element_names.insert(*name) {
                    return Err(header_error(
                        line_number,
                        format!("a second `{name}` element"),
                    ));
                }
                elements.push(Element {
                    name: (*name).to_owned(),
                    count,
                    properties: Vec::new(),
                });
            }
            (Some("property"), words) => {
                let (kind, name) =
                    parse_property(words).map_err(|m| header_error(line_number, m))?;
                let element_index = elements.len();
                let element = elements
                    .last_mut()
                    .ok_or_else(|| header_error(line_number, "a property before any element"))?;
                if !property_names.insert((element_index, name)) {
                    return Err(header_error(
                        line_number,
                        format!("a second property `{name}` in element `{}`", element.name),
                    ));
                }
                element.properties.push(Property {
                    name: name.to_owned(),
                    kind,
                });
            }
            (Some(keyword), _) => {
                return Err(header_error(
                    line_number,
                    format!("malformed line `{keyword} …`"),
                ));
            }
        }
    }
    let encoding =
        encoding.ok_or_else(|| MeshFileError::new("PLY header without `format` line"))?;
    Ok(Header {
        encoding,
        elements,
        data_start: bytes.len() - rest.len(),
        lines: line_number,
    })
}

/// The words after `property`: `TYPE NAME` or `list COUNT ITEM NAME`.
fn parse_property<'a>(words: &[&'a str]) -> Result<(Kind, &'a str), String> {
    let scalar = |name: &str| {
        Scalar::from_name(name).ok_or_else(|| format!("unknown property type `{name}`"))
    };
    match *words {
        ["list", count, item, name] => match scalar(count)? {
            Scalar::Int(count) => Ok((
                Kind::List {
                    count,
                    item: scalar(item)?,
                },
                name,
            )),
            Scalar::F32 | Scalar::F64 => Err(format!(
                "list `{name}` has the count type `{count}`, expected an integer type"
            )),
        },
        [ty, name] => Ok((Kind::Scalar(scalar(ty)?), name)),
        _ => Err("malformed `property` line".to_owned()),
    }
}

/// What a property is read for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Skip(Kind),
    Position(usize, Scalar),
    Normal(usize, Scalar),
    Uv(usize, Scalar),
    Indices(IntType, IntType),
}

/// Why a record could not be read (the caller names the record).
#[derive(Debug, Clone, PartialEq)]
enum Stop {
    /// The data ends inside the record.
    End,
    /// A value is malformed or out of range.
    Bad(String),
}

/// Reads records value by value, in either encoding.
trait Records {
    /// Begins a record (ASCII: the next non-blank line).
    fn start_record(&mut self) -> Result<(), Stop>;
    /// Ends a record (ASCII: only whitespace may be left on the line).
    fn end_record(&mut self) -> Result<(), Stop>;
    /// An integer value.
    fn int(&mut self, ty: IntType) -> Result<i64, Stop>;
    /// A value of any type as `f64` (an `f32` value exactly).
    fn float(&mut self, ty: Scalar) -> Result<f64, Stop>;
    /// Skips `count` values.
    fn skip(&mut self, ty: Scalar, count: u64) -> Result<(), Stop>;
    /// Skips all records of an element in one step where their size is
    /// fixed (binary, no lists); `false` if it did not.
    fn skip_element(&mut self, element: &Element) -> Result<bool, Stop>;
    /// Where the reader is, for messages.
    fn location(&self) -> String;
    /// Checks that nothing but whitespace follows the last record.
    fn finish(&self) -> Result<(), MeshFileError>;
}

/// Binary records.
struct Binary<'a> {
    data: &'a [u8],
    /// Offset in `data` of the next value.
    position: usize,
    /// Offset of `data` in the file.
    file_offset: usize,
    big_endian: bool,
}

impl Binary<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], Stop> {
        let bytes = self
            .data
            .get(self.position..)
            .and_then(<[u8]>::first_chunk::<N>)
            .ok_or(Stop::End)?;
        self.position += N;
        Ok(*bytes)
    }

    fn advance(&mut self, bytes: u64) -> Result<(), Stop> {
        let end = usize::try_from(bytes)
            .ok()
            .and_then(|b| self.position.checked_add(b))
            .filter(|&end| end <= self.data.len())
            .ok_or(Stop::End)?;
        self.position = end;
        Ok(())
    }
}

/// `$t::from_le_bytes` or `from_be_bytes` of the next bytes.
macro_rules! read_binary {
    ($reader:expr, $t:ty) => {{
        let bytes = $reader.take::<{ size_of::<$t>() }>()?;
        if $reader.big_endian {
            <$t>::from_be_bytes(bytes)
        } else {
            <$t>::from_le_bytes(bytes)
        }
    }};
}

impl Records for Binary<'_> {
    fn start_record(&mut self) -> Result<(), Stop> {
        Ok(())
    }

    fn end_record(&mut self) -> Result<(), Stop> {
        Ok(())
    }

    fn int(&mut self, ty: IntType) -> Result<i64, Stop> {
        Ok(match ty {
            IntType::I8 => read_binary!(self, i8).into(),
            IntType::U8 => read_binary!(self, u8).into(),
            IntType::I16 => read_binary!(self, i16).into(),
            IntType::U16 => read_binary!(self, u16).into(),
            IntType::I32 => read_binary!(self, i32).into(),
            IntType::U32 => read_binary!(self, u32).into(),
        })
    }

    fn float(&mut self, ty: Scalar) -> Result<f64, Stop> {
        Ok(match ty {
            // Every value of these types is exact in f64.
            Scalar::Int(t) => self.int(t)? as f64,
            Scalar::F32 => read_binary!(self, f32).into(),
            Scalar::F64 => read_binary!(self, f64),
        })
    }

    fn skip(&mut self, ty: Scalar, count: u64) -> Result<(), Stop> {
        self.advance(count.checked_mul(ty.size_bytes()).ok_or(Stop::End)?)
    }

    fn skip_element(&mut self, element: &Element) -> Result<bool, Stop> {
        let mut record_bytes = 0;
        for property in &element.properties {
            match property.kind {
                Kind::Scalar(t) => record_bytes += t.size_bytes(),
                Kind::List { .. } => return Ok(false),
            }
        }
        self.advance(element.count.checked_mul(record_bytes).ok_or(Stop::End)?)?;
        Ok(true)
    }

    fn location(&self) -> String {
        format!("byte {}", self.file_offset + self.position)
    }

    fn finish(&self) -> Result<(), MeshFileError> {
        match self.data.len().saturating_sub(self.position) {
            0 => Ok(()),
            extra => Err(MeshFileError(format!(
                "{extra} bytes after the last record (the header's counts do not match the data)"
            ))),
        }
    }
}

/// ASCII records: one per line.
struct Ascii<'a> {
    /// The lines after the current one.
    rest: &'a [u8],
    /// What is left of the current record's line.
    line: &'a [u8],
    /// Number of the current line in the file (from 1).
    line_number: usize,
}

impl<'a> Ascii<'a> {
    /// The next whitespace-separated value on the record's line.
    fn token(&mut self) -> Result<&'a str, Stop> {
        let start = self
            .line
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .ok_or_else(|| Stop::Bad("too few values on the line".to_owned()))?;
        let rest = self.line.get(start..).unwrap_or_default();
        let end = rest
            .iter()
            .position(u8::is_ascii_whitespace)
            .unwrap_or(rest.len());
        let (token, after) = rest.split_at_checked(end).unwrap_or((rest, &[]));
        self.line = after;
        std::str::from_utf8(token).map_err(|_| Stop::Bad("a value is not text".to_owned()))
    }
}

impl Records for Ascii<'_> {
    fn start_record(&mut self) -> Result<(), Stop> {
        loop {
            if self.rest.is_empty() {
                return Err(Stop::End);
            }
            let (line, rest) = split_line(self.rest);
            self.rest = rest;
            self.line_number += 1;
            if !line.trim_ascii().is_empty() {
                self.line = line;
                return Ok(());
            }
        }
    }

    fn end_record(&mut self) -> Result<(), Stop> {
        if self.line.trim_ascii().is_empty() {
            Ok(())
        } else {
            let extra = self.token()?;
            Err(Stop::Bad(format!("unexpected `{extra}` after the record")))
        }
    }

    fn int(&mut self, ty: IntType) -> Result<i64, Stop> {
        let token = self.token()?;
        let value: i64 = token
            .parse()
            .map_err(|_| Stop::Bad(format!("`{token}` is not an integer")))?;
        let (low, high) = ty.range();
        if (low..=high).contains(&value) {
            Ok(value)
        } else {
            Err(Stop::Bad(format!(
                "{value} is outside the range of its type ({low} to {high})"
            )))
        }
    }

    fn float(&mut self, ty: Scalar) -> Result<f64, Stop> {
        match ty {
            Scalar::Int(t) => Ok(self.int(t)? as f64),
            Scalar::F32 => {
                let token = self.token()?;
                token
                    .parse::<f32>()
                    .map(f64::from)
                    .map_err(|_| Stop::Bad(format!("`{token}` is not a number")))
            }
            Scalar::F64 => {
                let token = self.token()?;
                token
                    .parse::<f64>()
                    .map_err(|_| Stop::Bad(format!("`{token}` is not a number")))
            }
        }
    }

    fn skip(&mut self, _ty: Scalar, count: u64) -> Result<(), Stop> {
        for _ in 0..count {
            let token = self.token()?;
            if token.parse::<f64>().is_err() {
                return Err(Stop::Bad(format!("`{token}` is not a number")));
            }
        }
        Ok(())
    }

    fn skip_element(&mut self, _element: &Element) -> Result<bool, Stop> {
        Ok(false)
    }

    fn location(&self) -> String {
        format!("line {}", self.line_number)
    }

    fn finish(&self) -> Result<(), MeshFileError> {
        let mut rest = self.rest;
        let mut line_number = self.line_number;
        while !rest.is_empty() {
            let (line, next) = split_line(rest);
            line_number += 1;
            if !line.trim_ascii().is_empty() {
                return Err(MeshFileError(format!(
                    "line {line_number}: data after the last record (the header's counts do not match the data)"
                )));
            }
            rest = next;
        }
        Ok(())
    }
}

/// Parses a PLY file (ASCII or binary) into an indexed triangle mesh that
/// passes [`MeshData::validate`]; see the module documentation for what is
/// read and what is refused.
pub fn parse_ply(bytes: &[u8]) -> Result<MeshData, MeshFileError> {
    let header = parse_header(bytes)?;
    let data = bytes.get(header.data_start..).unwrap_or_default();
    let plan = Plan::new(&header, data.len())?;
    match header.encoding {
        Encoding::Ascii => plan.read(Ascii {
            rest: data,
            line: &[],
            line_number: header.lines,
        }),
        Encoding::Binary { big_endian } => plan.read(Binary {
            data,
            position: 0,
            file_offset: header.data_start,
            big_endian,
        }),
    }
}

/// The header checked, and the role of every property.
struct Plan<'h> {
    elements: Vec<(&'h Element, Vec<Role>)>,
    vertices: u64,
    faces: u64,
    normals: bool,
    uvs: bool,
}

impl<'h> Plan<'h> {
    /// Checks the header's elements and counts against the limits and the
    /// `data_bytes` after the header.
    fn new(header: &'h Header, data_bytes: usize) -> Result<Self, MeshFileError> {
        let find = |name: &str| header.elements.iter().find(|e| e.name == name);
        let vertex = find("vertex").ok_or_else(|| MeshFileError::new("no `vertex` element"))?;
        let mut vertex_roles: Vec<Role> = vertex
            .properties
            .iter()
            .map(|p| Role::Skip(p.kind))
            .collect();
        let mut assign = |set: &[(usize, Scalar)], role: fn(usize, Scalar) -> Role| {
            for (axis, &(i, t)) in set.iter().enumerate() {
                if let Some(r) = vertex_roles.get_mut(i) {
                    *r = role(axis, t);
                }
            }
        };
        let position = vertex.scalar_set(["x", "y", "z"])?.ok_or_else(|| {
            MeshFileError::new("the `vertex` element has no `x`, `y`, `z` properties")
        })?;
        assign(&position, Role::Position);
        let normals = vertex.scalar_set(["nx", "ny", "nz"])?;
        if let Some(set) = &normals {
            assign(set, Role::Normal);
        }
        let mut uvs = None;
        for names in [
            ["u", "v"],
            ["s", "t"],
            ["texture_u", "texture_v"],
            ["texture_s", "texture_t"],
        ] {
            let set = vertex.scalar_set(names)?;
            uvs = uvs.or(set);
        }
        if let Some(set) = &uvs {
            assign(set, Role::Uv);
        }

        let face = find("face").ok_or_else(|| {
            MeshFileError::new(if find("tristrips").is_some() {
                "no `face` element (triangle strips are not supported)"
            } else {
                "no `face` element"
            })
        })?;
        let list = ["vertex_indices", "vertex_index"]
            .iter()
            .find_map(|&name| face.properties.iter().position(|p| p.name == name))
            .ok_or_else(|| MeshFileError::new("the `face` element has no `vertex_indices` list"))?;
        let mut face_roles: Vec<Role> =
            face.properties.iter().map(|p| Role::Skip(p.kind)).collect();
        if let (Some(role), Some(property)) = (face_roles.get_mut(list), face.properties.get(list))
        {
            *role = match property.kind {
                Kind::List {
                    count,
                    item: Scalar::Int(item),
                } => Role::Indices(count, item),
                Kind::List { .. } => {
                    return Err(MeshFileError(format!(
                        "the face list `{}` holds non-integer items",
                        property.name
                    )));
                }
                Kind::Scalar(_) => {
                    return Err(MeshFileError(format!(
                        "the face property `{}` is a scalar, expected a list",
                        property.name
                    )));
                }
            };
        }

        for element in [vertex, face] {
            if element.count > MAX_MESH_ELEMENTS as u64 {
                return Err(MeshFileError(format!(
                    "the header declares {} {} records, above the limit of {MAX_MESH_ELEMENTS}",
                    element.count, element.name
                )));
            }
        }
        let needed = header.elements.iter().try_fold(0_u64, |sum, e| {
            e.count
                .checked_mul(e.min_record_bytes(header.encoding))
                .and_then(|b| sum.checked_add(b))
        });
        // The last ASCII value needs no separator.
        let available = data_bytes as u64 + u64::from(header.encoding == Encoding::Ascii);
        if needed.is_none_or(|n| n > available) {
            let needed = needed.map_or("more than 2^64".to_owned(), |n| n.to_string());
            return Err(MeshFileError(format!(
                "file too short for its header: the declared records need at least {needed} bytes, {data_bytes} follow the header"
            )));
        }

        let elements = header
            .elements
            .iter()
            .map(|e| {
                let roles = if e.name == "vertex" {
                    vertex_roles.clone()
                } else if e.name == "face" {
                    face_roles.clone()
                } else {
                    e.properties.iter().map(|p| Role::Skip(p.kind)).collect()
                };
                (e, roles)
            })
            .collect();
        Ok(Self {
            elements,
            vertices: vertex.count,
            faces: face.count,
            normals: normals.is_some(),
            uvs: uvs.is_some(),
        })
    }

    /// Reads the records.
    fn read(&self, mut reader: impl Records) -> Result<MeshData, MeshFileError> {
        // The counts were checked against the limit and the file size.
        let vertices = self.vertices as usize;
        let mut mesh = MeshData {
            positions: Vec::with_capacity(vertices),
            normals: Vec::with_capacity(if self.normals { vertices } else { 0 }),
            uvs: Vec::with_capacity(if self.uvs { vertices } else { 0 }),
            triangles: Vec::with_capacity(self.faces as usize),
        };
        for (element, roles) in &self.elements {
            let fail = |stop: Stop, reader: &dyn Records, record: u64| match stop {
                Stop::End => MeshFileError(format!(
                    "file ends in {} {record} of {}",
                    element.name, element.count
                )),
                Stop::Bad(message) => MeshFileError(format!(
                    "{} {record} ({}): {message}",
                    element.name,
                    reader.location()
                )),
            };
            let only_skips = roles.iter().all(|r| matches!(r, Role::Skip(_)));
            if element.properties.is_empty()
                || (only_skips
                    && reader
                        .skip_element(element)
                        .map_err(|stop| fail(stop, &reader, 0))?)
            {
                continue;
            }
            for record in 0..element.count {
                self.read_record(&mut reader, roles, &mut mesh)
                    .map_err(|stop| fail(stop, &reader, record))?;
            }
        }
        reader.finish()?;
        Ok(mesh)
    }

    /// Reads one record: a vertex, a face, or one to skip.
    fn read_record(
        &self,
        reader: &mut impl Records,
        roles: &[Role],
        mesh: &mut MeshData,
    ) -> Result<(), Stop> {
        reader.start_record()?;
        let (mut position, mut normal, mut uv) = ([0.0_f32; 3], [0.0_f32; 3], [0.0_f32; 2]);
        let mut is_vertex = false;
        for &role in roles {
            match role {
                Role::Position(axis, ty) => {
                    is_vertex = true;
                    let value = finite(reader.float(ty)?, &["x", "y", "z"], axis)?;
                    if let Some(slot) = position.get_mut(axis) {
                        *slot = value;
                    }
                }
                Role::Normal(axis, ty) => {
                    let value = finite(reader.float(ty)?, &["nx", "ny", "nz"], axis)?;
                    if let Some(slot) = normal.get_mut(axis) {
                        *slot = value;
                    }
                }
                Role::Uv(axis, ty) => {
                    let value = finite(reader.float(ty)?, &["u", "v"], axis)?;
                    if let Some(slot) = uv.get_mut(axis) {
                        *slot = value;
                    }
                }
                Role::Indices(count, item) => {
                    read_polygon(reader, count, item, self.vertices, &mut mesh.triangles)?;
                }
                Role::Skip(Kind::Scalar(ty)) => reader.skip(ty, 1)?,
                Role::Skip(Kind::List { count, item }) => {
                    let n = reader.int(count)?;
                    let n = u64::try_from(n)
                        .map_err(|_| Stop::Bad(format!("negative list length {n}")))?;
                    reader.skip(item, n)?;
                }
            }
        }
        reader.end_record()?;
        if is_vertex {
            mesh.positions.push(Vec3::from_array(position));
            if self.normals {
                mesh.normals.push(Vec3::from_array(normal));
            }
            if self.uvs {
                mesh.uvs.push(Vec2::from_array(uv));
            }
        }
        Ok(())
    }
}

/// `value` as a finite `f32`, or an error naming the component.
fn finite(value: f64, names: &[&str], axis: usize) -> Result<f32, Stop> {
    let rounded = value as f32;
    if rounded.is_finite() {
        Ok(rounded)
    } else {
        let name = names.get(axis).copied().unwrap_or_default();
        Err(Stop::Bad(format!(
            "{name} is {value}, not a finite single-precision value"
        )))
    }
}

/// Reads a face's index list and appends its fan triangulation.
fn read_polygon(
    reader: &mut impl Records,
    count: IntType,
    item: IntType,
    vertices: u64,
    triangles: &mut Vec<[u32; 3]>,
) -> Result<(), Stop> {
    let n = reader.int(count)?;
    if n < 3 {
        return Err(Stop::Bad(format!(
            "a face needs at least 3 vertices, this one has {n}"
        )));
    }
    let mut index = || -> Result<u32, Stop> {
        let i = reader.int(item)?;
        if i < 0 {
            return Err(Stop::Bad(format!("negative vertex index {i}")));
        }
        u32::try_from(i)
            .ok()
            .filter(|&i| u64::from(i) < vertices)
            .ok_or_else(|| {
                Stop::Bad(format!(
                    "vertex index {i} out of range ({vertices} vertices)"
                ))
            })
    };
    let first = index()?;
    let mut previous = index()?;
    for _ in 2..n {
        let next = index()?;
        if triangles.len() >= MAX_MESH_ELEMENTS {
            return Err(Stop::Bad(format!(
                "more than {MAX_MESH_ELEMENTS} triangles"
            )));
        }
        triangles.push([first, previous, next]);
        previous = next;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// How [`write_ply`] writes a mesh.
    #[derive(Debug, Clone, Copy)]
    struct Layout {
        /// `ascii`, `binary_little_endian` or `binary_big_endian`.
        format: &'static str,
        position: &'static str,
        normal: &'static str,
        uv: &'static str,
        uv_names: [&'static str; 2],
        count: &'static str,
        index: &'static str,
        /// Unknown elements (with lists) before, between and after, extra
        /// vertex and face properties (scalars and lists) between the
        /// known ones.
        extras: bool,
        /// The face element before the vertex element.
        faces_first: bool,
    }

    const FLOAT_LE: Layout = Layout {
        format: "binary_little_endian",
        position: "float",
        normal: "float",
        uv: "float",
        uv_names: ["u", "v"],
        count: "uchar",
        index: "int",
        extras: false,
        faces_first: false,
    };

    /// Appends `value` as a `ty` value in `format`.
    fn put(out: &mut Vec<u8>, format: &str, ty: &str, value: f64) {
        macro_rules! bytes {
            ($v:expr) => {
                if format == "binary_big_endian" {
                    $v.to_be_bytes().to_vec()
                } else {
                    $v.to_le_bytes().to_vec()
                }
            };
        }
        if format == "ascii" {
            let text = match ty {
                "float" | "float32" => format!("{}", value as f32),
                "double" | "float64" => format!("{value}"),
                _ => format!("{}", value as i64),
            };
            out.extend_from_slice(text.as_bytes());
            out.push(b' ');
            return;
        }
        out.extend(match ty {
            "char" | "int8" => bytes!(value as i8),
            "uchar" | "uint8" => bytes!(value as u8),
            "short" | "int16" => bytes!(value as i16),
            "ushort" | "uint16" => bytes!(value as u16),
            "int" | "int32" => bytes!(value as i32),
            "uint" | "uint32" => bytes!(value as u32),
            "float" | "float32" => bytes!(value as f32),
            "double" | "float64" => bytes!(value),
            _ => panic!("unknown type {ty}"),
        });
    }

    fn end_record(out: &mut Vec<u8>, format: &str) {
        if format == "ascii" {
            out.push(b'\n');
        }
    }

    /// A PLY file of `mesh` (its normals and uvs if any) with the polygons
    /// `faces`.
    fn write_ply(mesh: &MeshData, faces: &[Vec<u32>], layout: Layout) -> Vec<u8> {
        let Layout { format, .. } = layout;
        let mut header = format!("ply\nformat {format} 1.0\ncomment test mesh\n");
        let extra_before =
            "element material 2\nproperty uchar red\nproperty list uchar float weights\n";
        let extra_between = "element edge 1\nproperty int vertex1\nproperty int vertex2\n";
        let extra_after = "element note 1\nproperty list uint uchar text\n";
        let mut vertex = format!("element vertex {}\n", mesh.positions.len());
        vertex += &format!(
            "property {} x\nproperty {} y\n",
            layout.position, layout.position
        );
        if layout.extras {
            vertex += "property float confidence\nproperty list uchar int neighbours\n";
        }
        vertex += &format!("property {} z\n", layout.position);
        if !mesh.normals.is_empty() {
            for n in ["nx", "ny", "nz"] {
                vertex += &format!("property {} {n}\n", layout.normal);
            }
        }
        if !mesh.uvs.is_empty() {
            for n in layout.uv_names {
                vertex += &format!("property {} {n}\n", layout.uv);
            }
        }
        if layout.extras {
            vertex += "property uchar red\n";
        }
        let mut face = format!("element face {}\n", faces.len());
        if layout.extras {
            face += "property uchar flags\n";
        }
        face += &format!(
            "property list {} {} vertex_indices\n",
            layout.count, layout.index
        );
        if layout.extras {
            face += "property list uchar float texcoord\n";
        }

        let mut vertex_data = Vec::new();
        for (i, p) in mesh.positions.iter().enumerate() {
            put(&mut vertex_data, format, layout.position, p.x.into());
            put(&mut vertex_data, format, layout.position, p.y.into());
            if layout.extras {
                put(&mut vertex_data, format, "float", 0.5);
                put(&mut vertex_data, format, "uchar", 2.0);
                put(&mut vertex_data, format, "int", 7.0);
                put(&mut vertex_data, format, "int", -3.0);
            }
            put(&mut vertex_data, format, layout.position, p.z.into());
            if let Some(n) = mesh.normals.get(i) {
                for c in n.to_array() {
                    put(&mut vertex_data, format, layout.normal, c.into());
                }
            }
            if let Some(t) = mesh.uvs.get(i) {
                for c in t.to_array() {
                    put(&mut vertex_data, format, layout.uv, c.into());
                }
            }
            if layout.extras {
                put(&mut vertex_data, format, "uchar", 200.0);
            }
            end_record(&mut vertex_data, format);
        }
        let mut face_data = Vec::new();
        for polygon in faces {
            if layout.extras {
                put(&mut face_data, format, "uchar", 1.0);
            }
            put(&mut face_data, format, layout.count, polygon.len() as f64);
            for &i in polygon {
                put(&mut face_data, format, layout.index, i.into());
            }
            if layout.extras {
                put(&mut face_data, format, "uchar", 2.0);
                put(&mut face_data, format, "float", 0.25);
                put(&mut face_data, format, "float", 0.75);
            }
            end_record(&mut face_data, format);
        }
        let mut extra_data = [Vec::new(), Vec::new(), Vec::new()];
        for value in [[9.0, 1.0, 0.5], [3.0, 0.0, 0.0]] {
            // material: red, then a list of one or zero weights.
            put(&mut extra_data[0], format, "uchar", value[0]);
            put(&mut extra_data[0], format, "uchar", value[1]);
            if value[1] > 0.0 {
                put(&mut extra_data[0], format, "float", value[2]);
            }
            end_record(&mut extra_data[0], format);
        }
        put(&mut extra_data[1], format, "int", 0.0);
        put(&mut extra_data[1], format, "int", 1.0);
        end_record(&mut extra_data[1], format);
        put(&mut extra_data[2], format, "uint", 3.0);
        for c in b"abc" {
            put(&mut extra_data[2], format, "uchar", f64::from(*c));
        }
        end_record(&mut extra_data[2], format);

        let (first, second) = if layout.faces_first {
            ((face, face_data), (vertex, vertex_data))
        } else {
            ((vertex, vertex_data), (face, face_data))
        };
        let mut data = Vec::new();
        if layout.extras {
            header += extra_before;
            data.extend(&extra_data[0]);
        }
        header += &first.0;
        data.extend(first.1);
        if layout.extras {
            header += extra_between;
            data.extend(&extra_data[1]);
        }
        header += &second.0;
        data.extend(second.1);
        if layout.extras {
            header += extra_after;
            data.extend(&extra_data[2]);
        }
        header += "end_header\n";
        let mut file = header.into_bytes();
        file.extend(data);
        file
    }

    /// A unit cube's corners (scaled by `scale`, offset so that integer
    /// types hold them), with normals (one of zero length) and uvs.
    fn cube(scale: f32, offset: f32) -> MeshData {
        let positions: Vec<Vec3> = (0..8)
            .map(|i| {
                let corner = Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, (i >> 2) as f32);
                corner * scale + offset
            })
            .collect();
        let mut normals: Vec<Vec3> = positions.iter().map(|p| *p - 0.5).collect();
        normals[3] = Vec3::ZERO;
        let uvs = (0..8)
            .map(|i| Vec2::new(i as f32 / 8.0, 0.1 * i as f32))
            .collect();
        MeshData {
            positions,
            normals,
            uvs,
            triangles: Vec::new(),
        }
    }

    /// The cube's faces: quads, counter-clockwise from outside.
    fn cube_quads() -> Vec<Vec<u32>> {
        vec![
            vec![0, 2, 3, 1],
            vec![4, 5, 7, 6],
            vec![0, 1, 5, 4],
            vec![2, 6, 7, 3],
            vec![0, 4, 6, 2],
            vec![1, 3, 7, 5],
        ]
    }

    /// `faces` fan-triangulated.
    fn fan(faces: &[Vec<u32>]) -> Vec<[u32; 3]> {
        faces
            .iter()
            .flat_map(|f| (2..f.len()).map(move |k| [f[0], f[k - 1], f[k]]))
            .collect()
    }

    fn with_faces(mut mesh: MeshData, faces: &[Vec<u32>]) -> MeshData {
        mesh.triangles = fan(faces);
        mesh
    }

    fn error_of(bytes: &[u8]) -> String {
        match parse_ply(bytes) {
            Ok(mesh) => panic!(
                "parsed {} vertices, {} triangles, expected an error",
                mesh.positions.len(),
                mesh.triangles.len()
            ),
            Err(e) => e.0,
        }
    }

    const FORMATS: [&str; 3] = ["ascii", "binary_little_endian", "binary_big_endian"];

    #[test]
    fn ascii_and_binary_encodings_of_a_mesh_parse_to_the_same_mesh() {
        let faces = cube_quads();
        let float_types = ["float", "float32", "double", "float64"];
        let int_types = [
            "char", "int8", "uchar", "uint8", "short", "int16", "ushort", "uint16", "int", "int32",
            "uint", "uint32",
        ];
        let index_types = [
            ("uchar", "int"),
            ("uint8", "uint"),
            ("char", "ushort"),
            ("short", "uchar"),
            ("ushort", "int16"),
            ("int", "uint32"),
            ("uint", "int32"),
            ("int8", "uint16"),
        ];
        let mut checked = 0;
        for format in FORMATS {
            for (k, position) in float_types.iter().chain(&int_types).enumerate() {
                let integer = k >= float_types.len();
                // Fractions only where the type holds them.
                let mesh = if integer {
                    cube(3.0, 1.0)
                } else {
                    cube(0.3, -1.1)
                };
                let expected = with_faces(mesh.clone(), &faces);
                let (count, index) = index_types[k % index_types.len()];
                let normal = float_types[k % float_types.len()];
                let layout = Layout {
                    format,
                    position,
                    normal,
                    uv: float_types[(k + 1) % float_types.len()],
                    count,
                    index,
                    ..FLOAT_LE
                };
                let parsed = parse_ply(&write_ply(&mesh, &faces, layout))
                    .unwrap_or_else(|e| panic!("{layout:?}: {e}"));
                // Doubles round to the same f32 the mesh holds.
                assert_eq!(parsed, expected, "{layout:?}");
                assert_eq!(parsed.validate(), Ok(()));
                checked += 1;
            }
        }
        assert_eq!(checked, 3 * 16);
    }

    #[test]
    fn normals_and_uvs_are_optional() {
        let faces = cube_quads();
        for format in FORMATS {
            let layout = Layout { format, ..FLOAT_LE };
            let bare = MeshData {
                normals: Vec::new(),
                uvs: Vec::new(),
                ..cube(1.0, 0.0)
            };
            let parsed = parse_ply(&write_ply(&bare, &faces, layout)).unwrap();
            assert_eq!(parsed, with_faces(bare.clone(), &faces));
            let only_uvs = MeshData {
                normals: Vec::new(),
                ..cube(1.0, 0.0)
            };
            let parsed = parse_ply(&write_ply(&only_uvs, &faces, layout)).unwrap();
            assert_eq!(parsed, with_faces(only_uvs.clone(), &faces));
            assert!(parsed.normals.is_empty() && parsed.uvs.len() == 8);
        }
    }

    #[test]
    fn zero_length_normals_are_kept() {
        let mesh = cube(1.0, 0.0);
        let parsed = parse_ply(&write_ply(&mesh, &cube_quads(), FLOAT_LE)).unwrap();
        assert_eq!(parsed.normals[3], Vec3::ZERO);
        assert_eq!(parsed.normals.len(), 8);
    }

    #[test]
    fn quads_and_polygons_are_fan_triangulated_in_order() {
        let mut mesh = cube(1.0, 0.0);
        mesh.normals.clear();
        let faces = vec![vec![0, 1, 3, 2], vec![4, 5, 7, 6, 2, 1], vec![0, 4, 5]];
        for format in FORMATS {
            let layout = Layout { format, ..FLOAT_LE };
            let parsed = parse_ply(&write_ply(&mesh, &faces, layout)).unwrap();
            assert_eq!(
                parsed.triangles,
                vec![
                    [0, 1, 3],
                    [0, 3, 2],
                    [4, 5, 7],
                    [4, 7, 6],
                    [4, 6, 2],
                    [4, 2, 1],
                    [0, 4, 5]
                ],
                "{format}"
            );
        }
    }

    #[test]
    fn every_texture_coordinate_naming_is_read() {
        let mesh = cube(1.0, 0.0);
        for uv_names in [
            ["u", "v"],
            ["s", "t"],
            ["texture_u", "texture_v"],
            ["texture_s", "texture_t"],
        ] {
            for format in FORMATS {
                let layout = Layout {
                    format,
                    uv_names,
                    ..FLOAT_LE
                };
                let parsed = parse_ply(&write_ply(&mesh, &cube_quads(), layout)).unwrap();
                assert_eq!(parsed.uvs, mesh.uvs, "{uv_names:?} {format}");
            }
        }
        // Names of other properties are not texture coordinates.
        let layout = Layout {
            uv_names: ["tu", "tv"],
            ..FLOAT_LE
        };
        let parsed = parse_ply(&write_ply(&mesh, &cube_quads(), layout)).unwrap();
        assert!(parsed.uvs.is_empty());
        assert_eq!(parsed.positions, mesh.positions);
    }

    #[test]
    fn unknown_elements_and_extra_properties_are_skipped_in_any_order() {
        let mesh = cube(0.5, 0.25);
        let faces = cube_quads();
        let expected = with_faces(mesh.clone(), &faces);
        for format in FORMATS {
            for faces_first in [false, true] {
                let layout = Layout {
                    format,
                    extras: true,
                    faces_first,
                    ..FLOAT_LE
                };
                let bytes = write_ply(&mesh, &faces, layout);
                let parsed = parse_ply(&bytes).unwrap_or_else(|e| panic!("{layout:?}: {e}"));
                assert_eq!(parsed, expected, "{layout:?}");
            }
        }
    }

    #[test]
    fn header_lines_may_end_in_crlf_and_ascii_lines_in_whitespace() {
        let text = "ply\r\nformat ascii 1.0\r\ncomment x \u{e9}\r\nobj_info y\r\nelement vertex 3\r\n\
            property float x\r\nproperty float y\r\nproperty float z\r\nelement face 1\r\n\
            property list uchar int vertex_index\r\nend_header\r\n\
            0 0 0 \r\n1 0 0\t\r\n\r\n0 1 0\n3 0 1 2  \r\n\n";
        let mesh = parse_ply(text.as_bytes()).unwrap();
        assert_eq!(mesh.positions, vec![Vec3::ZERO, Vec3::X, Vec3::Y]);
        // A Latin-1 comment (not UTF-8) is still a comment.
        let latin1 = text
            .replace("comment x \u{e9}", "comment x ?")
            .replace('?', "\u{1}");
        let latin1: Vec<u8> = latin1
            .bytes()
            .map(|b| if b == 1 { 0xe9 } else { b })
            .collect();
        assert_eq!(parse_ply(&latin1).unwrap(), mesh);
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
        let binary = MeshData {
            normals: Vec::new(),
            uvs: Vec::new(),
            ..cube(1.0, 0.0)
        };
        let bytes = write_ply(&binary, &cube_quads(), FLOAT_LE);
        let text = String::from_utf8_lossy(&bytes);
        let header_end = text.find("end_header\n").unwrap() + "end_header\n".len();
        let crlf_header = bytes[..header_end]
            .iter()
            .flat_map(|&b| {
                if b == b'\n' {
                    vec![b'\r', b'\n']
                } else {
                    vec![b]
                }
            })
            .chain(bytes[header_end..].iter().copied())
            .collect::<Vec<u8>>();
        assert_eq!(
            parse_ply(&crlf_header).unwrap(),
            with_faces(binary, &cube_quads())
        );
    }

    /// A small ASCII file: `header_tail` after the vertex element's x y z,
    /// then `data`.
    fn ascii(header_tail: &str, data: &str) -> Vec<u8> {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\n{header_tail}end_header\n{data}"
        )
        .into_bytes()
    }

    const FACE: &str = "element face 1\nproperty list uchar int vertex_indices\n";
    const VERTICES: &str = "0 0 0\n1 0 0\n0 1 0\n";

    #[test]
    fn a_valid_small_file_parses() {
        let mesh = parse_ply(&ascii(FACE, &format!("{VERTICES}3 0 1 2\n"))).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
        assert_eq!(mesh.validate(), Ok(()));
    }

    #[test]
    fn malformed_files_are_refused_with_a_clear_message() {
        let valid_data = format!("{VERTICES}3 0 1 2\n");
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (b"".to_vec(), "not a PLY file"),
            (b"PLY\nformat ascii 1.0\nend_header\n".to_vec(), "not a PLY file"),
            (b"\x89PNG\r\n".to_vec(), "not a PLY file"),
            (
                b"ply\nformat binary_middle_endian 1.0\nend_header\n".to_vec(),
                "unknown format",
            ),
            (b"ply\nformat ascii 2.0\nend_header\n".to_vec(), "version"),
            (b"ply\nformat ascii\nend_header\n".to_vec(), "malformed"),
            (b"ply\nelement vertex 0\nend_header\n".to_vec(), "format"),
            (
                b"ply\nformat ascii 1.0\nformat ascii 1.0\nend_header\n".to_vec(),
                "second `format`",
            ),
            (ascii("propertee float w\n", VERTICES), "malformed line"),
            (ascii("property float\n", VERTICES), "malformed `property`"),
            (ascii("property quad w\n", VERTICES), "unknown property type"),
            (ascii("property float x\n", VERTICES), "second property"),
            (
                ascii("element face 1\nproperty list float int vertex_indices\n", ""),
                "count type",
            ),
            (ascii("element vertex 2\n", ""), "second `vertex`"),
            (
                b"ply\nformat ascii 1.0\nproperty float x\nend_header\n".to_vec(),
                "before any element",
            ),
            (
                b"ply\nformat ascii 1.0\nelement vertex -3\nend_header\n".to_vec(),
                "non-negative integer",
            ),
            (
                b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n".to_vec(),
                "end_header",
            ),
            (
                b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n\xff\xfe\x00".to_vec(),
                "not text",
            ),
            (
                b"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"
                    .to_vec(),
                "no `vertex` element",
            ),
            (ascii("", VERTICES), "no `face` element"),
            (
                ascii("element tristrips 0\nproperty list int int vertex_indices\n", VERTICES),
                "triangle strips",
            ),
            (
                b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                  element face 0\nproperty list uchar int vertex_indices\nend_header\n0 0\n"
                    .to_vec(),
                "only part of `x y z`: no `z`",
            ),
            (
                b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float w\n\
                  element face 0\nproperty list uchar int vertex_indices\nend_header\n0\n"
                    .to_vec(),
                "no `x`, `y`, `z`",
            ),
            (
                ascii("property list uchar float nx\n", VERTICES),
                "is a list",
            ),
            (ascii("property float nx\nproperty float ny\n", ""), "no `nz`"),
            (ascii("property float s\n", ""), "no `t`"),
            (ascii("element face 1\nproperty int vertex_indices\n", ""), "a scalar"),
            (
                ascii("element face 1\nproperty list uchar float vertex_indices\n", ""),
                "non-integer",
            ),
            (ascii("element face 1\nproperty int flags\n", ""), "no `vertex_indices`"),
            // Data.
            (ascii(FACE, "0.0000 0 0\n1 0 0\n0 1 0\n"), "file ends in face 0 of 1"),
            (ascii(FACE, "0.000000 0.000000 0\n1 0 0\n"), "file ends in vertex 2 of 3"),
            (ascii(FACE, "0 0 0\n1 0 0\n"), "file too short"),
            (ascii(FACE, &format!("{VERTICES}3 0 1\n")), "too few values"),
            (ascii(FACE, "0 0 0 junk\n1 0 0\n0 1 0\n3 0 1 2\n"), "unexpected `junk`"),
            (ascii(FACE, "0 0 zero\n1 0 0\n0 1 0\n3 0 1 2\n"), "not a number"),
            (ascii(FACE, "0 0 0\n1 0 nan\n0 1 0\n3 0 1 2\n"), "vertex 1 (line 11): z is NaN"),
            (ascii(FACE, "0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n"), "not a finite"),
            (ascii(FACE, "0 0 0\n1 1e39 0\n0 1 0\n3 0 1 2\n"), "not a finite"),
            (ascii(FACE, &format!("{VERTICES}3 0 1 3\n")), "face 0 (line 13): vertex index 3 out of range"),
            (ascii(FACE, &format!("{VERTICES}3 0 -1 2\n")), "negative vertex index"),
            (ascii(FACE, &format!("{VERTICES}2 0 1\n")), "at least 3 vertices"),
            (ascii(FACE, &format!("{VERTICES}0\n")), "at least 3 vertices"),
            (ascii(FACE, &format!("{VERTICES}300 0 1 2\n")), "outside the range"),
            (ascii(FACE, &format!("{VERTICES}3 0 1.5 2\n")), "not an integer"),
            (ascii(FACE, &format!("{valid_data}3 0 1 2\n")), "data after the last record"),
            (
                ascii(
                    &format!("{FACE}element extra 1\nproperty list int float w\n"),
                    &format!("{valid_data}-2 1 2\n"),
                ),
                "negative list length",
            ),
            (
                ascii(
                    &format!("{FACE}element extra 1\nproperty list int float w\n"),
                    &format!("{valid_data}4000000000 1 2\n"),
                ),
                "outside the range",
            ),
            (
                ascii(
                    &format!("{FACE}element extra 1\nproperty list uint float w\n"),
                    &format!("{valid_data}4000000000 1 2\n"),
                ),
                "too few values",
            ),
        ];
        for (bytes, word) in &cases {
            let message = error_of(bytes);
            assert!(
                message.contains(word),
                "{:?}: `{message}` does not contain `{word}`",
                String::from_utf8_lossy(bytes)
            );
        }
    }

    #[test]
    fn malformed_binary_data_is_refused() {
        let mesh = MeshData {
            normals: Vec::new(),
            uvs: Vec::new(),
            ..cube(1.0, 0.0)
        };
        let faces = cube_quads();
        let good = write_ply(&mesh, &faces, FLOAT_LE);
        assert!(parse_ply(&good).is_ok());
        // 8 vertices of 12 bytes, then 6 faces of 17 bytes.
        let data_start = good.len() - 8 * 12 - 6 * 17;
        let mut truncated = good.clone();
        truncated.truncate(good.len() - 5);
        assert!(error_of(&truncated).contains("file ends in face 5 of 6"));
        let mut extra = good.clone();
        extra.push(0);
        assert!(error_of(&extra).contains("1 bytes after the last record"));
        let mut bad_index = good.clone();
        // The last index of face 2.
        let at = data_start + 8 * 12 + 2 * 17 + 13;
        bad_index[at..at + 4].copy_from_slice(&9_i32.to_le_bytes());
        assert!(error_of(&bad_index).contains("face 2 (byte"));
        assert!(error_of(&bad_index).contains("vertex index 9 out of range (8 vertices)"));
        bad_index[at..at + 4].copy_from_slice(&(-1_i32).to_le_bytes());
        assert!(error_of(&bad_index).contains("negative vertex index -1"));
        let mut nan = good.clone();
        nan[data_start + 12 + 4..data_start + 12 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(error_of(&nan).contains("vertex 1 (byte"));
        assert!(error_of(&nan).contains("y is NaN"));
        let mut short_polygon = good.clone();
        short_polygon[data_start + 8 * 12] = 2;
        assert!(error_of(&short_polygon).contains("at least 3 vertices, this one has 2"));
        let mut doubles = write_ply(
            &mesh,
            &faces,
            Layout {
                position: "double",
                ..FLOAT_LE
            },
        );
        let data_start = doubles.len() - 8 * 24 - 6 * 17;
        doubles[data_start..data_start + 8].copy_from_slice(&1e300_f64.to_le_bytes());
        assert!(error_of(&doubles).contains("not a finite single-precision value"));
    }

    #[test]
    fn absurd_counts_fail_before_allocating() {
        let huge = |count: u64, format: &str, extra: &str| {
            format!(
                "ply\nformat {format} 1.0\nelement vertex {count}\nproperty float x\n\
                 property float y\nproperty float z\n{FACE}{extra}end_header\n0 0 0\n"
            )
            .into_bytes()
        };
        let start = std::time::Instant::now();
        // 2^40 vertices: above the limit, refused from the header.
        for format in FORMATS {
            assert!(error_of(&huge(1 << 40, format, "")).contains("above the limit"));
        }
        // Within the limit but far more than the file holds.
        for format in FORMATS {
            let message = error_of(&huge(1 << 27, format, ""));
            assert!(message.contains("file too short"), "{message}");
        }
        // A count beyond u64.
        assert!(error_of(&huge(u64::MAX, "ascii", "")).contains("above the limit"));
        // Unknown elements count too, even where the product overflows.
        for count in [1_u64 << 40, u64::MAX / 2] {
            let extra = format!("element other {count}\nproperty double w\n");
            let message = error_of(&huge(3, "binary_little_endian", &extra));
            assert!(message.contains("file too short"), "{message}");
        }
        // A list of 4·10⁹ items in an unknown binary element: the file ends.
        let mut bytes = huge(
            3,
            "binary_big_endian",
            "element other 1\nproperty list uint double w\n",
        );
        bytes.truncate(bytes.len() - "0 0 0\n".len());
        for _ in 0..9 {
            bytes.extend(0.0_f32.to_be_bytes());
        }
        bytes.extend([3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        bytes.extend(4_000_000_000_u32.to_be_bytes());
        assert!(error_of(&bytes).contains("file ends in other 0 of 1"));
        // A polygon of 4·10⁹ vertices: the file ends (no allocation first).
        let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty uchar x\n\
            property uchar y\nproperty uchar z\nelement face 1\nproperty list uint uint vertex_indices\n\
            end_header\n"
            .to_vec();
        bytes.extend([0; 9]);
        bytes.extend(4_000_000_000_u32.to_le_bytes());
        bytes.extend([0; 12]);
        assert!(error_of(&bytes).contains("file ends in face 0 of 1"));
        // Millions of empty records of an element without properties cost nothing.
        let mesh = parse_ply(&ascii(
            &format!("{FACE}element nothing 18446744073709551615\n"),
            &format!("{VERTICES}3 0 1 2\n"),
        ))
        .unwrap();
        assert_eq!(mesh.triangles.len(), 1);
        assert!(start.elapsed().as_secs_f64() < 1.0, "{:?}", start.elapsed());
    }

    /// The meshes of the Mitsuba test scenes (outside the project; absent
    /// in CI).
    const MITSUBA_MESHES: &str = "/work/shared/scenes/mitsuba/meshes";

    #[test]
    fn stanford_bunny_parses() {
        let path = Path::new(MITSUBA_MESHES).join("bunny.ply");
        let Ok(bytes) = std::fs::read(&path) else {
            println!("{} not found: skipped", path.display());
            return;
        };
        let start = std::time::Instant::now();
        let mesh = parse_ply(&bytes).unwrap();
        println!(
            "bunny.ply: {} vertices, {} triangles in {:.1} ms",
            mesh.positions.len(),
            mesh.triangles.len(),
            start.elapsed().as_secs_f64() * 1e3
        );
        assert_eq!(mesh.positions.len(), 35_947);
        assert_eq!(mesh.triangles.len(), 69_451);
        assert!(mesh.normals.is_empty() && mesh.uvs.is_empty());
        assert_eq!(mesh.validate(), Ok(()));
    }

    #[test]
    fn every_mitsuba_test_mesh_parses() {
        let Ok(entries) = std::fs::read_dir(MITSUBA_MESHES) else {
            println!("{MITSUBA_MESHES} not found: skipped");
            return;
        };
        let mut paths: Vec<_> = entries
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "ply"))
            .collect();
        paths.sort();
        for path in &paths {
            let mesh = parse_ply(&std::fs::read(path).unwrap())
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert_eq!(mesh.validate(), Ok(()), "{}", path.display());
            println!(
                "{}: {} vertices, {} triangles",
                path.display(),
                mesh.positions.len(),
                mesh.triangles.len()
            );
            if path.ends_with("teapot.ply") {
                assert_eq!(mesh.positions.len(), 1177);
                assert_eq!(mesh.triangles.len(), 2256);
            }
        }
        assert!(paths.len() >= 2, "{paths:?}");
    }
}
