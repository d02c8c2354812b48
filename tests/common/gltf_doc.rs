//! glTF documents written by tests: a buffer of accessors as a base64
//! data URI, and small PNG images.

use base64::Engine;
use serde_json::{json, Value};

/// A buffer being written: its bytes, views and accessors.
#[derive(Default)]
pub struct Buf {
    pub bytes: Vec<u8>,
    pub views: Vec<Value>,
    pub accessors: Vec<Value>,
}

impl Buf {
    pub fn view(&mut self, data: &[u8], stride: Option<usize>) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.bytes.len(), "byteLength": data.len()});
        if let Some(s) = stride {
            v["byteStride"] = json!(s);
        }
        self.bytes.extend_from_slice(data);
        self.views.push(v);
        self.views.len() - 1
    }
    pub fn accessor(&mut self, a: Value) -> usize {
        self.accessors.push(a);
        self.accessors.len() - 1
    }
    /// A float accessor of `ty` ("VEC3", …) over its own view.
    pub fn floats(&mut self, v: &[f32], ty: &str) -> usize {
        let n = match ty {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            _ => 4,
        };
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, None);
        self.accessor(
            json!({"bufferView": view, "componentType": 5126, "count": v.len() / n, "type": ty}),
        )
    }
    pub fn u16s(&mut self, v: &[u16]) -> usize {
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, None);
        self.accessor(
            json!({"bufferView": view, "componentType": 5123, "count": v.len(), "type": "SCALAR"}),
        )
    }
    pub fn u8s(&mut self, v: &[u8]) -> usize {
        let view = self.view(v, None);
        self.accessor(
            json!({"bufferView": view, "componentType": 5121, "count": v.len(), "type": "SCALAR"}),
        )
    }
    pub fn data_uri(&self) -> String {
        format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&self.bytes)
        )
    }
    /// A whole glTF document around `rest` (meshes, nodes, …).
    pub fn doc(&self, rest: Value) -> Value {
        let mut d = json!({
            "asset": {"version": "2.0"},
            "buffers": [{"byteLength": self.bytes.len(), "uri": self.data_uri()}],
            "bufferViews": self.views,
            "accessors": self.accessors,
        });
        for (k, v) in rest.as_object().unwrap() {
            d[k] = v.clone();
        }
        d
    }
}

/// An RGB PNG of `w` × `h` texels (`rgb` row by row, top row first) as a
/// data URI.
pub fn png_uri(w: u32, h: u32, rgb: &[u8]) -> String {
    let img = image::RgbImage::from_raw(w, h, rgb.to_vec()).expect("w × h × 3 bytes");
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(out)
    )
}

/// An RGBA PNG of `w` × `h` texels (`rgba` row by row, top row first)
/// as a data URI.
pub fn png_rgba_uri(w: u32, h: u32, rgba: &[u8]) -> String {
    let img = image::RgbaImage::from_raw(w, h, rgba.to_vec()).expect("w × h × 4 bytes");
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(out)
    )
}

/// The sRGB decoding of an 8-bit value (IEC 61966-2-1), written out here.
pub fn srgb_decode(v: u8) -> f64 {
    let v = v as f64 / 255.0;
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}
