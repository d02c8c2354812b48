//! Line-by-line checks of OBJ and MTL text before tobj parses it.
//!
//! tobj reports errors without a line ("texcoord parse error") and panics on
//! some malformed input (an MTL colour with fewer than three numbers; index
//! arithmetic on out-of-range OBJ indices). Each rule here mirrors what
//! tobj 4 accepts, so a file that passes cannot make it panic or fail, and
//! a file that does not pass gets a message naming the file and the line.

use std::path::{Path, PathBuf};

/// Longest piece of an offending line quoted back in a message.
const QUOTE_MAX: usize = 60;

/// Most corners one `f` line may have. Polygons are ear-clipped
/// (`mesh::triangulate`), whose time grows with the square of the corner
/// count for awkward (self-intersecting) outlines; a larger face is refused
/// naming its line. Meshes that need more are given as triangles.
pub const MAX_FACE_CORNERS: usize = 4096;

/// Why an OBJ file (or an MTL file it names) cannot be read. Each message
/// starts with the file, and with the line where one is at fault.
#[derive(Debug, thiserror::Error)]
pub enum ObjError {
    /// The file is not UTF-8 text.
    #[error("{}: not UTF-8 text: {source}", .path.display())]
    NotUtf8 {
        path: PathBuf,
        source: std::str::Utf8Error,
    },
    /// A line breaks one of the rules tobj reads by: `why` says which,
    /// `got` quotes the line (shortened).
    #[error("{}: line {line}: {why}, got {got:?}", .path.display())]
    Line {
        path: PathBuf,
        line: usize,
        why: String,
        got: String,
    },
    /// Some `v` lines carry a vertex colour and others do not: `later` is
    /// the first line that disagrees with line `earlier`.
    #[error("{}: line {later}: a v line {} a vertex colour, but line {earlier} {} (give every v line a colour or none)",
        .path.display(),
        if *.later_coloured { "with" } else { "without" },
        if *.later_coloured { "has none" } else { "has one" })]
    MixedColours {
        path: PathBuf,
        later: usize,
        earlier: usize,
        later_coloured: bool,
    },
    /// An MTL file the OBJ names that cannot be read.
    #[error("{}: {source}", .path.display())]
    ReadMtl {
        path: PathBuf,
        source: std::io::Error,
    },
    /// tobj's own refusal, at the line it most likely means.
    #[error("{}{}: {source}", .path.display(), at_line(*.line))]
    Parse {
        path: PathBuf,
        line: Option<usize>,
        source: tobj::LoadError,
    },
    /// The MTL files named could not be loaded: each one's error, or
    /// tobj's when there is none.
    #[error("{}: material library: {}", .path.display(), materials_message(.errors, .source))]
    Materials {
        path: PathBuf,
        errors: Vec<ObjError>,
        source: tobj::LoadError,
    },
}

fn at_line(line: Option<usize>) -> String {
    line.map(|l| format!(" at line {l}")).unwrap_or_default()
}

fn materials_message(errors: &[ObjError], tobj: &tobj::LoadError) -> String {
    if errors.is_empty() {
        return tobj.to_string();
    }
    let all: Vec<String> = errors.iter().map(ToString::to_string).collect();
    all.join("; ")
}

/// The line, shortened for a message.
fn quote(line: &str) -> String {
    crate::validate::truncate_echo(line.trim(), QUOTE_MAX)
}

/// `bytes` without a leading UTF-8 byte order mark, which some editors
/// write and which tobj would read as part of the first line's keyword.
pub(crate) fn strip_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes)
}

fn utf8<'a>(path: &Path, bytes: &'a [u8]) -> Result<&'a str, ObjError> {
    std::str::from_utf8(strip_bom(bytes)).map_err(|source| ObjError::NotUtf8 {
        path: path.to_path_buf(),
        source,
    })
}

/// The error for line `n` (1-based) breaking rule `why`.
fn line_error(path: &Path, n: usize, line: &str, why: String) -> ObjError {
    ObjError::Line {
        path: path.to_path_buf(),
        line: n,
        why,
        got: quote(line),
    }
}

/// Whether the first `n` words after the keyword are numbers (tobj ignores
/// any further words).
fn numbers(rest: &[&str], n: usize) -> bool {
    rest.len() >= n && rest[..n].iter().all(|s| s.parse::<f32>().is_ok())
}

