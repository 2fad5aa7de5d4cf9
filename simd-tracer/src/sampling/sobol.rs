//! Owen-scrambled Sobol points, one sequence per pixel.
//!
//! **The sequence.** Dimension `d` of Sobol point `i` is the digital
//! product `x_d(i) = ⊕_j b_j(i) · v_{d,j}` over the bits `b_j` of `i`,
//! with direction numbers `v_{d,j}` (32-bit fractions). Dimension 0 is van
//! der Corput (`v_{0,j} = 2^{31−j}`); dimensions 1 to 127 follow Bratley
//! and Fox's recurrence from a primitive polynomial of degree `s` (inner
//! coefficients the bits of `a`) and initial numbers `m_1 … m_s`:
//! `v_j = m_j 2^{32−j}` for `j ≤ s`, then
//! `v_j = v_{j−s} ⊕ (v_{j−s} ≫ s) ⊕ ⊕_{k=1}^{s−1} a_k v_{j−k}`.
//! The polynomials and initial numbers are Joe and Kuo's
//! `new-joe-kuo-6.21201` set (S. Joe and F. Y. Kuo, "Constructing Sobol
//! sequences with better two-dimensional projections", SIAM J. Sci.
//! Comput. 30 (2008) 2635–2654; <https://web.maths.unsw.edu.au/~fkuo/sobol/>),
//! whose first 127 rows `data/sobol_joe_kuo_6_21201_first_128.txt` holds;
//! the table is parsed from that file at compile time ([`DIRECTIONS`]).
//! Why Sobol: each dimension is a (0, 1)-sequence and dimensions 0 and 1
//! form a (0, 2)-sequence, so every aligned block of `2^m` points puts
//! exactly one point in each of the `2^m` elementary intervals of the
//! pixel's area; Joe and Kuo chose their numbers for good 2D projections
//! of every other pair of dimensions.
//!
//! **Scrambling.** Unscrambled, every pixel would see the same points
//! (structured aliasing), and the estimate would be deterministic, not an
//! unbiased random one. Each (pixel, dimension) gets its own nested
//! uniform (Owen) scramble: bit `k` of the fraction is flipped by a
//! random function of the bits above it. That keeps every elementary
//! interval's count (an interval `[a 2^{−q}, (a+1) 2^{−q})` is moved as a
//! whole to another one), makes each point uniform on `[0, 1)`, and makes
//! the pixels' errors independent. The scramble is the hash-based one of
//! Burley ("Practical Hash-based Owen Scrambling", JCGT 9(4), 2020): the
//! Laine–Karras permutation `x += seed; x ⊕= x·c_1; … x ⊕= x·c_4` (even
//! `c_k`, Burley's constants) applied to the bit-reversed fraction. In
//! reversed order each step changes bit `k` only as a function of bits
//! `≤ k` (carries and products by even numbers move information upward
//! only), i.e. in the fraction's order a flip of bit `k` depends only on
//! more significant bits: a nested scramble, and a bijection (each step
//! is one). The tests check the stratification it must keep.
//!
//! **Per pixel, per pass.** Point `i` of a pixel is pass `i`, so a pixel's
//! first `2^m` passes are an Owen-scrambled `(t, m, s)`-net whatever the
//! pass count; the scrambles' seeds hash (seed, pixel, dimension) and do
//! not depend on the pass or on which thread renders the pixel. Past the
//! table's [`SOBOL_DIMENSIONS`] dimensions the numbers are hashed random
//! ones of (seed, pixel, pass, dimension) instead: deep bounces, where
//! Russian roulette and the accumulated throughput already dominate the
//! noise.
//!
//! Eight lanes are eight pixels at the same pass and dimension: the
//! unscrambled point is one scalar per draw, and only the scramble runs
//! 8-wide ([`SobolPacket`], each lane bit-identical to its scalar
//! [`SobolStream`], the oracle; tested).

use super::rng::{hash32, hash32_x8, mix64, to_unit_f32, unit_f32x8};
use crate::simd::LANES;
use wide::bytemuck::cast;
use wide::{f32x8, i8x32, u8x32, u32x8};

/// Dimensions with Sobol direction numbers: van der Corput plus the first
/// 127 rows of Joe and Kuo's table.
pub const SOBOL_DIMENSIONS: usize = 128;

