//! Geometry passes: what draws into the visibility buffer.
//!
//! A frame runs the scene's geometry passes in order into one visibility
//! buffer (depth-tested against each other), then shades it. Each pass has
//! its own vertex stage (clip-space positions of the scene's vertices), cull
//! mode, source triangles and id range: source triangle i of the pass writes
//! id `id_base + i`, so the shading pass can tell the passes apart and shade
//! a pass's pixels with its own material (an outline pass drawing extruded
//! back faces in the outline colour, say). The default is one pass: every
//! triangle, projected by the camera, back faces culled except where a
//! material is double-sided, ids = triangle indices.

use crate::camera::View;
use glam::{Vec3, Vec4};
use rayon::prelude::*;
use std::fmt::Debug;
use std::ops::Range;
use std::sync::Arc;

/// Which faces a pass skips. Front faces are counter-clockwise on screen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Cull {
    /// Skip back faces, except triangles whose material is double-sided.
    #[default]
    Back,
    /// Skip front faces: draw back faces only (shaded with their normal
    /// flipped toward the viewer).
    Front,
    /// Draw both sides.
    None,
}

/// What a frame tells the stages that draw it: everything a stage may
/// depend on besides the scene and its own construction, handed to it per
/// frame rather than set on it from outside.
#[derive(Clone, Copy, Debug)]
pub struct FrameContext<'a> {
    /// The camera's view of this frame, at the sample resolution.
    pub view: &'a View,
    /// Samples per output pixel along each axis (widths given in output
    /// pixels are this many samples).
    pub ssaa: u32,
}

/// The scene's mesh as a vertex stage reads it: the world-space vertex
/// arrays and the triangles that index them
/// ([`SceneParts::mesh`](crate::scene::SceneParts::mesh)). A stage sees
/// the geometry alone, not the materials or lights.
#[derive(Clone, Copy, Debug)]
pub struct SceneMesh<'a> {
    pub positions: &'a [Vec3],
    /// Unit vertex normals, one per position.
    pub normals: &'a [Vec3],
    pub triangles: &'a [[u32; 3]],
}

/// Where a pass puts the scene's vertices.
///
/// The scene holds each stage as built (`GeometryPass::vertex`, shared by
/// the passes that use it); frames run their own instance of it
/// ([`VertexStage::instance`]), kept with the frame's visibility buffers,
/// which may keep what it likes from frame to frame in its own fields.
pub trait VertexStage: Debug + Send + Sync {
    /// A stage for a run of frames: the same construction, none of an
    /// earlier frame's state.
    fn instance(&self) -> Box<dyn VertexStage>;

    /// Clip-space position of every scene vertex (`mesh.positions` order)
    /// into `out`, which arrives cleared.
    fn clip_positions(&mut self, frame: &FrameContext, mesh: &SceneMesh, out: &mut Vec<[f32; 4]>);

    /// Right after `clip_positions` for a frame's view: whether source
    /// triangles `triangles`, drawn from those positions by a pass that
    /// follows the scene's main pass ([`GeometryPass::main`]), can write
    /// no pixel, so the frame may skip the pass. A stage answers `true`
    /// only where it has shown that; the default never does.
    fn hidden(&self, _triangles: Range<u32>) -> bool {
        false
    }

    /// Right after `clip_positions` for a frame's view: per source
    /// triangle t (bit t % 64 of word t / 64), set where the stage has
    /// shown that setup, given those positions and `Cull::Front`, skips
    /// the triangle as culled by its facing
    /// ([`crate::setup::front_face_shown`]). A `Cull::Front` pass skips
    /// such triangles without setting them up (same pixels, same counts).
    /// The default shows none.
    fn front_faces(&self) -> Option<Arc<Vec<u64>>> {
        None
    }
}

/// Bits of triangles `t..t + 4` in a [`VertexStage::front_faces`] mask
/// (bit k for triangle t + k; 0 past its end).
#[inline(always)]
pub(crate) fn mask_bits4(mask: &[u64], t: usize) -> u32 {
    let (word, off) = (t / 64, t % 64);
    let lo = mask.get(word).map_or(0, |w| w >> off);
    let hi = match off {
        61..=63 => mask.get(word + 1).map_or(0, |w| w << (64 - off)),
        _ => 0,
    };
    ((lo | hi) & 0xF) as u32
}

/// The camera's view-projection of the world-space positions.
#[derive(Clone, Copy, Debug, Default)]
pub struct Project;

impl VertexStage for Project {
    fn instance(&self) -> Box<dyn VertexStage> {
        Box::new(Project)
    }

    fn clip_positions(&mut self, frame: &FrameContext, mesh: &SceneMesh, out: &mut Vec<[f32; 4]>) {
        let m = frame.view.view_proj;
        mesh.positions
            .par_iter()
            .with_min_len(4096)
            .map(|p| (m * Vec4::from((*p, 1.0))).to_array())
            .collect_into_vec(out);
    }
}

#[derive(Clone, Debug)]
pub struct GeometryPass {
    /// For stats and messages.
    pub name: String,
    pub vertex: Arc<dyn VertexStage>,
    pub cull: Cull,
    /// Source triangles drawn (indices into `scene.triangles`).
    pub triangles: Range<u32>,
    /// Source triangle i writes id `id_base + i`.
    pub id_base: u32,
    /// Material index shading this pass's pixels; `None`: each triangle's own.
    pub material: Option<u32>,
}

