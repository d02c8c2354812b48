//! Primary visibility by Intel Embree 3 (Debian's `libembree-dev`, through
//! the raw `embree::sys` bindings): the independent reference the
//! rasterizer's visibility buffer is checked against, and the CPU ray
//! tracer its speed is compared with.
//!
//! One ray per pixel through the pixel centre with exactly the camera model
//! of the rasterizer (README "Conventions"), clipped to the same near and
//! far planes (tnear / tfar are the planes' distances along the ray). The
//! scene is one triangle mesh in `SceneData` order, so Embree's primID is
//! the visibility buffer's triangle id. Embree does not cull back faces;
//! compare against double-sided geometry, or closed meshes seen from
//! outside, where the nearest hit is front-facing anyway.

use embree::sys::*;
use rayon::prelude::*;
use specula_raster::{SceneData, View, MISS};
use std::ffi::CString;

/// A committed Embree scene (BVH built) of one specula scene.
pub struct EmbreeScene {
    device: RTCDevice,
    scene: RTCScene,
}

// SAFETY: after rtcCommitScene, Embree allows concurrent rtcIntersect* calls
// on a scene from any thread; nothing here mutates it afterwards.
unsafe impl Send for EmbreeScene {}
// SAFETY: as for Send: shared use is only rtcIntersect* on the committed
// scene, which Embree allows from many threads at once.
unsafe impl Sync for EmbreeScene {}

/// Per-pixel results, row-major: triangle id (MISS where nothing is hit),
/// hit distance t along the unit ray, and view depth w = t · (dir · forward)
/// (both inf on a miss).
pub struct Hits {
    pub id: Vec<u32>,
    pub t: Vec<f32>,
    pub w: Vec<f32>,
}

impl Hits {
    fn new(n: usize) -> Hits {
        Hits {
            id: vec![MISS; n],
            t: vec![f32::INFINITY; n],
            w: vec![f32::INFINITY; n],
        }
    }
}

/// Embree asks for flush-to-zero and denormals-are-zero on tracing threads
/// (MXCSR bits 15 and 6). Set for the duration of `f` and restored, so the
/// rasterizer's arithmetic on the same threads is not affected.
#[allow(deprecated)] // _mm_getcsr/_mm_setcsr: no replacement in std yet
fn with_ftz_daz<T>(f: impl FnOnce() -> T) -> T {
    use std::arch::x86_64::{_mm_getcsr, _mm_setcsr};
    // SAFETY: reading and writing MXCSR flush modes has no memory effects.
    let old = unsafe { _mm_getcsr() };
    // SAFETY: only the FTZ and DAZ bits are added to the current control
    // word; no exception is unmasked, so no instruction starts to trap.
    unsafe { _mm_setcsr(old | 0x8040) };
    let r = f();
    // SAFETY: puts back the control word this thread had on entry.
    unsafe { _mm_setcsr(old) };
    r
}

