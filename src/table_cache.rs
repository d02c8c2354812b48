//! The user's table cache: Kulla–Conty E tables (core::kulla_conty) kept
//! between runs. The common ones (GGX, Beckmann, GTR at the γ nodes) are
//! committed in core (kulla_conty/committed.rs) and never reach it; GTR with γ
//! outside the γ axis builds a table per γ (~0.6 s), which the cache
//! keeps so that it is paid once per machine, not once per run. The same
//! folder holds prefiltered environment maps (envmap_file.rs) and parsed
//! OBJ meshes (mesh_cache.rs), each under its own file names.
//!
//! Folder: `$SPECULA_CACHE_DIR` when set (empty: no cache), else
//! `specula` in the user's cache folder as `dirs::cache_dir` finds it (on
//! Linux `$XDG_CACHE_HOME` when it is an absolute path, else `~/.cache`).
//! One file per table, `<name>.f32`: its node values as f32 little-endian,
//! the name carrying everything the table depends on and the table
//! format's version. A file of the wrong length or with non-finite values is
//! ignored and rebuilt; files are written to a temporary name and renamed,
//! so a reader never sees half a file. The cache is an optimisation only:
//! any I/O error leaves the table built in memory, silently. Deleting the
//! folder is always safe.

use specula_core::kulla_conty::{set_table_store, TableStore};
use std::path::PathBuf;

/// The cache folder (module docs), or None when disabled or unknown.
pub(crate) fn cache_dir() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os("SPECULA_CACHE_DIR") {
        return (!d.is_empty()).then(|| PathBuf::from(d));
    }
    dirs::cache_dir().map(|d| d.join("specula"))
}

/// Tables as files in one folder.
pub(crate) struct DirStore {
    pub(crate) dir: PathBuf,
}

impl TableStore for DirStore {
    fn load(&self, name: &str) -> Option<Vec<f32>> {
        let bytes = std::fs::read(self.dir.join(format!("{name}.f32"))).ok()?;
        if bytes.len() % 4 != 0 {
            return None;
        }
        Some(
            bytes
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect(),
        )
    }

    fn save(&self, name: &str, values: &[f32]) {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let path = self.dir.join(format!("{name}.f32"));
        let tmp = self.dir.join(format!(".{name}.{}.tmp", std::process::id()));
        let ok = std::fs::create_dir_all(&self.dir).is_ok()
            && std::fs::write(&tmp, bytes).is_ok()
            && std::fs::rename(&tmp, &path).is_ok();
        if !ok {
            let _ = std::fs::remove_file(&tmp);
        }
    }
}

/// `specula kc-tables`: builds the tables core commits
/// (core/src/kulla_conty/committed.rs) and writes the file to `out`.
pub fn write_committed(out: &std::path::Path) -> Result<(), crate::output_plan::OutputError> {
    crate::output_plan::check_early("--output", out)?;
    let t = std::time::Instant::now();
    let total = specula_core::kulla_conty::committed::committed_tables().len() as u64;
    let progress = crate::progress::Progress::new("kc-tables", "tables", total, true);
    let tables = specula_core::kulla_conty::committed::build_all_reporting(&mut || progress.inc());
    progress.finish();
    let comments = vec![
        format!("written by `specula kc-tables --output {}`", out.display()),
        "Kulla-Conty E(mu, alpha), F = 1; mu: 64 nodes (j/63)^2; sqrt(alpha): 32 nodes k/31 (alpha floored at ALPHA_MIN)".into(),
        "GTR at gamma = 2^(-2 + 9 k / 27), k = 0..27, with GGX's and with the exact Lambda; names as KcTable::store_name".into(),
    ];
    let bytes = specula_core::kulla_conty::committed::encode(&tables, &comments);
    crate::output_plan::Output::new("--output", out)?.write(&bytes)?;
    eprintln!(
        "wrote {} tables to {} ({:.0} s)",
        tables.len(),
        out.display(),
        t.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Installs the user's cache folder as core's table store (no-op when
/// disabled).
pub fn install() {
    if let Some(dir) = cache_dir() {
        set_table_store(Box::new(DirStore { dir }));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_bad_files() {
        let dir = std::env::temp_dir().join(format!("specula-cache-test-{}", std::process::id()));
        let s = DirStore { dir: dir.clone() };
        assert_eq!(s.load("t"), None);
        let v = [0.25f32, -1.5, 3.0e-7, 1.0];
        s.save("t", &v);
        assert_eq!(s.load("t").as_deref(), Some(&v[..]));
        // A truncated file is not a table.
        std::fs::write(dir.join("u.f32"), [0u8; 6]).unwrap();
        assert_eq!(s.load("u"), None);
        // No temporary files stay behind.
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
