//! Process-wide settings of the C heap, for the `fspec` executable only
//! (a library embedded in someone else's process must not change its
//! allocator).
//!
//! **Why.** glibc serves a request of at least `M_MMAP_THRESHOLD` bytes
//! (128 KiB at start) with its own `mmap`, which `free` returns to the
//! system at once. But it raises the threshold to the size of every such
//! block freed, up to 32 MiB (`DEFAULT_MMAP_THRESHOLD_MAX` on 64-bit;
//! glibc's `malloc/malloc.c`, "dynamic mmap threshold"). A scene load frees
//! many large temporaries (the OBJ text, the parsed meshes, the tree
//! build's arrays), so later blocks of up to 32 MiB come from the heap and
//! its per-thread arenas, and what they leave when freed stays in the
//! process as holes between live blocks. Setting the threshold explicitly
//! turns the dynamic adjustment off, so large blocks keep going back to the
//! system when freed. Measured on a 1.31 M-triangle OBJ scene
//! (`docs/performance.md`, "glibc's mmap threshold"): peak resident memory
//! of the load alone 296 → 216 MB, of the render 333 → 280 MB, the same
//! time within the run-to-run spread.
//!
//! On other platforms (other C libraries, other systems) nothing is done.

/// The threshold fixed by [`return_large_blocks_to_the_system`]: glibc's
/// own starting value (`DEFAULT_MMAP_THRESHOLD_MIN`, 128 KiB), now kept.
pub const MMAP_THRESHOLD_BYTES: usize = 128 * 1024;

/// Fixes glibc's mmap threshold at [`MMAP_THRESHOLD_BYTES`] (module docs).
/// Returns whether the setting was applied (`false` on other platforms,
/// or if glibc refused it).
pub fn return_large_blocks_to_the_system() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        let Ok(threshold) = libc::c_int::try_from(MMAP_THRESHOLD_BYTES) else {
            return false;
        };
        // SAFETY: `mallopt` only changes the allocator's parameters, is
        // thread-safe, and may be called at any time; it takes no pointers
        // and returns 0 when it rejects a value.
        #[allow(unsafe_code, reason = "the one foreign call this crate exists for")]
        let accepted = unsafe { libc::mallopt(libc::M_MMAP_THRESHOLD, threshold) };
        accepted != 0
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// glibc accepts the setting; elsewhere nothing is applied. (Its effect
    /// on resident memory is measured, not tested: `tools/big_scene_bench.py`.)
    #[test]
    fn the_threshold_is_accepted_where_glibc_is_the_allocator() {
        let applied = return_large_blocks_to_the_system();
        assert_eq!(
            applied,
            cfg!(all(target_os = "linux", target_env = "gnu")),
            "mallopt(M_MMAP_THRESHOLD, {MMAP_THRESHOLD_BYTES})"
        );
    }
}
