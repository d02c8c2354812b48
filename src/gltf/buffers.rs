//! Buffer bytes and accessors (glTF 2.0 spec, "Buffers and Buffer Views",
//! "Accessors"): buffers from the GLB's BIN chunk, base64 data URIs or
//! external files; accessor elements read through their buffer view
//! (interleaved by `byteStride`), integer components normalized where the
//! accessor says so, and sparse substitutions applied. Every offset and
//! length is checked before it is read, and every allocation is counted
//! against the memory budget (`memory.rs`) first.

use super::{Ctx, DataUriError, GltfError};
use crate::memory;
use base64::Engine;
use gltf::json;
use json::accessor::{ComponentType, Type};
use json::validation::Checked;
use std::path::PathBuf;

/// The bytes of every buffer, in order.
pub(super) struct Buffers {
    pub(super) data: Vec<Vec<u8>>,
}

/// The payload of a `data:` URI (`data:[<mediatype>][;base64],<data>`);
/// only base64 payloads carry binary data, so anything else is an error.
pub(super) fn data_uri(uri: &str) -> Option<Result<Vec<u8>, DataUriError>> {
    let rest = uri.strip_prefix("data:")?;
    let Some((head, payload)) = rest.split_once(',') else {
        return Some(Err(DataUriError::NoComma));
    };
    if !head.ends_with(";base64") {
        return Some(Err(DataUriError::NotBase64(
            crate::validate::truncate_echo(head, 60).to_string(),
        )));
    }
    Some(
        base64::engine::general_purpose::STANDARD
            .decode(payload.trim())
            .map_err(DataUriError::Base64),
    )
}

/// A relative URI as a path: percent escapes decoded (`%20` → space).
pub(super) fn uri_path(uri: &str) -> PathBuf {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    PathBuf::from(String::from_utf8_lossy(&out).into_owned())
}

impl Buffers {
    /// Every buffer's bytes, at least `byteLength` of them.
    pub(super) fn load(ctx: &mut Ctx, bin: Option<&[u8]>) -> Result<Buffers, GltfError> {
        let mut data = Vec::with_capacity(ctx.root.buffers.len());
        for (i, b) in ctx.root.buffers.iter().enumerate() {
            let at = format!("buffers[{i}]");
            let len = b.byte_length.0;
            memory::reserve(&format!("{at} ({len} bytes)"), len)?;
            let bytes =
                match &b.uri {
                    None => match (i, bin) {
                        (0, Some(bin)) => bin.to_vec(),
                        _ => return Err(GltfError::at(
                            &at,
                            "no uri, and only the first buffer of a GLB file may use its BIN chunk",
                        )),
                    },
                    Some(uri) => match data_uri(uri) {
                        Some(r) => r.map_err(|source| GltfError::DataUri {
                            at: format!("{at}.uri"),
                            source,
                        })?,
                        None => {
                            let p = ctx.dir.join(uri_path(uri));
                            let bytes = (ctx.read)(&p).map_err(|source| GltfError::Read {
                                at: format!("{at}.uri"),
                                path: p.clone(),
                                source,
                            })?;
                            ctx.inputs.push(p);
                            bytes
                        }
                    },
                };
            if (bytes.len() as u64) < len {
                return Err(GltfError::at(
                    &at,
                    format!(
                        "byteLength is {len}, but only {} bytes are there",
                        bytes.len()
                    ),
                ));
            }
            data.push(bytes);
        }
        Ok(Buffers { data })
    }

    /// The bytes of buffer view `v` (`at` names it in messages).
    pub(super) fn view<'a>(
        &'a self,
        root: &json::Root,
        v: usize,
        at: &str,
    ) -> Result<(&'a [u8], Option<usize>), GltfError> {
        let view = root
            .buffer_views
            .get(v)
            .ok_or_else(|| GltfError::at(at, format!("bufferView {v} does not exist")))?;
        let buf = self.data.get(view.buffer.value()).ok_or_else(|| {
            GltfError::at(
                &format!("bufferViews[{v}].buffer"),
                format!("no buffer {}", view.buffer),
            )
        })?;
        let start = view.byte_offset.map_or(0, |o| o.0);
        let end = start.checked_add(view.byte_length.0);
        let declared = root.buffers[view.buffer.value()].byte_length.0;
        match end {
            Some(end) if end <= declared => Ok((
                &buf[start as usize..end as usize],
                view.byte_stride.map(|s| s.0),
            )),
            _ => Err(GltfError::at(
                &format!("bufferViews[{v}]"),
                format!(
                    "bytes {start}..{} run past the end of buffers[{}] ({declared} bytes)",
                    start.saturating_add(view.byte_length.0),
                    view.buffer
                ),
            )),
        }
    }
}

