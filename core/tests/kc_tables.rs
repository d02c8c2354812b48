//! The committed Kulla–Conty tables (core/data/kc_tables.bin) against a
//! fresh build of the same tables by the code that made them.

use specula_core::kulla_conty::committed::{committed, committed_tables, decode, encode};
use specula_core::kulla_conty::{gamma_node, KcTable, N_ALPHA, N_MU};
use specula_core::models::microfacet::{Ndf, Smith};

#[test]
fn committed_file_holds_every_listed_table() {
    let c = committed();
    let want = committed_tables();
    assert_eq!(c.len(), want.len());
    for (ndf, smith, exact) in want {
        let name = KcTable::store_name(ndf, smith, exact);
        let v = c.get(&name).unwrap_or_else(|| panic!("{name} missing"));
        assert_eq!(v.len(), N_MU * N_ALPHA);
    }
}

/// Regenerates a few tables (GGX, Beckmann and three GTR γ nodes, both
/// Smith forms and both GTR Λ among them) and compares every node with the file. Each
/// build is N_MU × N_ALPHA albedo quadratures, so only a few.
#[test]
fn committed_tables_match_a_fresh_build() {
    let some = [
        (Ndf::Ggx, Smith::HeightCorrelated, false),
        (Ndf::Beckmann, Smith::Separable, false),
        (
            Ndf::Gtr {
                gamma: gamma_node(0),
            },
            Smith::HeightCorrelated,
            false,
        ),
        (
            Ndf::Gtr {
                gamma: gamma_node(13),
            },
            Smith::Separable,
            false,
        ),
        (
            Ndf::Gtr {
                gamma: gamma_node(27),
            },
            Smith::HeightCorrelated,
            true,
        ),
    ];
    for (ndf, smith, exact) in some {
        let name = KcTable::store_name(ndf, smith, exact);
        let fresh = KcTable::build_values(ndf, smith, exact);
        let stored = &committed()[&name];
        let worst = fresh
            .iter()
            .zip(stored)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        // The same f64 quadrature rounded to f32: equal up to the last
        // bit or two where the compiler contracts differently.
        assert!(worst <= 1e-6, "{name}: max |Δ| = {worst:e}");
    }
}

#[test]
fn a_bad_file_is_refused_whole() {
    let v = vec![0.5f32; N_MU * N_ALPHA];
    let good = encode(&[("a".into(), v.clone())], &["test".into()]);
    assert_eq!(decode(&good).unwrap()["a"], v);
    // Truncated data, a wrong header, a non-finite value.
    assert!(decode(&good[..good.len() - 4]).is_err());
    let mut other = good.clone();
    other[11] = b'9';
    assert!(decode(&other).is_err());
    let mut nan = good.clone();
    let n = nan.len();
    nan[n - 4..].copy_from_slice(&f32::NAN.to_le_bytes());
    assert!(decode(&nan).is_err());
    assert!(decode(b"").is_err());
}

/// The generator's table list and names agree with the file (a new table
/// kind added to `committed_tables` without regenerating fails here).
#[test]
fn generator_list_matches_the_file_order() {
    let names: Vec<String> = committed_tables()
        .into_iter()
        .map(|(n, s, e)| KcTable::store_name(n, s, e))
        .collect();
    let mut file: Vec<&String> = committed().keys().collect();
    file.sort();
    let mut want: Vec<&String> = names.iter().collect();
    want.sort();
    assert_eq!(file, want);
}
