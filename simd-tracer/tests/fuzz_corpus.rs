//! Replays the committed fuzz corpora of this crate's targets
//! (`fuzz/corpus/{traversal,obj,obj_parallel,ply,serialized}`) through their bodies in
//! `simd_tracer::fuzzing`, so every seed and every regression input runs in
//! CI on stable Rust. The walk is `test_support::replay_corpus`: every
//! file, and an error if a corpus directory is missing or empty.

use test_support::replay_corpus;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

#[test]
fn traversal_corpus() -> TestResult {
    assert!(replay_corpus("traversal", simd_tracer::fuzzing::traversal)? >= 2);
    Ok(())
}

#[test]
fn obj_corpus() -> TestResult {
    assert!(replay_corpus("obj", simd_tracer::fuzzing::obj)? >= 3);
    Ok(())
}

#[test]
fn obj_parallel_corpus() -> TestResult {
    assert!(replay_corpus("obj_parallel", simd_tracer::fuzzing::obj_parallel)? >= 5);
    Ok(())
}

#[test]
fn ply_corpus() -> TestResult {
    assert!(replay_corpus("ply", simd_tracer::fuzzing::ply)? >= 6);
    Ok(())
}

#[test]
fn serialized_corpus() -> TestResult {
    assert!(replay_corpus("serialized", simd_tracer::fuzzing::serialized)? >= 6);
    Ok(())
}