/// Bits of an index and of a point.
const BITS: usize = 32;

/// Burley's Laine–Karras constants (even: each multiply moves bits upward).
const LK_MULTIPLIERS: [u32; 4] = [0x6c50_b47c, 0xb82f_1e52, 0xc7af_e638, 0x8d22_f6e6];

/// Mixed into a dimension's index to form its scramble seed.
const DIMENSION_SALT: u32 = 0x68e3_1da4;

/// Mixed into a pass index for the hashed dimensions past the table.
const PASS_SALT: u32 = 0xb529_7a4d;

/// Joe and Kuo's rows (`d s a m_1 … m_s`, one header line first).
const JOE_KUO_TABLE: &str = include_str!("../../../data/sobol_joe_kuo_6_21201_first_128.txt");

/// The direction numbers `v_{d,j}`, 32-bit fractions, by dimension and bit.
pub static DIRECTIONS: [[u32; BITS]; SOBOL_DIMENSIONS] = directions(JOE_KUO_TABLE);

/// The next unsigned decimal number of `text` from byte `at` (spaces and
/// line breaks skipped), and the byte after it.
const fn next_number(text: &[u8], mut at: usize) -> (u32, usize) {
    while at < text.len() && !text[at].is_ascii_digit() {
        at += 1;
    }
    assert!(at < text.len(), "the Joe–Kuo table ends early");
    let mut value = 0u32;
    while at < text.len() && text[at].is_ascii_digit() {
        value = value * 10 + (text[at] - b'0') as u32;
        at += 1;
    }
    (value, at)
}

/// The direction numbers of the table (module docs): checked while they
/// are built, so a malformed table is a compile error.
const fn directions(table: &str) -> [[u32; BITS]; SOBOL_DIMENSIONS] {
    let text = table.as_bytes();
    let mut v = [[0u32; BITS]; SOBOL_DIMENSIONS];
    let mut j = 0;
    while j < BITS {
        v[0][j] = 1 << (BITS - 1 - j);
        j += 1;
    }
    // Skip the header line.
    let mut at = 0;
    while text[at] != b'\n' {
        at += 1;
    }
    let mut d = 1;
    while d < SOBOL_DIMENSIONS {
        let (row, next) = next_number(text, at);
        assert!(row as usize == d + 1, "the Joe–Kuo rows are out of order");
        let (s, next) = next_number(text, next);
        let (a, next) = next_number(text, next);
        at = next;
        let s = s as usize;
        assert!(s >= 1 && s < BITS, "a degree outside 1..32");
        let mut j = 0;
        while j < s {
            let (m, next) = next_number(text, at);
            at = next;
            assert!(
                m % 2 == 1 && m < 1 << (j + 1),
                "m_j must be odd and below 2^j"
            );
            v[d][j] = m << (BITS - 1 - j);
            j += 1;
        }
        while j < BITS {
            let mut x = v[d][j - s] ^ (v[d][j - s] >> s);
            let mut k = 1;
            while k < s {
                if (a >> (s - 1 - k)) & 1 == 1 {
                    x ^= v[d][j - k];
                }
                k += 1;
            }
            v[d][j] = x;
            j += 1;
        }
        d += 1;
    }
    v
}

/// Unscrambled Sobol point `index` in `dimension` (< [`SOBOL_DIMENSIONS`]),
/// a 32-bit fraction.
#[inline]
pub fn sobol_bits(index: u32, dimension: usize) -> u32 {
    let v = &DIRECTIONS[dimension];
    let mut bits = index;
    let mut x = 0;
    while bits != 0 {
        x ^= v[bits.trailing_zeros() as usize];
        bits &= bits - 1;
    }
    x
}

/// The Laine–Karras permutation of the reversed fraction (module docs).
#[inline(always)]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    for c in LK_MULTIPLIERS {
        x ^= x.wrapping_mul(c);
    }
    x
}

/// [`laine_karras`] on 8 lanes, one seed each.
#[inline(always)]
fn laine_karras_x8(x: u32x8, seed: u32x8) -> u32x8 {
    let mut x = x + seed;
    for c in LK_MULTIPLIERS {
        x ^= x * u32x8::splat(c);
    }
    x
}

