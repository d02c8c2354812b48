//! Parsed OBJ meshes kept between runs, so that a large OBJ is parsed once
//! per machine, not once per run (tobj's text parse dominates the time from
//! process start to image for the benchmark scene).
//!
//! One file per mesh in the table cache folder (table_cache.rs, which says
//! where it is and how to turn it off), `mesh-<key>.bin`, the key a BLAKE3
//! hash of the format's version, the OBJ's path as given (messages carry
//! it) and its bytes. BLAKE3 rather than SHA-256 because every load hashes
//! the whole OBJ before it can look for the file, and BLAKE3 is several
//! times faster on long inputs while still cryptographic: any change of
//! the file changes the key. The file holds the [`MeshData`] the parse made, except the MTL
//! materials: it lists the MTL files the OBJ named, each with a SHA-256 of
//! its bytes, and a hit re-reads them, checks the hashes and parses them
//! again (they are small), so an edited MTL is a miss. Only parses whose
//! every MTL file was read and checked are kept.
//!
//! A file that is short, inconsistent (lengths, indices out of range) or
//! of another version is a miss and is rewritten; files are written to a
//! temporary file and renamed into place, so a reader never sees half a
//! file. The cache is an optimisation only: any I/O error leaves the mesh
//! parsed in memory, silently. Deleting the folder is always safe.

use crate::mesh::{MeshData, MtlSource};
use glam::{Vec2, Vec3};
use std::io::Write;
use std::path::{Path, PathBuf};

/// OBJ files smaller than this are parsed every time (they parse in a few
/// milliseconds; caching them would only fill the folder).
pub(crate) const MIN_OBJ_BYTES: usize = 1 << 20;

/// The file format's version; part of the key.
const VERSION: &[u8] = b"specula-mesh-v1";