/// Checks an MTL file's text the way tobj will read it.
pub(crate) fn check_mtl(path: &Path, bytes: &[u8]) -> Result<(), ObjError> {
    let text = utf8(path, bytes)?;
    for (i, line) in text.lines().enumerate() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some((&key, rest)) = words.split_first() else {
            continue;
        };
        let why = match key {
            "newmtl" if rest.is_empty() => Some("newmtl needs a material name".to_string()),
            "Ka" | "Kd" | "Ks" | "Ke" if !numbers(rest, 3) => {
                Some(format!("{key} needs three numbers (r g b)"))
            }
            "Ns" | "Ni" | "d" if !numbers(rest, 1) => Some(format!("{key} needs a number")),
            "illum" if rest.first().and_then(|s| s.parse::<u8>().ok()).is_none() => {
                Some("illum needs an integer 0..=255".to_string())
            }
            "map_Ka" | "map_Kd" | "map_Ks" | "map_Bump" | "map_bump" | "map_Ns" | "map_ns"
            | "map_NS" | "bump" | "map_d"
                if rest.is_empty() =>
            {
                Some(format!("{key} needs a file name"))
            }
            _ => None,
        };
        if let Some(why) = why {
            return Err(line_error(path, i + 1, line, why));
        }
    }
    Ok(())
}

/// What the OBJ check found: the text tobj should read, with the faces it
/// would mishandle blanked out (line numbers kept), and what was dropped.
#[derive(Debug)]
pub(crate) struct ObjScan {
    pub(crate) text: String,
    /// `f` lines with fewer than three corners (a point or a line, not a
    /// surface), and the first such line.
    pub(crate) dropped_faces: usize,
    pub(crate) first_dropped: Option<usize>,
    /// `l` lines (polylines): tobj would read one with three or more points
    /// as a face.
    pub(crate) polylines: usize,
    /// Each name `usemtl` gives, with the first line giving it.
    pub(crate) usemtl: Vec<(String, usize)>,
}

/// Counts of `v`, `vt`, `vn` seen so far, for checking face indices.
#[derive(Default)]
struct Counts {
    v: i64,
    vt: i64,
    vn: i64,
}

/// Checks one face corner `v`, `v/vt`, `v//vn` or `v/vt/vn` against the
/// elements defined so far (OBJ indices are 1-based; negative ones count
/// back from the last element defined): why it is refused, or None.
fn corner_fault(corner: &str, c: &Counts) -> Option<String> {
    let parts: Vec<&str> = corner.split('/').collect();
    if parts.len() > 3 {
        return Some(format!("corner {corner:?} has more than v/vt/vn"));
    }
    if parts[0].is_empty() {
        return Some(format!("corner {corner:?} has no vertex index"));
    }
    for (k, (part, (name, count))) in parts
        .iter()
        .zip([("v", c.v), ("vt", c.vt), ("vn", c.vn)])
        .enumerate()
    {
        if part.is_empty() && k > 0 {
            continue;
        }
        let Ok(i) = part.parse::<i64>() else {
            return Some(format!("corner {corner:?}: {part:?} is not an index"));
        };
        if i == 0 || i.abs() > count {
            return Some(format!(
                "corner {corner:?}: {name} index {i} is out of range ({count} {name} lines so far; indices are 1..={count} or -1..=-{count})"
            ));
        }
    }
    None
}

