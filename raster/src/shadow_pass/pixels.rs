//! Every drawn pixel's surface point, normal and one light's (or the
//! environment's sun's) shadow factor, as the shading pass sees them: for
//! tests and tools that compare the maps with exact visibility.

use crate::scene::SceneData;
use crate::shadow::LightShadow;
use crate::target::Target;
use crate::visibility::Visibility;
use glam::Vec3;

/// A drawn pixel's surface and one light's shadow factor there
/// ([`pixel_shadows`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelShadow {
    /// World position and unit shading normal at the pixel centre.
    pub p: Vec3,
    pub n: Vec3,
    /// The light's shadow factor (what the light loop multiplies by).
    pub factor: f32,
}

/// Every pixel of `target` (row-major) as the shading pass sees it for
/// light `k`: its surface point and normal, and the light's shadow factor
/// there; `None` where no triangle is drawn. Empty when light `k` has no
/// shadow map in `v`. For tests and tools that compare the maps with
/// exact visibility.
pub fn pixel_shadows(
    scene: &SceneData,
    target: &Target,
    v: &Visibility,
    k: usize,
) -> Vec<Option<PixelShadow>> {
    match v.shadows.light(k) {
        Some(light) => pixels_of(scene, target, v, light),
        None => Vec::new(),
    }
}

/// [`pixel_shadows`] for the sun taken out of the scene's environment map;
/// empty when the sun has no shadow map in `v`.
pub fn pixel_sun_shadows(
    scene: &SceneData,
    target: &Target,
    v: &Visibility,
) -> Vec<Option<PixelShadow>> {
    match v.shadows.sun() {
        Some(sun) => pixels_of(scene, target, v, sun),
        None => Vec::new(),
    }
}

/// Every pixel's surface and `light`'s factor there.
fn pixels_of(
    scene: &SceneData,
    target: &Target,
    v: &Visibility,
    light: &LightShadow,
) -> Vec<Option<PixelShadow>> {
    let ctx = crate::resolve::ResolveContext::new(scene, &v.planes, &v.view);
    let mut out = Vec::with_capacity(target.pixel_count());
    for y in 0..target.height {
        for x in 0..target.width {
            let id = v.vis.id[target.index(x, y)];
            if id == crate::target::MISS {
                out.push(None);
                continue;
            }
            let tris = crate::resolve::PacketTris::new(&[id], 1, &ctx);
            let f = ctx.resolve::<f32>(x, y, &tris);
            let (p, n) = (
                Vec3::new(f.p.x, f.p.y, f.p.z),
                Vec3::new(f.n.x, f.n.y, f.n.z),
            );
            out.push(Some(PixelShadow {
                p,
                n,
                factor: light.visibility(p, n),
            }));
        }
    }
    out
}
