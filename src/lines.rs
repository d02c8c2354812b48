//! The scene file's line tables: `[[outline]]` (any number, drawn in
//! order) and `[strokes]` (npr/src/outline.rs, sobel/, extrude/,
//! edges/, overlay/). Parsed with serde like the rest of the scene,
//! every field checked once here with a message naming it; the checked
//! description then becomes post stages and geometry passes.

use serde::Deserialize;
use std::collections::BTreeMap;

/// One `[[outline]]` table as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct OutlineDesc {
    method: MethodDesc,
    /// Line width in output pixels (extrusion, sobel).
    width: Option<f32>,
    #[serde(default)]
    color: [f32; 3],
    /// shading: n·v below which the surface is darkened; sobel: gradient
    /// magnitude, one number for every source or a table per source.
    threshold: Option<ThresholdDesc>,
    /// sobel only: the buffers searched for edges.
    sources: Option<Vec<SourceDesc>>,
    /// Only pixels (shading, sobel) or triangles (extrusion) of these
    /// materials; default all.
    materials: Option<Vec<String>>,
    /// sobel only: soft line edges (default true).
    antialias: Option<bool>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(crate) enum MethodDesc {
    Shading,
    Extrusion,
    Sobel,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum SourceDesc {
    Depth,
    Normal,
    Id,
    Color,
}

impl SourceDesc {
    fn name(self) -> &'static str {
        match self {
            SourceDesc::Depth => "depth",
            SourceDesc::Normal => "normal",
            SourceDesc::Id => "id",
            SourceDesc::Color => "color",
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum ThresholdDesc {
    All(f32),
    PerSource(BTreeMap<String, f32>),
}

/// `[strokes]` as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct StrokesDesc {
    #[serde(default = "all_edges")]
    edges: Vec<EdgeKindDesc>,
    /// Degrees: an edge whose faces' normals differ by more is a crease.
    #[serde(default = "sixty")]
    crease_angle: f32,
    #[serde(default = "one")]
    width: f32,
    #[serde(default)]
    color: [f32; 3],
    /// 0: constant width; 1: the width falls to 0 at both ends.
    #[serde(default)]
    taper: f32,
    #[serde(default)]
    join: JoinDesc,
    #[serde(default)]
    cap: CapDesc,
}

fn all_edges() -> Vec<EdgeKindDesc> {
    vec![
        EdgeKindDesc::Silhouette,
        EdgeKindDesc::Crease,
        EdgeKindDesc::Boundary,
        EdgeKindDesc::Material,
    ]
}
fn sixty() -> f32 {
    60.0
}
fn one() -> f32 {
    1.0
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum EdgeKindDesc {
    Silhouette,
    Crease,
    Boundary,
    Material,
}

#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(crate) enum JoinDesc {
    #[default]
    Round,
    Miter,
    Bevel,
}

#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(crate) enum CapDesc {
    #[default]
    Round,
    Butt,
    Square,
}

/// Widest accepted line, in output pixels (the extrusion and the dilation
/// work in supersamples: 64 × ssaa 16 = 1024 samples stays cheap).
pub(crate) const MAX_WIDTH: f32 = 64.0;

/// A checked `[[outline]]`.
#[derive(Clone, Debug, PartialEq)]
pub enum OutlineSpec {
    Shading {
        color: [f32; 3],
        threshold: f32,
        materials: Option<Vec<String>>,
    },
    Extrusion {
        color: [f32; 3],
        width: f32,
        materials: Option<Vec<String>>,
    },
    Sobel {
        color: [f32; 3],
        width: f32,
        /// (source, threshold), sorted by source, no repeats.
        sources: Vec<(SourceDesc, f32)>,
        materials: Option<Vec<String>>,
        antialias: bool,
    },
}

/// A checked `[strokes]`.
#[derive(Clone, Debug, PartialEq)]
pub struct StrokesSpec {
    pub edges: Vec<EdgeKindDesc>,
    pub crease_angle: f32,
    pub width: f32,
    pub(crate) color: [f32; 3],
    pub(crate) taper: f32,
    pub(crate) join: JoinDesc,
    pub(crate) cap: CapDesc,
}

/// A line table's field refused: the field as written (`outline[1].width`,
/// `strokes.edges`) and why. The messages are the ones users read.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub(crate) enum LineTableError {
    /// A check shared with the other tables (colours, weights).
    #[error(transparent)]
    Field(#[from] crate::checks::FieldError),
    /// A line width outside (0, [`MAX_WIDTH`]].
    #[error("{field}: must be a number in (0, {MAX_WIDTH}] pixels, got {got}")]
    Width { field: String, got: f32 },
    /// `materials = []`.
    #[error("{field}: name at least one material (or leave the field out for all)")]
    NoMaterials { field: String },
    /// A material name the scene does not have.
    #[error("{field}: no material named {name:?} in the scene")]
    UnknownMaterial { field: String, name: String },
    /// A field the outline's method does not read.
    #[error("{field}.{name}: not used by method {method:?}")]
    Unused {
        field: String,
        name: &'static str,
        method: &'static str,
    },
    /// A per-source threshold table on a shading outline.
    #[error("{field}.threshold: method \"shading\" takes one number (n·v), not a table")]
    ShadingThresholdTable { field: String },
    /// A shading outline's n·v threshold outside (0, 1).
    #[error("{field}.threshold: n·v threshold must be in (0, 1), got {got}")]
    ShadingThreshold { field: String, got: f32 },
    /// `sources = []`.
    #[error("{field}.sources: name at least one source (depth, normal, id, color)")]
    NoSources { field: String },
    /// A Sobel source named twice.
    #[error("{field}.sources: {name:?} is listed twice")]
    SourceTwice { field: String, name: &'static str },
    /// A Sobel threshold that is not a finite number > 0 (`field` names
    /// the threshold, per source where it is one).
    #[error("{field}: must be a finite number > 0, got {got}")]
    SobelThreshold { field: String, got: f32 },
    /// A per-source threshold for a source the outline does not search.
    #[error("{field}.threshold.{key}: not one of this outline's sources ({sources})")]
    NotASource {
        field: String,
        key: String,
        /// The outline's sources, comma separated.
        sources: String,
    },
    /// `strokes.edges = []`.
    #[error("strokes.edges: name at least one kind (silhouette, crease, boundary, material)")]
    NoEdges,
    /// An edge kind named twice in `strokes.edges`.
    #[error("strokes.edges: {0:?} is listed twice")]
    EdgeTwice(EdgeKindDesc),
    /// `strokes.crease_angle` outside (0, 180).
    #[error("strokes.crease_angle: must be in (0, 180) degrees, got {0}")]
    CreaseAngle(f32),
}

fn check_width(field: &str, w: f32) -> Result<(), LineTableError> {
    // `contains` is false for NaN.
    if w > 0.0 && w <= MAX_WIDTH {
        Ok(())
    } else {
        Err(LineTableError::Width {
            field: field.to_string(),
            got: w,
        })
    }
}

fn check_materials(
    field: &str,
    m: &Option<Vec<String>>,
    known: &dyn Fn(&str) -> bool,
) -> Result<(), LineTableError> {
    let Some(list) = m else { return Ok(()) };
    if list.is_empty() {
        return Err(LineTableError::NoMaterials {
            field: field.to_string(),
        });
    }
    if let Some(n) = list.iter().find(|n| !known(n.as_str())) {
        return Err(LineTableError::UnknownMaterial {
            field: field.to_string(),
            name: n.clone(),
        });
    }
    Ok(())
}

impl OutlineDesc {
    /// Checks the table (`field` is e.g. `outline[2]`); `known` says
    /// whether a material name exists in the scene.
    pub(crate) fn check(
        &self,
        field: &str,
        known: &dyn Fn(&str) -> bool,
    ) -> Result<OutlineSpec, LineTableError> {
        crate::checks::display_color(&format!("{field}.color"), self.color)?;
        check_materials(&format!("{field}.materials"), &self.materials, known)?;
        let method = match self.method {
            MethodDesc::Shading => "shading",
            MethodDesc::Extrusion => "extrusion",
            MethodDesc::Sobel => "sobel",
        };
        let unused = |name: &'static str| LineTableError::Unused {
            field: field.to_string(),
            name,
            method,
        };
        let width = match (self.method, self.width) {
            (MethodDesc::Shading, Some(_)) => return Err(unused("width")),
            (_, Some(w)) => {
                check_width(&format!("{field}.width"), w)?;
                w
            }
            (_, None) => 1.0,
        };
        if self.sources.is_some() && self.method != MethodDesc::Sobel {
            return Err(unused("sources"));
        }
        if self.antialias.is_some() && self.method != MethodDesc::Sobel {
            return Err(unused("antialias"));
        }
        let materials = self.materials.clone();
        let color = self.color;
        match self.method {
            MethodDesc::Shading => {
                let threshold = match &self.threshold {
                    None => 0.25,
                    Some(ThresholdDesc::All(t)) => *t,
                    Some(ThresholdDesc::PerSource(_)) => {
                        return Err(LineTableError::ShadingThresholdTable {
                            field: field.to_string(),
                        })
                    }
                };
                // n·v of a visible surface is in [0, 1]; 1 would darken all.
                if !(threshold > 0.0 && threshold < 1.0) {
                    return Err(LineTableError::ShadingThreshold {
                        field: field.to_string(),
                        got: threshold,
                    });
                }
                Ok(OutlineSpec::Shading {
                    color,
                    threshold,
                    materials,
                })
            }
            MethodDesc::Extrusion => {
                if self.threshold.is_some() {
                    return Err(unused("threshold"));
                }
                Ok(OutlineSpec::Extrusion {
                    color,
                    width,
                    materials,
                })
            }
            MethodDesc::Sobel => {
                let list = self.sources.clone().unwrap_or(vec![
                    SourceDesc::Depth,
                    SourceDesc::Normal,
                    SourceDesc::Id,
                ]);
                if list.is_empty() {
                    return Err(LineTableError::NoSources {
                        field: field.to_string(),
                    });
                }
                let mut sorted = list.clone();
                sorted.sort();
                if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
                    return Err(LineTableError::SourceTwice {
                        field: field.to_string(),
                        name: w[0].name(),
                    });
                }
                let default = 0.25;
                let mut sources = Vec::new();
                for s in sorted {
                    let (t, tf) = match &self.threshold {
                        None => (default, format!("{field}.threshold")),
                        Some(ThresholdDesc::All(t)) => (*t, format!("{field}.threshold")),
                        Some(ThresholdDesc::PerSource(m)) => (
                            m.get(s.name()).copied().unwrap_or(default),
                            format!("{field}.threshold.{}", s.name()),
                        ),
                    };
                    if !(t > 0.0 && t.is_finite()) {
                        return Err(LineTableError::SobelThreshold { field: tf, got: t });
                    }
                    sources.push((s, t));
                }
                if let Some(ThresholdDesc::PerSource(m)) = &self.threshold {
                    if let Some(k) = m
                        .keys()
                        .find(|k| !sources.iter().any(|(s, _)| s.name() == *k))
                    {
                        return Err(LineTableError::NotASource {
                            field: field.to_string(),
                            key: k.clone(),
                            sources: sources
                                .iter()
                                .map(|(s, _)| s.name())
                                .collect::<Vec<_>>()
                                .join(", "),
                        });
                    }
                }
                Ok(OutlineSpec::Sobel {
                    color,
                    width,
                    sources,
                    materials,
                    antialias: self.antialias.unwrap_or(true),
                })
            }
        }
    }
}

