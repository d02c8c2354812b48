//! Meshes in object space: procedural shapes and OBJ/MTL files (through tobj).

use crate::objcheck::ObjError;
use glam::{Vec2, Vec3};
use std::path::Path;

/// One mesh in object space. `tri_material` indexes `material_names`.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    pub positions: Vec<Vec3>,
    /// Unit normals, one per position.
    pub normals: Vec<Vec3>,
    /// One per position, or empty.
    pub(crate) uvs: Vec<Vec2>,
    /// Unit tangents (xyz) and the bitangent's sign (w = ±1), one per
    /// position, or empty (then made when the scene is built: tangents.rs
    /// for normal-mapped materials, `compute_tangents` otherwise).
    pub(crate) tangents: Vec<glam::Vec4>,
    /// Vertex colours (linear RGBA), one per position, or empty.
    pub(crate) colors: Vec<glam::Vec4>,
    pub triangles: Vec<[u32; 3]>,
    pub tri_material: Vec<u32>,
    /// Names of the materials the triangles use (`None`: none assigned).
    pub(crate) material_names: Vec<Option<String>>,
    /// Materials defined by the mesh's MTL files.
    pub(crate) mtl: Vec<tobj::Material>,
    /// The MTL files read (as passed to `read`): inputs, never outputs.
    pub(crate) mtl_files: Vec<std::path::PathBuf>,
    /// Things the loader dropped or changed that the user should hear of.
    pub(crate) warnings: Vec<String>,
}

impl MeshData {
    fn single_material(mut self) -> Self {
        self.tri_material = vec![0; self.triangles.len()];
        self.material_names = vec![None];
        self
    }

    /// Appends a (nu × nv)-cell grid of points `origin + du·s + dv·t`,
    /// s, t ∈ [0, 1], with triangles facing du × dv.
    fn grid(&mut self, origin: Vec3, du: Vec3, dv: Vec3, nu: u32, nv: u32) {
        let base = self.positions.len() as u32;
        let normal = du.cross(dv).normalize();
        for j in 0..=nv {
            for i in 0..=nu {
                let (s, t) = (i as f32 / nu as f32, j as f32 / nv as f32);
                self.positions.push(origin + du * s + dv * t);
                self.normals.push(normal);
                self.uvs.push(Vec2::new(s, t));
            }
        }
        let at = |i: u32, j: u32| base + j * (nu + 1) + i;
        for j in 0..nv {
            for i in 0..nu {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                self.triangles.push([a, b, c]);
                self.triangles.push([a, c, d]);
            }
        }
    }
}

/// UV sphere around the origin with its poles on ±Y: `segments` around,
/// `rings` from pole to pole; uv = (longitude, latitude) in [0, 1].
pub(crate) fn sphere(radius: f32, segments: u32, rings: u32) -> MeshData {
    let mut m = MeshData::default();
    // The seam's last column repeats the first, and each pole is one
    // point, bit for bit (sin π and sin 2π round away from 0 in f32): the
    // surface is closed, as shadow maps' solids need (raster's closed.rs).
    let theta = |r: u32| match r {
        0 => (0.0, 1.0),
        r if r == rings => (0.0, -1.0),
        r => (std::f32::consts::PI * r as f32 / rings as f32).sin_cos(),
    };
    let phi = |s: u32| match s {
        s if s == segments => (0.0, 1.0),
        s => (std::f32::consts::TAU * s as f32 / segments as f32).sin_cos(),
    };
    for r in 0..=rings {
        let (sin_theta, cos_theta) = theta(r);
        for s in 0..=segments {
            let (sin_phi, cos_phi) = phi(s);
            let n = Vec3::new(sin_theta * cos_phi, cos_theta, sin_theta * sin_phi);
            m.positions.push(n * radius);
            m.normals.push(n);
            m.uvs.push(Vec2::new(
                s as f32 / segments as f32,
                r as f32 / rings as f32,
            ));
        }
    }
    let at = |s: u32, r: u32| r * (segments + 1) + s;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (at(s, r), at(s + 1, r), at(s + 1, r + 1), at(s, r + 1));
            // ∂p/∂φ × ∂p/∂θ points outward, so (a, b, c) is counter-clockwise
            // seen from outside. The pole rows would give zero-area triangles.
            if r != 0 {
                m.triangles.push([a, b, c]);
            }
            if r != rings - 1 {
                m.triangles.push([a, c, d]);
            }
        }
    }
    m.single_material()
}

