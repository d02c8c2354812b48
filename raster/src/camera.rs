//! The pinhole camera: look-at placement, perspective projection with
//! reversed clip depth (right-handed view space looking down −z; NDC depth 1
//! at the near plane, 0 at the far plane or at infinity), and the mapping
//! from clip space to pixels (row 0 at the top, pixel centres at +0.5).
//!
//! Why reversed: NDC depth is A + B/w. With the near plane at 1 it is about
//! near/w, a small number that f32 stores with full relative precision at
//! any distance. The conventional mapping (near at 0) stores 1 − near/w,
//! which rounds to 1 once near/w drops below 6e-8: with near = 1e-7 a floor
//! 2 m away landed exactly on the cleared far value and vanished.

use glam::{Mat4, Vec3, Vec4};

#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
    pub near: f32,
    /// May be `f32::INFINITY`: an infinite far plane.
    pub far: f32,
}

/// A camera bound to an image size.
#[derive(Clone, Debug)]
pub struct View {
    pub view_proj: Mat4,
    pub eye: Vec3,
    /// Unit camera basis: right, up (true up, orthogonal), forward.
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
    /// tan(fov/2)·aspect and tan(fov/2): the primary ray through NDC (nx, ny)
    /// is forward + right·nx·tan_x + up·ny·tan_y.
    pub tan_x: f32,
    pub tan_y: f32,
    pub width: f32,
    pub height: f32,
}

impl Camera {
    pub fn view(&self, width: u32, height: u32) -> View {
        let aspect = width as f32 / height as f32;
        let fov = self.fov_y_deg.to_radians();
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        let tan_y = (fov * 0.5).tan();
        // World → view: rows right, up, −forward (view space looks down −z).
        let view = Mat4::from_cols(
            Vec4::new(right.x, up.x, -forward.x, 0.0),
            Vec4::new(right.y, up.y, -forward.y, 0.0),
            Vec4::new(right.z, up.z, -forward.z, 0.0),
            Vec4::new(
                -right.dot(self.eye),
                -up.dot(self.eye),
                forward.dot(self.eye),
                1.0,
            ),
        );
        // View → clip with w = −z_v and z = A·w + B, so NDC depth z/w = A + B/w
        // is 1 at w = near and 0 at w = far: B = near·far/(far − near),
        // A = −near/(far − near); for an infinite far plane A = 0, B = near.
        // Computed in f64 so that near/far ratios like 1e-9 keep their digits.
        let (n, f) = (self.near as f64, self.far as f64);
        let (a, b) = if f.is_finite() {
            (-n / (f - n), n * f / (f - n))
        } else {
            (0.0, n)
        };
        let proj = Mat4::from_cols(
            Vec4::new(1.0 / (tan_y * aspect), 0.0, 0.0, 0.0),
            Vec4::new(0.0, 1.0 / tan_y, 0.0, 0.0),
            Vec4::new(0.0, 0.0, -a as f32, -1.0),
            Vec4::new(0.0, 0.0, b as f32, 0.0),
        );
        View {
            view_proj: proj * view,
            eye: self.eye,
            right,
            up,
            forward,
            tan_x: tan_y * aspect,
            tan_y,
            width: width as f32,
            height: height as f32,
        }
    }
}