/// Bytes of one component.
fn component_size(c: ComponentType) -> usize {
    match c {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

/// Components per element (matrices are read column after column; the
/// spec's column padding applies to 1- and 2-byte matrices only).
fn multiplicity(t: Type) -> usize {
    match t {
        Type::Scalar => 1,
        Type::Vec2 => 2,
        Type::Vec3 => 3,
        Type::Vec4 | Type::Mat2 => 4,
        Type::Mat3 => 9,
        Type::Mat4 => 16,
    }
}

/// One component at `b`: its value, normalized when `norm` ("Accessor
/// data types": c / (2ⁿ⁻¹ − 1) for signed, at least −1; c / (2ⁿ − 1) for
/// unsigned).
fn component(b: &[u8], c: ComponentType, norm: bool) -> f64 {
    match c {
        ComponentType::I8 => {
            let v = b[0] as i8 as f64;
            if norm {
                (v / 127.0).max(-1.0)
            } else {
                v
            }
        }
        ComponentType::U8 => b[0] as f64 / if norm { 255.0 } else { 1.0 },
        ComponentType::I16 => {
            let v = i16::from_le_bytes([b[0], b[1]]) as f64;
            if norm {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        ComponentType::U16 => {
            u16::from_le_bytes([b[0], b[1]]) as f64 / if norm { 65535.0 } else { 1.0 }
        }
        ComponentType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        ComponentType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
    }
}

/// An accessor's elements, flattened: `count × components` values.
pub(super) struct Elements {
    pub(super) values: Vec<f64>,
    pub(super) components: usize,
    pub(super) count: usize,
}

/// Reads accessor `a` (`at` is the JSON path that referred to it, for
/// messages); `types` are the element types the caller accepts.
pub(super) fn read_accessor(
    root: &json::Root,
    buffers: &Buffers,
    a: usize,
    at: &str,
    types: &[Type],
) -> Result<Elements, GltfError> {
    let acc = root
        .accessors
        .get(a)
        .ok_or_else(|| GltfError::at(at, format!("accessor {a} does not exist")))?;
    let here = format!("accessors[{a}]");
    let (Checked::Valid(ty), Checked::Valid(ct)) = (acc.type_, acc.component_type) else {
        return Err(GltfError::at(&here, "invalid type or componentType"));
    };
    let ct = ct.0;
    if !types.contains(&ty) {
        return Err(GltfError::at(
            at,
            format!("accessor {a} has type {ty:?}, expected one of {types:?}"),
        ));
    }
    let n = multiplicity(ty);
    let count = acc.count.0;
    let total = count
        .checked_mul(n as u64)
        .filter(|t| *t <= u32::MAX as u64)
        .ok_or_else(|| {
            GltfError::at(
                &format!("{here}.count"),
                format!("{count} elements is too many"),
            )
        })?;
    memory::reserve(
        &format!("{here} ({count} elements of {ty:?})"),
        total.saturating_mul(8),
    )?;
    let (count, total) = (count as usize, total as usize);
    let mut values = vec![0.0f64; total];
    let csize = component_size(ct);
    let elem = n * csize;
    if let Some(v) = acc.buffer_view {
        let (bytes, stride) = buffers.view(root, v.value(), &format!("{here}.bufferView"))?;
        let stride = stride.unwrap_or(elem);
        if stride < elem {
            return Err(GltfError::at(
                &format!("bufferViews[{v}].byteStride"),
                format!("{stride} is less than the {elem} bytes of an element of {here}"),
            ));
        }
        let offset = acc.byte_offset.map_or(0, |o| o.0) as usize;
        if count > 0 {
            let need = (count - 1)
                .checked_mul(stride)
                .and_then(|x| x.checked_add(offset))
                .and_then(|x| x.checked_add(elem));
            if need.is_none_or(|need| need > bytes.len()) {
                return Err(GltfError::at(&here, format!("{count} elements from byte {offset} with stride {stride} run past the end of bufferViews[{v}] ({} bytes)", bytes.len())));
            }
        }
        for (i, out) in values.chunks_exact_mut(n).enumerate() {
            let base = offset + i * stride;
            for (k, o) in out.iter_mut().enumerate() {
                *o = component(&bytes[base + k * csize..], ct, acc.normalized);
            }
        }
    }
    if let Some(s) = &acc.sparse {
        let sp = format!("{here}.sparse");
        let m = s.count.0;
        if m > count as u64 {
            return Err(GltfError::at(
                &format!("{sp}.count"),
                format!("{m} substitutions for {count} elements"),
            ));
        }
        let m = m as usize;
        let Checked::Valid(ict) = s.indices.component_type else {
            return Err(GltfError::at(
                &format!("{sp}.indices.componentType"),
                "invalid",
            ));
        };
        let ict = ict.0;
        let isize = component_size(ict);
        let (ib, _) = buffers.view(
            root,
            s.indices.buffer_view.value(),
            &format!("{sp}.indices.bufferView"),
        )?;
        let ioff = s.indices.byte_offset.0 as usize;
        if ioff.checked_add(m * isize).is_none_or(|e| e > ib.len()) {
            return Err(GltfError::at(
                &format!("{sp}.indices"),
                format!("{m} indices from byte {ioff} run past the end of their buffer view"),
            ));
        }
        let (vb, _) = buffers.view(
            root,
            s.values.buffer_view.value(),
            &format!("{sp}.values.bufferView"),
        )?;
        let voff = s.values.byte_offset.0 as usize;
        if voff.checked_add(m * elem).is_none_or(|e| e > vb.len()) {
            return Err(GltfError::at(
                &format!("{sp}.values"),
                format!("{m} elements from byte {voff} run past the end of their buffer view"),
            ));
        }
        for j in 0..m {
            let idx = component(&ib[ioff + j * isize..], ict, false) as usize;
            if idx >= count {
                return Err(GltfError::at(
                    &format!("{sp}.indices[{j}]"),
                    format!("{idx} is past the accessor's {count} elements"),
                ));
            }
            for k in 0..n {
                values[idx * n + k] =
                    component(&vb[voff + j * elem + k * csize..], ct, acc.normalized);
            }
        }
    }
    Ok(Elements {
        values,
        components: n,
        count,
    })
}
