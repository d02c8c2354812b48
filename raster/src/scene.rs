//! A prepared scene: flat world-space arrays the passes read.

use crate::camera::Camera;
use glam::{Vec2, Vec3};
use specula_core::light::Light;
use specula_core::Material;

#[derive(Clone, Debug)]
pub struct SceneData {
    /// World-space vertex positions.
    pub positions: Vec<Vec3>,
    /// World-space unit vertex normals, one per position.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per position, or empty when no mesh has any.
    pub uvs: Vec<Vec2>,
    /// Vertex indices; a triangle's id is its index here.
    pub triangles: Vec<[u32; 3]>,
    /// Index into `materials`, one per triangle.
    pub tri_material: Vec<u32>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    /// Uniform environment radiance, lighting every surface and seen where
    /// no surface is.
    pub environment: Option<[f32; 3]>,
    /// Radiance of pixels no triangle covers when there is no environment.
    pub background: [f32; 3],
    pub camera: Camera,
}

impl SceneData {
    /// Checks the invariants the passes rely on (indices in range, array
    /// lengths agree); loaders call it once so kernels can trust the data.
    pub fn validate(&self) -> Result<(), String> {
        let nv = self.positions.len();
        if self.normals.len() != nv {
            return Err(format!("{} normals for {nv} positions", self.normals.len()));
        }
        if !self.uvs.is_empty() && self.uvs.len() != nv {
            return Err(format!("{} uvs for {nv} positions", self.uvs.len()));
        }
        if self.tri_material.len() != self.triangles.len() {
            return Err("one material index per triangle is required".into());
        }
        if self.triangles.len() >= crate::target::MISS as usize {
            return Err("too many triangles for 32-bit ids".into());
        }
        if let Some(t) = self
            .triangles
            .iter()
            .position(|t| t.iter().any(|&i| i as usize >= nv))
        {
            return Err(format!("triangle {t} indexes a vertex past the {nv} given"));
        }
        let nm = self.materials.len();
        if let Some(t) = self.tri_material.iter().position(|&m| m as usize >= nm) {
            return Err(format!(
                "triangle {t} uses material index past the {nm} given"
            ));
        }
        Ok(())
    }
}
