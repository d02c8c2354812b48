//! NPR lines end to end: the `[[outline]]` / `[strokes]` schema, the three
//! outline methods and the stroke overlays (issue 10).

mod common;

use std::path::Path;

const BASE: &str = r#"
[camera]
eye = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
fov_y = 40.0
near = 0.1
far = 10.0

[output]
width = 64
height = 64

[[mesh]]
sphere = { radius = 1.0, segments = 32, rings = 16 }
material = "toon"

[materials.toon]
model = "lambert"
base_color = [0.8, 0.5, 0.2]

[[light]]
type = "directional"
direction = [-0.5, -0.4, -1.0]
irradiance = [3.0, 3.0, 3.0]
"#;

fn load(extra: &str) -> Result<specula::scene::LoadedScene, String> {
    let text = format!("{BASE}\n{extra}");
    specula::scene::load_scene_str(Path::new("lines.toml"), &text, &|_| {
        Err(std::io::ErrorKind::NotFound.into())
    })
    .map_err(|e| e.to_string())
}

#[test]
fn the_issue_schema_loads() {
    let s = load(
        r#"
[[outline]]
method = "shading"
color = [0.0, 0.0, 0.0]
threshold = 0.25
materials = ["toon"]

[[outline]]
method = "extrusion"
width = 2.0

[[outline]]
method = "sobel"
width = 2.0
threshold = { depth = 0.1, normal = 0.4 }
sources = ["depth", "normal", "id"]

[strokes]
edges = ["silhouette", "crease", "boundary", "material"]
crease_angle = 60.0
width = 1.5
color = [0.05, 0.05, 0.05]
taper = 0.0
"#,
    )
    .unwrap();
    use specula::lines::{OutlineSpec, SourceDesc};
    assert_eq!(s.outlines.len(), 3);
    match &s.outlines[2] {
        OutlineSpec::Sobel { sources, width, .. } => {
            assert_eq!(*width, 2.0);
            assert_eq!(
                sources,
                &vec![
                    (SourceDesc::Depth, 0.1),
                    (SourceDesc::Normal, 0.4),
                    (SourceDesc::Id, 0.25)
                ]
            );
        }
        o => panic!("{o:?}"),
    }
    let st = s.strokes.unwrap();
    assert_eq!((st.width, st.crease_angle, st.edges.len()), (1.5, 60.0, 4));
}

#[test]
fn every_line_field_is_checked_and_named() {
    for (extra, want) in [
        ("[[outline]]\nmethod = \"sobel\"\nwdth = 2.0\n", "unknown field `wdth`"),
        ("[[outline]]\nmethod = \"pencil\"\n", "unknown variant `pencil`"),
        ("[[outline]]\nmethod = \"sobel\"\nwidth = nan\n", "outline[0].width"),
        ("[[outline]]\nmethod = \"sobel\"\nwidth = 0.0\n", "outline[0].width"),
        ("[[outline]]\nmethod = \"extrusion\"\nwidth = 65.0\n", "outline[0].width"),
        ("[[outline]]\nmethod = \"shading\"\nwidth = 2.0\n", "outline[0].width: not used"),
        ("[[outline]]\nmethod = \"shading\"\nthreshold = 1.5\n", "outline[0].threshold"),
        ("[[outline]]\nmethod = \"shading\"\nthreshold = nan\n", "outline[0].threshold"),
        ("[[outline]]\nmethod = \"shading\"\nsources = [\"depth\"]\n", "outline[0].sources: not used"),
        ("[[outline]]\nmethod = \"extrusion\"\nthreshold = 0.2\n", "outline[0].threshold: not used"),
        ("[[outline]]\nmethod = \"sobel\"\ncolor = [0.0, 2.0, 0.0]\n", "outline[0].color"),
        ("[[outline]]\nmethod = \"sobel\"\ncolor = [0.0, nan, 0.0]\n", "outline[0].color"),
        ("[[outline]]\nmethod = \"sobel\"\nsources = []\n", "outline[0].sources"),
        ("[[outline]]\nmethod = \"sobel\"\nsources = [\"id\", \"id\"]\n", "listed twice"),
        ("[[outline]]\nmethod = \"sobel\"\nsources = [\"ids\"]\n", "unknown variant `ids`"),
        ("[[outline]]\nmethod = \"sobel\"\nthreshold = -1.0\n", "outline[0].threshold"),
        ("[[outline]]\nmethod = \"sobel\"\nthreshold = { depth = nan }\n", "outline[0].threshold.depth"),
        ("[[outline]]\nmethod = \"sobel\"\nsources = [\"depth\"]\nthreshold = { normal = 0.2 }\n", "outline[0].threshold.normal"),
        ("[[outline]]\nmethod = \"sobel\"\nmaterials = [\"paper\"]\n", "outline[0].materials: no material named \"paper\""),
        ("[[outline]]\nmethod = \"sobel\"\nmaterials = []\n", "outline[0].materials"),
        ("[[outline]]\nmethod = \"sobel\"\n[[outline]]\nmethod = \"shading\"\nthreshold = 0.0\n", "outline[1].threshold"),
        ("[strokes]\nedges = []\n", "strokes.edges"),
        ("[strokes]\nedges = [\"crease\", \"crease\"]\n", "strokes.edges"),
        ("[strokes]\nedges = [\"ridge\"]\n", "unknown variant `ridge`"),
        ("[strokes]\ncrease_angle = 0.0\n", "strokes.crease_angle"),
        ("[strokes]\ncrease_angle = nan\n", "strokes.crease_angle"),
        ("[strokes]\nwidth = inf\n", "strokes.width"),
        ("[strokes]\ntaper = 1.5\n", "strokes.taper"),
        ("[strokes]\ntaper = nan\n", "strokes.taper"),
        ("[strokes]\ncolor = [-0.1, 0.0, 0.0]\n", "strokes.color"),
        ("[strokes]\njoin = \"pointy\"\n", "unknown variant `pointy`"),
        ("[strokes]\nwidth = 1.0\nstyle = 2\n", "unknown field `style`"),
    ] {
        let e = load(extra).err().unwrap_or_else(|| panic!("accepted: {extra}"));
        assert!(e.contains(want), "{extra}\n→ {e}\n(want {want:?})");
        assert!(e.starts_with("lines.toml"), "{e}");
    }
}
