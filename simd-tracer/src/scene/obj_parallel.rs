//! OBJ text read on every core: exactly the meshes of `tobj::load_obj_buf`
//! with [`load_options`](super::obj::load_options) (triangulated, one index
//! per vertex, points and lines dropped) and no MTL, for the files in its
//! grammar; `None` for the others, which the caller reads with tobj.
//!
//! Why: tobj reads a file on one thread, with a `String` per line and a
//! hash-map lookup per face corner; on a million-triangle OBJ that was the
//! largest part of loading that ran on one core (the timings are in
//! `docs/performance.md`). Here the text is cut into chunks at line ends and
//! the chunks are parsed in parallel; only the numbering of vertices, which
//! is cheap, runs in file order.
//!
//! # The passes
//!
//! 1. In parallel, each chunk counts its `v`, `vt` and `vn` lines; prefix
//!    sums give each chunk the counts before it, which resolve relative
//!    (negative) indices as tobj does: against the counts at the face's line.
//! 2. In parallel, each chunk parses its positions, texture coordinates,
//!    normals and faces. A face of n ≥ 3 corners becomes the fan
//!    (a, b, c), (a, c, d), … (tobj's triangulation of quads and polygons).
//!    An `o` or `g` line ends the current model when it has faces (tobj's
//!    `pop_model`); the counts at that line bound the model's indices, as
//!    tobj checks them when it exports the model.
//! 3. Model by model, in file order, each distinct (v, vt, vn) triple gets
//!    the next vertex number in the order of first use: what tobj's
//!    per-model map gives. A table by position index answers the common case
//!    (one triple per position) without hashing; a hash map keeps the other
//!    triples of a position.
//!
//! # The grammar, and why `None` is safe
//!
//! Accepted: `v x y z`; `vt u v …` and `vn x y z …` (tobj ignores extra
//! values); `f` with three or more corners `v`, `v/vt`, `v//vn`, `v/vt/vn`
//! (1-based or negative); `o`, `g`; `usemtl` with a name and `mtllib`
//! (ignored: no MTL is loaded, as when tobj's MTL loader fails, so every
//! mesh has no material, like Mitsuba's `obj` shape); `#` comments, blank
//! lines and lines of any other keyword (ignored, as tobj ignores them).
//!
//! Anything else returns `None`: vertex colours or a `w`, points and lines
//! (`l`, or an `f` of one or two corners), the index 0, an index outside the
//! values defined before the model ends, an unparsable number, text that is
//! not UTF-8. tobj then gives its own result or its error, so the answer
//! never differs from tobj's. [`crate::fuzzing::obj_parallel`] checks that
//! on arbitrary text, cutting it into chunks of a few bytes.

use rayon::prelude::*;
use std::collections::HashMap;

/// Bytes per chunk (cut at the next line end): large enough that a chunk's
/// parse outweighs the scheduling of a task, small enough that a 2-core
/// machine gets tens of chunks from a file of tens of megabytes.
const CHUNK_BYTES: usize = 1 << 20;

/// An absent texture-coordinate or normal index (tobj's `MISSING_INDEX`).
const MISSING: u32 = u32::MAX;

/// The meshes tobj reads from `bytes` (see the module docs), or `None` when
/// the text is outside this reader's grammar.
pub fn parallel_obj_meshes(bytes: &[u8]) -> Option<Vec<tobj::Mesh>> {
    meshes_in_chunks(bytes, CHUNK_BYTES)
}

/// [`parallel_obj_meshes`] with chunks of about `chunk_bytes` (at least 1):
/// the result does not depend on it.
pub(crate) fn meshes_in_chunks(bytes: &[u8], chunk_bytes: usize) -> Option<Vec<tobj::Mesh>> {
    let counted: Vec<(&str, Counts)> = line_chunks(bytes, chunk_bytes.max(1))
        .par_iter()
        .map(|&chunk| {
            let text = std::str::from_utf8(chunk).ok()?;
            Some((text, count_values(text)))
        })
        .collect::<Option<_>>()?;
    let mut before = Counts::default();
    let based: Vec<(&str, Counts)> = counted
        .iter()
        .map(|&(text, counts)| {
            let base = before;
            before = before.plus(counts);
            (text, base)
        })
        .collect();
    let chunks: Vec<ParsedChunk> = based
        .par_iter()
        .map(|&(text, base)| parse_chunk(text, base))
        .collect::<Option<_>>()?;
    number_vertices(&chunks, before)
}

/// How many `v`, `vt` and `vn` lines.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Counts {
    positions: usize,
    texcoords: usize,
    normals: usize,
}

impl Counts {
    fn plus(self, other: Self) -> Self {
        Self {
            positions: self.positions + other.positions,
            texcoords: self.texcoords + other.texcoords,
            normals: self.normals + other.normals,
        }
    }
}

