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
use crate::scene::SceneData;
use glam::Vec4;
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

/// Where a pass puts the scene's vertices.
pub trait VertexStage: Debug + Send + Sync {
    /// Clip-space position of every scene vertex (`scene.positions` order)
    /// into `out`, which arrives cleared.
    fn clip_positions(&self, scene: &SceneData, view: &View, out: &mut Vec<[f32; 4]>);
}

/// The camera's view-projection of the world-space positions.
#[derive(Clone, Copy, Debug, Default)]
pub struct Project;

impl VertexStage for Project {
    fn clip_positions(&self, scene: &SceneData, view: &View, out: &mut Vec<[f32; 4]>) {
        let m = view.view_proj;
        scene
            .positions
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

/// Checks a pass list against the scene: triangle ranges in bounds, id
/// ranges disjoint and below the miss id, override materials present.
pub fn validate_passes(
    passes: &[GeometryPass],
    triangles: usize,
    materials: usize,
) -> Result<(), String> {
    for (i, p) in passes.iter().enumerate() {
        let name = &p.name;
        if p.triangles.start > p.triangles.end || p.triangles.end as usize > triangles {
            return Err(format!(
                "geometry pass {i} ({name}): triangles {:?} outside the scene's {triangles}",
                p.triangles
            ));
        }
        if p.ids().end > crate::target::MISS as u64 {
            return Err(format!(
                "geometry pass {i} ({name}): ids past the 32-bit range"
            ));
        }
        if let Some(m) = p.material {
            if m as usize >= materials {
                return Err(format!(
                    "geometry pass {i} ({name}): material index {m} past the {materials} given"
                ));
            }
        }
        for (j, q) in passes[..i].iter().enumerate() {
            let (a, b) = (p.ids(), q.ids());
            if a.start < b.end && b.start < a.end {
                return Err(format!(
                    "geometry passes {j} ({}) and {i} ({name}) write overlapping ids {b:?} and {a:?}",
                    q.name
                ));
            }
        }
    }
    Ok(())
}