/// Plane in XZ through the origin facing +Y, `size` = (x extent, z extent).
pub fn plane(size: [f32; 2], segments: [u32; 2]) -> MeshData {
    let mut m = MeshData::default();
    let (sx, sz) = (size[0], size[1]);
    // du = +Z, dv = +X: Z × X = +Y.
    m.grid(
        Vec3::new(-sx / 2.0, 0.0, -sz / 2.0),
        Vec3::Z * sz,
        Vec3::X * sx,
        segments[1],
        segments[0],
    );
    m.single_material()
}

/// Axis-aligned cube centred at the origin, each face a `segments²` grid.
pub fn cube(size: f32, segments: u32) -> MeshData {
    let mut m = MeshData::default();
    let h = size / 2.0;
    // (normal, du, dv) with du × dv = normal.
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (-Vec3::X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (-Vec3::Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (-Vec3::Z, Vec3::Y, Vec3::X),
    ];
    for (n, du, dv) in faces {
        m.grid((n - du - dv) * h, du * size, dv * size, segments, segments);
    }
    m.single_material()
}

/// Area-weighted vertex normals, for meshes that come without any.
fn smooth_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let face = (b - a).cross(c - a); // length = 2·area: area weighting
        for &i in t {
            n[i as usize] += face;
        }
    }
    n.into_iter()
        .map(|v| v.try_normalize().unwrap_or(Vec3::Z))
        .collect()
}

/// Splits tobj's faces (indices with `face_arities`; none means all
/// triangles) into triangles appended to `out`, offset by `base`. A polygon
/// of four or more corners is ear-clipped in its own plane (earcut), so a
/// concave one keeps its notch; every triangle is wound like the polygon
/// (counter-clockwise about its Newell normal). A polygon with no plane
/// (collinear corners) gives no triangles: it has no area.
fn triangulate(mesh: &tobj::Mesh, out: &mut Vec<[u32; 3]>, base: u32) {
    let idx = &mesh.indices;
    if mesh.face_arities.is_empty() {
        out.extend(
            idx.chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
        return;
    }
    let pos = |i: u32| {
        let p = &mesh.positions[3 * i as usize..3 * i as usize + 3];
        [p[0] as f64, p[1] as f64, p[2] as f64]
    };
    let mut earcut = earcut::Earcut::new();
    let (mut flat, mut ears) = (Vec::new(), Vec::<u32>::new());
    let mut start = 0usize;
    for &n in &mesh.face_arities {
        let face = &idx[start..start + n as usize];
        start += n as usize;
        if face.len() < 3 {
            continue;
        }
        if face.len() == 3 {
            out.push([base + face[0], base + face[1], base + face[2]]);
            continue;
        }
        let corners: Vec<[f64; 3]> = face.iter().map(|&i| pos(i)).collect();
        // Newell normal: the polygon's area vector, robust for any shape.
        let mut normal = Vec3::ZERO.as_dvec3();
        for (k, a) in corners.iter().enumerate() {
            let b = corners[(k + 1) % corners.len()];
            normal += glam::DVec3::from(*a).cross(glam::DVec3::from(b));
        }
        if !earcut::utils3d::project3d_to_2d(&corners, corners.len(), &mut flat) {
            continue;
        }
        earcut.earcut(flat.iter().copied(), &[] as &[u32], &mut ears);
        for t in ears.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|k| k as usize);
            let (pa, pb, pc) = (corners[a], corners[b], corners[c]);
            let n = (glam::DVec3::from(pb) - glam::DVec3::from(pa))
                .cross(glam::DVec3::from(pc) - glam::DVec3::from(pa));
            let tri = if n.dot(normal) < 0.0 {
                [face[a], face[c], face[b]]
            } else {
                [face[a], face[b], face[c]]
            };
            out.push(tri.map(|i| base + i));
        }
    }
}

