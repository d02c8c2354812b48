//! The committed Kulla–Conty E tables (`core/data/kc_tables.bin`): the
//! tables every run would otherwise build on first use (kulla_conty.rs),
//! so that neither `specula eval` sweeping GTR's γ nor a render starts by
//! computing them (~45 s for the 56 γ node tables on an empty cache).
//!
//! Held: GGX and Beckmann, and GTR at every node of [`GAMMA_AXIS`] with
//! GGX's Λ and with its exact Λ, each with separable and with
//! height-correlated Smith ([`committed_tables`]; 116 tables of 8 KB).
//! Not held: GTR off the γ axis (γ < ¼ or > 128), whose tables are built
//! on first use and kept in the user's cache folder (src/table_cache.rs).
//!
//! Format (written by `specula kc-tables --output core/data/kc_tables.bin`,
//! [`encode`]): a text header, then binary data.
//! - line 1: `specula-kc 1 <N_MU> <N_ALPHA> <count>`;
//! - lines `# ...`: comments (the command that wrote the file);
//! - `count` lines `t <name>`: each table's store name
//!   ([`KcTable::store_name`]: NDF, γ bits, Smith form, exact Λ and
//!   `TABLE_VERSION`), in data order;
//! - the line `end`;
//! - per table, N_MU × N_ALPHA f32 little-endian, α rows in order, μ
//!   inside a row (the [`crate::kulla_conty::TableStore`] layout).
//!
//! A table is looked up by its store name, so a stale file (other axes, a
//! new TABLE_VERSION) matches nothing and every table is built as before;
//! a malformed file is ignored likewise ([`committed`]). The test
//! `committed_tables_match_a_fresh_build` (core/tests/kc_tables.rs)
//! rebuilds a few tables and compares them with the file.
//!
//! [`GAMMA_AXIS`]: crate::kulla_conty::GAMMA_AXIS
//! [`KcTable::store_name`]: crate::kulla_conty::KcTable::store_name

use super::{gamma_node, KcTable, N_ALPHA, N_GAMMA, N_MU};
use crate::masking::Smith;
use crate::ndf::Ndf;
use std::collections::HashMap;
use std::sync::OnceLock;

/// The first header line's prefix.
pub(crate) const MAGIC: &str = "specula-kc 1";

/// The committed file.
static DATA: &[u8] = include_bytes!("../../data/kc_tables.bin");

/// Values per table.
const LEN: usize = N_MU * N_ALPHA;

/// The (NDF, Smith, exact GTR Λ) triples the committed file holds: GGX,
/// Beckmann, then GTR at each γ node with GGX's Λ and with its exact Λ;
/// each with both Smith forms.
pub fn committed_tables() -> Vec<(Ndf, Smith, bool)> {
    let gtr = |exact: bool| {
        (0..N_GAMMA).map(move |k| {
            (
                Ndf::Gtr {
                    gamma: gamma_node(k),
                },
                exact,
            )
        })
    };
    [(Ndf::Ggx, false), (Ndf::Beckmann, false)]
        .into_iter()
        .chain(gtr(false))
        .chain(gtr(true))
        .flat_map(|(n, e)| [(n, Smith::HeightCorrelated, e), (n, Smith::Separable, e)])
        .collect()
}

/// The file's bytes for `tables` (store name, values in store layout),
/// with `comments` (lines without the leading `#`) in the header.
pub fn encode(tables: &[(String, Vec<f32>)], comments: &[String]) -> Vec<u8> {
    let mut head = format!("{MAGIC} {N_MU} {N_ALPHA} {}\n", tables.len());
    for c in comments {
        head += &format!("# {c}\n");
    }
    for (name, _) in tables {
        head += &format!("t {name}\n");
    }
    head += "end\n";
    let mut bytes = head.into_bytes();
    for (_, v) in tables {
        assert_eq!(v.len(), LEN, "a table has N_MU × N_ALPHA values");
        bytes.extend(v.iter().flat_map(|x| x.to_le_bytes()));
    }
    bytes
}

/// Reads a file of the format above: store name → values.
pub fn decode(bytes: &[u8]) -> Result<HashMap<String, Vec<f32>>, String> {
    let end = bytes
        .windows(5)
        .position(|w| w == b"\nend\n")
        .ok_or("no `end` line")?
        + 5;
    let head = std::str::from_utf8(&bytes[..end]).map_err(|_| "header is not text")?;
    let mut lines = head.lines();
    let first = lines.next().unwrap_or_default();
    let count: usize = first
        .strip_prefix(&format!("{MAGIC} {N_MU} {N_ALPHA} "))
        .and_then(|c| c.parse().ok())
        .ok_or_else(|| format!("unexpected header {first:?}"))?;
    let names: Vec<&str> = lines.filter_map(|l| l.strip_prefix("t ")).collect();
    let data = &bytes[end..];
    if names.len() != count || data.len() != count * LEN * 4 {
        return Err(format!(
            "{} names and {} data bytes for {count} tables",
            names.len(),
            data.len()
        ));
    }
    let mut out = HashMap::new();
    for (name, chunk) in names.iter().zip(data.chunks_exact(LEN * 4)) {
        let v: Vec<f32> = chunk
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        if !v.iter().all(|x| x.is_finite()) {
            return Err(format!("table {name}: non-finite value"));
        }
        out.insert(name.to_string(), v);
    }
    Ok(out)
}

/// The committed tables by store name; empty when the file does not
/// decode (then every table is built on first use, as without it).
pub fn committed() -> &'static HashMap<String, Vec<f32>> {
    static TABLES: OnceLock<HashMap<String, Vec<f32>>> = OnceLock::new();
    TABLES.get_or_init(|| decode(DATA).unwrap_or_default())
}

/// Builds every table of [`committed_tables`] (what the generator writes):
/// (store name, values), calling `built` after each table (the generator's
/// progress).
pub fn build_all_reporting(built: &mut dyn FnMut()) -> Vec<(String, Vec<f32>)> {
    committed_tables()
        .into_iter()
        .map(|(ndf, smith, exact)| {
            let t = (
                KcTable::store_name(ndf, smith, exact),
                KcTable::build_values(ndf, smith, exact),
            );
            built();
            t
        })
        .collect()
}
