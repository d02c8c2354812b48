//! Tonal art maps: nesting in tone, darkness per level against its target
//! (measured here from the pixels), the same darkness at every level, and
//! determinism by seed.

use specula_npr::tam::{generate, grey_darkness, Tam, TamError, TamParams, TamTexture};

fn small() -> Tam {
    generate(TamParams {
        tones: 6,
        levels: 4,
        size: 128,
        seed: 7,
    })
    .unwrap()
}

#[test]
fn tones_nest_and_reach_their_darkness_at_every_level() {
    let tam = small();
    let p = tam.params;
    assert_eq!(tam.images.len(), 6);
    for t in 0..p.tones {
        let target = 0.8 * (t + 1) as f64 / 6.0;
        assert!((tam.darkness[t] - target).abs() < 1e-12);
        let mut per_level = Vec::new();
        for l in 0..p.levels {
            let img = &tam.images[t][l];
            let n = (128 >> l) as usize;
            assert_eq!(img.len(), n * n);
            let d = grey_darkness(img);
            assert!(
                (d - target).abs() < 0.02,
                "tone {t} level {l}: darkness {d:.4}, target {target:.4}"
            );
            per_level.push(d);
            if t + 1 < p.tones {
                let darker = &tam.images[t + 1][l];
                let lighter_px = img.iter().zip(darker).filter(|(a, b)| b > a).count();
                assert_eq!(
                    lighter_px, 0,
                    "tone {t} level {l}: the darker tone is lighter at {lighter_px} pixels"
                );
            }
        }
        let (lo, hi) = per_level
            .iter()
            .fold((1.0f64, 0.0f64), |(a, b), &d| (a.min(d), b.max(d)));
        assert!(
            hi - lo < 0.03,
            "tone {t}: darkness varies over levels {per_level:?}"
        );
    }
}

#[test]
fn same_seed_same_bytes_other_seed_other_bytes() {
    let p = TamParams {
        tones: 3,
        levels: 2,
        size: 32,
        seed: 42,
    };
    let (a, b) = (generate(p).unwrap(), generate(p).unwrap());
    assert_eq!(a, b);
    let c = generate(TamParams { seed: 43, ..p }).unwrap();
    assert_ne!(a.images, c.images);
}

#[test]
fn files_round_trip_and_bad_parameters_are_named() {
    let tam = generate(TamParams {
        tones: 2,
        levels: 2,
        size: 32,
        seed: 1,
    })
    .unwrap();
    let dir = std::env::temp_dir().join(format!("specula-tam-test-{}", std::process::id()));
    tam.write_dir(&dir).unwrap();
    assert!(dir.join("tam_t1_l1.png").exists());
    let back = TamTexture::read_dir(&dir).unwrap();
    assert_eq!(back, TamTexture::from_tam(&tam).unwrap());
    let m: specula_npr::tam::Manifest =
        serde_json::from_str(&std::fs::read_to_string(dir.join("tam.json")).unwrap()).unwrap();
    assert_eq!(m.sizes, vec![32, 16]);
    std::fs::remove_file(dir.join("tam_t1_l0.png")).unwrap();
    let err = TamTexture::read_dir(&dir).unwrap_err();
    assert!(
        matches!(&err, TamError::Io { path, .. } if path.ends_with("tam_t1_l0.png")),
        "{err:?}"
    );
    assert!(err.to_string().contains("tam_t1_l0.png"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();

    let bad = |p: TamParams| generate(p).unwrap_err();
    let ok = TamParams::new(6, 256, 0);
    assert_eq!(ok.levels, 5);
    let option = |p: TamParams| match bad(p) {
        TamError::Option { option, .. } => option,
        e => panic!("not an option error: {e:?}"),
    };
    assert_eq!(option(TamParams { size: 100, ..ok }), "size");
    assert_eq!(option(TamParams { levels: 6, ..ok }), "levels");
    assert_eq!(option(TamParams { tones: 0, ..ok }), "tones");
    assert!(bad(TamParams { tones: 0, ..ok })
        .to_string()
        .starts_with("tones: "));
}