/// One MTL file's materials, from bytes [`crate::objcheck::check_mtl`]
/// accepted.
pub(crate) fn load_mtl(bytes: &[u8]) -> tobj::MTLLoadResult {
    tobj::load_mtl_buf(&mut crate::objcheck::strip_bom(bytes))
}

/// Finds the line a tobj error most likely refers to, for the message: the
/// first line of the kind the error names that does not parse.
fn locate_obj_error(text: &str, err: tobj::LoadError) -> Option<usize> {
    use tobj::LoadError as E;
    let floats = |rest: &str, n: usize| {
        let v: Vec<_> = rest.split_whitespace().collect();
        v.len() >= n && v.iter().all(|s| s.parse::<f32>().is_ok())
    };
    let mut counts = [0i64; 3]; // v, vt, vn seen so far
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        let (key, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let bad = match key {
            "v" => {
                counts[0] += 1;
                matches!(err, E::PositionParseError) && !floats(rest, 3)
            }
            "vt" => {
                counts[1] += 1;
                matches!(err, E::TexcoordParseError) && !floats(rest, 1)
            }
            "vn" => {
                counts[2] += 1;
                matches!(err, E::NormalParseError) && !floats(rest, 3)
            }
            "f" => {
                let corners: Vec<_> = rest.split_whitespace().collect();
                let index_ok = |s: &str, k: usize| {
                    s.is_empty()
                        || s.parse::<i64>()
                            .is_ok_and(|x| x != 0 && (x.abs() <= counts[k]))
                };
                let bad_corner = corners.iter().any(|c| {
                    let mut parts = c.split('/');
                    let v = parts.next().unwrap_or("");
                    let t = parts.next().unwrap_or("");
                    let n = parts.next().unwrap_or("");
                    v.is_empty() || !index_ok(v, 0) || !index_ok(t, 1) || !index_ok(n, 2)
                });
                matches!(
                    err,
                    E::FaceParseError
                        | E::InvalidPolygon
                        | E::FaceVertexOutOfBounds
                        | E::FaceNormalOutOfBounds
                        | E::FaceTexCoordOutOfBounds
                ) && (corners.len() < 3 || bad_corner)
            }
            _ => false,
        };
        if bad {
            return Some(i + 1);
        }
    }
    None
}

/// An MTL file an OBJ named, as the mesh cache (mesh_cache.rs) checks
/// it on a hit: the name as the `mtllib` line gives it
/// (resolved against the OBJ's folder) and the hash of its bytes.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct MtlSource {
    pub(crate) name: String,
    pub(crate) hash: [u8; 32],
}

impl MtlSource {
    /// None when the name is not UTF-8 (such a mesh is not cached).
    pub(crate) fn new(name: &Path, bytes: &[u8]) -> Option<MtlSource> {
        Some(MtlSource {
            name: name.to_str()?.to_string(),
            hash: <sha2::Sha256 as sha2::Digest>::digest(bytes).into(),
        })
    }
}