impl GeometryPass {
    /// The default pass over `triangle_count` triangles (module docs).
    pub fn main(triangle_count: usize) -> GeometryPass {
        GeometryPass {
            name: "main".into(),
            vertex: Arc::new(Project),
            cull: Cull::Back,
            triangles: 0..triangle_count as u32,
            id_base: 0,
            material: None,
        }
    }

    /// The ids this pass writes.
    pub fn ids(&self) -> Range<u64> {
        let b = self.id_base as u64;
        b + self.triangles.start as u64..b + self.triangles.end as u64
    }
}

/// Why [`crate::SceneData::new`] refused a scene's geometry passes; `pass`
/// counts from 0, and each pass is named as its `name` says.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PassError {
    #[error("geometry pass {pass} ({name}): triangles {triangles:?} outside the scene's {scene}")]
    Triangles {
        pass: usize,
        name: String,
        triangles: Range<u32>,
        scene: usize,
    },
    #[error("geometry pass {pass} ({name}): ids past the 32-bit range")]
    Ids { pass: usize, name: String },
    #[error("geometry pass {pass} ({name}): material index {material} past the {materials} given")]
    Material {
        pass: usize,
        name: String,
        material: u32,
        materials: usize,
    },
    #[error("geometry passes {first} ({first_name}) and {second} ({second_name}) write overlapping ids {first_ids:?} and {second_ids:?}")]
    Overlap {
        first: usize,
        first_name: String,
        first_ids: Range<u64>,
        second: usize,
        second_name: String,
        second_ids: Range<u64>,
    },
}

/// Checks a pass list against the scene: triangle ranges in bounds, id
/// ranges disjoint and below the miss id, override materials present.
pub(crate) fn validate_passes(
    passes: &[GeometryPass],
    triangles: usize,
    materials: usize,
) -> Result<(), PassError> {
    for (i, p) in passes.iter().enumerate() {
        let name = || p.name.clone();
        if p.triangles.start > p.triangles.end || p.triangles.end as usize > triangles {
            return Err(PassError::Triangles {
                pass: i,
                name: name(),
                triangles: p.triangles.clone(),
                scene: triangles,
            });
        }
        if p.ids().end > crate::target::MISS as u64 {
            return Err(PassError::Ids {
                pass: i,
                name: name(),
            });
        }
        if let Some(m) = p.material {
            if m as usize >= materials {
                return Err(PassError::Material {
                    pass: i,
                    name: name(),
                    material: m,
                    materials,
                });
            }
        }
        for (j, q) in passes[..i].iter().enumerate() {
            let (a, b) = (p.ids(), q.ids());
            if a.start < b.end && b.start < a.end {
                return Err(PassError::Overlap {
                    first: j,
                    first_name: q.name.clone(),
                    first_ids: b,
                    second: i,
                    second_name: name(),
                    second_ids: a,
                });
            }
        }
    }
    Ok(())
}

/// Visibility-buffer id → (source triangle, material), from the passes'
/// id ranges; built once per frame so the per-packet look-up scans a few
/// small entries (usually one) instead of the pass list.
#[derive(Clone, Debug, Default)]
pub struct IdMap {
    ranges: Vec<IdRange>,
    /// One range whose ids are the triangle indices, no override: the
    /// default single pass, answered without scanning.
    identity: bool,
}

#[derive(Clone, Copy, Debug)]
struct IdRange {
    start: u32,
    end: u32,
    id_base: u32,
    /// Override material, or `u32::MAX` for each triangle's own.
    material: u32,
}

impl IdMap {
    /// From passes that `validate_passes` accepted.
    pub fn new(passes: &[GeometryPass]) -> IdMap {
        let ranges: Vec<IdRange> = passes
            .iter()
            .filter(|p| !p.triangles.is_empty())
            .map(|p| IdRange {
                start: p.ids().start as u32,
                end: p.ids().end as u32,
                id_base: p.id_base,
                material: p.material.unwrap_or(u32::MAX),
            })
            .collect();
        let identity = matches!(ranges.as_slice(), [r] if r.id_base == 0 && r.material == u32::MAX);
        IdMap { ranges, identity }
    }

    /// Ids are the scene's triangle indices (one pass, no override).
    pub(crate) fn is_identity(&self) -> bool {
        self.identity
    }

    /// The source triangle and material of `id`, an id some pass wrote.
    #[inline(always)]
    pub fn look_up(&self, id: u32, tri_material: &[u32]) -> (u32, u32) {
        if self.identity {
            return (id, tri_material[id as usize]);
        }
        for r in &self.ranges {
            if id >= r.start && id < r.end {
                let tri = id - r.id_base;
                let m = if r.material == u32::MAX {
                    tri_material[tri as usize]
                } else {
                    r.material
                };
                return (tri, m);
            }
        }
        // Unreachable for ids from the visibility buffer; a finite answer
        // rather than a panic in per-pixel code.
        (0, tri_material.first().copied().unwrap_or(0))
    }
}
