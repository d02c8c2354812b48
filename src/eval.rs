//! `specula eval`: reference BRDF values for other renderers.
//!
//! The contract (README, "Reference values"): JSON Lines on stdin, one
//! object per line, `{"material": {...}, "wi": [x, y, z], "wo": [x, y, z]}`
//! in the local shading frame (normal +Z, tangent +X, bitangent +Y;
//! directions away from the surface, need not be normalized). Each line
//! gets one line on stdout, in order: `{"f": [r, g, b]}`, the BRDF value
//! (no cosine; 0 when either direction is at or below the horizon),
//! evaluated in f64 (`unlit` adds `"emission": [r, g, b]`, its radiance
//! toward `wo`, and reflects nothing); or `{"error": "line N: ..."}`, and
//! the run goes on.
//! Material objects use the scene files' field names.

use crate::material_desc::{MaterialDesc, Shading, Tables};
use serde::Deserialize;
use specula_core::{ShadingFrame, V3};
use std::collections::HashMap;
use std::io::{BufRead, Write};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Query {
    material: serde_json::Value,
    wi: [f64; 3],
    wo: [f64; 3],
}

/// Materials already built, keyed by their JSON text (scripts usually
/// sweep directions over few materials).
#[derive(Default)]
pub struct Cache {
    built: HashMap<String, Shading>,
}

/// Most materials kept; the cache is cleared when full.
const CACHE_MAX: usize = 4096;

fn unit(field: &str, v: [f64; 3]) -> Result<V3<f64>, String> {
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if !(len.is_finite() && len > 0.0) {
        return Err(format!(
            "{field}: must be a finite non-zero vector, got {v:?}"
        ));
    }
    Ok(V3::new(v[0] / len, v[1] / len, v[2] / len))
}

/// One answer: the BRDF value, and for `unlit` the emitted radiance.
struct Answer {
    f: [f64; 3],
    emission: Option<[f64; 3]>,
}

fn eval(line: &str, cache: &mut Cache) -> Result<Answer, String> {
    let q: Query = serde_json::from_str(line).map_err(|e| e.to_string())?;
    let wi = unit("wi", q.wi)?;
    let wo = unit("wo", q.wo)?;
    let key = q.material.to_string();
    if !cache.built.contains_key(&key) {
        let desc: MaterialDesc =
            serde_json::from_value(q.material).map_err(|e| format!("material: {e}"))?;
        let (m, _) = desc
            .build_shading(Tables::Skip, &mut Vec::new())
            .map_err(|e| format!("material.{e}"))?;
        if cache.built.len() >= CACHE_MAX {
            cache.built.clear();
        }
        cache.built.insert(key.clone(), m);
    }
    Ok(match &cache.built[&key] {
        Shading::Lit(model) => {
            // The identity frame: tangent +X, bitangent +Y, normal +Z
            // (anisotropic models read the tangent).
            let frame = ShadingFrame {
                t: V3::new(1.0, 0.0, 0.0),
                b: V3::new(0.0, 1.0, 0.0),
                n: V3::new(0.0, 0.0, 1.0),
            };
            let f = model.f_in(&frame, wi, wo);
            Answer {
                f: [f.x, f.y, f.z],
                emission: None,
            }
        }
        // No reflection; emits toward every direction above the horizon.
        Shading::Unlit(u) => Answer {
            f: [0.0; 3],
            emission: Some(if wo.z > 0.0 {
                u.radiance().map(|c| c as f64)
            } else {
                [0.0; 3]
            }),
        },
    })
}

/// The output line (without newline) for input line `lineno` (1-based).
pub fn eval_line(line: &str, lineno: usize, cache: &mut Cache) -> String {
    match eval(line, cache) {
        Ok(Answer { f, emission: None }) => serde_json::json!({ "f": f }).to_string(),
        Ok(Answer {
            f,
            emission: Some(e),
        }) => serde_json::json!({ "f": f, "emission": e }).to_string(),
        Err(e) => serde_json::json!({ "error": format!("line {lineno}: {e}") }).to_string(),
    }
}

/// Runs the contract over `input`, writing to `output`. Fails only on I/O.
pub fn run(input: impl BufRead, mut output: impl Write) -> std::io::Result<()> {
    let mut cache = Cache::default();
    for (i, line) in input.lines().enumerate() {
        let line = line?;
        writeln!(output, "{}", eval_line(&line, i + 1, &mut cache))?;
    }
    output.flush()
}