/// `bytes` cut into pieces of about `chunk_bytes`, each ending after a line
/// end (the last at the end of the text).
fn line_chunks(bytes: &[u8], chunk_bytes: usize) -> Vec<&[u8]> {
    let mut chunks = Vec::with_capacity(bytes.len() / chunk_bytes + 1);
    let mut start = 0;
    while start < bytes.len() {
        let probe = (start + chunk_bytes).min(bytes.len());
        let end = bytes[probe..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| probe + i + 1);
        chunks.push(&bytes[start..end]);
        start = end;
    }
    chunks
}

/// The `v`, `vt` and `vn` lines of `text` (by their first word, as tobj
/// dispatches; whether their values parse is the second pass's concern).
fn count_values(text: &str) -> Counts {
    let mut counts = Counts::default();
    for line in text.split('\n') {
        match line.split_whitespace().next() {
            Some("v") => counts.positions += 1,
            Some("vt") => counts.texcoords += 1,
            Some("vn") => counts.normals += 1,
            _ => {}
        }
    }
    counts
}

/// One face corner: 0-based indices into the file's positions, texture
/// coordinates and normals ([`MISSING`] where absent).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Corner {
    v: u32,
    vt: u32,
    vn: u32,
}

/// An `o` or `g` line: the chunk's triangle count and the file's value
/// counts at that line.
#[derive(Debug, Clone, Copy)]
struct ModelBreak {
    triangle: usize,
    counts: Counts,
}

/// What one chunk holds.
#[derive(Debug, Default)]
struct ParsedChunk {
    positions: Vec<f32>,
    texcoords: Vec<f32>,
    normals: Vec<f32>,
    /// Three corners a triangle.
    corners: Vec<Corner>,
    breaks: Vec<ModelBreak>,
}

impl ParsedChunk {
    fn triangles(&self) -> usize {
        self.corners.len() / 3
    }
}

/// The values of `text`, a chunk after `base` values; `None` outside the
/// grammar.
fn parse_chunk(text: &str, base: Counts) -> Option<ParsedChunk> {
    let mut chunk = ParsedChunk::default();
    for line in text.split('\n') {
        let mut words = line.split_whitespace();
        let seen = Counts {
            positions: base.positions + chunk.positions.len() / 3,
            texcoords: base.texcoords + chunk.texcoords.len() / 2,
            normals: base.normals + chunk.normals.len() / 3,
        };
        match words.next() {
            Some("v") => {
                push_floats(&mut words, &mut chunk.positions, 3)?;
                // A fourth value is a `w` or the start of a colour.
                if words.next().is_some() {
                    return None;
                }
            }
            Some("vt") => push_floats(&mut words, &mut chunk.texcoords, 2)?,
            Some("vn") => push_floats(&mut words, &mut chunk.normals, 3)?,
            Some("f") => push_fan(words, seen, &mut chunk.corners)?,
            Some("l") => return None,
            Some("o" | "g") => chunk.breaks.push(ModelBreak {
                triangle: chunk.triangles(),
                counts: seen,
            }),
            // tobj takes the name after the first space and refuses an
            // empty one.
            Some("usemtl") if line.split_once(' ').unwrap_or_default().1.trim().is_empty() => {
                return None;
            }
            _ => {}
        }
    }
    Some(chunk)
}

/// Parses the next `n` words as `f32` onto `values` (tobj's `parse_floatn`).
fn push_floats<'a>(
    words: &mut impl Iterator<Item = &'a str>,
    values: &mut Vec<f32>,
    n: usize,
) -> Option<()> {
    for _ in 0..n {
        values.push(words.next()?.parse::<f32>().ok()?);
    }
    Some(())
}

/// The fan of an `f` line's corners onto `corners`; `None` for fewer than
/// three corners or a corner outside the grammar.
fn push_fan<'a>(
    words: impl Iterator<Item = &'a str>,
    seen: Counts,
    corners: &mut Vec<Corner>,
) -> Option<()> {
    let mut first = None;
    let mut previous = None;
    let mut count = 0usize;
    for word in words {
        let corner = parse_corner(word, seen)?;
        count += 1;
        match (first, previous) {
            (None, _) => first = Some(corner),
            (Some(_), None) => previous = Some(corner),
            (Some(a), Some(b)) => {
                corners.extend([a, b, corner]);
                previous = Some(corner);
            }
        }
    }
    (count >= 3).then_some(())
}

