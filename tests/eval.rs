//! `specula eval` end to end through the binary: values against plainly
//! written formulas, bad lines answered with errors in order, and the run
//! going on after them.

use std::io::Write;
use std::process::{Command, Stdio};

fn eval(input: &str) -> Vec<serde_json::Value> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_specula"))
        .arg("eval")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run specula eval");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect()
}

fn f(v: &serde_json::Value) -> [f64; 3] {
    let a = v["f"]
        .as_array()
        .unwrap_or_else(|| panic!("not a value: {v}"));
    [0, 1, 2].map(|i| a[i].as_f64().unwrap())
}

#[test]
fn values_errors_and_order() {
    let alpha: f64 = 0.3;
    let input = [
        // 1: Lambert, f = ρ/π.
        r#"{"material":{"model":"lambert","base_color":[0.2,0.5,0.8]},"wi":[0.1,0.2,1],"wo":[0,-0.4,2]}"#,
        // 2: GGX mirror configuration (h = n), F = 1.
        r#"{"material":{"model":"microfacet","ndf":"ggx","alpha":0.3,"fresnel":{"type":"schlick","f0":[1,1,1]}},"wi":[0.3,0,1],"wo":[-0.3,0,1]}"#,
        // 3: not JSON.
        "not json",
        // 4: unknown field.
        r#"{"material":{"model":"microfacet","ndf":"ggx","alpha":0.3,"shine":2,"fresnel":{"type":"schlick","f0":[1,1,1]}},"wi":[0,0,1],"wo":[0,0,1]}"#,
        // 5: below the horizon.
        r#"{"material":{"model":"lambert","base_color":[1,1,1]},"wi":[0,0,-1],"wo":[0,0,1]}"#,
        // 6: zero direction.
        r#"{"material":{"model":"lambert","base_color":[1,1,1]},"wi":[0,0,0],"wo":[0,0,1]}"#,
        // 7: metallic-roughness at normal incidence, metal: F0 D V with V = 1/4.
        r#"{"material":{"model":"metallic_roughness","base_color":[1,0.5,0.2],"roughness":0.5,"metallic":1},"wi":[0,0,1],"wo":[0,0,1]}"#,
        // 8, 9: a rough lobe with and without Kulla-Conty compensation.
        r#"{"material":{"model":"microfacet","ndf":"ggx","alpha":0.8,"energy_compensation":true,"fresnel":{"type":"schlick","f0":[1,1,1]}},"wi":[0.5,0,1],"wo":[0,0.3,1]}"#,
        r#"{"material":{"model":"microfacet","ndf":"ggx","alpha":0.8,"fresnel":{"type":"schlick","f0":[1,1,1]}},"wi":[0.5,0,1],"wo":[0,0.3,1]}"#,
    ]
    .join("\n");
    let out = eval(&(input + "\n"));
    assert_eq!(out.len(), 9, "{out:?}");
    // Compensation only adds energy (F = 1: the lobe is ≥ 0).
    let (with, without) = (f(&out[7]), f(&out[8]));
    assert!(
        with[0] > without[0] && with[0].is_finite(),
        "{with:?} vs {without:?}"
    );

    let l = f(&out[0]);
    for (g, rho) in l.iter().zip([0.2f32, 0.5, 0.8]) {
        assert!((g - rho as f64 / std::f64::consts::PI).abs() < 1e-7);
    }

    // D(h = n) = 1/(π α²); Λ(θ) = (−1 + √(1 + α² tan²θ))/2; G2 = 1/(1 + 2Λ).
    let cos = 1.0 / 1.09f64.sqrt();
    let tan2 = (1.0 - cos * cos) / (cos * cos);
    let lambda = (-1.0 + (1.0 + alpha * alpha * tan2).sqrt()) / 2.0;
    let want =
        1.0 / (std::f64::consts::PI * alpha * alpha) / (1.0 + 2.0 * lambda) / (4.0 * cos * cos);
    for g in f(&out[1]) {
        assert!((g - want).abs() < 1e-5 * want, "{g} vs {want}");
    }

    for (i, needle) in [(2, "line 3"), (3, "line 4"), (5, "line 6")] {
        let e = out[i]["error"]
            .as_str()
            .unwrap_or_else(|| panic!("line {}: expected an error, got {}", i + 1, out[i]));
        assert!(e.starts_with(needle), "{e}");
    }
    assert!(out[3]["error"].as_str().unwrap().contains("shine"));
    assert!(out[5]["error"].as_str().unwrap().contains("wi"));
    assert_eq!(f(&out[4]), [0.0; 3]);

    let mr = f(&out[6]);
    let d = 1.0 / (std::f64::consts::PI * 0.25f64.powi(2));
    for (g, base) in mr.iter().zip([1.0f32, 0.5, 0.2]) {
        let want = base as f64 * d * 0.25;
        assert!((g - want).abs() < 1e-5 * want, "{g} vs {want}");
    }
}

#[test]
fn unlit_reflects_nothing_and_emits_its_radiance_above_the_horizon() {
    let m = r#"{"model": "unlit", "color": [0.25, 0.5, 1.0], "intensity": 3.0}"#;
    let out = eval(&format!(
        "{{\"material\": {m}, \"wi\": [0.3, 0, 1], \"wo\": [-0.2, 0.1, 1]}}\n\
         {{\"material\": {m}, \"wi\": [0.3, 0, 1], \"wo\": [0, 0.1, -1]}}\n\
         {{\"material\": {{\"model\": \"unlit\", \"color\": [1, 1, 1], \"intensity\": -1}}, \"wi\": [0, 0, 1], \"wo\": [0, 0, 1]}}\n"
    ));
    assert_eq!(f(&out[0]), [0.0; 3]);
    let e: Vec<f64> = out[0]["emission"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(e, [0.75, 1.5, 3.0]);
    assert_eq!(out[1]["emission"], serde_json::json!([0.0, 0.0, 0.0]));
    let err = out[2]["error"].as_str().unwrap();
    assert!(err.starts_with("line 3: material.intensity"), "{err}");
}
