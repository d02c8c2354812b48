//! `specula eval` end to end through the binary: values against plainly
//! written formulas, bad lines answered with errors in order, and the run
//! going on after them.

mod common;

use common::eval;

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

/// Directions need not be normalized: any finite non-zero scale gives
/// the answer of the unit vector, even where the squared length would
/// leave f64's range.
#[test]
fn directions_of_any_finite_scale_are_normalized() {
    let line = |s: f64| {
        format!(
            r#"{{"material":{{"model":"microfacet","ndf":"ggx","alpha":0.3,"fresnel":{{"type":"schlick","f0":[1,1,1]}}}},"wi":[{:e},0,{:e}],"wo":[-0.3,0,1]}}"#,
            0.3 * s,
            s
        )
    };
    let input: Vec<String> = [1.0, 1e-170, 1e160, 1e300].map(line).to_vec();
    let out = eval(&input.join("\n"));
    let unit = f(&out[0]);
    assert!(unit[0] > 0.0);
    for (v, s) in out.iter().skip(1).zip(["1e-170", "1e160", "1e300"]) {
        let got = f(v);
        for c in 0..3 {
            assert!(
                (got[c] - unit[c]).abs() <= 1e-12 * unit[c],
                "scale {s}: {got:?} vs {unit:?}"
            );
        }
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

/// `"model": "disney"` end to end: defaults, the anisotropic tangent frame
/// (+X is the tangent), and errors naming the field. Expected values from
/// the BRDF Explorer's formulas written out here.
#[test]
fn disney_values_frame_and_errors() {
    use std::f64::consts::PI;
    let out = eval(concat!(
        // 1: defaults, mirror configuration at normal incidence: h = n.
        r#"{"material":{"model":"disney"},"wi":[0,0,1],"wo":[0,0,1]}"#,
        "\n",
        // 2, 3: metal, anisotropic, the same pair rotated by 90° about n.
        r#"{"material":{"model":"disney","metallic":1,"base_color":[1,1,1],"anisotropic":1,"roughness":0.5},"wi":[0.6,0,0.8],"wo":[-0.6,0,0.8]}"#,
        "\n",
        r#"{"material":{"model":"disney","metallic":1,"base_color":[1,1,1],"anisotropic":1,"roughness":0.5},"wi":[0,0.6,0.8],"wo":[0,-0.6,0.8]}"#,
        "\n",
        // 4: NaN cannot be written in JSON; a negative roughness is an error.
        r#"{"material":{"model":"disney","roughness":-0.1},"wi":[0,0,1],"wo":[0,0,1]}"#,
        "\n",
        // 5: a mixing weight past 1.
        r#"{"material":{"model":"disney","sheen_tint":1.5},"wi":[0,0,1],"wo":[0,0,1]}"#,
        "\n",
        // 6: accepted beyond [0, 1], with a warning naming each field.
        r#"{"material":{"model":"disney","specular":2,"sheen":3},"wi":[0,0,1],"wo":[0,0,1]}"#,
        "\n",
        // 7: an unknown field.
        r#"{"material":{"model":"disney","glossiness":1},"wi":[0,0,1],"wo":[0,0,1]}"#,
        "\n",
    ));
    assert_eq!(out.len(), 7, "{out:?}");

    // 1: μ = 1, cos θd = 1: F_d = 1, F_H = 0 (no sheen), F_s = C_spec0 = 0.04;
    // D(n) = 1/(π α²) with α = 0.25, G = 1.
    let base = [0.82, 0.67, 0.16];
    let d = 1.0 / (PI * 0.25f64.powi(2));
    for (c, g) in f(&out[0]).iter().enumerate() {
        let want = base[c] / PI + 0.04 * d / 4.0;
        assert!((g - want).abs() < 1e-6 * want, "{g} vs {want}");
    }

    // 2, 3: h = n, cos θd = 0.8, F = 1 (white metal); D(n) = 1/(π αx αy);
    // G1 = 2μ / (μ + √(μ² + αx² x² + αy² y²)): the elongated axis is x, so
    // G1 along x (line 2) is smaller than along y (line 3).
    let aspect = 0.1f64.sqrt();
    let (ax, ay) = (0.25 / aspect, 0.25 * aspect);
    let g1 = |a: f64| 2.0 * 0.8 / (0.8 + (0.64 + a * a * 0.36).sqrt());
    let dn = 1.0 / (PI * ax * ay);
    let along_x = dn * g1(ax).powi(2) / (4.0 * 0.64);
    let along_y = dn * g1(ay).powi(2) / (4.0 * 0.64);
    assert!(
        (f(&out[1])[0] - along_x).abs() < 1e-6 * along_x,
        "{:?} vs {along_x}",
        out[1]
    );
    assert!(
        (f(&out[2])[0] - along_y).abs() < 1e-6 * along_y,
        "{:?} vs {along_y}",
        out[2]
    );

    for (i, field) in [
        (3, "material.roughness"),
        (4, "material.sheen_tint"),
        (6, "glossiness"),
    ] {
        let e = out[i]["error"]
            .as_str()
            .unwrap_or_else(|| panic!("line {}: expected an error, got {}", i + 1, out[i]));
        assert!(e.contains(field), "{e}");
    }
    assert!(f(&out[5])[0] > 0.0);
    let w = out[5]["warning"]
        .as_str()
        .unwrap_or_else(|| panic!("line 6: expected a warning, got {}", out[5]));
    assert!(
        w.contains("material.specular") && w.contains("material.sheen"),
        "{w}"
    );
    assert!(out[0].get("warning").is_none(), "{}", out[0]);
}