/// One corner `v[/vt[/vn]]` (empty parts absent, as in tobj's
/// `VertexIndices::parse`), resolved to 0-based indices.
fn parse_corner(word: &str, seen: Counts) -> Option<Corner> {
    let mut indices = [MISSING; 3];
    let before = [seen.positions, seen.texcoords, seen.normals];
    for (slot, part) in word.split('/').enumerate() {
        if part.is_empty() {
            continue;
        }
        let value: isize = part.parse().ok()?;
        let count = *before.get(slot)?;
        let index = match value {
            0 => return None,
            v if v < 0 => count.checked_sub(v.unsigned_abs())?,
            v => v.unsigned_abs() - 1,
        };
        indices[slot] = u32::try_from(index).ok().filter(|&i| i != MISSING)?;
    }
    let [v, vt, vn] = indices;
    (v != MISSING).then_some(Corner { v, vt, vn })
}

/// A model: its triangles `[first, end)` over the file, and the value counts
/// when tobj exports it.
#[derive(Debug, Clone, Copy)]
struct ModelSpan {
    first: usize,
    end: usize,
    counts: Counts,
}

/// The models of tobj: a span of triangles closed by an `o`/`g` line when it
/// has triangles, and always the last one (tobj exports it even if empty).
fn model_spans(chunks: &[ParsedChunk], totals: Counts) -> Vec<ModelSpan> {
    let mut spans = Vec::new();
    let mut first = 0;
    let mut chunk_start = 0;
    for chunk in chunks {
        for model_break in &chunk.breaks {
            let at = chunk_start + model_break.triangle;
            if at > first {
                spans.push(ModelSpan {
                    first,
                    end: at,
                    counts: model_break.counts,
                });
                first = at;
            }
        }
        chunk_start += chunk.triangles();
    }
    spans.push(ModelSpan {
        first,
        end: chunk_start,
        counts: totals,
    });
    spans
}

/// Where a position's first (vt, vn) pair in the current model went.
#[derive(Debug, Clone, Copy)]
struct FirstUse {
    model: u32,
    vertex: u32,
    vt: u32,
    vn: u32,
}

/// Pass 3: tobj's vertex numbering, model by model (module docs).
fn number_vertices(chunks: &[ParsedChunk], totals: Counts) -> Option<Vec<tobj::Mesh>> {
    let concat = |pick: fn(&ParsedChunk) -> &Vec<f32>| -> Vec<f32> {
        let mut all = Vec::with_capacity(chunks.iter().map(|c| pick(c).len()).sum());
        for chunk in chunks {
            all.extend_from_slice(pick(chunk));
        }
        all
    };
    let positions = concat(|c| &c.positions);
    let texcoords = concat(|c| &c.texcoords);
    let normals = concat(|c| &c.normals);
    let corners: Vec<&[Corner]> = chunks.iter().map(|c| c.corners.as_slice()).collect();
    let mut first_use = vec![
        FirstUse {
            model: u32::MAX,
            vertex: 0,
            vt: MISSING,
            vn: MISSING,
        };
        totals.positions
    ];
    let mut others: HashMap<Corner, u32> = HashMap::new();
    let mut meshes = Vec::new();
    let mut walker = CornerWalker::new(&corners);
    for (model, span) in model_spans(chunks, totals).iter().enumerate() {
        let model = u32::try_from(model).ok()?;
        others.clear();
        let mut mesh = tobj::Mesh {
            indices: Vec::with_capacity(3 * (span.end - span.first)),
            ..Default::default()
        };
        let mut next_vertex = 0u32;
        for _ in 3 * span.first..3 * span.end {
            let corner = walker.next()?;
            let v = corner.v as usize;
            if v >= span.counts.positions {
                return None;
            }
            let slot = &mut first_use[v];
            let known = if slot.model != model {
                None
            } else if slot.vt == corner.vt && slot.vn == corner.vn {
                Some(slot.vertex)
            } else {
                others.get(&corner).copied()
            };
            if let Some(vertex) = known {
                mesh.indices.push(vertex);
                continue;
            }
            // A new vertex: tobj checks its indices and copies its values.
            mesh.positions
                .extend_from_slice(&positions[3 * v..3 * v + 3]);
            copy_value::<2>(
                &texcoords,
                span.counts.texcoords,
                corner.vt,
                &mut mesh.texcoords,
            )?;
            copy_value::<3>(&normals, span.counts.normals, corner.vn, &mut mesh.normals)?;
            if slot.model == model {
                others.insert(corner, next_vertex);
            } else {
                *slot = FirstUse {
                    model,
                    vertex: next_vertex,
                    vt: corner.vt,
                    vn: corner.vn,
                };
            }
            mesh.indices.push(next_vertex);
            next_vertex = next_vertex.checked_add(1)?;
        }
        meshes.push(mesh);
    }
    Some(meshes)
}

