//! Kulla–Conty tables come from an installed [`TableStore`] when it holds a
//! valid one, and are built and saved there when it does not (its own
//! test binary: the store is process-wide).

use specula_core::kulla_conty::{set_table_store, KcTable, TableStore, N_ALPHA, N_MU};
use specula_core::models::microfacet::{Ndf, Smith};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

struct MemStore(Arc<Mutex<HashMap<String, Vec<f32>>>>);

impl TableStore for MemStore {
    fn load(&self, name: &str) -> Option<Vec<f32>> {
        self.0.lock().unwrap().get(name).cloned()
    }
    fn save(&self, name: &str, values: &[f32]) {
        self.0.lock().unwrap().insert(name.into(), values.to_vec());
    }
}

#[test]
fn tables_load_from_the_store_and_bad_entries_are_rebuilt() {
    let map = Arc::new(Mutex::new(HashMap::new()));
    let (good, bad) = (Ndf::Gtr { gamma: 3.0 }, Ndf::Gtr { gamma: 5.0 });
    let hc = Smith::HeightCorrelated;
    // A stored table no quadrature would give (E = 0.5 everywhere) and a
    // truncated one.
    map.lock().unwrap().insert(
        KcTable::store_name(good, hc, false),
        vec![0.5; N_MU * N_ALPHA],
    );
    map.lock()
        .unwrap()
        .insert(KcTable::store_name(bad, hc, false), vec![0.5; 7]);
    set_table_store(Box::new(MemStore(map.clone())));

    let t = KcTable::get_with(good, hc, false);
    assert!((0..N_MU).all(|i| (0..N_ALPHA).all(|j| t.e.node_value(i, j)[0] == 0.5)));

    let t = KcTable::get_with(bad, hc, false);
    // Built: E(μ = 1) of a rough lobe is neither 0.5 nor outside (0, 1].
    let e = t.e.node_value(N_MU - 1, N_ALPHA / 2)[0];
    assert!(e > 0.6 && e <= 1.0, "{e}");
    let saved = map.lock().unwrap()[&KcTable::store_name(bad, hc, false)].clone();
    assert_eq!(saved.len(), N_MU * N_ALPHA);
    assert_eq!(saved[(N_ALPHA / 2) * N_MU + N_MU - 1], e);
}
