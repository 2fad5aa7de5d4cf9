//! Mitsuba's `serialized` meshes (versions 3 and 4), read into a
//! [`MeshData`].
//!
//! The format is described in the documentation comment of Mitsuba 3's
//! `src/shapes/serialized.cpp` (also Mitsuba 0.5/0.6's), which this follows.
//! A file holds one or more shapes, each a small uncompressed header and a
//! zlib stream, then a table of where each shape starts. Everything is
//! little endian:
//!
//! ```text
//! per shape, at its offset:
//!   u16 0x041C                 magic
//!   u16 version                3 or 4
//!   zlib stream:
//!     u32 flags                0x0001 vertex normals, 0x0002 texture coordinates,
//!                              0x0008 vertex colours, 0x0010 face normals,
//!                              0x1000 single precision, 0x2000 double precision
//!     name\0                   version 4 only: the shape's UTF-8 name, NUL-terminated
//!     u64 V, u64 F             vertex and triangle counts
//!     3V reals                 positions (f32, or f64 with 0x2000)
//!     3V reals                 normals, if 0x0001
//!     2V reals                 texture coordinates, if 0x0002
//!     3V reals                 colours, if 0x0008 (skipped here, as by Mitsuba)
//!     3F u32                   vertex indices of each triangle
//! at the end of the file:
//!   u64 offset per shape       (u32 in version 3 files); the first is 0
//!   u32 shape count
//! ```
//!
//! The documentation says the indices are `u64` when `V` exceeds 2³²
//! (Mitsuba's reader reads `u32` in any case); such a mesh is above
//! [`MAX_MESH_ELEMENTS`] and refused, so indices are always `u32` here.
//! With the face-normals flag the stored normals are dropped: the mesh is
//! shaded flat, as Mitsuba renders it. Double-precision values are rounded
//! to `f32`. Unknown flag bits are ignored, as by Mitsuba.
//!
//! Refused, with one line (prefixed with the shape for errors inside one):
//! a wrong magic number; a version other than 3 and 4 (version 5, the
//! newest Mitsuba's packed records, is not supported); both precision
//! flags; a shape index out of range (the message says how many shapes the
//! file holds); a broken offset table; truncated or corrupt zlib data
//! (including a wrong checksum); counts above [`MAX_MESH_ELEMENTS`]; a
//! stream that ends before its declared data or holds more than it (`the
//! counts or flags disagree with the data`); bytes between the end of a
//! stream and the next shape; a vertex index out of range; a NaN or
//! infinite value.
//!
//! Why the memory stays bounded: the counts are read from the start of the
//! stream, refused above the limit, and refused if their data would need
//! more than [`MAX_DEFLATE_RATIO`] times the compressed bytes (no DEFLATE
//! stream expands further). The stream is then inflated piece by piece into
//! the mesh's own arrays, and at most one byte past the declared data is
//! ever inflated, so a zip bomb costs no more memory than an honest file of
//! its size.

use crate::scene::mesh::{MAX_MESH_ELEMENTS, MeshData, MeshFileError};
use glam::{Vec2, Vec3};
use miniz_oxide::inflate::stream::{InflateState, inflate};
use miniz_oxide::{DataFormat, MZError, MZFlush, MZStatus};

/// The first `u16` of every shape.
const MAGIC: u16 = 0x041C;
/// Flag: the shape stores vertex normals.
const HAS_NORMALS: u32 = 0x0001;
/// Flag: the shape stores texture coordinates.
const HAS_TEXCOORDS: u32 = 0x0002;
/// Flag: the shape stores vertex colours.
const HAS_COLORS: u32 = 0x0008;
/// Flag: render with face normals (the vertex normals are not used).
const FACE_NORMALS: u32 = 0x0010;
/// Flag: the reals are `f32`.
const SINGLE_PRECISION: u32 = 0x1000;
/// Flag: the reals are `f64`.
const DOUBLE_PRECISION: u32 = 0x2000;
/// The longest shape name read (a version 4 name is NUL-terminated; this
/// bounds the search for the NUL).
const MAX_NAME_BYTES: usize = 1 << 16;

/// The most bytes one byte of a DEFLATE stream can expand to: a 258-byte
/// match coded in 2 bits (RFC 1951's longest match, 1-bit length and
/// distance codes). Data declared beyond this many times the compressed
/// size cannot be in the stream, so it is refused before anything is
/// allocated.
pub const MAX_DEFLATE_RATIO: u64 = 1032;