/// `u32::reverse_bits` on 8 lanes: the bytes of each lane in reverse
/// order, and the bits of each byte reversed, by three byte-table lookups
/// within 128-bit halves (`vpshufb`, [`u8x32::swizzle_half`]): one that
/// moves bytes, two that map a byte's low and high nibbles to the reversed
/// high and low nibbles. Seven operations where the swaps of halves,
/// bytes, nibbles, pairs and bits took seventeen.
#[inline(always)]
fn reverse_bits_x8(x: u32x8) -> u32x8 {
    /// Per 16-byte half: lane `k`'s bytes `3 2 1 0` from `4k + 3 … 4k`.
    const BYTE_ORDER: [i8; 32] = {
        let mut order = [0i8; 32];
        let mut at = 0;
        while at < 32 {
            order[at] = ((at % 16) / 4 * 4 + 3 - at % 4) as i8;
            at += 1;
        }
        order
    };
    /// `rev4(i)`, the 4-bit reversal of nibble `i`, in the low or the high
    /// nibble of a byte, repeated for both halves.
    const fn nibble_table(shift: u32) -> [u8; 32] {
        let mut table = [0u8; 32];
        let mut at = 0;
        while at < 32 {
            let i = (at % 16) as u8;
            let reversed = ((i & 1) << 3) | ((i & 2) << 1) | ((i & 4) >> 1) | ((i & 8) >> 3);
            table[at] = reversed << shift;
            at += 1;
        }
        table
    }
    /// A low nibble's reversal in the high nibble, a high nibble's in the
    /// low one (tables made at compile time).
    const LOW_TO_HIGH: [u8; 32] = nibble_table(4);
    const HIGH_TO_LOW: [u8; 32] = nibble_table(0);
    let low_nibble = u8x32::splat(0x0f);
    let bytes: u8x32 = cast(i8x32::swizzle_half(cast(x), i8x32::new(BYTE_ORDER)));
    let low = bytes & low_nibble;
    let high = cast::<u32x8, u8x32>(cast::<u8x32, u32x8>(bytes) >> 4_u32) & low_nibble;
    let reversed = u8x32::new(LOW_TO_HIGH).swizzle_half(cast(low))
        | u8x32::new(HIGH_TO_LOW).swizzle_half(cast(high));
    cast(reversed)
}

/// The nested uniform scramble of the 32-bit fraction `x` under `seed`.
#[inline]
pub fn owen_scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// The part of `dimension`'s scramble seed shared by every pixel,
/// `hash32(dimension ⊕ salt)`: from a table for the Sobol dimensions (a
/// hash fewer a draw), hashed past them.
#[inline(always)]
fn dimension_key(dimension: u32) -> u32 {
    match DIMENSION_KEYS.get(dimension as usize) {
        Some(&key) => key,
        None => hash32(dimension ^ DIMENSION_SALT),
    }
}

/// [`dimension_key`] of the first [`SOBOL_DIMENSIONS`] dimensions, made at
/// compile time.
static DIMENSION_KEYS: [u32; SOBOL_DIMENSIONS] = {
    let mut keys = [0u32; SOBOL_DIMENSIONS];
    let mut d = 0;
    while d < SOBOL_DIMENSIONS {
        keys[d] = hash32(d as u32 ^ DIMENSION_SALT);
        d += 1;
    }
    keys
};

/// The scramble seed of `dimension` for a pixel's seed.
#[inline(always)]
fn dimension_seed(pixel_seed: u32, dimension: u32) -> u32 {
    hash32(pixel_seed ^ dimension_key(dimension))
}

/// The part of a scramble key shared by every pixel: the render's seed,
/// hashed once. It does not depend on the pass (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SobolKey {
    low: u32,
    high: u32,
}

impl SobolKey {
    /// The key of a render's `seed`.
    pub fn new(seed: u64) -> Self {
        // Distinct from the independent sampler's keys, which hash a pass
        // and a purpose in as well.
        let key = mix64(!seed);
        Self {
            low: key as u32,
            high: (key >> 32) as u32,
        }
    }

