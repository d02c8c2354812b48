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
//!
//! A line may give `"light"` instead of `"wi"`: `{"material": {...}, "wo":
//! [x, y, z], "light": {"polygon": [[x, y, z], ...], "radiance": [r, g, b],
//! "two_sided": false}, "method": "ltc"}` answers `{"radiance": [r, g, b]}`,
//! the radiance reflected toward `wo` at the origin by a polygon light (in
//! the same local frame, validated as in scene files); `"method":
//! "reference"` integrates numerically and adds `"error"`, the estimated
//! absolute error of each channel's value.

use crate::material_desc::{MaterialDesc, Shading, Tables};
use serde::Deserialize;
use specula_core::light::{PolygonLocal, MAX_POLYGON_VERTICES};
use specula_core::ltc::reference::{integrate_polygon_toward, Peak, Tolerance};
use specula_core::{Brdf, BrdfVisitor, Model, ShadingFrame, V3};
use std::collections::HashMap;
use std::io::{BufRead, Write};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Query {
    material: serde_json::Value,
    wi: Option<[f64; 3]>,
    wo: [f64; 3],
    light: Option<PolygonQuery>,
    method: Option<Method>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PolygonQuery {
    polygon: Vec<[f32; 3]>,
    radiance: [f64; 3],
    #[serde(default)]
    two_sided: bool,
}

#[derive(Clone, Copy, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
enum Method {
    Ltc,
    Reference,
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

/// `v` normalized. Scaled by its largest component first, so any finite
/// non-zero vector qualifies: the squares of 1e-170 or 1e160 would leave
/// f64's range.
fn unit(field: &str, v: [f64; 3]) -> Result<V3<f64>, String> {
    let big = v.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    if !(big.is_finite() && big > 0.0) {
        return Err(format!(
            "{field}: must be a finite non-zero vector, got {v:?}"
        ));
    }
    let [x, y, z] = v.map(|c| c / big);
    let len = (x * x + y * y + z * z).sqrt();
    Ok(V3::new(x / len, y / len, z / len))
}

/// One answer: the BRDF value, and for `unlit` the emitted radiance.
struct Answer {
    f: [f64; 3],
    emission: Option<[f64; 3]>,
    /// Adjustments made to the material (e.g. a clamped alpha), joined.
    warning: Option<String>,
}

/// What a line answers.
enum Reply {
    Brdf(Answer),
    /// With the material's adjustments, as for BRDF lines.
    Light(LightAnswer, Option<String>),
}

/// A `"light"` line's answer: reflected radiance, and the reference's
/// estimated error.
struct LightAnswer {
    radiance: [f64; 3],
    error: Option<[f64; 3]>,
}

/// ∫ f cos over the polygon by the model's own LTC integral (f64 lanes).
struct LtcIntegral<'a> {
    wo: V3<f64>,
    poly: &'a PolygonLocal<f64>,
}

impl BrdfVisitor for LtcIntegral<'_> {
    type Output = Option<[f64; 3]>;
    fn visit<B: Brdf>(self, b: &B) -> Option<[f64; 3]> {
        if !B::POLYGON_LIGHTS {
            return None;
        }
        let e = b.polygon_local(&b.prepare(self.wo), self.poly);
        Some([e.x, e.y, e.z])
    }
}

/// The reference integral of the model's f cos over the polygon.
struct RefIntegral<'a> {
    wo: V3<f64>,
    vertices: &'a [V3<f64>],
    two_sided: bool,
}

impl BrdfVisitor for RefIntegral<'_> {
    type Output = ([f64; 3], f64);
    fn visit<B: Brdf>(self, b: &B) -> ([f64; 3], f64) {
        let p = b.prepare(self.wo);
        let f = |wi: V3<f64>| {
            let c = b.f_cos_local(&p, wi);
            [c.x, c.y, c.z]
        };
        // The glossy lobe peaks around the mirror direction, at most about
        // α wide (narrower for GTR's large γ): the quadrature is graded
        // toward it, down to 1e-4 α.
        let alpha = {
            let r = b.env_lobes(&p).roughness;
            (r * r).max(1e-3)
        };
        let peak = Peak {
            direction: V3::new(-self.wo.x, -self.wo.y, self.wo.z).normalize(),
            angle: 1e-4 * alpha,
        };
        let e = integrate_polygon_toward(
            self.vertices,
            self.two_sided,
            &f,
            Tolerance::FINE,
            Some(peak),
        );
        (e.value, e.error)
    }
}

