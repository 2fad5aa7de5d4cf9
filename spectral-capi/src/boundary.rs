//! The only `unsafe` of the crate: C pointers turned into slices and
//! values, after every check that can be made on them.
//!
//! What a C pointer cannot tell, the caller promises (each entry point's
//! `# Safety`): a non-null pointer points to at least the stated number of
//! initialised elements, valid for the duration of the call. What can be
//! checked is checked first, so that the call returns a status instead of
//! invoking undefined behaviour or panicking: null, alignment, and a byte
//! length that fits in `isize`.
//!
//! Inputs are read, and outputs written, without ever holding a `&mut`
//! that may overlap an input: outputs are computed into Rust locals and then
//! copied out ([`write`]), so a caller may pass the same buffer as input and
//! output (an in-place product).

use crate::status::FspecStatus;
use core::ffi::c_void;
use core::mem::{align_of, size_of};

/// The checks every pointer gets before it is dereferenced: not null,
/// aligned for `T`, and `count` elements of `T` span at most `isize::MAX`
/// bytes (the limit of `core::slice::from_raw_parts`).
fn check<T>(pointer: *const T, count: usize) -> Result<(), FspecStatus> {
    if pointer.is_null() {
        return Err(FspecStatus::NullPointer);
    }
    if !pointer.is_aligned() {
        return Err(FspecStatus::Misaligned);
    }
    match count.checked_mul(size_of::<T>()) {
        Some(bytes) if bytes <= isize::MAX as usize => Ok(()),
        _ => Err(FspecStatus::BadLength),
    }
}

/// `count` elements of `T` at `pointer`, borrowed for the call.
///
/// # Safety
///
/// A non-null, aligned `pointer` must point to `count` initialised `T`s
/// that no one writes during the returned borrow.
pub(crate) unsafe fn slice<'a, T>(pointer: *const T, count: usize) -> Result<&'a [T], FspecStatus> {
    check(pointer, count)?;
    // SAFETY: `check` rejected null, misaligned and oversized spans; the
    // caller guarantees `count` initialised, unaliased-by-writers elements.
    Ok(unsafe { core::slice::from_raw_parts(pointer, count) })
}

/// The `K` elements at `pointer`, copied into an array.
///
/// # Safety
///
/// As [`slice`] with `count = K`.
pub(crate) unsafe fn array<T: Copy + Default, const K: usize>(
    pointer: *const T,
) -> Result<[T; K], FspecStatus> {
    // SAFETY: forwarded to the caller of this function.
    let elements = unsafe { slice(pointer, K) }?;
    let mut copy = [T::default(); K];
    copy.copy_from_slice(elements);
    Ok(copy)
}

/// Copies `out.len()` elements from `pointer` into `out`.
///
/// # Safety
///
/// As [`slice`] with `count = out.len()`.
pub(crate) unsafe fn read_into<T: Copy>(
    pointer: *const T,
    out: &mut [T],
) -> Result<(), FspecStatus> {
    // SAFETY: forwarded to the caller of this function.
    let elements = unsafe { slice(pointer, out.len()) }?;
    crate::fill(out, elements)
}

/// Checks an output pointer for `count` elements of `T` without writing.
/// Entry points check their outputs before computing, so that a bad output
/// pointer fails the call before any work.
pub(crate) fn check_out<T>(pointer: *mut T, count: usize) -> Result<(), FspecStatus> {
    check(pointer.cast_const(), count)
}

/// Copies `values` to `pointer`.
///
/// # Safety
///
/// A non-null, aligned `pointer` must be valid for writing `values.len()`
/// elements of `T`. It may alias any input of the call: inputs have been
/// copied or are no longer borrowed when outputs are written, and `values`
/// lives in Rust memory, which C cannot name.
pub(crate) unsafe fn write<T: Copy>(pointer: *mut T, values: &[T]) -> Result<(), FspecStatus> {
    check_out(pointer, values.len())?;
    // SAFETY: `check_out` rejected null, misaligned and oversized spans, the
    // caller guarantees the span is writable, and `values` is Rust memory,
    // so the two do not overlap.
    unsafe { core::ptr::copy_nonoverlapping(values.as_ptr(), pointer, values.len()) };
    Ok(())
}

/// [`write`] for numeric results: `Err(NonFiniteResult)`, and nothing
/// written, if any value is NaN or infinite (finite input can overflow).
///
/// # Safety
///
/// As [`write`].
pub(crate) unsafe fn write_finite<T: Copy + Into<f64>>(
    pointer: *mut T,
    values: &[T],
) -> Result<(), FspecStatus> {
    crate::check_finite_result(values)?;
    // SAFETY: forwarded to the caller of this function.
    unsafe { write(pointer, values) }
}

/// The header at the start of every caller-allocated buffer that holds a
/// value of this crate (an XYZ converter, a Fourier table, a control
/// variate): which kind of value, for how many coefficients.
#[repr(C)]
#[derive(Clone, Copy)]
struct Header {
    magic: u32,
    kind: u16,
    coeffs: u16,
}

