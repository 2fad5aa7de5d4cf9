//! Replays the committed fuzz corpora of this crate's targets
//! (`fuzz/corpus/{traversal,obj}`) through their bodies in
//! `simd_tracer::fuzzing`, so every seed and every regression input runs in
//! CI on stable Rust.

use std::path::Path;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

fn replay(target: &str, body: fn(&[u8])) -> TestResult<usize> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/corpus")
        .join(target);
    let mut count = 0;
    for entry in std::fs::read_dir(&dir)? {
        let path = entry?.path();
        if path.is_file() {
            body(&std::fs::read(&path)?);
            count += 1;
        }
    }
    Ok(count)
}

#[test]
fn traversal_corpus() -> TestResult {
    assert!(replay("traversal", simd_tracer::fuzzing::traversal)? >= 2);
    Ok(())
}

#[test]
fn obj_corpus() -> TestResult {
    assert!(replay("obj", simd_tracer::fuzzing::obj)? >= 3);
    Ok(())
}