impl StrokesDesc {
    pub(crate) fn check(&self) -> Result<StrokesSpec, LineTableError> {
        let f = "strokes";
        if self.edges.is_empty() {
            return Err(LineTableError::NoEdges);
        }
        let mut edges = self.edges.clone();
        edges.sort();
        if let Some(w) = edges.windows(2).find(|w| w[0] == w[1]) {
            return Err(LineTableError::EdgeTwice(w[0]));
        }
        if !(self.crease_angle > 0.0 && self.crease_angle < 180.0) {
            return Err(LineTableError::CreaseAngle(self.crease_angle));
        }
        check_width(&format!("{f}.width"), self.width)?;
        crate::checks::display_color(&format!("{f}.color"), self.color)?;
        crate::checks::unit(&format!("{f}.taper"), self.taper)?;
        Ok(StrokesSpec {
            edges,
            crease_angle: self.crease_angle,
            width: self.width,
            color: self.color,
            taper: self.taper,
            join: self.join,
            cap: self.cap,
        })
    }
}

/// What the line tables add to a loaded scene.
#[derive(Default)]
pub struct LineStages {
    /// Post stages, in the tables' order (after the tone map).
    pub(crate) post: Vec<std::sync::Arc<dyn specula_raster::post::PostStage>>,
    /// The stroke overlay (also among `post`), for `--svg-lines`.
    pub strokes: Option<std::sync::Arc<specula_npr::overlay::Strokes>>,
}

