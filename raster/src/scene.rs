//! A prepared scene: flat world-space arrays the passes read.

use crate::camera::Camera;
use crate::geometry::{validate_passes, GeometryPass};
use crate::shader::Material;
use crate::shadow::ShadowSettings;
use glam::{Vec2, Vec3, Vec4};
use specula_core::light::Light;

#[derive(Clone, Debug)]
pub struct SceneData {
    /// World-space vertex positions.
    pub positions: Vec<Vec3>,
    /// World-space unit vertex normals, one per position.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per position, or empty when no mesh has any.
    pub uvs: Vec<Vec2>,
    /// Unit tangents (xyz, along increasing u, orthogonal to the normal) and
    /// handedness (w = ±1), one per position; empty when `uvs` is.
    pub tangents: Vec<Vec4>,
    /// Vertex colours (glTF's COLOR_0: linear RGBA, 1 where a mesh has
    /// none), one per position, or empty when no mesh has any.
    pub colors: Vec<Vec4>,
    /// Vertex indices; a triangle's id is its index here.
    pub triangles: Vec<[u32; 3]>,
    /// Index into `materials`, one per triangle.
    pub tri_material: Vec<u32>,
    pub materials: Vec<Material>,
    /// The geometry passes of a frame, in order (geometry.rs); loaders put
    /// [`GeometryPass::main`] here.
    pub geometry: Vec<GeometryPass>,
    pub lights: Vec<Light>,
    /// Shadow settings per light (`lights` order; `None`: no shadow), or
    /// empty when no light has shadows.
    pub shadows: Vec<Option<ShadowSettings>>,
    /// Uniform environment radiance, lighting every surface and seen where
    /// no surface is.
    pub environment: Option<[f32; 3]>,
    /// An environment map lighting every surface (and seen where no
    /// surface is when it is visible); `environment` is then `None`.
    pub env_map: Option<std::sync::Arc<crate::envmap::EnvMap>>,
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
        if self.tangents.len() != self.uvs.len() {
            return Err(format!(
                "{} tangents for {} uvs",
                self.tangents.len(),
                self.uvs.len()
            ));
        }
        if !self.colors.is_empty() && self.colors.len() != nv {
            return Err(format!(
                "{} vertex colours for {nv} positions",
                self.colors.len()
            ));
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
        validate_passes(&self.geometry, self.triangles.len(), nm)?;
        if !self.shadows.is_empty() && self.shadows.len() != self.lights.len() {
            return Err(format!(
                "{} shadow settings for {} lights",
                self.shadows.len(),
                self.lights.len()
            ));
        }
        for (k, s) in self.shadows.iter().enumerate() {
            if let Some(s) = s {
                s.check().map_err(|e| format!("light {}: {e}", k + 1))?;
            }
        }
        for m in &self.materials {
            m.shader
                .check_lights(&self.lights)
                .map_err(|e| format!("material {:?}: {e}", m.name))?;
        }
        Ok(())
    }

    /// Every material's texture maps sampled with `filter` from now on,
    /// whatever their own samplers say (`--texture-filter`).
    pub fn force_texture_filter(&mut self, filter: crate::texture::Filter) {
        for m in &mut self.materials {
            if let Some(shader) = m.shader.with_texture_filter(filter) {
                m.shader = shader;
            }
            if let Some(a) = &m.alpha {
                m.alpha = Some(std::sync::Arc::new(a.with_texture_filter(filter)));
            }
        }
    }
}

/// Per-vertex tangent frames from uvs \[Lengyel01\]: each triangle's ∂p/∂u
/// and ∂p/∂v, summed per vertex (area weighted), the tangent made
/// orthogonal to the normal; w = ±1 says whether (n × t) or its opposite
/// points along ∂p/∂v. Degenerate uv triangles contribute nothing; a vertex
/// left without a tangent gets any unit vector orthogonal to its normal.
pub fn compute_tangents(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: &[Vec2],
    triangles: &[[u32; 3]],
) -> Vec<Vec4> {
    if uvs.is_empty() {
        return Vec::new();
    }
    let mut du = vec![Vec3::ZERO; positions.len()];
    let mut dv = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| i as usize);
        let (e1, e2) = (positions[b] - positions[a], positions[c] - positions[a]);
        let (s1, s2) = (uvs[b] - uvs[a], uvs[c] - uvs[a]);
        let det = s1.x * s2.y - s2.x * s1.y;
        if det == 0.0 || !det.is_finite() {
            continue;
        }
        // Solve [e1 e2] = [∂p/∂u ∂p/∂v] [s1 s2]; scaled by det (area weight).
        let pu = e1 * s2.y - e2 * s1.y;
        let pv = e2 * s1.x - e1 * s2.x;
        let sign = det.signum();
        for i in [a, b, c] {
            du[i] += pu * sign;
            dv[i] += pv * sign;
        }
    }
    normals
        .iter()
        .zip(du.iter().zip(&dv))
        .map(|(n, (pu, pv))| {
            let t = (*pu - *n * n.dot(*pu))
                .try_normalize()
                .unwrap_or_else(|| n.any_orthonormal_vector());
            let w = if n.cross(t).dot(*pv) < 0.0 { -1.0 } else { 1.0 };
            t.extend(w)
        })
        .collect()
}
