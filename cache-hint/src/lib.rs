//! A cache prefetch hint: [`prefetch`] asks the memory system to start
//! bringing the cache lines of a value toward the core, and returns at once.
//!
//! **Why.** The tracer's walks through a large 8-wide tree (a million
//! triangles, a tree of about 100 MB) wait for memory at almost every
//! node and triangle block: the node just tested names the children to
//! load next. A node's hit children that are pushed on the stack are
//! visited later, so their lines can be requested as they are pushed,
//! and a walk finds them in the cache when it pops them. A plain load
//! cannot do this: a load that misses holds retirement until its data
//! arrives, so the reorder buffer fills behind it, which is why an earlier
//! try that read the lines early was no faster (`docs/performance.md`,
//! "Prefetching a wide node's hit children"). A prefetch instruction
//! retires at once.
//!
//! **Safety.** A prefetch is a hint: it never faults and never changes a
//! value, whatever the address. The one `unsafe` block of this crate issues
//! it for addresses within or beside a live reference (the `x86_64`
//! intrinsic is `unsafe` only because it takes a raw pointer). The
//! workspace forbids `unsafe`; this crate denies it except at that block,
//! as `heap-tuning` does for its one foreign call.
//!
//! **Portability.** On `x86_64` each line gets `prefetcht0` (into every
//! level of the cache); elsewhere [`prefetch`] does nothing, which changes
//! only speed.
#![no_std]

/// Bytes of a cache line on the processors the hint is tuned for (every
/// `x86_64` processor since the Pentium 4 uses 64).
pub const LINE_BYTES: usize = 64;

/// Starts loading every cache line that `value` occupies, from the line
/// holding its first byte to the line holding its last (nothing for a
/// zero-sized value), and returns without waiting for them.
#[inline(always)]
pub fn prefetch<T>(value: &T) {
    let first = core::ptr::from_ref(value).cast::<u8>();
    let (misalignment, lines) = line_span(first.addr(), size_of::<T>());
    // The first line's start: `misalignment` bytes before the value.
    let line_start = first.wrapping_sub(misalignment);
    for line in 0..lines {
        prefetch_line(line_start.wrapping_add(line * LINE_BYTES));
    }
}

/// For a value of `size` bytes at address `address`: its offset into its
/// first cache line and the number of lines it touches.
#[inline(always)]
const fn line_span(address: usize, size: usize) -> (usize, usize) {
    let misalignment = address % LINE_BYTES;
    if size == 0 {
        return (misalignment, 0);
    }
    (misalignment, (misalignment + size).div_ceil(LINE_BYTES))
}

/// Issues the prefetch of the line holding `address`.
#[inline(always)]
fn prefetch_line(address: *const u8) {
    #[cfg(target_arch = "x86_64")]
    {
        #[allow(unsafe_code, reason = "the one instruction this crate exists for")]
        // SAFETY: `prefetcht0` is a hint: it does not fault on any address
        // (invalid, unmapped or otherwise) and writes nothing (Intel SDM,
        // vol. 2B, PREFETCHh: "does not affect program behavior").
        unsafe {
            core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(
                address.cast::<i8>(),
            );
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = address;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lines of [`line_span`] are exactly those that hold some byte of
    /// the value, for every offset into a line and sizes across several
    /// lines (checked byte by byte).
    #[test]
    fn the_span_covers_exactly_the_value_s_lines() {
        for base_line in [0usize, 7, 1 << 20] {
            for offset in 0..LINE_BYTES {
                let address = base_line * LINE_BYTES + offset;
                for size in 0..5 * LINE_BYTES {
                    let (misalignment, lines) = line_span(address, size);
                    assert_eq!(misalignment, offset);
                    let first_line = (address - misalignment) / LINE_BYTES;
                    let touched = (address..address + size).map(|byte| byte / LINE_BYTES);
                    let wanted = touched
                        .clone()
                        .max()
                        .map_or(0, |last| last - first_line + 1);
                    assert_eq!(lines, wanted, "address {address}, size {size}");
                    assert!(
                        touched
                            .clone()
                            .all(|l| l >= first_line && l < first_line + lines)
                    );
                }
            }
        }
    }

    /// Prefetching values of every shape (zero-sized, unaligned, larger
    /// than a page, at the end of an allocation) neither faults nor
    /// changes them.
    #[test]
    fn prefetching_changes_nothing() {
        let bytes = [7u8; 4096 + 3];
        prefetch(&bytes);
        prefetch(&bytes[4096 + 2]);
        prefetch(&());
        let words = [1.5f32; 120];
        prefetch(&words);
        prefetch(&words[119]);
        assert!(bytes.iter().all(|&b| b == 7));
        assert!(words.iter().all(|&w| w == 1.5));
    }
}
