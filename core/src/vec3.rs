//! `V3<R>`: a structure-of-arrays 3-vector over any lane type. With `R = f32x8`
//! it holds 8 vectors, one per lane (x of all lanes, then y, then z), which is
//! the layout the shading kernels want. Also used for linear RGB.

use crate::real::Real;
use core::ops::{Add, AddAssign, Mul, Neg, Sub};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<R> {
    pub x: R,
    pub y: R,
    pub z: R,
}

/// Linear RGB radiometric quantity, one colour per lane.
pub type Rgb<R> = V3<R>;

impl<R: Real> V3<R> {
    #[inline(always)]
    pub fn new(x: R, y: R, z: R) -> Self {
        V3 { x, y, z }
    }
    #[inline(always)]
    pub fn splat(v: R) -> Self {
        V3 { x: v, y: v, z: v }
    }
    /// The same vector in every lane.
    #[inline(always)]
    pub fn from_f32(v: [f32; 3]) -> Self {
        V3 {
            x: R::splat(v[0] as f64),
            y: R::splat(v[1] as f64),
            z: R::splat(v[2] as f64),
        }
    }
    #[inline(always)]
    pub fn zero() -> Self {
        Self::splat(R::ZERO)
    }
    /// Lane `i`, in f64.
    #[inline(always)]
    pub fn lane(self, i: usize) -> V3<f64> {
        V3 {
            x: self.x.lane(i),
            y: self.y.lane(i),
            z: self.z.lane(i),
        }
    }
    #[inline(always)]
    pub fn dot(self, o: Self) -> R {
        self.x.mul_add(o.x, self.y.mul_add(o.y, self.z * o.z))
    }
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        V3 {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }
    #[inline(always)]
    pub fn length_squared(self) -> R {
        self.dot(self)
    }
    #[inline(always)]
    pub fn length(self) -> R {
        self.dot(self).sqrt()
    }
    /// Unit vector (through [`Real::rsqrt`]: within 3e-7 of unit length).
    /// A zero or tiny vector gives NaN lanes; callers that can see one
    /// (interpolated normals that cancel) use [`V3::normalize_or`].
    #[inline(always)]
    pub fn normalize(self) -> Self {
        self * self.length_squared().rsqrt()
    }
    /// Unit vector, or `fallback` in lanes whose squared length is not a
    /// finite normal number above 1e-30 (where `rsqrt` would not be).
    #[inline(always)]
    pub fn normalize_or(self, fallback: Self) -> Self {
        let len2 = self.length_squared();
        let ok = len2.gt(R::splat(1e-30)) & len2.is_finite();
        let n = self * len2.rsqrt();
        Self::select(ok, n, fallback)
    }
    /// Component-wise product (colour times colour).
    #[inline(always)]
    pub fn mul_elem(self, o: Self) -> Self {
        V3 {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }
    /// `self * o + acc` component by component (colour times colour,
    /// accumulated), fused.
    #[inline(always)]
    pub fn mul_elem_add(self, o: Self, acc: Self) -> Self {
        V3 {
            x: self.x.mul_add(o.x, acc.x),
            y: self.y.mul_add(o.y, acc.y),
            z: self.z.mul_add(o.z, acc.z),
        }
    }
    /// `self * s + acc`, component-wise fused.
    #[inline(always)]
    pub fn mul_add(self, s: R, acc: Self) -> Self {
        V3 {
            x: self.x.mul_add(s, acc.x),
            y: self.y.mul_add(s, acc.y),
            z: self.z.mul_add(s, acc.z),
        }
    }
    #[inline(always)]
    pub fn select(m: R::Mask, a: Self, b: Self) -> Self {
        V3 {
            x: R::select(m, a.x, b.x),
            y: R::select(m, a.y, b.y),
            z: R::select(m, a.z, b.z),
        }
    }
    /// Linear interpolation `a + (b - a) t`, per component.
    #[inline(always)]
    pub(crate) fn lerp(a: Self, b: Self, t: R) -> Self {
        V3 {
            x: (b.x - a.x).mul_add(t, a.x),
            y: (b.y - a.y).mul_add(t, a.y),
            z: (b.z - a.z).mul_add(t, a.z),
        }
    }
}

impl<R: Real> Add for V3<R> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl<R: Real> AddAssign for V3<R> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl<R: Real> Sub for V3<R> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl<R: Real> Mul<R> for V3<R> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: R) -> Self {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

impl<R: Real> Neg for V3<R> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        V3 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}