/// Loads an OBJ (and the MTL files it names, through `read`) from its bytes.
/// `path` is used for messages and to resolve `mtllib` names. Large files
/// go through the mesh cache (this module) in the table cache folder.
pub(crate) fn load_obj(
    path: &Path,
    bytes: &[u8],
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<MeshData, crate::objcheck::ObjError> {
    let cache = crate::table_cache::cache_dir().filter(|_| bytes.len() >= MIN_OBJ_BYTES);
    Ok(load_obj_cached(path, bytes, read, cache.as_deref())?.0)
}

/// [`load_obj`] with the mesh cache in `cache` (None: no cache), and
/// whether the mesh came from it.
pub(crate) fn load_obj_cached(
    path: &Path,
    bytes: &[u8],
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    cache: Option<&Path>,
) -> Result<(MeshData, bool), crate::objcheck::ObjError> {
    let key = cache.map(|_| key(path, bytes));
    if let (Some(dir), Some(key)) = (cache, &key) {
        if let Some(m) = load(dir, key, path, read) {
            return Ok((m, true));
        }
    }
    let mut mtls = Vec::new();
    let m = crate::mesh::parse_obj(path, bytes, read, &mut mtls)?;
    if let (Some(dir), Some(key), Some(mtls)) =
        (cache, &key, mtls.into_iter().collect::<Option<Vec<_>>>())
    {
        store(dir, key, &m, &mtls);
    }
    Ok((m, false))
}

/// The cache key of an OBJ at `path` with `bytes`.
pub(crate) fn key(path: &Path, bytes: &[u8]) -> String {
    let mut h = key_hasher(path);
    h.update(bytes);
    h.finalize().to_hex().to_string()
}

/// The hasher of a key, fed all but the OBJ's bytes.
fn key_hasher(path: &Path) -> blake3::Hasher {
    let mut h = blake3::Hasher::new();
    let path = path.as_os_str().as_encoded_bytes();
    for part in [VERSION, path] {
        h.update(&(part.len() as u64).to_le_bytes());
        h.update(part);
    }
    h
}

/// The cache key of the OBJ file at `file` (named `path` in the scene,
/// as [`load_obj`] names it) and the file's length, without reading the
/// file into memory: its bytes are hashed through a small buffer as they
/// are read. `None` when the cache is off, the file is below
/// [`MIN_OBJ_BYTES`] or cannot be read. Look the key up with
/// [`load_cached`]; on a miss the caller reads and parses the file with
/// [`load_obj`], which keys the bytes it read (not these: the file may
/// have changed in between).
pub(crate) fn file_key(path: &Path, file: &Path) -> Option<(String, u64)> {
    crate::table_cache::cache_dir()?;
    key_of_file(path, file, MIN_OBJ_BYTES as u64)
}

/// [`file_key`] whatever the cache, for files of at least `min` bytes.
fn key_of_file(path: &Path, file: &Path, min: u64) -> Option<(String, u64)> {
    let f = std::fs::File::open(file).ok()?;
    let len = f.metadata().ok()?.len();
    if len < min {
        return None;
    }
    let mut h = key_hasher(path);
    h.update_reader(f).ok()?;
    Some((h.finalize().to_hex().to_string(), len))
}

/// The cached mesh of `key` (from [`file_key`]) for the OBJ named `path`,
/// or None on a miss.
pub(crate) fn load_cached(
    key: &str,
    path: &Path,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Option<MeshData> {
    load(&crate::table_cache::cache_dir()?, key, path, read)
}

fn file(dir: &Path, key: &str) -> PathBuf {
    dir.join(format!("mesh-{key}.bin"))
}

/// The cached mesh of `key`, with its MTL materials read again through
/// `read` (relative to `path`'s folder), or None on any miss.
pub(crate) fn load(
    dir: &Path,
    key: &str,
    path: &Path,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Option<MeshData> {
    let f = std::fs::File::open(file(dir, key)).ok()?;
    let len = f.metadata().ok()?.len();
    let (mut mesh, mtls) = decode(std::io::BufReader::new(f), len)?;
    let obj_dir = path.parent().unwrap_or(Path::new(""));
    for src in &mtls {
        let p = obj_dir.join(&src.name);
        let b = read(&p).ok()?;
        if MtlSource::new(Path::new(&src.name), &b).as_ref() != Some(src) {
            return None;
        }
        crate::objcheck::check_mtl(&p, &b).ok()?;
        let (mut materials, _) = crate::mesh::load_mtl(&b).ok()?;
        mesh.mtl.append(&mut materials);
        mesh.mtl_files.push(p);
    }
    // The names the parse took from the materials, then "none".
    let names = mesh.mtl.iter().map(|m| Some(m.name.clone()));
    if !names.chain([None]).eq(mesh.material_names.iter().cloned()) {
        return None;
    }
    Some(mesh)
}

/// Writes `mesh` (parsed with the MTL files `mtls`) under `key`.
pub(crate) fn store(dir: &Path, key: &str, mesh: &MeshData, mtls: &[MtlSource]) {
    let bytes = encode(mesh, mtls);
    let write = || -> std::io::Result<()> {
        std::fs::create_dir_all(dir)?;
        let mut tmp = tempfile::NamedTempFile::new_in(dir)?;
        tmp.write_all(&bytes)?;
        tmp.persist(file(dir, key)).map_err(|e| e.error)?;
        Ok(())
    };
    let _ = write();
}

const MAGIC: &[u8; 8] = b"SPCMESH1";

fn encode(m: &MeshData, mtls: &[MtlSource]) -> Vec<u8> {
    let mut w =
        Vec::with_capacity(64 + m.positions.len() * 32 + m.uvs.len() * 8 + m.triangles.len() * 16);
    let u32_ = |w: &mut Vec<u8>, v: usize| w.extend_from_slice(&(v as u32).to_le_bytes());
    let str_ = |w: &mut Vec<u8>, s: &str| {
        u32_(w, s.len());
        w.extend_from_slice(s.as_bytes());
    };
    let f32s =
        |w: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|x| w.extend_from_slice(&x.to_le_bytes()));
    w.extend_from_slice(MAGIC);
    u32_(&mut w, mtls.len());
    for s in mtls {
        str_(&mut w, &s.name);
        w.extend_from_slice(&s.hash);
    }
    u32_(&mut w, m.positions.len());
    m.positions.iter().for_each(|p| f32s(&mut w, &p.to_array()));
    m.normals.iter().for_each(|n| f32s(&mut w, &n.to_array()));
    u32_(&mut w, m.uvs.len());
    m.uvs.iter().for_each(|t| f32s(&mut w, &t.to_array()));
    u32_(&mut w, m.triangles.len());
    for t in &m.triangles {
        t.iter().for_each(|&i| u32_(&mut w, i as usize));
    }
    m.tri_material
        .iter()
        .for_each(|&i| u32_(&mut w, i as usize));
    u32_(&mut w, m.material_names.len());
    for n in &m.material_names {
        match n {
            Some(n) => {
                w.push(1);
                str_(&mut w, n);
            }
            None => w.push(0),
        }
    }
    u32_(&mut w, m.warnings.len());
    m.warnings.iter().for_each(|s| str_(&mut w, s));
    w
}

/// Bounds-checked reading of [`encode`]'s layout from a stream of `left`
/// bytes: arrays are read straight into the vectors they become.
struct Reader<R> {
    src: R,
    left: u64,
}

impl<R: std::io::Read> Reader<R> {
    fn take(&mut self, n: usize) -> Option<Vec<u8>> {
        (n as u64 <= self.left).then_some(())?;
        let mut b = vec![0; n];
        self.fill(&mut b)?;
        Some(b)
    }
    /// Reads exactly `b.len()` bytes, no more than are left.
    fn fill(&mut self, b: &mut [u8]) -> Option<()> {
        self.left = self.left.checked_sub(b.len() as u64)?;
        self.src.read_exact(b).ok()
    }
    fn u32(&mut self) -> Option<u32> {
        let mut b = [0; 4];
        self.fill(&mut b)?;
        Some(u32::from_le_bytes(b))
    }
    /// A count of items of `size` bytes each, no more than the bytes left.
    fn count(&mut self, size: usize) -> Option<usize> {
        let n = self.u32()? as usize;
        ((n as u64).checked_mul(size as u64)? <= self.left).then_some(n)
    }
    fn string(&mut self) -> Option<String> {
        let n = self.count(1)?;
        String::from_utf8(self.take(n)?).ok()
    }
    /// `n` arrays of `N` little-endian 4-byte words (f32 or u32).
    fn words<T: bytemuck::Pod, const N: usize>(&mut self, n: usize) -> Option<Vec<[T; N]>> {
        const { assert!(std::mem::size_of::<T>() == 4) };
        (n as u64)
            .checked_mul(4 * N as u64)
            .filter(|&b| b <= self.left)?;
        let mut v = vec![[T::zeroed(); N]; n];
        self.fill(bytemuck::cast_slice_mut(v.as_flattened_mut()))?;
        if cfg!(target_endian = "big") {
            for w in bytemuck::cast_slice_mut::<T, u32>(v.as_flattened_mut()) {
                *w = u32::from_le(*w);
            }
        }
        Some(v)
    }
}

/// The mesh and MTL list [`encode`] wrote, from `src` of `len` bytes.
fn decode(src: impl std::io::Read, len: u64) -> Option<(MeshData, Vec<MtlSource>)> {
    let mut r = Reader { src, left: len };
    if r.take(MAGIC.len())? != MAGIC {
        return None;
    }
    let n_mtl = r.count(4 + 32)?;
    let mut mtls = Vec::with_capacity(n_mtl);
    for _ in 0..n_mtl {
        let name = r.string()?;
        let hash = r.take(32)?.try_into().ok()?;
        mtls.push(MtlSource { name, hash });
    }
    let n = r.count(24)?;
    let positions = r
        .words::<f32, 3>(n)?
        .into_iter()
        .map(Vec3::from_array)
        .collect();
    let normals = r
        .words::<f32, 3>(n)?
        .into_iter()
        .map(Vec3::from_array)
        .collect();
    let n_uv = r.count(8)?;
    if n_uv != 0 && n_uv != n {
        return None;
    }
    let uvs = r
        .words::<f32, 2>(n_uv)?
        .into_iter()
        .map(Vec2::from_array)
        .collect();
    let n_tri = r.count(16)?;
    let triangles: Vec<[u32; 3]> = r.words::<u32, 3>(n_tri)?;
    let tri_material: Vec<u32> = r.words::<u32, 1>(n_tri)?.into_iter().map(|[i]| i).collect();
    let n_names = r.count(1)?;
    let mut material_names = Vec::new();
    for _ in 0..n_names {
        material_names.push(match r.take(1)?[0] {
            0 => None,
            1 => Some(r.string()?),
            _ => return None,
        });
    }
    let n_warn = r.count(4)?;
    let warnings = (0..n_warn)
        .map(|_| r.string())
        .collect::<Option<Vec<_>>>()?;
    let in_range = triangles.iter().flatten().all(|&i| (i as usize) < n)
        && tri_material.iter().all(|&i| (i as usize) < n_names);
    if r.left != 0 || !in_range {
        return None;
    }
    let mesh = MeshData {
        positions,
        normals,
        uvs,
        triangles,
        tri_material,
        material_names,
        warnings,
        ..MeshData::default()
    };
    Some((mesh, mtls))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;
    use std::fmt::Write as _;

    /// An OBJ of `n` × `n` quads (two materials in alternate rows, uvs,
    /// no normals so the parse computes them, one polyline for a warning)
    /// and its MTL file.
    fn grid(n: usize) -> (Vec<u8>, Vec<u8>) {
        let mut s = String::from("mtllib grid.mtl\n");
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
                let z = (x * 7.0).sin() * (y * 5.0).cos() * 0.1;
                writeln!(s, "v {x} {y} {z}\nvt {x} {y}").unwrap();
            }
        }
        s.push_str("l 1 2\n");
        let at = |i: usize, j: usize| j * (n + 1) + i + 1;
        for j in 0..n {
            writeln!(s, "usemtl {}", if j % 2 == 0 { "red" } else { "blue" }).unwrap();
            for i in 0..n {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                writeln!(s, "f {a}/{a} {b}/{b} {c}/{c} {d}/{d}").unwrap();
            }
        }
        let mtl = b"newmtl red\nKd 0.8 0.1 0.1\nnewmtl blue\nKd 0.1 0.1 0.8\n".to_vec();
        (s.into_bytes(), mtl)
    }

    type Files = std::cell::RefCell<HashMap<PathBuf, Vec<u8>>>;

    fn reader(files: &Files) -> impl Fn(&Path) -> std::io::Result<Vec<u8>> + '_ {
        move |p: &Path| {
            files
                .borrow()
                .get(p)
                .cloned()
                .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "absent"))
        }
    }

    /// Everything a mesh holds, tobj's materials included.
    fn all(m: &MeshData) -> String {
        format!("{m:?}")
    }

    #[test]
    fn a_cached_mesh_is_the_parsed_one_and_an_edited_mtl_is_a_miss() {
        let dir = tempfile::tempdir().unwrap();
        let (obj, mtl) = grid(40);
        let path = Path::new("scenes/grid.obj");
        let files: Files = Default::default();
        files
            .borrow_mut()
            .insert(PathBuf::from("scenes/grid.mtl"), mtl);
        let read = reader(&files);

        let (parsed, hit) = load_obj_cached(path, &obj, &read, Some(dir.path())).unwrap();
        assert!(!hit);
        assert_eq!(parsed.triangles.len(), 2 * 40 * 40);
        assert_eq!(parsed.mtl.len(), 2);
        assert_eq!(parsed.warnings.len(), 1, "{:?}", parsed.warnings);
        let (cached, hit) = load_obj_cached(path, &obj, &read, Some(dir.path())).unwrap();
        assert!(hit, "second load is a hit");
        assert_eq!(all(&cached), all(&parsed));

        // The same bytes under another name: its own entry (messages name it).
        let other = Path::new("scenes/copy.obj");
        let (_, hit) = load_obj_cached(other, &obj, &read, Some(dir.path())).unwrap();
        assert!(!hit);

        // An edited MTL: a miss, and the new colour.
        let edited = b"newmtl red\nKd 0.2 0.9 0.1\nnewmtl blue\nKd 0.1 0.1 0.8\n".to_vec();
        files
            .borrow_mut()
            .insert(PathBuf::from("scenes/grid.mtl"), edited);
        let (m, hit) = load_obj_cached(path, &obj, &read, Some(dir.path())).unwrap();
        assert!(!hit);
        assert_eq!(m.mtl[0].diffuse, Some([0.2, 0.9, 0.1]));
        let (m2, hit) = load_obj_cached(path, &obj, &read, Some(dir.path())).unwrap();
        assert!(hit);
        assert_eq!(all(&m2), all(&m));

        // A missing MTL: not a hit, and the parse's own error or warning.
        files.borrow_mut().clear();
        let both = |c: Option<&Path>| {
            load_obj_cached(path, &obj, &read, c)
                .map(|(m, hit)| (all(&m), hit))
                .map_err(|e| e.to_string())
        };
        let uncached = both(None);
        let got = both(Some(dir.path()));
        assert!(!matches!(got, Ok((_, true))));
        assert_eq!(got.map(|(m, _)| m), uncached.map(|(m, _)| m));
    }

    #[test]
    fn a_file_hashed_as_it_is_read_has_its_bytes_key() {
        let cache = tempfile::tempdir().unwrap();
        let scene = tempfile::tempdir().unwrap();
        // A file of many of the hash's reads, and a part of one.
        let (mut obj, mtl) = grid(100);
        obj.resize(obj.len() + 3 * 65_536 + 12_345, b'\n');
        let path = Path::new("scenes/grid.obj");
        let file = scene.path().join("grid.obj");
        std::fs::write(&file, &obj).unwrap();
        let files: Files = Default::default();
        files
            .borrow_mut()
            .insert(PathBuf::from("scenes/grid.mtl"), mtl);
        let read = reader(&files);

        let (k, len) = key_of_file(path, &file, 0).unwrap();
        assert_eq!(k, key(path, &obj));
        assert_eq!(len, obj.len() as u64);
        assert!(
            load(cache.path(), &k, path, &read).is_none(),
            "nothing cached yet"
        );
        let (parsed, hit) = load_obj_cached(path, &obj, &read, Some(cache.path())).unwrap();
        assert!(!hit);
        let cached = load(cache.path(), &k, path, &read).expect("a hit once the parse is stored");
        assert_eq!(all(&cached), all(&parsed));
        // Another name for the same bytes, and the file edited: other keys.
        assert_ne!(
            key_of_file(Path::new("scenes/copy.obj"), &file, 0)
                .unwrap()
                .0,
            k
        );
        obj.extend_from_slice(b"v 0 0 0\n");
        std::fs::write(&file, &obj).unwrap();
        assert_eq!(key_of_file(path, &file, 0).unwrap().0, key(path, &obj));
        assert_ne!(key_of_file(path, &file, 0).unwrap().0, k);
    }

    #[test]
    fn a_damaged_cache_file_is_a_miss_and_is_rewritten() {
        let dir = tempfile::tempdir().unwrap();
        let (obj, mtl) = grid(12);
        let path = Path::new("g/grid.obj");
        let files: Files = Default::default();
        files.borrow_mut().insert(PathBuf::from("g/grid.mtl"), mtl);
        let read = reader(&files);
        let (parsed, _) = load_obj_cached(path, &obj, &read, Some(dir.path())).unwrap();
        let cache_file = file(dir.path(), &key(path, &obj));
        let good = std::fs::read(&cache_file).unwrap();

        let mut damaged = Vec::new();
        // Cut short at several places, a triangle index out of range, a
        // count far beyond the file, a trailing byte.
        for cut in [0, 7, 100, good.len() / 2, good.len() - 1] {
            damaged.push(good[..cut].to_vec());
        }
        let tri_at = good.len() - parsed_tail_len(&parsed) - 12 * parsed.triangles.len();
        let first = parsed.triangles[0][0].to_le_bytes();
        assert_eq!(
            good[tri_at..tri_at + 4],
            first,
            "layout of the test's damage"
        );
        let mut bad_index = good.clone();
        bad_index[tri_at..tri_at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        damaged.push(bad_index);
        let mut huge = good.clone();
        huge[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
        damaged.push(huge);
        // A vertex count far beyond the file, after the one MTL entry.
        let at = 8 + 4 + 4 + "grid.mtl".len() + 32;
        let n = (parsed.positions.len() as u32).to_le_bytes();
        assert_eq!(good[at..at + 4], n, "layout of the test's damage");
        let mut huge_vertices = good.clone();
        huge_vertices[at..at + 4].copy_from_slice(&(u32::MAX / 2).to_le_bytes());
        damaged.push(huge_vertices);
        let mut trailing = good.clone();
        trailing.push(0);
        damaged.push(trailing);

        for (k, bytes) in damaged.iter().enumerate() {
            std::fs::write(&cache_file, bytes).unwrap();
            let (m, hit) = load_obj_cached(path, &obj, &read, Some(dir.path())).unwrap();
            assert!(!hit, "damage {k} read as a hit");
            assert_eq!(all(&m), all(&parsed), "damage {k}");
            assert_eq!(
                std::fs::read(&cache_file).unwrap(),
                good,
                "damage {k}: rewritten"
            );
        }
    }

    /// Bytes after the triangles' corner indices in [`encode`]'s layout
    /// (their materials, the names, the warnings).
    fn parsed_tail_len(m: &MeshData) -> usize {
        let names: usize = m
            .material_names
            .iter()
            .map(|n| 1 + n.as_ref().map_or(0, |n| 4 + n.len()))
            .sum();
        let warnings: usize = m.warnings.iter().map(|w| 4 + w.len()).sum();
        4 * m.tri_material.len() + 4 + names + 4 + warnings
    }
}
