//! A prepared scene: flat world-space arrays the passes read.
//!
//! A loader assembles [`SceneParts`] and hands them to [`SceneData::new`],
//! which checks every invariant the passes rely on; a `SceneData` is
//! therefore valid by construction, and its fields can be read (through
//! `Deref`) but not changed. To change a scene, take its parts back
//! ([`SceneData::into_parts`]) and build it again.

use crate::alpha::{AlphaMode, MaterialAlpha};
use crate::camera::Camera;
use crate::closed::ClosedSolids;
use crate::geometry::{validate_passes, GeometryPass, PassError, SceneMesh};
use crate::shader::SurfaceShader;
use crate::shadow::{ShadowSettings, ShadowSettingsError};
use glam::{Vec2, Vec3, Vec4};
use specula_core::light::Light;
use std::sync::Arc;

/// What a scene is made of, as a loader assembles it: not yet checked.
#[derive(Clone, Debug)]
pub struct SceneParts {
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
    pub env_map: Option<Arc<crate::envmap::EnvMap>>,
    /// Shadow settings of the sun taken out of `env_map`
    /// ([`crate::envmap::EnvMap::sun_world`]), shadowed as a directional
    /// light; `None`: unshadowed. Needs a map with a sun.
    pub sun_shadows: Option<ShadowSettings>,
    /// Radiance of pixels no triangle covers when there is no environment.
    pub(crate) background: [f32; 3],
    pub camera: Camera,
}

impl SceneParts {
    /// No geometry, lights or environment: the start of a loader's scene.
    pub fn empty(camera: Camera, background: [f32; 3]) -> SceneParts {
        SceneParts {
            positions: Vec::new(),
            normals: Vec::new(),
            uvs: Vec::new(),
            tangents: Vec::new(),
            colors: Vec::new(),
            triangles: Vec::new(),
            tri_material: Vec::new(),
            materials: Vec::new(),
            geometry: Vec::new(),
            lights: Vec::new(),
            shadows: Vec::new(),
            environment: None,
            env_map: None,
            sun_shadows: None,
            background,
            camera,
        }
    }

    /// The mesh a vertex stage reads.
    pub fn mesh(&self) -> SceneMesh<'_> {
        SceneMesh {
            positions: &self.positions,
            normals: &self.normals,
            triangles: &self.triangles,
        }
    }
}

/// A material as the passes see it: a shader plus the properties the
/// geometry passes need.
#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    pub shader: Arc<dyn SurfaceShader>,
    /// Back faces are drawn (and shaded with the normal flipped toward the
    /// viewer) instead of culled by a pass with [`crate::geometry::Cull::Back`].
    pub double_sided: bool,
    /// Masked or blended (glTF's alphaMode MASK and BLEND; alpha.rs);
    /// `None`: opaque.
    pub(crate) alpha: Option<Arc<MaterialAlpha>>,
}

impl Material {
    pub fn new(name: &str, shader: impl SurfaceShader, double_sided: bool) -> Material {
        Material {
            name: name.to_string(),
            shader: Arc::new(shader),
            double_sided,
            alpha: None,
        }
    }

    /// This material masked or blended by `alpha`. A mask whose alpha is
    /// a constant at or above its cutoff covers every sample: the material
    /// stays opaque, so its triangles skip the per-sample test.
    pub fn with_alpha(mut self, alpha: MaterialAlpha) -> Material {
        if let (AlphaMode::Mask { cutoff }, Some(a)) = (alpha.mode, alpha.constant()) {
            if a >= cutoff {
                return self;
            }
        }
        self.alpha = Some(Arc::new(alpha));
        self
    }

    /// How alpha decides this material's coverage; `None`: opaque.
    pub fn alpha_mode(&self) -> Option<AlphaMode> {
        self.alpha.as_ref().map(|a| a.mode)
    }
}

/// A scene the passes can trust: made only by [`SceneData::new`], which
/// checks its parts. Its parts are read through `Deref`.
#[derive(Clone, Debug)]
pub struct SceneData {
    parts: SceneParts,
    /// The mesh's closed solids, when a light casts shadows (their depth
    /// passes skip the solids' back faces).
    solids: Option<Arc<ClosedSolids>>,
}

