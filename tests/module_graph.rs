//! No import circles between the top-level modules of a crate: a module
//! may use its children and its siblings, and no chain of sibling uses
//! comes back to where it started. Checked from the sources: every
//! `crate::a::…` path and every `super::…` path in code (comments and
//! `#[cfg(test)]` modules left out: a test may reach up the layers to
//! cross-check) is an edge from the file's top-level module to the one it
//! names. Checked in every crate of the workspace.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The module path of a source file under `root` (`a/b.rs` and
/// `a/b/mod.rs` are `[a, b]`; `lib.rs` and `main.rs` are the root).
fn module_path(root: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(root).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

/// The code of a file: no line comments, no `#[cfg(test)] mod … { … }`
/// blocks (matched by braces; other test-only items stay, which can only
/// add edges).
fn code(text: &str) -> String {
    let mut text = text.to_string();
    while let Some(at) = test_module(&text) {
        let open = at + text[at..].find('{').expect("a module body");
        let mut depth = 0;
        let end = text[open..]
            .char_indices()
            .find_map(|(i, c)| {
                depth += match c {
                    '{' => 1,
                    '}' => -1,
                    _ => 0,
                };
                (depth == 0).then_some(open + i + 1)
            })
            .unwrap_or(text.len());
        text.replace_range(at..end, "");
    }
    text.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .map(|l| l.split(" // ").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Where the first `#[cfg(test)]` that opens an inline module starts.
fn test_module(text: &str) -> Option<usize> {
    text.match_indices("#[cfg(test)]")
        .map(|(i, _)| i)
        .find(|&i| {
            let rest = text[i + "#[cfg(test)]".len()..].trim_start();
            let rest = rest.strip_prefix("pub(crate) ").unwrap_or(rest);
            let rest = rest.strip_prefix("pub(super) ").unwrap_or(rest);
            rest.strip_prefix("mod ").is_some_and(|r| {
                r.trim_start_matches(|c: char| c.is_alphanumeric() || c == '_')
                    .trim_start()
                    .starts_with('{')
            })
        })
}

/// The identifiers after each occurrence of `prefix` (`crate::` or
/// `super::`), as path segments.
fn paths_after<'a>(code: &'a str, prefix: &'a str) -> impl Iterator<Item = Vec<&'a str>> + 'a {
    code.match_indices(prefix).filter_map(move |(i, _)| {
        let before = code[..i].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            return None;
        }
        let rest = &code[i + prefix.len()..];
        let end = rest
            .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
            .unwrap_or(rest.len());
        let segs: Vec<&str> = rest[..end].split("::").filter(|s| !s.is_empty()).collect();
        (!segs.is_empty()).then_some(segs)
    })
}

/// Edges between the top-level modules of the crate whose sources are in
/// `root`.
fn graph(root: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut files = Vec::new();
    rust_files(root, &mut files);
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let path = module_path(root, &f);
        let Some(me) = path.first().cloned() else {
            continue;
        };
        let code = code(&std::fs::read_to_string(&f).unwrap());
        let mut add = |target: &str| {
            if target != me {
                edges
                    .entry(me.clone())
                    .or_default()
                    .insert(target.to_string());
            }
        };
        for segs in paths_after(&code, "crate::") {
            add(segs[0]);
        }
        for segs in paths_after(&code, "super::") {
            // `super` is the parent of the file's module.
            let mut base = path[..path.len() - 1].to_vec();
            let mut rest = segs.as_slice();
            while rest.first() == Some(&"super") {
                base.pop();
                rest = &rest[1..];
            }
            let target = base.first().map(String::as_str).or(rest.first().copied());
            if let Some(t) = target {
                add(t);
            }
        }
    }
    edges
}

/// The strongly connected components of more than one module (Tarjan).
fn circles(edges: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct T<'a> {
        edges: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        out: Vec<Vec<String>>,
    }
    impl<'a> T<'a> {
        fn visit(&mut self, v: &'a str) {
            let n = self.index.len();
            self.index.insert(v, n);
            self.low.insert(v, n);
            self.stack.push(v);
            for w in self.edges.get(v).into_iter().flatten() {
                if !self.index.contains_key(w.as_str()) {
                    self.visit(w);
                    let lw = self.low[w.as_str()];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(lw);
                } else if self.stack.contains(&w.as_str()) {
                    let iw = self.index[w.as_str()];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(iw);
                }
            }
            if self.low[v] == self.index[v] {
                let mut comp = Vec::new();
                while let Some(w) = self.stack.pop() {
                    comp.push(w.to_string());
                    if w == v {
                        break;
                    }
                }
                if comp.len() > 1 {
                    comp.sort();
                    self.out.push(comp);
                }
            }
        }
    }
    let mut t = T {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        out: Vec::new(),
    };
    for v in edges.keys() {
        if !t.index.contains_key(v.as_str()) {
            t.visit(v);
        }
    }
    t.out
}

#[test]
fn the_checker_finds_a_circle() {
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (a, b) in [("a", "b"), ("b", "c"), ("c", "a"), ("c", "d")] {
        edges.entry(a.into()).or_default().insert(b.into());
    }
    assert_eq!(circles(&edges), [["a", "b", "c"]]);
    let code = code("use crate::x::Y; // crate::z\n// use crate::w;\nfn f() { super::v::g() }");
    let found: Vec<_> = paths_after(&code, "crate::").collect();
    assert_eq!(found, [vec!["x", "Y"]]);
    assert_eq!(paths_after(&code, "super::").count(), 1);
    // A test module goes; code after it and test-only items stay.
    let text = "#[cfg(test)]\nuse crate::t::T;\n#[cfg(test)]\nmod tests {\n    \
                use crate::b::B;\n    fn f() { if x {} }\n}\nuse crate::c::C;";
    let kept = self::code(text);
    let found: Vec<_> = paths_after(&kept, "crate::").map(|p| p[0]).collect();
    assert_eq!(found, ["t", "c"]);
}

#[test]
fn no_crate_has_an_import_circle() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for dir in ["core/src", "raster/src", "npr/src", "src", "bench/src"] {
        let found = circles(&graph(&root.join(dir)));
        assert!(found.is_empty(), "{dir}: modules in a circle: {found:?}");
    }
}