/// Checks an OBJ file's text the way tobj will read it, line by line, and
/// returns the text to give tobj (see [`ObjScan`]).
pub(crate) fn check_obj(path: &Path, bytes: &[u8]) -> Result<ObjScan, ObjError> {
    let text = utf8(path, bytes)?;
    let mut out = String::with_capacity(text.len());
    let mut scan = ObjScan {
        text: String::new(),
        dropped_faces: 0,
        first_dropped: None,
        polylines: 0,
        usemtl: Vec::new(),
    };
    let mut counts = Counts::default();
    // First `v` line with and without a colour: tobj needs all or none.
    let (mut coloured, mut plain) = (None, None);
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        let mut keep = true;
        let why = match words.split_first() {
            None => None,
            Some((&key, rest)) => match key {
                "v" => {
                    counts.v += 1;
                    if !numbers(rest, 3) {
                        Some("v needs three numbers (x y z)".to_string())
                    } else {
                        match rest.len() {
                            3 => {
                                plain.get_or_insert(n);
                                None
                            }
                            4 => {
                                plain.get_or_insert(n);
                                match rest[3].parse::<f32>() {
                                    Ok(w) if w != 0.0 && w.is_finite() => None,
                                    _ => Some("the weight w of v x y z w must be a finite non-zero number".to_string()),
                                }
                            }
                            6 if numbers(&rest[3..], 3) => {
                                coloured.get_or_insert(n);
                                None
                            }
                            6 => Some(
                                "the vertex colour of v x y z r g b needs three numbers"
                                    .to_string(),
                            ),
                            _ => Some("v takes x y z, then optionally w or r g b".to_string()),
                        }
                    }
                }
                "vt" => {
                    counts.vt += 1;
                    (!numbers(rest, 2))
                        .then(|| "vt needs two numbers (u v); one-number texture coordinates are not read".to_string())
                }
                "vn" => {
                    counts.vn += 1;
                    (!numbers(rest, 3)).then(|| "vn needs three numbers (x y z)".to_string())
                }
                "f" if rest.len() > MAX_FACE_CORNERS => Some(format!(
                    "a face has {} corners, at most {MAX_FACE_CORNERS} are read (split it into smaller faces or triangles)",
                    rest.len()
                )),
                "f" | "l" => match rest.iter().find_map(|c| corner_fault(c, &counts)) {
                    Some(why) => Some(why),
                    None => {
                        keep = false;
                        if key == "l" {
                            scan.polylines += 1;
                        } else if rest.len() < 3 {
                            scan.dropped_faces += 1;
                            scan.first_dropped.get_or_insert(n);
                        } else {
                            keep = true;
                        }
                        None
                    }
                },
                "usemtl" | "mtllib" => {
                    // tobj takes the name after the first space.
                    let name = line.split_once(' ').map(|(_, r)| r.trim()).unwrap_or("");
                    if key == "usemtl"
                        && !name.is_empty()
                        && !scan.usemtl.iter().any(|(u, _)| u == name)
                    {
                        scan.usemtl.push((name.to_string(), n));
                    }
                    name.is_empty()
                        .then(|| format!("{key} needs a name after a space"))
                }
                _ => None,
            },
        };
        if let Some(why) = why {
            return Err(line_error(path, n, line, why));
        }
        if let (Some(c), Some(p)) = (coloured, plain) {
            return Err(ObjError::MixedColours {
                path: path.to_path_buf(),
                later: c.max(p),
                earlier: c.min(p),
                later_coloured: c > p,
            });
        }
        if keep {
            out.push_str(line);
        }
        out.push('\n');
    }
    scan.text = out;
    Ok(scan)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_mtl_colours_are_errors_with_the_line() {
        for (bad, key) in [
            ("Kd 0.5", "Kd"),
            ("Ka 1 1", "Ka"),
            ("Kd", "Kd"),
            ("Ke 0.1", "Ke"),
            ("Ks 1 x 1", "Ks"),
            ("Ns", "Ns"),
            ("illum x", "illum"),
            ("map_Kd", "map_Kd"),
        ] {
            let mtl = format!("# comment\nnewmtl a\n{bad}\n");
            let err = check_mtl(Path::new("m.mtl"), mtl.as_bytes())
                .unwrap_err()
                .to_string();
            assert!(
                err.contains("m.mtl") && err.contains("line 3") && err.contains(key),
                "{bad}: {err}"
            );
        }
        let good =
            "newmtl a\nKd 0.5 0.5 0.5\nKa 0 0 0 extra\nNs 10\nillum 2\nmap_Kd t.png\nPr 0.3\n";
        check_mtl(Path::new("m.mtl"), good.as_bytes()).unwrap();
    }

    fn obj_err(text: &str) -> String {
        check_obj(Path::new("m.obj"), text.as_bytes())
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn obj_errors_name_the_line() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        for (bad, line, needle) in [
            ("vt 0.5", 4, "vt needs two numbers"),
            ("v 1 0 0 0", 4, "weight w"),
            ("v 1 0 0 1 1", 4, "v takes x y z"),
            ("vn 0 1", 4, "vn needs three"),
            ("f 1 2 4", 4, "v index 4 is out of range"),
            ("f 1 2 0", 4, "v index 0"),
            ("f 1 2 -4", 4, "v index -4"),
            ("f 1/1 2 3", 4, "vt index 1"),
            ("f 1/x 2 3", 4, "not an index"),
            ("f 1/1/1/1 2 3", 4, "more than v/vt/vn"),
            ("f /1 2 3", 4, "no vertex index"),
            ("usemtl", 4, "usemtl needs a name"),
            ("v 0 0 1 0.5 0.5 0.5", 4, "line 1 has none"),
        ] {
            let e = obj_err(&format!("{tri}{bad}\n"));
            assert!(
                e.contains("m.obj") && e.contains(&format!("line {line}")) && e.contains(needle),
                "{bad}: {e}"
            );
        }
        let e = obj_err("v 0 0 0 1 1 1\nv 1 0 0\n");
        assert!(e.contains("line 2") && e.contains("line 1 has one"), "{e}");
    }

    #[test]
    fn points_lines_and_polylines_are_counted_and_blanked() {
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\nf 1\nl 1 2 3\nf 1 2 3\nf -3 -2 -1\n";
        let s = check_obj(Path::new("m.obj"), obj.as_bytes()).unwrap();
        assert_eq!(
            (s.dropped_faces, s.first_dropped, s.polylines),
            (2, Some(4), 1)
        );
        let lines: Vec<&str> = s.text.lines().collect();
        assert_eq!(lines.len(), 8, "line numbers are kept");
        assert_eq!(&lines[3..6], ["", "", ""]);
        assert_eq!(lines[6], "f 1 2 3");
    }
}