/// Why [`SceneData::new`] refused a scene's parts.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SceneDataError {
    #[error("{normals} normals for {positions} positions")]
    Normals { normals: usize, positions: usize },
    #[error("{uvs} uvs for {positions} positions")]
    Uvs { uvs: usize, positions: usize },
    #[error("{tangents} tangents for {uvs} uvs")]
    Tangents { tangents: usize, uvs: usize },
    #[error("{colors} vertex colours for {positions} positions")]
    Colors { colors: usize, positions: usize },
    #[error("one material index per triangle is required")]
    MaterialPerTriangle,
    #[error("too many triangles for 32-bit ids")]
    TooManyTriangles,
    #[error("triangle {triangle} indexes a vertex past the {vertices} given")]
    VertexIndex { triangle: usize, vertices: usize },
    #[error("triangle {triangle} uses material index past the {materials} given")]
    MaterialIndex { triangle: usize, materials: usize },
    #[error(transparent)]
    Passes(#[from] PassError),
    #[error("{settings} shadow settings for {lights} lights")]
    ShadowCount { settings: usize, lights: usize },
    /// A light's shadow settings refused; `light` counts from 1.
    #[error("light {light}: {source}")]
    Shadow {
        light: usize,
        source: ShadowSettingsError,
    },
    /// Sun shadows without an environment map, or with a map that has no
    /// sun taken out of it.
    #[error("sun shadows need an environment map with a sun (a compact bright source taken out of the map)")]
    SunShadowsWithoutSun,
    /// The sun's shadow settings refused.
    #[error("sun: {0}")]
    SunShadow(#[source] ShadowSettingsError),
    /// A material whose shader cannot shade the scene's lights.
    #[error("material {name:?}: {source}")]
    Lights {
        name: String,
        source: crate::shader::LightRefusal,
    },
}

impl std::ops::Deref for SceneData {
    type Target = SceneParts;
    fn deref(&self) -> &SceneParts {
        &self.parts
    }
}

impl SceneData {
    /// The scene of `parts`, once they hold the invariants the passes rely
    /// on (indices in range, array lengths agree, passes, shadow settings
    /// and the materials' lights accepted).
    pub fn new(parts: SceneParts) -> Result<SceneData, SceneDataError> {
        check(&parts)?;
        let shadows = parts.shadows.iter().any(Option::is_some) || parts.sun_shadows.is_some();
        let solids = shadows.then(|| {
            let opaque: Vec<bool> = parts.materials.iter().map(|m| m.alpha.is_none()).collect();
            Arc::new(ClosedSolids::of(
                &parts.positions,
                &parts.triangles,
                &parts.tri_material,
                &opaque,
            ))
        });
        Ok(SceneData { parts, solids })
    }

    /// The mesh's closed solids: made when some light casts shadows.
    pub fn solids(&self) -> Option<&ClosedSolids> {
        self.solids.as_deref()
    }

    /// The parts back, to change and build again.
    pub fn into_parts(self) -> SceneParts {
        self.parts
    }

    /// Every material's texture maps sampled with `filter` from now on,
    /// whatever their own samplers say (`--texture-filter`). The scene
    /// stays valid: only how its textures are filtered changes.
    pub fn force_texture_filter(&mut self, filter: crate::texture::Filter) {
        for m in &mut self.parts.materials {
            if let Some(shader) = m.shader.with_texture_filter(filter) {
                m.shader = shader;
            }
            if let Some(a) = &m.alpha {
                m.alpha = Some(Arc::new(a.with_texture_filter(filter)));
            }
        }
    }
}

/// The checks of [`SceneData::new`].
fn check(s: &SceneParts) -> Result<(), SceneDataError> {
    let nv = s.positions.len();
    if s.normals.len() != nv {
        return Err(SceneDataError::Normals {
            normals: s.normals.len(),
            positions: nv,
        });
    }
    if !s.uvs.is_empty() && s.uvs.len() != nv {
        return Err(SceneDataError::Uvs {
            uvs: s.uvs.len(),
            positions: nv,
        });
    }
    if s.tangents.len() != s.uvs.len() {
        return Err(SceneDataError::Tangents {
            tangents: s.tangents.len(),
            uvs: s.uvs.len(),
        });
    }
    if !s.colors.is_empty() && s.colors.len() != nv {
        return Err(SceneDataError::Colors {
            colors: s.colors.len(),
            positions: nv,
        });
    }
    if s.tri_material.len() != s.triangles.len() {
        return Err(SceneDataError::MaterialPerTriangle);
    }
    if s.triangles.len() >= crate::target::MISS as usize {
        return Err(SceneDataError::TooManyTriangles);
    }
    if let Some(t) = s
        .triangles
        .iter()
        .position(|t| t.iter().any(|&i| i as usize >= nv))
    {
        return Err(SceneDataError::VertexIndex {
            triangle: t,
            vertices: nv,
        });
    }
    let nm = s.materials.len();
    if let Some(t) = s.tri_material.iter().position(|&m| m as usize >= nm) {
        return Err(SceneDataError::MaterialIndex {
            triangle: t,
            materials: nm,
        });
    }
    validate_passes(&s.geometry, s.triangles.len(), nm)?;
    if !s.shadows.is_empty() && s.shadows.len() != s.lights.len() {
        return Err(SceneDataError::ShadowCount {
            settings: s.shadows.len(),
            lights: s.lights.len(),
        });
    }
    for (k, settings) in s.shadows.iter().enumerate() {
        if let Some(settings) = settings {
            settings.check().map_err(|source| SceneDataError::Shadow {
                light: k + 1,
                source,
            })?;
        }
    }
    if let Some(settings) = &s.sun_shadows {
        if s.env_map.as_ref().and_then(|m| m.sun_world()).is_none() {
            return Err(SceneDataError::SunShadowsWithoutSun);
        }
        settings.check().map_err(SceneDataError::SunShadow)?;
    }
    for m in &s.materials {
        m.shader
            .check_lights(&s.lights)
            .map_err(|source| SceneDataError::Lights {
                name: m.name.clone(),
                source,
            })?;
    }
    Ok(())
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