/// Slack on top of [`MAX_DEFLATE_RATIO`] for the stream's own header,
/// block headers and checksum.
const DEFLATE_SLACK_BYTES: u64 = 1024;

/// Values inflated per step when reading an array.
const CHUNK_VALUES: usize = 4096;

/// Reads the `u16` at `offset`.
fn u16_at(bytes: &[u8], offset: usize) -> Option<u16> {
    let b = bytes.get(offset..)?.first_chunk::<2>()?;
    Some(u16::from_le_bytes(*b))
}

/// Reads the `u32` at `offset`.
fn u32_at(bytes: &[u8], offset: usize) -> Option<u32> {
    let b = bytes.get(offset..)?.first_chunk::<4>()?;
    Some(u32::from_le_bytes(*b))
}

/// Reads the `u64` at `offset`.
fn u64_at(bytes: &[u8], offset: usize) -> Option<u64> {
    let b = bytes.get(offset..)?.first_chunk::<8>()?;
    Some(u64::from_le_bytes(*b))
}

/// Checks a shape header (magic and version) at `offset`; returns the
/// version.
fn shape_version(bytes: &[u8], offset: usize) -> Result<u16, MeshFileError> {
    let (Some(magic), Some(version)) = (u16_at(bytes, offset), u16_at(bytes, offset + 2)) else {
        return Err(MeshFileError::new(
            "too short for a Mitsuba serialized mesh",
        ));
    };
    if magic != MAGIC {
        return Err(MeshFileError(format!(
            "not a Mitsuba serialized mesh (magic number {magic:#06x}, expected {MAGIC:#06x})"
        )));
    }
    match version {
        3 | 4 => Ok(version),
        5 => Err(MeshFileError::new(
            "serialized mesh version 5 (packed records) is not supported (versions 3 and 4 are)",
        )),
        other => Err(MeshFileError(format!(
            "serialized mesh version {other} is not supported (versions 3 and 4 are)"
        ))),
    }
}

/// The offset table at the end of a file.
struct Table<'a> {
    bytes: &'a [u8],
    count: u32,
    /// Bytes per offset: 8 (version 4) or 4 (version 3).
    entry_bytes: usize,
    /// Where the table starts (the end of the last shape).
    start: usize,
}

impl<'a> Table<'a> {
    fn new(bytes: &'a [u8]) -> Result<Self, MeshFileError> {
        let version = shape_version(bytes, 0)?;
        let entry_bytes = if version == 3 { 4 } else { 8 };
        let count_at = bytes
            .len()
            .checked_sub(4)
            .ok_or_else(|| MeshFileError::new("too short for a Mitsuba serialized mesh"))?;
        let count = u32_at(bytes, count_at).unwrap_or_default();
        if count == 0 {
            return Err(MeshFileError::new(
                "the shape table at the end of the file declares no shape",
            ));
        }
        // At least the first shape's 4-byte header precedes the table.
        let start = (count as usize)
            .checked_mul(entry_bytes)
            .and_then(|table| count_at.checked_sub(table))
            .filter(|&start| start >= 4)
            .ok_or_else(|| {
                MeshFileError(format!(
                    "the shape table at the end of the file declares {count} shapes, more than the file holds"
                ))
            })?;
        Ok(Self {
            bytes,
            count,
            entry_bytes,
            start,
        })
    }

    /// The offset of shape `index` (< count).
    fn offset(&self, index: u32) -> Option<u64> {
        let at = self.start + index as usize * self.entry_bytes;
        if self.entry_bytes == 4 {
            u32_at(self.bytes, at).map(u64::from)
        } else {
            u64_at(self.bytes, at)
        }
    }