/// A value of this crate in a caller-allocated buffer.
#[repr(C)]
struct Tagged<T> {
    header: Header,
    value: T,
}

/// A recognisable bit pattern ("FSPC"), so that a buffer that never went
/// through an `_init`/`_build` function is rejected in the common cases
/// (zeroed or garbage memory) instead of being read as a value.
const MAGIC: u32 = 0x4653_5043;

/// What a caller-allocated buffer holds.
#[derive(Clone, Copy, PartialEq, Eq)]
#[repr(u16)]
pub(crate) enum Kind {
    /// `spectral_core::xyz::XyzConverter<N>`.
    XyzConverter = 1,
    /// `spectral_core::table::FourierTable<N, TABLE_ROWS>`.
    FourierTable = 2,
    /// `spectral_core::control_variate::ControlVariate`.
    ControlVariate = 3,
}

/// Bytes a buffer needs to hold a `T`, header included.
pub(crate) const fn tagged_size<T>() -> usize {
    size_of::<Tagged<T>>()
}

/// Alignment a buffer needs to hold a `T`, header included.
pub(crate) const fn tagged_align<T>() -> usize {
    align_of::<Tagged<T>>()
}

/// Checks a caller-allocated buffer: not null, aligned, large enough.
fn check_buffer<T>(buffer: *const c_void, bytes: usize) -> Result<(), FspecStatus> {
    if buffer.is_null() {
        return Err(FspecStatus::NullPointer);
    }
    if !buffer.cast::<Tagged<T>>().is_aligned() {
        return Err(FspecStatus::Misaligned);
    }
    if bytes < tagged_size::<T>() {
        return Err(FspecStatus::BufferTooSmall);
    }
    Ok(())
}

/// Moves `value` into the caller's buffer, tagged with its kind and
/// coefficient count.
///
/// # Safety
///
/// `buffer` must be valid for writing `bytes` bytes.
pub(crate) unsafe fn store<T>(
    buffer: *mut c_void,
    bytes: usize,
    kind: Kind,
    coeffs: usize,
    value: T,
) -> Result<(), FspecStatus> {
    check_buffer::<T>(buffer.cast_const(), bytes)?;
    let header = Header {
        magic: MAGIC,
        kind: kind as u16,
        coeffs: u16::try_from(coeffs).map_err(|_| FspecStatus::UnsupportedCount)?,
    };
    // SAFETY: `check_buffer` rejected null, misaligned and short buffers,
    // and the caller guarantees `bytes` writable bytes. `write` does not
    // read or drop the old contents.
    unsafe { buffer.cast::<Tagged<T>>().write(Tagged { header, value }) };
    Ok(())
}

/// The coefficient count recorded in a buffer of `kind`, after checking
/// its header. Used to dispatch to the value's type before [`load`].
///
/// # Safety
///
/// A non-null `buffer` must be valid for reading a [`Header`] (8 bytes)
/// and initialised.
pub(crate) unsafe fn stored_coeffs(
    buffer: *const c_void,
    kind: Kind,
) -> Result<usize, FspecStatus> {
    check_buffer::<()>(buffer, size_of::<Header>())?;
    // SAFETY: `check_buffer::<()>` rejected null and misaligned (for the
    // header's alignment, 4) pointers; the caller guarantees 8 readable,
    // initialised bytes, and every bit pattern is a valid `Header`.
    let header = unsafe { buffer.cast::<Header>().read() };
    if header.magic != MAGIC || header.kind != kind as u16 {
        return Err(FspecStatus::NotInitialised);
    }
    Ok(usize::from(header.coeffs))
}

/// The value in a buffer written by [`store`] with the same `T`, shared.
///
/// # Safety
///
/// `buffer` must hold a value written by [`store`] for this `T` (checked:
/// the header's kind and coefficient count, which the callers match to `T`
/// through [`stored_coeffs`]; the size was checked by [`store`]), not
/// modified since except through this crate, and not written by others
/// during the returned borrow.
pub(crate) unsafe fn load<'a, T>(buffer: *const c_void) -> Result<&'a T, FspecStatus> {
    check_buffer::<T>(buffer, tagged_size::<T>())?;
    // SAFETY: `check_buffer` rejected null and misaligned buffers; the
    // caller guarantees that a `Tagged<T>` was stored there and is not
    // written during the borrow.
    let tagged = unsafe { &*buffer.cast::<Tagged<T>>() };
    Ok(&tagged.value)
}

/// The value in a buffer written by [`store`] with the same `T`, for
/// updating.
///
/// # Safety
///
/// As [`load`], and no one else reads or writes the buffer during the
/// returned borrow.
pub(crate) unsafe fn load_mut<'a, T>(buffer: *mut c_void) -> Result<&'a mut T, FspecStatus> {
    check_buffer::<T>(buffer.cast_const(), tagged_size::<T>())?;
    // SAFETY: `check_buffer` rejected null and misaligned buffers; the
    // caller guarantees that a `Tagged<T>` was stored there and is not
    // otherwise accessed during the borrow.
    let tagged = unsafe { &mut *buffer.cast::<Tagged<T>>() };
    Ok(&mut tagged.value)
}
