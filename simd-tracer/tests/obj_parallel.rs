//! The parallel OBJ reader against tobj, its oracle: random OBJ text, mostly
//! inside the reader's grammar (positions, texture coordinates and normals
//! up front, then faces of three to six corners in every index form,
//! relative and absolute, models, comments, CRLF ends) with a few lines
//! outside it, cut into chunks of 1–64 bytes. Wherever the reader reads a
//! text, tobj must read the same meshes bit for bit
//! (`simd_tracer::fuzzing::obj_parallel`); and the reader must read most of
//! these texts, or the comparison would test nothing.

use proptest::prelude::*;
use proptest::strategy::ValueTree;
use simd_tracer::scene::obj_parallel::parallel_obj_meshes;

/// Values defined before the faces.
const POSITIONS: i32 = 8;
const TEXCOORDS: i32 = 4;
const NORMALS: i32 = 3;

/// An index into `count` values: absolute (1-based) or relative.
fn index(count: i32) -> impl Strategy<Value = String> {
    prop_oneof![
        (1..=count).prop_map(|i| i.to_string()),
        (1..=count).prop_map(|i| format!("-{i}")),
    ]
}

/// One corner in one of the four forms.
fn corner() -> impl Strategy<Value = String> {
    (index(POSITIONS), index(TEXCOORDS), index(NORMALS), 0..4u8).prop_map(|(v, vt, vn, form)| {
        match form {
            0 => v,
            1 => format!("{v}/{vt}"),
            2 => format!("{v}//{vn}"),
            _ => format!("{v}/{vt}/{vn}"),
        }
    })
}

fn value() -> impl Strategy<Value = String> {
    prop_oneof![
        (-4.0f32..4.0).prop_map(|x| x.to_string()),
        Just("1e-3".to_string()),
        Just("-0".to_string()),
        Just("nan".to_string()),
    ]
}

/// A line after the header: mostly faces, some other lines of the grammar,
/// rarely one outside it.
fn body_line() -> impl Strategy<Value = String> {
    prop_oneof![
        12 => prop::collection::vec(corner(), 3..=6).prop_map(|c| format!("f {}", c.join(" "))),
        2 => (value(), value(), value()).prop_map(|(x, y, z)| format!("v {x} {y} {z}")),
        1 => (value(), value()).prop_map(|(u, v)| format!("vt {u} {v}")),
        1 => (value(), value(), value()).prop_map(|(x, y, z)| format!("vn {x} {y} {z}")),
        1 => Just("o part".to_string()),
        1 => Just("g".to_string()),
        1 => Just("usemtl red".to_string()),
        1 => Just("# comment f 1 2 3".to_string()),
        1 => Just("s off".to_string()),
        1 => Just(String::new()),
        // Outside the grammar: a `w`, a line, an index 0.
        1 => prop_oneof![
            Just("v 1 2 3 4".to_string()),
            Just("l 1 2".to_string()),
            Just("f 0 1 2".to_string()),
        ],
    ]
}

/// A whole text: the header, the body, LF or CRLF line ends.
fn obj_text() -> impl Strategy<Value = String> {
    let header = (
        prop::collection::vec((value(), value(), value()), POSITIONS as usize),
        prop::collection::vec((value(), value()), TEXCOORDS as usize),
        prop::collection::vec((value(), value(), value()), NORMALS as usize),
    );
    (
        header,
        prop::collection::vec(body_line(), 0..40),
        any::<bool>(),
    )
        .prop_map(|((v, vt, vn), body, crlf)| {
            let mut lines: Vec<String> = Vec::new();
            lines.extend(v.iter().map(|(x, y, z)| format!("v {x} {y} {z}")));
            lines.extend(vt.iter().map(|(u, v)| format!("vt {u} {v}")));
            lines.extend(vn.iter().map(|(x, y, z)| format!("vn {x} {y} {z}")));
            lines.extend(body);
            lines.join(if crlf { "\r\n" } else { "\n" })
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn the_parallel_reader_reads_what_tobj_reads(text in obj_text(), chunk_selector in any::<u8>()) {
        let mut bytes = vec![chunk_selector];
        bytes.extend_from_slice(text.as_bytes());
        simd_tracer::fuzzing::obj_parallel(&bytes);
    }
}

/// The texts above without their lines outside the grammar are all read:
/// the comparison runs on the reader's own results, not on `None`.
#[test]
fn texts_inside_the_grammar_are_read() {
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let strategy = obj_text().prop_map(|text| {
        text.lines()
            .filter(|line| !matches!(line.trim(), "v 1 2 3 4" | "l 1 2" | "f 0 1 2"))
            .collect::<Vec<_>>()
            .join("\n")
    });
    for _ in 0..256 {
        let text = strategy
            .new_tree(&mut runner)
            .expect("the strategy makes a text")
            .current();
        assert!(parallel_obj_meshes(text.as_bytes()).is_some(), "{text}");
    }
}