    /// The bytes of shape `index`: from its offset to the next shape's (or
    /// the table).
    fn shape(&self, index: u32) -> Result<&'a [u8], MeshFileError> {
        if index >= self.count {
            return Err(MeshFileError(format!(
                "shape index {index} out of range: the file holds {} shape{} (0 to {})",
                self.count,
                if self.count == 1 { "" } else { "s" },
                self.count - 1
            )));
        }
        // Both entries lie in the table, so they can be read.
        let start = self.offset(index).unwrap_or(u64::MAX);
        let end = if index + 1 < self.count {
            self.offset(index + 1).unwrap_or(u64::MAX)
        } else {
            self.start as u64
        };
        let broken = || {
            MeshFileError(format!(
                "the shape table is broken: shape {index} starts at byte {start}, the next shape (or the table) at {end}, the table at {}",
                self.start
            ))
        };
        if (index == 0 && start != 0) || start.saturating_add(4) > end || end > self.start as u64 {
            return Err(broken());
        }
        // Both are within the file, hence within usize.
        self.bytes
            .get(start as usize..end as usize)
            .ok_or_else(broken)
    }
}

/// How many shapes a serialized file holds (from the table at its end).
pub fn serialized_shape_count(bytes: &[u8]) -> Result<u32, MeshFileError> {
    Ok(Table::new(bytes)?.count)
}

/// Parses shape `shape_index` (from 0) of a Mitsuba serialized file into a
/// mesh that passes [`MeshData::validate`]; see the module documentation for
/// the format and what is refused.
pub fn parse_serialized(bytes: &[u8], shape_index: u32) -> Result<MeshData, MeshFileError> {
    let table = Table::new(bytes)?;
    let shape = table.shape(shape_index)?;
    parse_shape(shape).map_err(|e| MeshFileError(format!("shape {shape_index}: {e}")))
}

/// Why inflating stopped early.
enum Stop {
    /// The stream ended (properly) before the data asked for.
    Ended,
    /// The compressed bytes ran out inside the stream.
    Truncated,
    /// The compressed bytes are not a valid zlib stream.
    Corrupt,
}

/// A zlib stream read piece by piece.
struct Inflater<'a> {
    state: Box<InflateState>,
    /// Compressed bytes not yet consumed.
    input: &'a [u8],
    ended: bool,
}

impl<'a> Inflater<'a> {
    fn new(input: &'a [u8]) -> Self {
        Self {
            state: InflateState::new_boxed(DataFormat::Zlib),
            input,
            ended: false,
        }
    }

    /// Fills `out` with the next inflated bytes.
    fn read(&mut self, out: &mut [u8]) -> Result<(), Stop> {
        let mut filled = 0;
        while let Some(rest) = out.get_mut(filled..).filter(|r| !r.is_empty()) {
            if self.ended {
                return Err(Stop::Ended);
            }
            let result = inflate(&mut self.state, self.input, rest, MZFlush::None);
            self.input = self.input.get(result.bytes_consumed..).unwrap_or_default();
            filled += result.bytes_written;
            match result.status {
                Ok(MZStatus::StreamEnd) => self.ended = true,
                Ok(_) if result.bytes_consumed == 0 && result.bytes_written == 0 => {
                    return Err(Stop::Truncated);
                }
                Ok(_) => {}
                Err(MZError::Buf) => return Err(Stop::Truncated),
                Err(_) => return Err(Stop::Corrupt),
            }
        }
        Ok(())
    }

    /// Reads `out`, or says why not naming `what` was being read.
    fn read_for(&mut self, out: &mut [u8], what: &str) -> Result<(), String> {
        self.read(out).map_err(|stop| match stop {
            Stop::Ended => {
                format!("the data ends in {what} (the counts or flags disagree with the data)")
            }
            Stop::Truncated => format!("the compressed data is truncated (in {what})"),
            Stop::Corrupt => format!("the compressed data is corrupt (found reading {what})"),
        })
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let mut b = [0; 4];
        self.read_for(&mut b, what)?;
        Ok(u32::from_le_bytes(b))
    }

    fn u64(&mut self, what: &str) -> Result<u64, String> {
        let mut b = [0; 8];
        self.read_for(&mut b, what)?;
        Ok(u64::from_le_bytes(b))
    }

    /// Checks that the stream ends here and that no compressed byte follows.
    fn finish(&mut self, counts: &str) -> Result<(), String> {
        match self.read(&mut [0]) {
            Err(Stop::Ended) => {}
            Ok(()) => return Err(format!("more data than {counts} declare")),
            Err(Stop::Truncated) => {
                return Err("the compressed data is truncated (after the triangles)".to_owned());
            }
            Err(Stop::Corrupt) => {
                return Err("the compressed data is corrupt (after the triangles)".to_owned());
            }
        }
        match self.input.len() {
            0 => Ok(()),
            extra => Err(format!(
                "{extra} bytes after the end of the compressed data"
            )),
        }
    }

