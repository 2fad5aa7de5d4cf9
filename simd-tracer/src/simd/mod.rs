//! Three-component vectors over the 8 ray lanes (`Vec3x8`, SoA `f32x8`)
//! for the packet-wide shading math, with lane-wise scalar twins in
//! `glam::Vec3` (every operation is checked lane by lane in the tests).
//!
//! NaN policy: plain IEEE arithmetic; [`Vec3x8::normalize`] of a zero vector
//! gives NaN lanes, as `glam::Vec3::normalize` does. Callers mask such lanes.

mod exp;
mod lanes;
pub use exp::{EXP_ARGUMENT_MIN, exp_nonpositive_x8};
pub use lanes::{LANES, LaneMask};

use glam::Vec3;
use std::ops::{Add, Mul, Neg, Sub};
use wide::bytemuck::cast;
use wide::{f32x8, u32x8};

/// Lane `i` is `table[index[i]]`: a lookup in a table of up to [`LANES`]
/// entries held in one register (one `vpermd` on AVX2). Indices must be
/// below [`LANES`].
#[inline(always)]
pub fn lookup_u32x8(table: u32x8, index: u32x8) -> u32x8 {
    debug_assert!(index.to_array().iter().all(|&i| (i as usize) < LANES));
    table.shuffle(index)
}

/// [`lookup_u32x8`] of `f32` entries (their bits move unchanged).
#[inline(always)]
pub fn lookup_f32x8(table: f32x8, index: u32x8) -> f32x8 {
    cast(lookup_u32x8(cast(table), index))
}

/// Eight 3-vectors, one per ray lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vec3x8 {
    /// x components.
    pub x: f32x8,
    /// y components.
    pub y: f32x8,
    /// z components.
    pub z: f32x8,
}

impl Vec3x8 {
    /// The zero vector in every lane.
    pub const ZERO: Self = Self {
        x: f32x8::ZERO,
        y: f32x8::ZERO,
        z: f32x8::ZERO,
    };

    /// From components.
    #[inline(always)]
    pub fn new(x: f32x8, y: f32x8, z: f32x8) -> Self {
        Self { x, y, z }
    }

    /// The same vector in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> Self {
        Self::new(f32x8::splat(v.x), f32x8::splat(v.y), f32x8::splat(v.z))
    }

    /// Lane `lane` is `f(lane)`.
    #[inline(always)]
    pub fn from_fn(mut f: impl FnMut(usize) -> Vec3) -> Self {
        let lanes: [Vec3; LANES] = core::array::from_fn(&mut f);
        Self::from_lanes(&lanes)
    }

    /// From eight vectors.
    #[inline(always)]
    pub fn from_lanes(lanes: &[Vec3; LANES]) -> Self {
        Self::new(
            f32x8::new(core::array::from_fn(|i| lanes[i].x)),
            f32x8::new(core::array::from_fn(|i| lanes[i].y)),
            f32x8::new(core::array::from_fn(|i| lanes[i].z)),
        )
    }

    /// From the SoA arrays of a ray packet.
    #[inline(always)]
    pub fn from_array(v: [f32x8; 3]) -> Self {
        Self::new(v[0], v[1], v[2])
    }

    /// As SoA arrays.
    #[inline(always)]
    pub fn to_array(self) -> [f32x8; 3] {
        [self.x, self.y, self.z]
    }

    /// Lane `lane`.
    #[inline(always)]
    pub fn lane(&self, lane: usize) -> Vec3 {
        Vec3::new(
            self.x.to_array()[lane],
            self.y.to_array()[lane],
            self.z.to_array()[lane],
        )
    }

    /// All lanes.
    #[inline(always)]
    pub fn to_lanes(&self) -> [Vec3; LANES] {
        let (x, y, z) = (self.x.to_array(), self.y.to_array(), self.z.to_array());
        core::array::from_fn(|i| Vec3::new(x[i], y[i], z[i]))
    }

    /// Dot product.
    #[inline(always)]
    pub fn dot(self, o: Self) -> f32x8 {
        self.x.mul_add(o.x, self.y.mul_add(o.y, self.z * o.z))
    }

    /// Cross product.
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }

    /// Squared length.
    #[inline(always)]
    pub fn length_squared(self) -> f32x8 {
        self.dot(self)
    }

    /// Length.
    #[inline(always)]
    pub fn length(self) -> f32x8 {
        self.length_squared().sqrt()
    }

    /// Unit vector (NaN lanes for zero vectors).
    #[inline(always)]
    pub fn normalize(self) -> Self {
        self * (f32x8::ONE / self.length())
    }

    /// Lane-wise `if mask { a } else { b }`.
    #[inline(always)]
    pub fn select(mask: f32x8, a: Self, b: Self) -> Self {
        Self::new(
            mask.select(a.x, b.x),
            mask.select(a.y, b.y),
            mask.select(a.z, b.z),
        )
    }

    /// Largest absolute component per lane.
    #[inline(always)]
    pub fn max_abs(self) -> f32x8 {
        self.x.abs().max(self.y.abs()).max(self.z.abs())
    }

    /// `self · s + o` per lane.
    #[inline(always)]
    pub fn mul_add(self, s: f32x8, o: Self) -> Self {
        Self::new(
            self.x.mul_add(s, o.x),
            self.y.mul_add(s, o.y),
            self.z.mul_add(s, o.z),
        )
    }
}

