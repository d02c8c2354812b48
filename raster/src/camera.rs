//! The pinhole camera: look-at placement, perspective projection with clip
//! depth in [0, 1] (right-handed view space looking down −z), and the mapping
//! from clip space to pixels (row 0 at the top, pixel centres at +0.5).

use glam::{Mat4, Vec3, Vec4};

#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
    pub near: f32,
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
        // View → clip, depth in [0, 1]: z_v = −near ↦ 0, z_v = −far ↦ w (1),
        // w = −z_v.
        let (n, f) = (self.near, self.far);
        let proj = Mat4::from_cols(
            Vec4::new(1.0 / (tan_y * aspect), 0.0, 0.0, 0.0),
            Vec4::new(0.0, 1.0 / tan_y, 0.0, 0.0),
            Vec4::new(0.0, 0.0, f / (n - f), -1.0),
            Vec4::new(0.0, 0.0, n * f / (n - f), 0.0),
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