impl EmbreeScene {
    /// Builds the BVH with at most `threads` Embree threads.
    pub fn new(scene: &SceneData, threads: usize) -> Result<EmbreeScene, String> {
        let config = CString::new(format!("threads={threads}")).expect("no NUL");
        // SAFETY: plain Embree API calls; buffers are written within the
        // sizes Embree allocated for them; every handle is released in Drop.
        unsafe {
            let device = rtcNewDevice(config.as_ptr());
            if device.is_null() {
                return Err("rtcNewDevice failed".into());
            }
            let geom = rtcNewGeometry(device, RTCGeometryType::TRIANGLE);
            let nv = scene.positions.len();
            let nt = scene.triangles.len();
            let vb =
                rtcSetNewGeometryBuffer(geom, RTCBufferType::VERTEX, 0, RTCFormat::FLOAT3, 12, nv)
                    as *mut f32;
            let ib =
                rtcSetNewGeometryBuffer(geom, RTCBufferType::INDEX, 0, RTCFormat::UINT3, 12, nt)
                    as *mut u32;
            if vb.is_null() || ib.is_null() {
                rtcReleaseGeometry(geom);
                rtcReleaseDevice(device);
                return Err("Embree could not allocate the mesh buffers".into());
            }
            let verts = std::slice::from_raw_parts_mut(vb, nv * 3);
            for (d, p) in verts.chunks_exact_mut(3).zip(&scene.positions) {
                d.copy_from_slice(&p.to_array());
            }
            let idx = std::slice::from_raw_parts_mut(ib, nt * 3);
            for (d, t) in idx.chunks_exact_mut(3).zip(&scene.triangles) {
                d.copy_from_slice(t);
            }
            rtcCommitGeometry(geom);
            let s = rtcNewScene(device);
            rtcAttachGeometry(s, geom);
            rtcReleaseGeometry(geom);
            rtcCommitScene(s);
            let err = rtcGetDeviceError(device);
            if err != RTCError::NONE {
                rtcReleaseScene(s);
                rtcReleaseDevice(device);
                return Err(format!("Embree error {err:?}"));
            }
            Ok(EmbreeScene { device, scene: s })
        }
    }

    /// The primary ray through the centre of pixel (px, py): unit direction,
    /// and the near/far planes' distances along it.
    #[inline]
    fn ray(view: &View, near: f32, far: f32, px: u32, py: u32) -> ([f32; 3], f32, f32) {
        let sx = 2.0 * (px as f32 + 0.5) / view.width - 1.0;
        let sy = 1.0 - 2.0 * (py as f32 + 0.5) / view.height;
        let d = view.forward + view.right * (sx * view.tan_x) + view.up * (sy * view.tan_y);
        let d = d.normalize();
        let cos = d.dot(view.forward);
        (d.to_array(), near / cos, far / cos)
    }

    /// Runs `row(py, hits)` for every image row, in parallel in the calling
    /// pool, with FTZ/DAZ set on the worker for the duration.
    fn trace_rows(view: &View, row: impl Fn(usize, &mut RowHits) + Sync) -> Hits {
        let w = view.width as usize;
        let mut hits = Hits::new(w * view.height as usize);
        let rows = hits
            .id
            .par_chunks_mut(w)
            .zip(hits.t.par_chunks_mut(w))
            .zip(hits.w.par_chunks_mut(w));
        rows.enumerate()
            .for_each(|(py, ((id, t), w))| with_ftz_daz(|| row(py, &mut RowHits { id, t, w })));
        hits
    }