    /// Reads `count` vectors of `N` reals (`f64` if `double`), each made
    /// finite-checked into a `T`; `what` names them in messages.
    fn vectors<const N: usize, T>(
        &mut self,
        count: usize,
        double: bool,
        what: &str,
        make: impl Fn([f32; N]) -> T,
    ) -> Result<Vec<T>, String> {
        let real_bytes = if double { 8 } else { 4 };
        let mut out = Vec::with_capacity(count);
        let mut chunk = vec![0_u8; CHUNK_VALUES * N * real_bytes];
        while out.len() < count {
            let n = (count - out.len()).min(CHUNK_VALUES);
            let bytes = chunk.get_mut(..n * N * real_bytes).unwrap_or_default();
            self.read_for(bytes, what)?;
            for vector in bytes.chunks_exact(N * real_bytes) {
                let mut value = [0.0_f32; N];
                for (v, bytes) in value.iter_mut().zip(vector.chunks_exact(real_bytes)) {
                    *v = real(bytes);
                }
                if value.iter().any(|v| !v.is_finite()) {
                    return Err(format!(
                        "{what}: vertex {} is {value:?}, not finite in single precision",
                        out.len()
                    ));
                }
                out.push(make(value));
            }
        }
        Ok(out)
    }

    /// Reads and drops `count` reals.
    fn skip(&mut self, count: usize, double: bool, what: &str) -> Result<(), String> {
        let real_bytes = if double { 8 } else { 4 };
        let mut chunk = vec![0_u8; CHUNK_VALUES * real_bytes];
        let mut left = count;
        while left > 0 {
            let n = left.min(CHUNK_VALUES);
            self.read_for(chunk.get_mut(..n * real_bytes).unwrap_or_default(), what)?;
            left -= n;
        }
        Ok(())
    }
}

/// A little-endian `f64` (8 bytes, rounded) or `f32` (4 bytes) as `f32`.
fn real(bytes: &[u8]) -> f32 {
    match (bytes.first_chunk::<8>(), bytes.first_chunk::<4>()) {
        (Some(b), _) => f64::from_le_bytes(*b) as f32,
        (None, Some(b)) => f32::from_le_bytes(*b),
        (None, None) => f32::NAN,
    }
}