impl Add for Vec3x8 {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl Sub for Vec3x8 {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl Mul<f32x8> for Vec3x8 {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: f32x8) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}

impl Neg for Vec3x8 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}

/// An orthonormal basis around unit normals, lane-wise (Duff et al. 2017),
/// the twin of [`crate::shading::material::basis`].
#[inline(always)]
pub fn basis(n: Vec3x8) -> (Vec3x8, Vec3x8) {
    let sign = f32x8::ONE.copysign(n.z);
    let a = -f32x8::ONE / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3x8::new(f32x8::ONE + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3x8::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lanes() -> [Vec3; LANES] {
        core::array::from_fn(|i| {
            Vec3::new(
                i as f32 - 3.5,
                (i * i) as f32 * 0.1 - 1.0,
                0.3 * i as f32 + 0.1,
            )
        })
    }

    #[test]
    fn lookups_read_the_indexed_entry_bit_for_bit() {
        let table = [1.5, -0.0, f32::NAN, f32::INFINITY, 3.0, -2.25, 1e-40, 7.0];
        let mut rng = crate::sampling::rng::Rng::new(3, 9);
        for _ in 0..200 {
            let index: [u32; LANES] = core::array::from_fn(|_| rng.next_u32() % LANES as u32);
            let looked_up = lookup_f32x8(f32x8::new(table), u32x8::new(index)).to_array();
            let words = lookup_u32x8(u32x8::new(index), u32x8::new(index)).to_array();
            for lane in 0..LANES {
                let entry = table[index[lane] as usize];
                assert_eq!(looked_up[lane].to_bits(), entry.to_bits());
                assert_eq!(words[lane], index[index[lane] as usize]);
            }
        }
    }

    #[test]
    fn operations_match_glam_lane_by_lane() {
        let a = lanes();
        let mut b: [Vec3; LANES] = core::array::from_fn(|i| a[(i + 3) % LANES] * 0.7 + Vec3::X);
        // A negative zero z exercises the sign choice of the basis.
        b[0].z = -0.0;
        let (va, vb) = (Vec3x8::from_lanes(&a), Vec3x8::from_lanes(&b));
        let s = f32x8::new(core::array::from_fn(|i| i as f32 * 0.25 - 1.0));
        let mask = va.x.simd_ge(f32x8::ZERO);
        for i in 0..LANES {
            let close = |x: Vec3, y: Vec3| (x - y).length() <= 1e-5 * (1.0 + y.length());
            assert!(close((va + vb).lane(i), a[i] + b[i]));
            assert!(close((va - vb).lane(i), a[i] - b[i]));
            assert!(close((va * s).lane(i), a[i] * s.to_array()[i]));
            assert!(close((-va).lane(i), -a[i]));
            assert!(close(va.cross(vb).lane(i), a[i].cross(b[i])));
            assert!(close(va.normalize().lane(i), a[i].normalize()));
            assert!(close(
                va.mul_add(s, vb).lane(i),
                a[i] * s.to_array()[i] + b[i]
            ));
            assert!(
                (va.dot(vb).to_array()[i] - a[i].dot(b[i])).abs()
                    <= 1e-5 * (1.0 + a[i].length() * b[i].length())
            );
            assert!((va.length().to_array()[i] - a[i].length()).abs() <= 1e-5 * a[i].length());
            assert_eq!(va.max_abs().to_array()[i], a[i].abs().max_element());
            let chosen = Vec3x8::select(mask, va, vb).lane(i);
            assert_eq!(chosen, if a[i].x >= 0.0 { a[i] } else { b[i] });
            for (v, scalar) in [(va, a[i]), (vb, b[i])] {
                let (t, s2) = basis(v.normalize());
                let (tt, ss) = crate::shading::material::basis(scalar.normalize());
                assert!(close(t.lane(i), tt) && close(s2.lane(i), ss), "lane {i}");
            }
        }
        assert_eq!(Vec3x8::from_lanes(&a).to_lanes(), a);
        assert_eq!(Vec3x8::from_fn(|i| a[i]), va);
        assert_eq!(Vec3x8::splat(Vec3::ONE).lane(5), Vec3::ONE);
        assert_eq!(Vec3x8::from_array(va.to_array()), va);
    }
}
