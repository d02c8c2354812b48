//! The file format of the committed LTC tables (`core/data/ltc_*.bin`):
//! a text header line `MAGIC NX NY CHANNELS`, comment lines starting with
//! `#` (how the table was made), an `end` line, then NX × NY cells of
//! CHANNELS little-endian f32 each, rows (y) outer, x inner.

use crate::table::{Axis, Table2};

/// The header line of a table of `nx × ny` cells of `channels` values.
fn header(magic: &str, nx: usize, ny: usize, channels: usize) -> String {
    format!("{magic} {nx} {ny} {channels}")
}

/// A table file's bytes: `cells` in row order, each giving its channels.
pub(crate) fn encode<'a, const C: usize>(
    magic: &str,
    nx: usize,
    ny: usize,
    cells: impl IntoIterator<Item = [f32; C]>,
    comments: impl IntoIterator<Item = &'a String>,
) -> Vec<u8> {
    let mut out = header(magic, nx, ny, C) + "\n";
    for c in comments {
        out += &format!("# {c}\n");
    }
    out += "end\n";
    let mut bytes = out.into_bytes();
    for cell in cells {
        for v in cell {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    bytes
}

/// Reads a table file written by [`encode`] with the same magic and size.
pub(crate) fn decode<const C: usize>(
    bytes: &[u8],
    magic: &str,
    (x_axis, y_axis): (Axis, Axis),
) -> Result<Table2<C>, String> {
    let (nx, ny) = (x_axis.n(), y_axis.n());
    let first = bytes
        .iter()
        .position(|&b| b == b'\n')
        .ok_or("no header line")?;
    let head = std::str::from_utf8(&bytes[..first]).map_err(|_| "header is not text")?;
    if head != header(magic, nx, ny, C) {
        return Err(format!("unexpected header {head:?}"));
    }
    let end = bytes
        .windows(5)
        .position(|w| w == b"\nend\n")
        .ok_or("no `end` line")?
        + 5;
    let data = &bytes[end..];
    if data.len() != nx * ny * C * 4 {
        return Err(format!(
            "{} data bytes, want {}",
            data.len(),
            nx * ny * C * 4
        ));
    }
    let vals: Vec<f32> = data
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    if !vals.iter().all(|v| v.is_finite()) {
        return Err("non-finite value".into());
    }
    let rows = (0..ny)
        .map(|j| {
            (0..nx)
                .map(|i| {
                    let k = (j * nx + i) * C;
                    core::array::from_fn(|c| vals[k + c])
                })
                .collect()
        })
        .collect();
    Ok(Table2::from_rows(x_axis, y_axis, rows))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::{Nodes, Warp};

    #[test]
    fn tables_round_trip_and_bad_files_are_refused() {
        let axes = (
            Axis::new(3, 0.0, 1.0, Warp::Linear, Nodes::Ends),
            Axis::new(2, 0.0, 1.0, Warp::Linear, Nodes::Ends),
        );
        let cells: Vec<[f32; 2]> = (0..6).map(|k| [k as f32, -0.5 * k as f32]).collect();
        let comments = ["made by a test".to_string()];
        let bytes = encode("magic 1", 3, 2, cells.iter().copied(), &comments);
        let t = decode::<2>(&bytes, "magic 1", axes).expect("round trip");
        for (k, want) in cells.iter().enumerate() {
            assert_eq!(t.node_value(k % 3, k / 3), *want);
        }
        assert!(decode::<2>(&bytes, "magic 2", axes)
            .unwrap_err()
            .contains("header"));
        assert!(decode::<3>(&bytes, "magic 1", axes).is_err());
        let short = &bytes[..bytes.len() - 4];
        assert!(decode::<2>(short, "magic 1", axes)
            .unwrap_err()
            .contains("data bytes"));
        let mut nan = bytes.clone();
        let n = nan.len();
        nan[n - 4..].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(decode::<2>(&nan, "magic 1", axes)
            .unwrap_err()
            .contains("non-finite"));
    }
}