/// One shape: its header and zlib stream.
fn parse_shape(shape: &[u8]) -> Result<MeshData, String> {
    let version = shape_version(shape, 0).map_err(|e| e.0)?;
    let compressed = shape.get(4..).unwrap_or_default();
    let mut z = Inflater::new(compressed);
    let flags = z.u32("the flags")?;
    if flags & SINGLE_PRECISION != 0 && flags & DOUBLE_PRECISION != 0 {
        return Err(format!(
            "flags {flags:#06x} claim both single and double precision"
        ));
    }
    let double = flags & DOUBLE_PRECISION != 0;
    if version == 4 {
        let mut name_bytes = 0;
        loop {
            let mut byte = [0];
            z.read_for(&mut byte, "the shape name")?;
            if byte == [0] {
                break;
            }
            name_bytes += 1;
            if name_bytes > MAX_NAME_BYTES {
                return Err(format!(
                    "the shape name is longer than {MAX_NAME_BYTES} bytes (or not NUL-terminated)"
                ));
            }
        }
    }
    let vertices = z.u64("the vertex count")?;
    let triangles = z.u64("the triangle count")?;
    if vertices > MAX_MESH_ELEMENTS as u64 || triangles > MAX_MESH_ELEMENTS as u64 {
        return Err(format!(
            "{vertices} vertices, {triangles} triangles: above the limit of {MAX_MESH_ELEMENTS}"
        ));
    }
    let real_bytes: u64 = if double { 8 } else { 4 };
    let reals_per_vertex = 3
        + if flags & HAS_NORMALS != 0 { 3 } else { 0 }
        + if flags & HAS_TEXCOORDS != 0 { 2 } else { 0 }
        + if flags & HAS_COLORS != 0 { 3 } else { 0 };
    // Below 2^28 · 88 + 2^28 · 12: no overflow.
    let data_bytes = vertices * reals_per_vertex * real_bytes + triangles * 12;
    let most = (compressed.len() as u64)
        .saturating_mul(MAX_DEFLATE_RATIO)
        .saturating_add(DEFLATE_SLACK_BYTES);
    if data_bytes > most {
        return Err(format!(
            "{vertices} vertices and {triangles} triangles need {data_bytes} bytes, more than {} compressed bytes can hold",
            compressed.len()
        ));
    }
    // Within the limit, hence within usize.
    let (vertex_count, triangle_count) = (vertices as usize, triangles as usize);
    let positions = z.vectors(vertex_count, double, "the positions", Vec3::from_array)?;
    let normals = match (flags & HAS_NORMALS != 0, flags & FACE_NORMALS != 0) {
        (true, false) => z.vectors(vertex_count, double, "the normals", Vec3::from_array)?,
        // Shaded flat: the stored normals are not used.
        (true, true) => {
            z.skip(3 * vertex_count, double, "the normals")?;
            Vec::new()
        }
        (false, _) => Vec::new(),
    };
    let uvs = if flags & HAS_TEXCOORDS != 0 {
        z.vectors(
            vertex_count,
            double,
            "the texture coordinates",
            Vec2::from_array,
        )?
    } else {
        Vec::new()
    };
    if flags & HAS_COLORS != 0 {
        z.skip(3 * vertex_count, double, "the vertex colours")?;
    }
    let mut triangle_indices = Vec::with_capacity(triangle_count);
    let mut chunk = vec![0_u8; CHUNK_VALUES * 12];
    while triangle_indices.len() < triangle_count {
        let n = (triangle_count - triangle_indices.len()).min(CHUNK_VALUES);
        let bytes = chunk.get_mut(..n * 12).unwrap_or_default();
        z.read_for(bytes, "the triangles")?;
        for corners in bytes.chunks_exact(12) {
            let mut triangle = [0_u32; 3];
            for (index, b) in triangle.iter_mut().zip(corners.chunks_exact(4)) {
                *index = b.first_chunk::<4>().map_or(0, |b| u32::from_le_bytes(*b));
            }
            if let Some(&bad) = triangle.iter().find(|&&i| u64::from(i) >= vertices) {
                return Err(format!(
                    "triangle {} refers to vertex {bad} ({vertices} vertices)",
                    triangle_indices.len()
                ));
            }
            triangle_indices.push(triangle);
        }
    }
    z.finish(&format!("{vertices} vertices and {triangles} triangles"))?;
    Ok(MeshData {
        positions,
        normals,
        uvs,
        triangles: triangle_indices,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use miniz_oxide::deflate::compress_to_vec_zlib;
    use std::path::Path;

    /// How [`payload`] writes a shape.
    #[derive(Debug, Clone, Copy)]
    struct Options {
        version: u16,
        double: bool,
        colors: bool,
        face_normals: bool,
    }

    const V4: Options = Options {
        version: 4,
        double: false,
        colors: false,
        face_normals: false,
    };

    /// The uncompressed stream of a shape.
    fn payload(mesh: &MeshData, options: Options) -> Vec<u8> {
        let mut flags = if options.double {
            DOUBLE_PRECISION
        } else {
            SINGLE_PRECISION
        };
        if !mesh.normals.is_empty() {
            flags |= HAS_NORMALS;
        }
        if !mesh.uvs.is_empty() {
            flags |= HAS_TEXCOORDS;
        }
        if options.colors {
            flags |= HAS_COLORS;
        }
        if options.face_normals {
            flags |= FACE_NORMALS;
        }
        let mut out = flags.to_le_bytes().to_vec();
        if options.version == 4 {
            out.extend(b"a shape\0");
        }
        out.extend((mesh.positions.len() as u64).to_le_bytes());
        out.extend((mesh.triangles.len() as u64).to_le_bytes());
        let mut reals = |values: &[f32]| {
            for &v in values {
                if options.double {
                    out.extend(f64::from(v).to_le_bytes());
                } else {
                    out.extend(v.to_le_bytes());
                }
            }
        };
        for p in &mesh.positions {
            reals(&p.to_array());
        }
        for n in &mesh.normals {
            reals(&n.to_array());
        }
        for t in &mesh.uvs {
            reals(&t.to_array());
        }
        if options.colors {
            for _ in &mesh.positions {
                reals(&[0.25, f32::NAN, 1.0]);
            }
        }
        for t in &mesh.triangles {
            for i in t {
                out.extend(i.to_le_bytes());
            }
        }
        out
    }

    /// A shape: its header and the compressed `payload`.
    fn shape(version: u16, payload: &[u8]) -> Vec<u8> {
        let mut out = MAGIC.to_le_bytes().to_vec();
        out.extend(version.to_le_bytes());
        out.extend(compress_to_vec_zlib(payload, 6));
        out
    }

    /// A file of `shapes`, with the offset table of `version`.
    fn file(version: u16, shapes: &[Vec<u8>]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut offsets = Vec::new();
        for s in shapes {
            offsets.push(out.len() as u64);
            out.extend(s);
        }
        for offset in offsets {
            if version == 3 {
                out.extend((offset as u32).to_le_bytes());
            } else {
                out.extend(offset.to_le_bytes());
            }
        }
        out.extend((shapes.len() as u32).to_le_bytes());
        out
    }

    fn one_shape(mesh: &MeshData, options: Options) -> Vec<u8> {
        file(
            options.version,
            &[shape(options.version, &payload(mesh, options))],
        )
    }

    fn quad() -> MeshData {
        MeshData {
            positions: vec![
                Vec3::new(-1.5, 0.1, 2.0),
                Vec3::X,
                Vec3::new(1.0, 1.0, 0.3),
                Vec3::Y,
            ],
            normals: vec![Vec3::Z, Vec3::Z, Vec3::ZERO, Vec3::new(0.0, 0.6, 0.8)],
            uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::new(0.1, 0.9)],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    fn error_of(bytes: &[u8], index: u32) -> String {
        match parse_serialized(bytes, index) {
            Ok(mesh) => panic!("parsed {mesh:?}, expected an error"),
            Err(e) => e.0,
        }
    }

    #[test]
    fn versions_3_and_4_in_single_and_double_precision_parse_to_the_mesh() {
        for version in [3, 4] {
            for double in [false, true] {
                for colors in [false, true] {
                    let options = Options {
                        version,
                        double,
                        colors,
                        ..V4
                    };
                    let bytes = one_shape(&quad(), options);
                    assert_eq!(serialized_shape_count(&bytes), Ok(1));
                    let mesh =
                        parse_serialized(&bytes, 0).unwrap_or_else(|e| panic!("{options:?}: {e}"));
                    assert_eq!(mesh, quad(), "{options:?}");
                    assert_eq!(mesh.validate(), Ok(()));
                }
            }
        }
    }

    #[test]
    fn normals_and_uvs_are_optional() {
        let bare = MeshData {
            normals: Vec::new(),
            uvs: Vec::new(),
            ..quad()
        };
        let uvs_only = MeshData {
            normals: Vec::new(),
            ..quad()
        };
        let normals_only = MeshData {
            uvs: Vec::new(),
            ..quad()
        };
        for mesh in [bare, uvs_only, normals_only] {
            for version in [3, 4] {
                let options = Options { version, ..V4 };
                assert_eq!(
                    parse_serialized(&one_shape(&mesh, options), 0),
                    Ok(mesh.clone())
                );
            }
        }
    }

    #[test]
    fn the_face_normals_flag_drops_the_normals() {
        let options = Options {
            face_normals: true,
            double: true,
            ..V4
        };
        let mesh = parse_serialized(&one_shape(&quad(), options), 0).unwrap();
        assert!(mesh.normals.is_empty());
        assert_eq!(mesh.uvs, quad().uvs);
        assert_eq!(mesh.positions, quad().positions);
    }

    #[test]
    fn shapes_are_selected_by_index() {
        let first = quad();
        let second = MeshData {
            positions: vec![Vec3::ZERO, Vec3::Z, Vec3::X, Vec3::ONE, Vec3::NEG_Y],
            normals: Vec::new(),
            uvs: Vec::new(),
            triangles: vec![[4, 3, 2], [0, 1, 2], [1, 3, 4]],
        };
        for version in [3, 4] {
            let options = Options { version, ..V4 };
            let bytes = file(
                version,
                &[
                    shape(version, &payload(&first, options)),
                    shape(version, &payload(&second, options)),
                ],
            );
            assert_eq!(serialized_shape_count(&bytes), Ok(2));
            assert_eq!(parse_serialized(&bytes, 0), Ok(first.clone()));
            assert_eq!(parse_serialized(&bytes, 1), Ok(second.clone()));
            let message = error_of(&bytes, 2);
            assert!(message.contains("the file holds 2 shapes"), "{message}");
        }
    }

    #[test]
    fn malformed_files_are_refused_with_a_clear_message() {
        let good = one_shape(&quad(), V4);
        let good_payload = payload(&quad(), V4);
        let with_payload = |payload: &[u8]| file(4, &[shape(4, payload)]);
        let mut bad_magic = good.clone();
        bad_magic[0] = 0x1D;
        let mut version_5 = good.clone();
        version_5[2] = 5;
        let mut version_2 = good.clone();
        version_2[2] = 2;
        let compressed = compress_to_vec_zlib(&good_payload, 6);
        let truncate_stream = |keep: usize| {
            let mut s = MAGIC.to_le_bytes().to_vec();
            s.extend(4_u16.to_le_bytes());
            s.extend(&compressed[..keep]);
            file(4, &[s])
        };
        let mut corrupt = good.clone();
        // The Adler-32 checksum, just before the table and count.
        let checksum_at = good.len() - 8 - 4 - 1;
        corrupt[checksum_at] ^= 0x55;
        let mut garbage_after = shape(4, &good_payload);
        garbage_after.extend(b"xyz");
        let mut flags_both = good_payload.clone();
        flags_both[..4].copy_from_slice(&(SINGLE_PRECISION | DOUBLE_PRECISION).to_le_bytes());
        let name_end = 4 + b"a shape\0".len();
        let mut more_vertices = good_payload.clone();
        more_vertices[name_end..name_end + 8].copy_from_slice(&5_u64.to_le_bytes());
        let mut fewer_triangles = good_payload.clone();
        fewer_triangles[name_end + 8..name_end + 16].copy_from_slice(&1_u64.to_le_bytes());
        let mut bad_index = good_payload.clone();
        let last = bad_index.len() - 4;
        bad_index[last..].copy_from_slice(&4_u32.to_le_bytes());
        let mut nan = good_payload.clone();
        nan[name_end + 16 + 4..name_end + 16 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
        let mut inf_normal = good_payload.clone();
        let normals_at = name_end + 16 + 4 * 12;
        inf_normal[normals_at..normals_at + 4].copy_from_slice(&f32::INFINITY.to_le_bytes());
        let mut huge_double = payload(&quad(), Options { double: true, ..V4 });
        huge_double[name_end + 16..name_end + 24].copy_from_slice(&1e300_f64.to_le_bytes());
        let mut over_limit = good_payload.clone();
        over_limit[name_end..name_end + 8].copy_from_slice(&(1_u64 << 40).to_le_bytes());
        let mut too_much_for_the_stream = good_payload[..name_end].to_vec();
        too_much_for_the_stream.extend((1_u64 << 27).to_le_bytes());
        too_much_for_the_stream.extend((1_u64 << 27).to_le_bytes());
        let mut unterminated_name = SINGLE_PRECISION.to_le_bytes().to_vec();
        unterminated_name.extend(vec![b'n'; MAX_NAME_BYTES + 10]);
        let mut table_count_huge = good.clone();
        let n = table_count_huge.len();
        table_count_huge[n - 4..].copy_from_slice(&u32::MAX.to_le_bytes());
        let mut table_no_shapes = good.clone();
        table_no_shapes[n - 4..].copy_from_slice(&0_u32.to_le_bytes());
        let two = file(4, &[shape(4, &good_payload), shape(4, &good_payload)]);
        let mut table_out_of_order = two.clone();
        let m = two.len();
        table_out_of_order[m - 12..m - 4].copy_from_slice(&u64::MAX.to_le_bytes());
        let mut first_not_at_zero = good.clone();
        first_not_at_zero[n - 12..n - 4].copy_from_slice(&2_u64.to_le_bytes());
        let mut second_bad_magic = two.clone();
        second_bad_magic[shape(4, &good_payload).len()] = 0;

        let cases: Vec<(Vec<u8>, u32, &str)> = vec![
            (Vec::new(), 0, "too short"),
            (b"\x1c\x04".to_vec(), 0, "too short"),
            (bad_magic, 0, "not a Mitsuba serialized mesh"),
            (version_5, 0, "version 5"),
            (version_2, 0, "version 2 is not supported"),
            (
                good.clone(),
                1,
                "out of range: the file holds 1 shape (0 to 0)",
            ),
            (truncate_stream(compressed.len() / 2), 0, "truncated"),
            (truncate_stream(1), 0, "truncated (in the flags)"),
            (corrupt, 0, "corrupt"),
            (file(4, &[garbage_after]), 0, "3 bytes after the end"),
            (with_payload(&flags_both), 0, "both single and double"),
            (with_payload(&more_vertices), 0, "counts or flags disagree"),
            (
                with_payload(&fewer_triangles),
                0,
                "more data than 4 vertices and 1 triangles",
            ),
            (
                with_payload(&bad_index),
                0,
                "triangle 1 refers to vertex 4 (4 vertices)",
            ),
            (with_payload(&nan), 0, "the positions: vertex 0"),
            (with_payload(&inf_normal), 0, "the normals: vertex 0"),
            (with_payload(&huge_double), 0, "not finite"),
            (with_payload(&over_limit), 0, "above the limit"),
            (
                with_payload(&too_much_for_the_stream),
                0,
                "compressed bytes can hold",
            ),
            (with_payload(&unterminated_name), 0, "shape name is longer"),
            (
                with_payload(&good_payload[..name_end - 3]),
                0,
                "the shape name",
            ),
            (table_count_huge, 0, "more than the file holds"),
            (table_no_shapes, 0, "no shape"),
            (table_out_of_order.clone(), 0, "table is broken"),
            (table_out_of_order, 1, "table is broken"),
            (first_not_at_zero, 0, "table is broken"),
            (second_bad_magic, 1, "shape 1: not a Mitsuba"),
        ];
        for (bytes, index, word) in &cases {
            let message = error_of(bytes, *index);
            assert!(
                message.contains(word),
                "`{message}` does not contain `{word}`"
            );
        }
    }

    #[test]
    fn a_zip_bomb_is_refused_after_one_byte_too_many() {
        // 64 MiB of zeros after an honest triangle: about 64 KiB compressed.
        let mut bomb = payload(&quad(), V4);
        bomb.extend(vec![0; 64 << 20]);
        let bytes = file(4, &[shape(4, &bomb)]);
        assert!(bytes.len() < 1 << 20, "{}", bytes.len());
        let start = std::time::Instant::now();
        let message = error_of(&bytes, 0);
        assert!(message.contains("more data than"), "{message}");
        assert!(start.elapsed().as_secs_f64() < 0.5, "{:?}", start.elapsed());
    }

    #[test]
    fn large_meshes_cross_chunk_boundaries() {
        let n = CHUNK_VALUES as u32 * 2 + 7;
        let mesh = MeshData {
            positions: (0..n)
                .map(|i| Vec3::new(i as f32, 0.5, -(i as f32)))
                .collect(),
            normals: Vec::new(),
            uvs: (0..n).map(|i| Vec2::new(i as f32, 1.0)).collect(),
            triangles: (0..n - 2).map(|i| [i, i + 1, i + 2]).collect(),
        };
        for double in [false, true] {
            let options = Options { double, ..V4 };
            assert_eq!(
                parse_serialized(&one_shape(&mesh, options), 0),
                Ok(mesh.clone())
            );
        }
    }

    /// The Mitsuba test scenes (outside the project; absent in CI).
    const MITSUBA_SCENES: &str = "/work/shared/scenes/mitsuba";

    #[test]
    fn every_mitsuba_serialized_mesh_parses() {
        fn walk(dir: &Path, found: &mut Vec<std::path::PathBuf>) {
            for entry in std::fs::read_dir(dir).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    walk(&path, found);
                } else if path.extension().is_some_and(|e| e == "serialized") {
                    found.push(path);
                }
            }
        }
        let root = Path::new(MITSUBA_SCENES);
        if !root.is_dir() {
            println!("{MITSUBA_SCENES} not found: skipped");
            return;
        }
        let mut found = Vec::new();
        walk(root, &mut found);
        for path in &found {
            let bytes = std::fs::read(path).unwrap();
            let count = serialized_shape_count(&bytes)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            for index in 0..count {
                let mesh = parse_serialized(&bytes, index)
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                assert_eq!(mesh.validate(), Ok(()));
            }
        }
        println!("{} serialized files under {MITSUBA_SCENES}", found.len());
    }
}
