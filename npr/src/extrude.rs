//! Outline by geometry: a second geometry pass draws the scene's back
//! faces pushed outward along their vertex normals, in the outline
//! colour; the front faces of the main pass then cover its inside (the
//! depth test decides, so the passes' order only matters for ties), and
//! what stays visible is a ring around each silhouette.
//!
//! The push is made in clip space so the ring has a constant width in
//! pixels whatever the distance: with p the clip position and n = M·(n, 0)
//! the clip-space normal, the screen direction of the normal is
//! n.xy − (p.xy / p.w)·n.w (the derivative of p.xy / p.w along n), taken
//! to pixels (× viewport / 2) and normalized; the vertex moves `width`
//! pixels that way: p.xy += dir_ndc · p.w. Vertices at or behind the eye
//! (p.w ≤ 0) or whose normal points along the view ray stay put.
//!
//! Meshes with split normals (a cube's 24 vertices) would crack at the
//! corners, each face pushed along its own normal; the pass pushes along
//! smoothed normals instead: every vertex takes the normalized sum of the
//! normals of all vertices at the same position, so copies of a corner
//! move together and the pushed shell stays closed.
//!
//! The width is in output pixels; the renderer tells the stage its
//! supersampling ([`Extrude::set_ssaa`]) so the ring is `width × ssaa`
//! samples wide and `width` pixels after the resolve.

use glam::{Vec3, Vec4};
use rayon::prelude::*;
use specula_raster::camera::View;
use specula_raster::geometry::{Cull, GeometryPass, VertexStage};
use specula_raster::SceneData;
use std::collections::HashMap;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

/// The vertex stage of an extrusion pass.
#[derive(Debug)]
pub struct Extrude {
    /// Ring width in output pixels.
    pub width: f32,
    ssaa: AtomicU32,
    /// Smoothed unit normal per scene vertex (module docs).
    smooth: Vec<Vec3>,
}

impl Extrude {
    pub fn new(scene: &SceneData, width: f32) -> Extrude {
        Extrude {
            width,
            ssaa: AtomicU32::new(1),
            smooth: smooth_normals(&scene.positions, &scene.normals),
        }
    }

    /// Supersampling of the frames to come: the push is `width × ssaa`
    /// samples.
    pub fn set_ssaa(&self, ssaa: u32) {
        self.ssaa.store(ssaa.max(1), Ordering::Relaxed);
    }

    pub fn smoothed_normals(&self) -> &[Vec3] {
        &self.smooth
    }
}

/// Per vertex, the normalized sum of the normals of every vertex at the
/// same position (bit-equal coordinates, −0 = +0); a sum that cancels
/// keeps the vertex's own normal.
pub fn smooth_normals(positions: &[Vec3], normals: &[Vec3]) -> Vec<Vec3> {
    let key = |p: Vec3| p.to_array().map(|c| (c + 0.0).to_bits());
    let mut sums: HashMap<[u32; 3], Vec3> = HashMap::with_capacity(positions.len());
    for (p, n) in positions.iter().zip(normals) {
        *sums.entry(key(*p)).or_insert(Vec3::ZERO) += *n;
    }
    positions
        .iter()
        .zip(normals)
        .map(|(p, n)| sums[&key(*p)].try_normalize().unwrap_or(*n))
        .collect()
}

impl VertexStage for Extrude {
    fn clip_positions(&self, scene: &SceneData, view: &View, out: &mut Vec<[f32; 4]>) {
        let m = view.view_proj;
        let px = self.width * self.ssaa.load(Ordering::Relaxed) as f32;
        let (hw, hh) = (view.width * 0.5, view.height * 0.5);
        scene
            .positions
            .par_iter()
            .zip(self.smooth.par_iter())
            .with_min_len(4096)
            .map(|(p, n)| {
                let c = m * Vec4::from((*p, 1.0));
                let nc = m * Vec4::from((*n, 0.0));
                if c.w <= 0.0 {
                    return c.to_array();
                }
                // Screen direction of the normal, in pixels.
                let dx = (nc.x - c.x / c.w * nc.w) * hw;
                let dy = (nc.y - c.y / c.w * nc.w) * hh;
                let len = (dx * dx + dy * dy).sqrt();
                if !(len > 1e-12 && len.is_finite()) {
                    return c.to_array();
                }
                let (ox, oy) = (dx / len * px / hw, dy / len * px / hh);
                [c.x + ox * c.w, c.y + oy * c.w, c.z, c.w]
            })
            .collect_into_vec(out);
    }
}

/// The geometry passes of one extrusion outline over the triangles whose
/// material `selected` accepts: one pass per run of consecutive selected
/// triangles (a pass draws a range), back faces only (`Cull::Front`),
/// shaded by `material`, ids from `id_base` (triangle i writes
/// `id_base + i`).
pub fn extrusion_passes(
    scene: &SceneData,
    stage: Arc<Extrude>,
    material: u32,
    id_base: u32,
    selected: &dyn Fn(u32) -> bool,
) -> Vec<GeometryPass> {
    let mut passes = Vec::new();
    let n = scene.triangles.len() as u32;
    let mut i = 0;
    while i < n {
        if !selected(scene.tri_material[i as usize]) {
            i += 1;
            continue;
        }
        let start = i;
        while i < n && selected(scene.tri_material[i as usize]) {
            i += 1;
        }
        passes.push(GeometryPass {
            name: "outline-extrusion".into(),
            vertex: stage.clone(),
            cull: Cull::Front,
            triangles: start..i,
            id_base,
            material: Some(material),
        });
    }
    passes
}