    /// A pixel's seed: its index mixed into the key by two rounds of
    /// `hash32` (a bijection of 32-bit words, so the pixels of an image
    /// below 2³² get distinct seeds).
    #[inline]
    pub fn pixel_seed(&self, pixel: u64) -> u32 {
        hash32(hash32(pixel as u32 ^ self.low) ^ (pixel >> 32) as u32 ^ self.high)
    }
}

/// One pixel's scrambled Sobol sequence at one pass: the scalar oracle of
/// [`SobolPacket`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SobolStream {
    pixel_seed: u32,
    index: u32,
}

impl SobolStream {
    /// Point `index` (the pass) of `pixel`'s sequence under `key`.
    pub fn new(key: SobolKey, pixel: u64, index: u32) -> Self {
        Self {
            pixel_seed: key.pixel_seed(pixel),
            index,
        }
    }

    /// The 32 bits of `dimension`: scrambled Sobol below
    /// [`SOBOL_DIMENSIONS`], hashed past it (module docs).
    #[inline]
    pub fn bits(&self, dimension: u32) -> u32 {
        let seed = dimension_seed(self.pixel_seed, dimension);
        match usize::try_from(dimension) {
            Ok(d) if d < SOBOL_DIMENSIONS => owen_scramble(sobol_bits(self.index, d), seed),
            _ => hash32(seed ^ hash32(self.index ^ PASS_SALT)),
        }
    }

    /// `dimension` as a uniform `f32` in `[0, 1)` (its top 24 bits).
    #[inline]
    pub fn sample(&self, dimension: u32) -> f32 {
        to_unit_f32(self.bits(dimension))
    }
}

/// The sequences of the 8 pixels of a packet at one pass, each lane's
/// pixel seed in a `u32x8`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SobolPacket {
    pixel_seed: u32x8,
    index: u32,
}

impl SobolPacket {
    /// Lane `l` is [`SobolStream::new`]`(key, pixels[l], index)`.
    #[inline]
    pub fn new(key: SobolKey, pixels: &[u64; LANES], index: u32) -> Self {
        let low = u32x8::new(pixels.map(|p| p as u32));
        let high = u32x8::new(pixels.map(|p| (p >> 32) as u32));
        let first = hash32_x8(low ^ u32x8::splat(key.low));
        Self {
            pixel_seed: hash32_x8(first ^ high ^ u32x8::splat(key.high)),
            index,
        }
    }

    /// The stream of ray lane `lane`.
    pub fn lane(&self, lane: usize) -> SobolStream {
        SobolStream {
            pixel_seed: self.pixel_seed.to_array()[lane],
            index: self.index,
        }
    }