/// Copies value `index` of `values` (texture coordinates or normals, of
/// which `count` are defined when the model ends) onto a new vertex's list
/// as tobj does: nothing when the file has none of them so far or the
/// corner names none; `None` for an index out of range.
fn copy_value<const WIDTH: usize>(
    values: &[f32],
    count: usize,
    index: u32,
    to: &mut Vec<f32>,
) -> Option<()> {
    if count == 0 || index == MISSING {
        return Some(());
    }
    let i = index as usize;
    if i >= count {
        return None;
    }
    to.extend_from_slice(values.get(WIDTH * i..WIDTH * (i + 1))?);
    Some(())
}

/// The corners of every chunk in file order.
struct CornerWalker<'a> {
    chunks: &'a [&'a [Corner]],
    chunk: usize,
    at: usize,
}

impl<'a> CornerWalker<'a> {
    fn new(chunks: &'a [&'a [Corner]]) -> Self {
        Self {
            chunks,
            chunk: 0,
            at: 0,
        }
    }
}

impl Iterator for CornerWalker<'_> {
    type Item = Corner;

    fn next(&mut self) -> Option<Corner> {
        loop {
            let chunk = self.chunks.get(self.chunk)?;
            if let Some(&corner) = chunk.get(self.at) {
                self.at += 1;
                return Some(corner);
            }
            self.chunk += 1;
            self.at = 0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fuzzing::{same_meshes, tobj_meshes_without_mtl};

    fn tobj_meshes(text: &str) -> Result<Vec<tobj::Mesh>, tobj::LoadError> {
        tobj_meshes_without_mtl(text.as_bytes())
    }

    /// Every chunk size from one byte to the whole text gives tobj's meshes.
    fn assert_as_tobj(text: &str) {
        let expected = tobj_meshes(text).expect("tobj reads the test text");
        for chunk_bytes in [1, 2, 3, 7, 16, 64, text.len().max(1)] {
            let got = meshes_in_chunks(text.as_bytes(), chunk_bytes)
                .unwrap_or_else(|| panic!("inside the grammar (chunks of {chunk_bytes})"));
            assert!(
                same_meshes(&got, &expected),
                "chunks of {chunk_bytes}:\n{got:?}\n{expected:?}"
            );
        }
    }

    #[test]
    fn shared_corners_quads_polygons_and_models_number_as_tobj() {
        assert_as_tobj(
            "# a quad, a pentagon and a triangle sharing corners\n\
             v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 2 0\nv 2 2 2\n\
             f 1 2 3 4\nf 4 3 5 6 1\no second\ng\nf 1 2 3\n  f  -4 -3 -2\r\n\
             s off\nusemtl red\nmtllib none.mtl\nvp 1 2\n",
        );
    }

    #[test]
    fn texture_seams_and_normals_make_vertices_per_triple() {
        // Position 1 with two texture coordinates (a seam) and normals
        // given for some triples only, relative and absolute.
        assert_as_tobj(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
             vt 0 0\nvt 1 0 0.5\nvt 1 1\nvt 0 1\nvn 0 0 1\nvn 0 0 -1\n\
             f 1/1/1 2/2/1 3/3/1\nf 1/4/2 3/3/1 4/4/2\nf 1//1 2//1 4//1\n\
             f -4/-4/-2 -3/-3 -1/-1/-1\n",
        );
    }

    #[test]
    fn forward_references_are_bounded_at_the_model_end() {
        // tobj checks indices when the model ends: a face may name a vertex
        // defined later in the same model, not one after the next `o`.
        assert_as_tobj("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\no end\n");
        let late = "f 1 2 3\no end\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
        assert!(tobj_meshes(late).is_err());
        assert!(meshes_in_chunks(late.as_bytes(), 4).is_none());
    }

    #[test]
    fn empty_text_and_trailing_groups_give_tobj_empty_models() {
        assert_as_tobj("");
        assert_as_tobj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ng tail\n");
        assert_as_tobj("o a\no b\nv 0 0 0\n");
    }

    #[test]
    fn text_outside_the_grammar_is_left_to_tobj() {
        for text in [
            "v 0 0 0 2\n",         // w
            "v 0 0 0 1 0 0\n",     // colour
            "v 0 0\n",             // too few values
            "v 0 0 x\n",           // not a number
            "v 0 0 0\nf 1 1\n",    // a line
            "v 0 0 0\nl 1 1 1\n",  // `l`
            "v 0 0 0\nf 0 1 1\n",  // index 0
            "v 0 0 0\nf -2 1 1\n", // before the first vertex
            "v 0 0 0\nf 1 1 2\n",  // past the last vertex
            "v 0 0 0\nf 1/1/1/1 1 1\n",
            "v 0 0 0\nusemtl\n",
            "v 0 0 0\nf\n",
        ] {
            assert!(meshes_in_chunks(text.as_bytes(), 3).is_none(), "{text:?}");
        }
        assert!(meshes_in_chunks(b"v 0 0 \xff\n", 64).is_none());
    }
}
