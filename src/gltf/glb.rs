//! The GLB container (glTF 2.0 spec, "Binary glTF Layout"): a 12-byte
//! header (magic `glTF`, version 2, total length), then chunks of
//! (length, type, data), each 4-byte aligned: first the JSON, then an
//! optional BIN chunk. Every length is checked against the bytes present.

use super::GltfError;

/// `glTF` as a little-endian u32.
pub(super) const MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// The JSON chunk and the BIN chunk (if any) of a GLB file.
pub(super) struct Glb<'a> {
    pub(super) json: &'a [u8],
    pub(super) bin: Option<&'a [u8]>,
}

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Splits a GLB file into its chunks; the message says what is wrong
/// (wrong magic, version, a length past the end of the file).
pub(super) fn split(bytes: &[u8]) -> Result<Glb<'_>, GltfError> {
    if bytes.len() < 12 {
        return Err(GltfError::Glb(format!(
            "truncated: {} bytes, shorter than the 12-byte header",
            bytes.len()
        )));
    }
    if &bytes[..4] != MAGIC {
        return Err(GltfError::Glb(format!(
            "wrong magic {:?} (expected \"glTF\")",
            String::from_utf8_lossy(&bytes[..4])
        )));
    }
    let version = u32_at(bytes, 4).unwrap_or(0);
    if version != 2 {
        return Err(GltfError::Glb(format!(
            "header version {version}: only glTF 2 is read"
        )));
    }
    let length = u32_at(bytes, 8).unwrap_or(0) as usize;
    if length > bytes.len() {
        return Err(GltfError::Glb(format!(
            "truncated: the header gives a length of {length} bytes, the file has {}",
            bytes.len()
        )));
    }
    let body = &bytes[..length];
    let mut at = 12usize;
    let mut chunks = Vec::new();
    while at < body.len() {
        let (Some(len), Some(kind)) = (u32_at(body, at), u32_at(body, at + 4)) else {
            return Err(GltfError::Glb(format!(
                "truncated chunk header at byte {at} (of {length})"
            )));
        };
        let start = at + 8;
        let end = start
            .checked_add(len as usize)
            .filter(|e| *e <= body.len())
            .ok_or_else(|| {
                GltfError::Glb(format!(
                    "truncated: chunk {} at byte {at} claims {len} bytes, {} remain",
                    chunks.len(),
                    body.len().saturating_sub(start)
                ))
            })?;
        chunks.push((kind, &body[start..end]));
        // Chunks are padded to 4 bytes.
        at = end.div_ceil(4) * 4;
    }
    let Some(&(kind, json)) = chunks.first() else {
        return Err(GltfError::Glb(
            "no chunks (the JSON chunk is required)".into(),
        ));
    };
    if kind != CHUNK_JSON {
        return Err(GltfError::Glb(format!(
            "the first chunk has type {kind:#010x}, expected JSON ({CHUNK_JSON:#010x})"
        )));
    }
    let bin = chunks
        .get(1)
        .filter(|(kind, _)| *kind == CHUNK_BIN)
        .map(|(_, b)| *b);
    Ok(Glb { json, bin })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
        let pad = |v: &[u8], fill: u8| {
            let mut v = v.to_vec();
            while !v.len().is_multiple_of(4) {
                v.push(fill);
            }
            v
        };
        let json = pad(json, b' ');
        let mut body = Vec::new();
        body.extend_from_slice(&(json.len() as u32).to_le_bytes());
        body.extend_from_slice(&CHUNK_JSON.to_le_bytes());
        body.extend_from_slice(&json);
        if let Some(b) = bin {
            let b = pad(b, 0);
            body.extend_from_slice(&(b.len() as u32).to_le_bytes());
            body.extend_from_slice(&CHUNK_BIN.to_le_bytes());
            body.extend_from_slice(&b);
        }
        let mut out = b"glTF".to_vec();
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&((body.len() + 12) as u32).to_le_bytes());
        out.extend_from_slice(&body);
        out
    }

    #[test]
    fn chunks_are_found_and_bad_headers_refused() {
        let f = glb(b"{}", Some(&[1, 2, 3]));
        let g = split(&f).unwrap();
        assert_eq!(g.json, b"{}  ");
        assert_eq!(g.bin, Some(&[1u8, 2, 3, 0][..]));
        for cut in [0, 5, 11, 13, 20, f.len() - 1] {
            let e = split(&f[..cut]).err().expect("truncated").to_string();
            assert!(e.contains("truncated"), "{cut}: {e}");
        }
        let mut bad = f.clone();
        bad[0] = b'x';
        assert!(split(&bad)
            .err()
            .unwrap()
            .to_string()
            .contains("wrong magic"));
        let mut v1 = f.clone();
        v1[4] = 1;
        assert!(split(&v1).err().unwrap().to_string().contains("version 1"));
    }
}