/// The OBJ parse behind the mesh cache's `load_obj`. `mtls` receives, per MTL file asked
/// for, its name as the OBJ gives it and a hash of the bytes read, or None
/// where it could not be read or checked.
pub(crate) fn parse_obj(
    path: &Path,
    bytes: &[u8],
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    mtls: &mut Vec<Option<MtlSource>>,
) -> Result<MeshData, ObjError> {
    // tobj reports errors without a line and can panic on bad indices:
    // check every line first; faces it would mishandle are blanked out.
    let scan = crate::objcheck::check_obj(path, bytes)?;
    let text = scan.text.as_str();
    let bytes = text.as_bytes();
    let mut warnings = Vec::new();
    if scan.dropped_faces > 0 {
        warnings.push(format!(
            "{}: {} faces with fewer than 3 corners (first at line {}) dropped: a point or a line is not a surface",
            path.display(),
            scan.dropped_faces,
            scan.first_dropped.unwrap_or(0)
        ));
    }
    if scan.polylines > 0 {
        warnings.push(format!(
            "{}: {} polylines (l lines) skipped: only faces are rendered",
            path.display(),
            scan.polylines
        ));
    }
    let opts = tobj::LoadOptions {
        // Polygons are triangulated here (ear clipping), not as tobj's fans.
        triangulate: false,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let mtl_errors = std::cell::RefCell::new(Vec::new());
    let mtl_files = std::cell::RefCell::new(Vec::new());
    let mtl_sources = std::cell::RefCell::new(Vec::new());
    let loaded = tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &opts, |mtl: &Path| {
        let p = dir.join(mtl);
        mtl_files.borrow_mut().push(p.clone());
        match read(&p) {
            // tobj panics on some malformed MTL lines: check first.
            Ok(b) => match crate::objcheck::check_mtl(&p, &b) {
                Ok(()) => {
                    mtl_sources.borrow_mut().push(MtlSource::new(mtl, &b));
                    load_mtl(&b)
                }
                Err(e) => {
                    mtl_sources.borrow_mut().push(None);
                    mtl_errors.borrow_mut().push(e);
                    Err(tobj::LoadError::MaterialParseError)
                }
            },
            Err(source) => {
                mtl_sources.borrow_mut().push(None);
                mtl_errors
                    .borrow_mut()
                    .push(ObjError::ReadMtl { path: p, source });
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    });
    let (models, materials) = match loaded {
        Ok(r) => r,
        Err(source) => {
            return Err(ObjError::Parse {
                path: path.to_path_buf(),
                line: locate_obj_error(text, source),
                source,
            });
        }
    };
    let materials = match materials {
        Ok(m) => m,
        Err(source) => {
            return Err(ObjError::Materials {
                path: path.to_path_buf(),
                errors: mtl_errors.into_inner(),
                source,
            });
        }
    };

    for (name, line) in &scan.usemtl {
        if !materials.iter().any(|mt| &mt.name == name) {
            warnings.push(format!(
                "{}: line {line}: usemtl {name:?} names no material of the mesh's MTL files; its faces get the mesh entry's material or the default one",
                path.display()
            ));
        }
    }
    *mtls = mtl_sources.into_inner();
    let mut m = MeshData {
        material_names: materials.iter().map(|mt| Some(mt.name.clone())).collect(),
        mtl: materials,
        mtl_files: mtl_files.into_inner(),
        warnings,
        ..Default::default()
    };
    let no_material = m.material_names.len() as u32;
    m.material_names.push(None);
    let mut any_uv = false;
    let mut all_normals = true;
    for model in &models {
        let mesh = &model.mesh;
        let nv = mesh.positions.len() / 3;
        any_uv |= !mesh.texcoords.is_empty();
        all_normals &= mesh.normals.len() == mesh.positions.len();
        let base = m.positions.len() as u32;
        m.positions.extend(
            mesh.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        if mesh.normals.len() == mesh.positions.len() {
            m.normals.extend(
                mesh.normals
                    .chunks_exact(3)
                    .map(|p| Vec3::new(p[0], p[1], p[2])),
            );
        } else {
            m.normals.extend(std::iter::repeat_n(Vec3::ZERO, nv));
        }
        if mesh.texcoords.len() / 2 == nv {
            m.uvs.extend(
                mesh.texcoords
                    .chunks_exact(2)
                    .map(|t| Vec2::new(t[0], t[1])),
            );
        } else {
            m.uvs.extend(std::iter::repeat_n(Vec2::ZERO, nv));
        }
        let mat = mesh.material_id.map(|i| i as u32).unwrap_or(no_material);
        let before = m.triangles.len();
        triangulate(mesh, &mut m.triangles, base);
        let added = m.triangles.len() - before;
        m.tri_material.extend(std::iter::repeat_n(mat, added));
    }
    if !any_uv {
        m.uvs.clear();
    }
    if !all_normals {
        m.normals = smooth_normals(&m.positions, &m.triangles);
    } else {
        for n in &mut m.normals {
            *n = n.try_normalize().unwrap_or(Vec3::Z);
        }
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The parse alone (these OBJs are far below the mesh cache's size).
    fn load_obj(
        path: &Path,
        bytes: &[u8],
        read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    ) -> Result<MeshData, ObjError> {
        parse_obj(path, bytes, read, &mut Vec::new())
    }

    /// Sum over triangles of (signed area × outward direction) = 0 for a
    /// closed surface, and the triangles must face outward: check with the
    /// divergence theorem, Σ (a × b)·c / 6 = volume > 0.
    fn signed_volume(m: &MeshData) -> f32 {
        m.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                a.cross(b).dot(c) / 6.0
            })
            .sum()
    }

    #[test]
    fn procedural_solids_are_closed_and_face_outward() {
        let s = sphere(1.0, 64, 32);
        let v = signed_volume(&s);
        let want = 4.0 / 3.0 * std::f32::consts::PI;
        assert!(
            (v - want).abs() / want < 0.01,
            "sphere volume {v} vs {want}"
        );
        let c = cube(2.0, 3);
        assert!((signed_volume(&c) - 8.0).abs() < 1e-4);
        for t in &c.triangles {
            let [a, b, cc] = t.map(|i| c.positions[i as usize]);
            let n = (b - a).cross(cc - a);
            assert!(
                n.dot(c.normals[t[0] as usize]) > 0.0,
                "cube face winding disagrees with its normal"
            );
        }
    }

    #[test]
    fn plane_faces_up() {
        let p = plane([2.0, 4.0], [2, 3]);
        assert_eq!(p.triangles.len(), 12);
        for t in &p.triangles {
            let [a, b, c] = t.map(|i| p.positions[i as usize]);
            assert!((b - a).cross(c - a).y > 0.0);
        }
    }

    #[test]
    fn obj_errors_name_the_line() {
        let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n";
        let err = load_obj(Path::new("bad.obj"), obj, &|_| {
            Err(std::io::ErrorKind::NotFound.into())
        })
        .unwrap_err();
        assert!(matches!(err, ObjError::Line { line: 5, .. }), "{err:?}");
        let err = err.to_string();
        assert!(err.contains("bad.obj") && err.contains("line 5"), "{err}");
        let obj = b"v 0 0 0\nv 1 zero 0\n";
        let err = load_obj(Path::new("bad.obj"), obj, &|_| {
            Err(std::io::ErrorKind::NotFound.into())
        })
        .unwrap_err();
        assert!(matches!(err, ObjError::Line { line: 2, .. }), "{err:?}");
        assert!(err.to_string().contains("line 2"), "{err}");
    }

    /// A bad MTL line and a missing MTL file each fail the load, naming
    /// the MTL file (and the line) under the OBJ's material library.
    #[test]
    fn mtl_errors_name_the_mtl_file_and_line() {
        let obj = b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        let err = load_obj(Path::new("d/a.obj"), obj, &|p| {
            assert_eq!(p, Path::new("d/m.mtl"));
            Ok(b"newmtl x\nKd 0.5 0.5\n".to_vec())
        })
        .unwrap_err();
        let ObjError::Materials { errors, .. } = &err else {
            panic!("{err:?}");
        };
        assert!(
            matches!(&errors[..], [ObjError::Line { line: 2, .. }]),
            "{errors:?}"
        );
        let msg = err.to_string();
        assert!(
            msg.starts_with("d/a.obj: material library: d/m.mtl: line 2: Kd needs three numbers"),
            "{msg}"
        );
        let err = load_obj(Path::new("a.obj"), obj, &|_| {
            Err(std::io::ErrorKind::NotFound.into())
        })
        .unwrap_err();
        let ObjError::Materials { errors, .. } = &err else {
            panic!("{err:?}");
        };
        assert!(
            matches!(&errors[..], [ObjError::ReadMtl { .. }]),
            "{errors:?}"
        );
        assert!(err.to_string().contains("m.mtl"), "{err}");
    }

    /// A concave pentagon (a square with a notch cut into its top edge),
    /// listed from the notch's corner so that a fan would cover the notch.
    #[test]
    fn concave_polygons_keep_their_notch() {
        let obj = b"v 2 2 0\nv 1 1 0\nv 0 2 0\nv 0 0 0\nv 2 0 0\nf 1 2 3 4 5\n";
        let m = load_obj(Path::new("c.obj"), obj, &|_| {
            Err(std::io::ErrorKind::NotFound.into())
        })
        .unwrap();
        assert_eq!(m.triangles.len(), 3, "n − 2 ears");
        let mut area = 0.0;
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let n = (b - a).cross(c - a);
            assert!(
                n.z > 0.0,
                "wound like the polygon (counter-clockwise about +z)"
            );
            area += n.z / 2.0;
            // The notch's inside, (1, 1.6), lies in no triangle.
            let p = Vec3::new(1.0, 1.6, 0.0);
            let inside = [(a, b), (b, c), (c, a)]
                .iter()
                .all(|(u, v)| (*v - *u).cross(p - *u).z > 0.0);
            assert!(!inside, "triangle {t:?} covers the notch");
        }
        assert!(
            (area - 3.0).abs() < 1e-5,
            "square 4 minus notch 1, got {area}"
        );
    }

    #[test]
    fn faces_with_fewer_than_three_corners_are_counted() {
        let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\nf 3\nf 1 2 3\n";
        let m = load_obj(Path::new("p.obj"), obj, &|_| {
            Err(std::io::ErrorKind::NotFound.into())
        })
        .unwrap();
        assert_eq!(m.triangles.len(), 1);
        assert!(
            m.warnings.iter().any(|w| w.contains("p.obj")
                && w.contains("2 faces with fewer than 3 corners (first at line 4)")),
            "{:?}",
            m.warnings
        );
    }

    /// A byte order mark before the first line of an OBJ or an MTL is not
    /// part of the line: `mtllib` and the first `newmtl` still count.
    #[test]
    fn byte_order_marks_are_skipped() {
        let obj = b"\xEF\xBB\xBFmtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n";
        let m = load_obj(Path::new("b.obj"), obj, &|_| {
            Ok(b"\xEF\xBB\xBFnewmtl red\nKd 1 0 0\n".to_vec())
        })
        .unwrap();
        assert_eq!(m.mtl.len(), 1, "{:?}", m.warnings);
        assert_eq!(m.mtl[0].name, "red");
        assert_eq!(m.mtl[0].diffuse, Some([1.0, 0.0, 0.0]));
        assert_eq!(
            m.material_names[m.tri_material[0] as usize].as_deref(),
            Some("red")
        );
        assert!(m.warnings.is_empty(), "{:?}", m.warnings);
    }

    #[test]
    fn usemtl_of_a_missing_material_is_a_warning_with_its_line() {
        let obj = b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl blue\nf 1 2 3\n";
        let m = load_obj(Path::new("u.obj"), obj, &|_| {
            Ok(b"newmtl red\nKd 1 0 0\n".to_vec())
        })
        .unwrap();
        assert!(
            m.warnings
                .iter()
                .any(|w| w.contains("u.obj: line 5") && w.contains("\"blue\"")),
            "{:?}",
            m.warnings
        );
    }
}
