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
//! the run goes on, for any bytes (a line that is not UTF-8 is a bad line).
//! A material adjusted while building (a clamped alpha) adds `"warning"`.
//! Material objects use the scene files' field names.

use crate::material_desc::{MaterialDesc, Shading, Tables};
use serde::Deserialize;
use specula_core::V3;
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
    /// The built material and what building it adjusted (a clamped alpha).
    built: HashMap<String, (Shading, Vec<String>)>,
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
    /// Adjustments made to the material (e.g. a clamped alpha), joined.
    warning: Option<String>,
}

fn eval(line: &str, cache: &mut Cache) -> Result<Answer, String> {
    let q: Query = serde_json::from_str(line).map_err(|e| e.to_string())?;
    let wi = unit("wi", q.wi)?;
    let wo = unit("wo", q.wo)?;
    let key = q.material.to_string();
    if !cache.built.contains_key(&key) {
        let desc: MaterialDesc =
            serde_json::from_value(q.material).map_err(|e| format!("material: {e}"))?;
        let mut notes = Vec::new();
        let (m, _) = desc
            .build_shading(Tables::Skip, &mut notes)
            .map_err(|e| format!("material.{e}"))?;
        if cache.built.len() >= CACHE_MAX {
            cache.built.clear();
        }
        let notes = notes.into_iter().map(|n| format!("material.{n}")).collect();
        cache.built.insert(key.clone(), (m, notes));
    }
    let (shading, notes) = &cache.built[&key];
    let warning = (!notes.is_empty()).then(|| notes.join("; "));
    Ok(match shading {
        Shading::Lit(model) => {
            let f = model.f(V3::new(0.0, 0.0, 1.0), wi, wo);
            Answer {
                f: [f.x, f.y, f.z],
                emission: None,
                warning,
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
            warning,
        },
    })
}

/// The output line (without newline) for input line `lineno` (1-based).
pub fn eval_line(line: &str, lineno: usize, cache: &mut Cache) -> String {
    match eval(line, cache) {
        Ok(Answer {
            f,
            emission,
            warning,
        }) => {
            let mut answer = serde_json::json!({ "f": f });
            if let Some(e) = emission {
                answer["emission"] = serde_json::json!(e);
            }
            if let Some(w) = warning {
                answer["warning"] = serde_json::json!(w);
            }
            answer.to_string()
        }
        // Errors may quote the input (an unknown variant's name): cut long ones.
        Err(e) => serde_json::json!({
            "error": format!("line {lineno}: {}", crate::validate::truncate_echo(&e, 1000))
        })
        .to_string(),
    }
}

/// Runs the contract over `input`, writing to `output`. Fails only on I/O:
/// any bytes make lines (split at `\n`, a trailing `\r` dropped), and a
/// line that is not UTF-8 is answered with an error like any bad line.
pub fn run(input: impl BufRead, mut output: impl Write) -> std::io::Result<()> {
    let mut cache = Cache::default();
    for (i, line) in input.split(b'\n').enumerate() {
        let mut line = line?;
        if line.last() == Some(&b'\r') {
            line.pop();
        }
        let answer = match std::str::from_utf8(&line) {
            Ok(text) => eval_line(text, i + 1, &mut cache),
            Err(e) => {
                serde_json::json!({ "error": format!("line {}: not UTF-8 text: {e}", i + 1) })
                    .to_string()
            }
        };
        writeln!(output, "{answer}")?;
    }
    output.flush()
}