    /// Shadow rays (`rtcOccluded1`): for each (origin, unit direction,
    /// tnear, tfar), whether some triangle lies between tnear and tfar
    /// along it; in parallel in the calling pool.
    pub fn occluded(&self, rays: &[([f32; 3], [f32; 3], f32, f32)]) -> Vec<bool> {
        rays.par_chunks(1024)
            .flat_map_iter(|chunk| {
                with_ftz_daz(|| {
                    let mut ctx = embree::IntersectContext::incoherent();
                    (chunk.iter())
                        .map(|&(o, d, tnear, tfar)| {
                            let mut ray = RTCRay {
                                org_x: o[0],
                                org_y: o[1],
                                org_z: o[2],
                                tnear,
                                dir_x: d[0],
                                dir_y: d[1],
                                dir_z: d[2],
                                time: 0.0,
                                tfar,
                                mask: u32::MAX,
                                id: 0,
                                flags: 0,
                            };
                            // SAFETY: valid committed scene, context and ray.
                            unsafe { rtcOccluded1(self.scene, &mut ctx, &mut ray) };
                            // Embree sets tfar to −inf when the ray is blocked.
                            ray.tfar == f32::NEG_INFINITY
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect()
    }

    /// One `rtcIntersect1` per pixel, rows in parallel in the calling pool.
    pub fn trace_single(&self, view: &View, near: f32, far: f32) -> Hits {
        let o = view.eye.to_array();
        Self::trace_rows(view, |py, hits| {
            let mut ctx = embree::IntersectContext::coherent();
            for px in 0..hits.id.len() {
                let (d, tn, tf) = Self::ray(view, near, far, px as u32, py as u32);
                let mut rh = RTCRayHit {
                    ray: RTCRay {
                        org_x: o[0],
                        org_y: o[1],
                        org_z: o[2],
                        tnear: tn,
                        dir_x: d[0],
                        dir_y: d[1],
                        dir_z: d[2],
                        time: 0.0,
                        tfar: tf,
                        mask: u32::MAX,
                        id: 0,
                        flags: 0,
                    },
                    hit: RTCHit {
                        Ng_x: 0.0,
                        Ng_y: 0.0,
                        Ng_z: 0.0,
                        u: 0.0,
                        v: 0.0,
                        primID: u32::MAX,
                        geomID: u32::MAX,
                        instID: [u32::MAX],
                    },
                };
                // SAFETY: valid committed scene, context and ray.
                unsafe { rtcIntersect1(self.scene, &mut ctx, &mut rh) };
                if rh.hit.geomID != u32::MAX {
                    hits.set(px, rh.hit.primID, rh.ray.tfar, cos_to_forward(view, d));
                }
            }
        })
    }

    /// `rtcIntersect8` on 8 horizontally adjacent pixels per packet.
    pub fn trace_packet8(&self, view: &View, near: f32, far: f32) -> Hits {
        let o = view.eye.to_array();
        Self::trace_rows(view, |py, hits| {
            let w = hits.id.len();
            let mut ctx = embree::IntersectContext::coherent();
            // SAFETY: all-zero is a valid bit pattern for these C structs.
            let mut rh: RTCRayHit8 = unsafe { std::mem::zeroed() };
            let mut cosines = [0.0f32; 8];
            for x0 in (0..w).step_by(8) {
                let mut valid = [0i32; 8];
                for l in 0..8.min(w - x0) {
                    valid[l] = -1;
                    let (d, tn, tf) = Self::ray(view, near, far, (x0 + l) as u32, py as u32);
                    rh.ray.org_x[l] = o[0];
                    rh.ray.org_y[l] = o[1];
                    rh.ray.org_z[l] = o[2];
                    rh.ray.dir_x[l] = d[0];
                    rh.ray.dir_y[l] = d[1];
                    rh.ray.dir_z[l] = d[2];
                    rh.ray.tnear[l] = tn;
                    rh.ray.tfar[l] = tf;
                    rh.ray.mask[l] = u32::MAX;
                    rh.ray.time[l] = 0.0;
                    rh.ray.flags[l] = 0;
                    rh.hit.geomID[l] = u32::MAX;
                    cosines[l] = cos_to_forward(view, d);
                }
                // SAFETY: valid committed scene; rh is 32-byte aligned by its type.
                unsafe { rtcIntersect8(valid.as_ptr(), self.scene, &mut ctx, &mut rh) };
                for l in 0..8 {
                    if valid[l] != 0 && rh.hit.geomID[l] != u32::MAX {
                        hits.set(x0 + l, rh.hit.primID[l], rh.ray.tfar[l], cosines[l]);
                    }
                }
            }
        })
    }
}

/// One row's slices of [`Hits`].
struct RowHits<'a> {
    id: &'a mut [u32],
    t: &'a mut [f32],
    w: &'a mut [f32],
}

impl RowHits<'_> {
    fn set(&mut self, px: usize, id: u32, t: f32, cos: f32) {
        self.id[px] = id;
        self.t[px] = t;
        self.w[px] = t * cos;
    }
}

/// dir · forward: converts a hit distance to view depth.
fn cos_to_forward(view: &View, d: [f32; 3]) -> f32 {
    d[0].mul_add(
        view.forward.x,
        d[1].mul_add(view.forward.y, d[2] * view.forward.z),
    )
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: handles created in `new`, released once.
        unsafe {
            rtcReleaseScene(self.scene);
            rtcReleaseDevice(self.device);
        }
    }
}