fn eval_light(
    model: &Model,
    wo: V3<f64>,
    light: &PolygonQuery,
    method: Method,
) -> Result<LightAnswer, String> {
    crate::polygon_light::check_polygon("light.polygon", &light.polygon)?;
    let max = crate::checks::MAX_RADIOMETRIC as f64;
    if !light.radiance.iter().all(|c| (0.0..=max).contains(c)) {
        return Err(format!(
            "light.radiance: every component must be in [0, {max:e}] (as in scene files), got {:?}",
            light.radiance
        ));
    }
    // What a polygon light reflects depends on the directions to its
    // points, not on its distance: scaled so its largest coordinate is 1,
    // a polygon of 1e-15 is integrated as well as one of 1.
    let big = light
        .polygon
        .iter()
        .flatten()
        .fold(0.0f64, |m, c| m.max((*c as f64).abs()));
    let verts: Vec<V3<f64>> = light
        .polygon
        .iter()
        .map(|p| V3::new(p[0] as f64 / big, p[1] as f64 / big, p[2] as f64 / big))
        .collect();
    let l = light.radiance;
    match method {
        Method::Ltc => {
            if let Some(why) = crate::polygon_light::ltc_refusal(model) {
                return Err(format!("method: {why}; use \"reference\""));
            }
            let mut poly = PolygonLocal {
                vertices: [V3::zero(); MAX_POLYGON_VERTICES],
                len: verts.len(),
                two_sided: light.two_sided,
            };
            poly.vertices[..verts.len()].copy_from_slice(&verts);
            let e = model
                .visit(LtcIntegral { wo, poly: &poly })
                .ok_or_else(|| {
                    format!(
                        "method: the \"{}\" model has no LTC integral; use \"reference\"",
                        model.name()
                    )
                })?;
            Ok(LightAnswer {
                radiance: [0, 1, 2].map(|c| e[c] * l[c]),
                error: None,
            })
        }
        Method::Reference => {
            let (e, err) = model.visit(RefIntegral {
                wo,
                vertices: &verts,
                two_sided: light.two_sided,
            });
            Ok(LightAnswer {
                radiance: [0, 1, 2].map(|c| e[c] * l[c]),
                error: Some(l.map(|c| err * c)),
            })
        }
    }
}

fn eval(line: &str, cache: &mut Cache) -> Result<Reply, String> {
    let q: Query = serde_json::from_str(line).map_err(|e| e.to_string())?;
    let wo = unit("wo", q.wo)?;
    let wi = match (&q.wi, &q.light) {
        (Some(wi), None) => Some(unit("wi", *wi)?),
        (None, Some(_)) => None,
        _ => return Err("give exactly one of \"wi\" and \"light\"".into()),
    };
    if wi.is_some() && q.method.is_some() {
        return Err("\"method\" goes with \"light\", not \"wi\"".into());
    }
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
    let Some(wi) = wi else {
        let light = q.light.as_ref().expect("checked above");
        let method = q.method.unwrap_or(Method::Ltc);
        let answer = match shading {
            Shading::Lit(model) => eval_light(model, wo, light, method)?,
            Shading::Unlit(_) => LightAnswer {
                radiance: [0.0; 3],
                error: (method == Method::Reference).then_some([0.0; 3]),
            },
        };
        return Ok(Reply::Light(answer, warning));
    };
    Ok(Reply::Brdf(match shading {
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
    }))
}

/// The output line (without newline) for input line `lineno` (1-based).
pub fn eval_line(line: &str, lineno: usize, cache: &mut Cache) -> String {
    match eval(line, cache) {
        Ok(reply) => {
            let (mut answer, warning) = match reply {
                Reply::Brdf(Answer {
                    f,
                    emission,
                    warning,
                }) => {
                    let mut answer = serde_json::json!({ "f": f });
                    if let Some(e) = emission {
                        answer["emission"] = serde_json::json!(e);
                    }
                    (answer, warning)
                }
                Reply::Light(LightAnswer { radiance, error }, warning) => {
                    let mut answer = serde_json::json!({ "radiance": radiance });
                    if let Some(e) = error {
                        answer["error"] = serde_json::json!(e);
                    }
                    (answer, warning)
                }
            };
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