    /// [`SobolStream::sample`] of every lane.
    #[inline]
    pub fn sample_x8(&self, dimension: u32) -> f32x8 {
        let seed = hash32_x8(self.pixel_seed ^ u32x8::splat(dimension_key(dimension)));
        let bits = match usize::try_from(dimension) {
            Ok(d) if d < SOBOL_DIMENSIONS => {
                let reversed = u32x8::splat(sobol_bits(self.index, d).reverse_bits());
                reverse_bits_x8(laine_karras_x8(reversed, seed))
            }
            _ => hash32_x8(seed ^ u32x8::splat(hash32(self.index ^ PASS_SALT))),
        };
        unit_f32x8(bits)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first points of dimensions 0–2 by hand: van der Corput, and
    /// Joe–Kuo's dimension 2 (`s = 1`, `m_1 = 1`: `v_j = v_{j−1} ⊕
    /// (v_{j−1} ≫ 1)`: 1/2, 3/4, 5/8 …), in natural (not Gray-code)
    /// order, and dimension 3's direction numbers from `m = 1, 3`, `a = 1`.
    #[test]
    fn first_points_match_the_published_sequence() {
        let unit = |x: u32| f64::from(x) / 2f64.powi(32);
        let dim0: Vec<f64> = (0..5).map(|i| unit(sobol_bits(i, 0))).collect();
        let dim1: Vec<f64> = (0..5).map(|i| unit(sobol_bits(i, 1))).collect();
        assert_eq!(dim0, [0.0, 0.5, 0.25, 0.75, 0.125]);
        assert_eq!(dim1, [0.0, 0.5, 0.75, 0.25, 0.625]);
        // Dimension 3 (index 2): m = 1, 3 → v = 1/2, 3/4; v_3 = v_1 ⊕ v_1/4 ⊕ v_2.
        let v = DIRECTIONS[2];
        assert_eq!(v[0], 1 << 31);
        assert_eq!(v[1], 3 << 30);
        assert_eq!(v[2], v[0] ^ (v[0] >> 2) ^ v[1]);
    }

    /// The table in the data file has the row count and the invariants the
    /// parser checks; every dimension's generator matrix is invertible
    /// (bit `31 − j` of `v_j` set and no lower one: an upper-triangular
    /// matrix with a unit diagonal), which makes each dimension a (0, 1)-sequence.
    #[test]
    fn direction_numbers_are_well_formed() {
        let rows = JOE_KUO_TABLE.lines().skip(1).count();
        assert_eq!(rows + 1, SOBOL_DIMENSIONS);
        for (d, v) in DIRECTIONS.iter().enumerate() {
            for (j, &x) in v.iter().enumerate() {
                let diagonal = 1u32 << (BITS - 1 - j);
                // Column j of the matrix: the diagonal bit set, none below it.
                assert_eq!(
                    x & (diagonal | (diagonal - 1)),
                    diagonal,
                    "dimension {d}, bit {j}"
                );
            }
        }
    }

    /// Counts of the points `first .. first + 2^m` of `point` in the
    /// elementary intervals of `2^{m}` cells: `2^{q}` columns × `2^{m−q}`
    /// rows, for every `q`; true when each holds exactly one.
    fn is_net(point: impl Fn(u32) -> (f32, f32), first: u32, m: u32) -> bool {
        (0..=m).all(|q| {
            let mut counts = vec![0u32; 1 << m];
            for i in first..first + (1 << m) {
                let (x, y) = point(i);
                let column = (f64::from(x) * f64::from(1u32 << q)) as usize;
                let row = (f64::from(y) * f64::from(1u32 << (m - q))) as usize;
                counts[(row << q) | column] += 1;
            }
            counts.iter().all(|&c| c == 1)
        })
    }

    /// Whether the points `first .. first + 2^m` of `point` put one point in
    /// each interval `[k 2^{−m}, (k+1) 2^{−m})`.
    fn is_stratified(point: impl Fn(u32) -> f32, first: u32, m: u32) -> bool {
        let mut counts = vec![0u32; 1 << m];
        for i in first..first + (1 << m) {
            counts[(f64::from(point(i)) * f64::from(1u32 << m)) as usize] += 1;
        }
        counts.iter().all(|&c| c == 1)
    }

    /// Every aligned block of `2^m` passes of a pixel's two pixel
    /// dimensions is a (0, m, 2)-net (one point in every elementary
    /// interval of area `2^{−m}`), scrambled or not, for several pixels,
    /// seeds and blocks; and every dimension alone is stratified (one
    /// point per interval `[k 2^{−m}, (k+1) 2^{−m})`). Negative control:
    /// pairing dimension 0 with a *hashed* dimension breaks the net.
    #[test]
    fn scrambled_pixel_dimensions_are_nets() {
        for seed in [0u64, 7, 1 << 40] {
            let key = SobolKey::new(seed);
            for pixel in [0u64, 1, 12_345, u64::MAX - 3] {
                let point = |i: u32| {
                    (
                        SobolStream::new(key, pixel, i).sample(0),
                        SobolStream::new(key, pixel, i).sample(1),
                    )
                };
                for m in [1, 4, 8, 10] {
                    for block in [0u32, 1, 5] {
                        assert!(
                            is_net(point, block << m, m),
                            "seed {seed} pixel {pixel} m {m}"
                        );
                    }
                }
                for d in 0..SOBOL_DIMENSIONS as u32 {
                    let one_d = |i: u32| SobolStream::new(key, pixel, i).sample(d);
                    assert!(is_stratified(one_d, 64, 6), "dimension {d}");
                }
            }
        }
        let unscrambled = |i: u32| (to_unit_f32(sobol_bits(i, 0)), to_unit_f32(sobol_bits(i, 1)));
        assert!(is_net(unscrambled, 0, 10));
        let key = SobolKey::new(3);
        let hashed = SOBOL_DIMENSIONS as u32 + 5;
        let broken = |i: u32| {
            (
                SobolStream::new(key, 9, i).sample(0),
                SobolStream::new(key, 9, i).sample(hashed),
            )
        };
        assert!(!is_net(broken, 0, 8));
        let hashed_1d = |i: u32| SobolStream::new(key, 9, i).sample(hashed);
        assert!(!is_stratified(hashed_1d, 0, 6));
    }

    /// The scramble changes the points with the seed, the pixel and the
    /// dimension (different seeds: almost every point moves), is a
    /// bijection of 32-bit fractions on a sample, and each scrambled
    /// coordinate is uniform over pixels (χ² over 64 bins at a fixed pass).
    #[test]
    fn scrambles_depend_on_seed_pixel_and_dimension() {
        let a = SobolKey::new(1);
        let b = SobolKey::new(2);
        let moved = (0..1000)
            .filter(|&i| SobolStream::new(a, 5, i).bits(3) != SobolStream::new(b, 5, i).bits(3))
            .count();
        assert!(moved > 990, "{moved}");
        let moved = (0..1000)
            .filter(|&i| SobolStream::new(a, 5, i).bits(3) != SobolStream::new(a, 6, i).bits(3))
            .count();
        assert!(moved > 990, "{moved}");
        assert_ne!(
            SobolStream::new(a, 5, 0).bits(3),
            SobolStream::new(a, 5, 0).bits(4)
        );
        let mut images: Vec<u32> = (0..1u32 << 16)
            .map(|x| owen_scramble(x << 16, 99))
            .collect();
        images.sort_unstable();
        images.dedup();
        assert_eq!(images.len(), 1 << 16);
        let bins = 64;
        let pixels = 1u64 << 16;
        for dimension in [0, 1, 9, 200] {
            let mut counts = vec![0.0f64; bins];
            for pixel in 0..pixels {
                let u = SobolStream::new(a, pixel, 3).sample(dimension);
                counts[(f64::from(u) * bins as f64) as usize] += 1.0;
            }
            let expected = pixels as f64 / bins as f64;
            let chi2: f64 = counts
                .iter()
                .map(|c| (c - expected).powi(2) / expected)
                .sum();
            // 63 degrees of freedom: the 0.1 % tail starts at 103.4.
            assert!(chi2 < 103.4, "dimension {dimension}: chi2 {chi2}");
        }
    }

    /// Each packet lane equals its scalar stream bit for bit, in Sobol and
    /// hashed dimensions, for ordinary, wide and padding pixel indices.
    #[test]
    fn packet_lanes_equal_their_scalar_streams() {
        let key = SobolKey::new(42);
        let sets: [[u64; LANES]; 3] = [
            core::array::from_fn(|lane| 1000 + lane as u64),
            core::array::from_fn(|lane| (lane as u64) << 33 | 7),
            core::array::from_fn(|lane| u64::MAX - lane as u64),
        ];
        for pixels in sets {
            for index in [0u32, 1, 77, u32::MAX] {
                let packet = SobolPacket::new(key, &pixels, index);
                for dimension in [0u32, 1, 2, 63, 127, 128, 5000, u32::MAX] {
                    let drawn = packet.sample_x8(dimension).to_array();
                    for (lane, &pixel) in pixels.iter().enumerate() {
                        let scalar = SobolStream::new(key, pixel, index);
                        assert_eq!(packet.lane(lane), scalar);
                        assert_eq!(drawn[lane].to_bits(), scalar.sample(dimension).to_bits());
                    }
                }
            }
        }
        // The bit reversal lane by lane, on single bits, their complements
        // and hashed words.
        let words = (0..32u32)
            .flat_map(|bit| [1 << bit, !(1 << bit)])
            .chain((0..4096u32).map(hash32))
            .collect::<Vec<u32>>();
        for chunk in words.chunks_exact(LANES) {
            let x = u32x8::new(core::array::from_fn(|l| chunk[l]));
            let reversed = reverse_bits_x8(x).to_array();
            for (lane, value) in chunk.iter().enumerate() {
                assert_eq!(reversed[lane], value.reverse_bits(), "{value:#x}");
            }
        }
    }
}