/// The radiance an unlit outline material needs for its pixels to come out
/// as `color` (display-linear, [0, 1]) after exposure and the tone map:
/// the tone curve inverted by bisection (all three curves increase).
fn radiance_for(
    color: [f32; 3],
    tonemap: specula_raster::post::Tonemap,
    exposure: f32,
) -> [f32; 3] {
    color.map(|c| {
        let (mut lo, mut hi) = (0.0f32, 1e6f32);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if tonemap.apply(mid) < c {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi * (-exposure).exp2()
    })
}

/// Builds the checked outlines into `data` (extrusion passes and their
/// materials) and post stages; outline colours are display colours after
/// the output's `tonemap` and `exposure`.
pub(crate) fn build(
    data: &mut specula_raster::SceneParts,
    outlines: &[OutlineSpec],
    strokes: Option<&StrokesSpec>,
    tonemap: specula_raster::post::Tonemap,
    exposure: f32,
) -> LineStages {
    use specula_npr::outline::id_materials;
    use specula_npr::outline::{Selection, ShadingOutline};
    use specula_npr::sobel::{Sobel, Source};
    use std::sync::Arc;
    let index = |data: &specula_raster::SceneParts, names: &Option<Vec<String>>| {
        names.as_ref().map(|list| {
            list.iter()
                .filter_map(|n| data.materials.iter().position(|m| &m.name == n))
                .map(|i| i as u32)
                .collect::<Vec<u32>>()
        })
    };
    let mut out = LineStages::default();
    // Extrusion passes first: the other stages' id tables must know them.
    for (k, o) in outlines.iter().enumerate() {
        if let OutlineSpec::Extrusion {
            color,
            width,
            materials,
        } = o
        {
            let sel = index(data, materials);
            let radiance = radiance_for(*color, tonemap, exposure);
            let m = data.materials.len() as u32;
            data.materials.push(specula_raster::Material::new(
                &format!("outline[{k}]"),
                specula_raster::Unlit {
                    color: radiance,
                    intensity: 1.0,
                },
                true,
            ));
            let stage = Arc::new(specula_npr::extrude::Extrude::new(data, *width));
            let id_base = data.geometry.iter().map(|p| p.ids().end).max().unwrap_or(0) as u32;
            let passes = specula_npr::extrude::extrusion_passes(data, stage, m, id_base, &|mat| {
                sel.as_ref().is_none_or(|s| s.contains(&mat))
            });
            data.geometry.extend(passes);
        }
    }
    let id_material = id_materials(data);
    let selection = |names: &Option<Vec<String>>| match index(data, names) {
        Some(m) => Selection::materials(&id_material, &m),
        None => Selection::all(),
    };
    for o in outlines {
        match o {
            OutlineSpec::Extrusion { .. } => {}
            OutlineSpec::Shading {
                color,
                threshold,
                materials,
            } => {
                out.post.push(Arc::new(ShadingOutline::new(
                    data.camera.clone(),
                    *threshold,
                    *color,
                    selection(materials),
                )));
            }
            OutlineSpec::Sobel {
                color,
                width,
                sources,
                materials,
                antialias,
            } => {
                out.post.push(Arc::new(Sobel {
                    sources: sources
                        .iter()
                        .map(|(s, t)| {
                            let s = match s {
                                SourceDesc::Depth => Source::Depth,
                                SourceDesc::Normal => Source::Normal,
                                SourceDesc::Id => Source::Id,
                                SourceDesc::Color => Source::Color,
                            };
                            (s, *t)
                        })
                        .collect(),
                    width: *width,
                    color: *color,
                    antialias: *antialias,
                    id_material: id_material.clone(),
                    selection: selection(materials),
                    scratch: Default::default(),
                }));
            }
        }
    }
    if let Some(st) = strokes {
        use specula_npr::edges::{EdgeKind, MeshEdges};
        let kinds: Vec<EdgeKind> = st
            .edges
            .iter()
            .map(|k| match k {
                EdgeKindDesc::Silhouette => EdgeKind::Silhouette,
                EdgeKindDesc::Crease => EdgeKind::Crease,
                EdgeKindDesc::Boundary => EdgeKind::Boundary,
                EdgeKindDesc::Material => EdgeKind::Material,
            })
            .collect();
        let stage = Arc::new(specula_npr::overlay::Strokes::new(
            MeshEdges::from_scene(data, &kinds, st.crease_angle),
            data.camera.clone(),
            st.style(),
        ));
        out.post.push(stage.clone());
        out.strokes = Some(stage);
    }
    out
}

impl StrokesSpec {
    /// The overlay's drawing style.
    pub(crate) fn style(&self) -> specula_npr::overlay::StrokeStyle {
        use specula_npr::overlay::{LineCap, LineJoin};
        specula_npr::overlay::StrokeStyle {
            width: self.width,
            color: self.color,
            taper: self.taper,
            join: match self.join {
                JoinDesc::Round => LineJoin::Round,
                JoinDesc::Miter => LineJoin::Miter,
                JoinDesc::Bevel => LineJoin::Bevel,
            },
            cap: match self.cap {
                CapDesc::Round => LineCap::Round,
                CapDesc::Butt => LineCap::Butt,
                CapDesc::Square => LineCap::Square,
            },
        }
    }
}
