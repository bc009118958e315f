//! The layers of DESIGN.md, read from the code's own `use crate::` and `use super::`
//! lines: io ← surfel ← tree ← render ← apps, each layer importing only those to its
//! left (io none, render tree only), and no cycle between the files of the crate.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`.
fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(sources(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    out
}

/// The module path of a source file: `src/tree/mod.rs` → `tree`, `src/io/ply/ascii.rs`
/// → `io::ply::ascii`, `src/lib.rs` → ``.
fn module_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .filter(|p| p != "mod" && p != "lib" && p != "main")
        .collect();
    parts.join("::")
}

/// The modules a file imports, resolved to full paths (`super::` included), as the
/// longest prefix that names a module of the crate.
fn imports(module: &str, text: &str, modules: &BTreeSet<String>) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    // `super` is the parent module, whether the file is `mod.rs` or a leaf file.
    let mut base: Vec<&str> = module.split("::").filter(|s| !s.is_empty()).collect();
    base.pop();
    for line in text.lines().map(str::trim) {
        let Some(rest) = line
            .strip_prefix("use ")
            .or_else(|| line.strip_prefix("pub use "))
        else {
            continue;
        };
        let path: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
            .collect();
        let mut parts: Vec<&str> = path.split("::").filter(|s| !s.is_empty()).collect();
        let resolved: Vec<String> = match parts.first() {
            Some(&"crate") => parts.drain(1..).map(str::to_owned).collect(),
            Some(&"super") => {
                let mut b: Vec<String> = base.iter().map(|s| s.to_string()).collect();
                for p in parts {
                    if p == "super" {
                        continue;
                    }
                    b.push(p.to_owned());
                }
                b
            }
            _ => continue,
        };
        // The longest prefix that is a module.
        for k in (1..=resolved.len()).rev() {
            let m = resolved[..k].join("::");
            if modules.contains(&m) {
                out.insert(m);
                break;
            }
        }
    }
    out
}

fn layer(module: &str) -> &str {
    module.split("::").next().unwrap_or("")
}

/// File-level import graph of `src/`: module → modules it imports.
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let files = sources(&src);
    let modules: BTreeSet<String> = files.iter().map(|f| module_of(&src, f)).collect();
    files
        .iter()
        .filter(|f| !f.ends_with("main.rs"))
        .map(|f| {
            let m = module_of(&src, f);
            let text = std::fs::read_to_string(f).unwrap();
            let deps = imports(&m, &text, &modules)
                .into_iter()
                .filter(|d| *d != m)
                .collect();
            (m, deps)
        })
        .collect()
}

#[test]
fn layers_point_one_way() {
    let allowed: &[(&str, &[&str])] = &[
        ("io", &["io"]),
        ("surfel", &["surfel", "io"]),
        ("tree", &["tree", "surfel", "io"]),
        ("render", &["render", "tree"]),
    ];
    let mut wrong = Vec::new();
    for (m, deps) in graph() {
        let Some((_, ok)) = allowed.iter().find(|(l, _)| *l == layer(&m)) else {
            continue;
        };
        for d in deps {
            if !ok.contains(&layer(&d)) {
                wrong.push(format!("{m} → {d}"));
            }
        }
    }
    assert!(wrong.is_empty(), "imports against the layers: {wrong:?}");
}

/// A module that reaches itself through imports, if any: the cycle's path.
fn find_cycle(g: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        m: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(m.to_owned(), 1);
        stack.push(m.to_owned());
        for d in g.get(m).into_iter().flatten() {
            match state.get(d.as_str()) {
                Some(1) => {
                    let at = stack.iter().position(|s| s == d).unwrap();
                    let mut cycle = stack[at..].to_vec();
                    cycle.push(d.clone());
                    return Some(cycle);
                }
                Some(_) => {}
                None => {
                    if let Some(c) = visit(d, g, state, stack) {
                        return Some(c);
                    }
                }
            }
        }
        stack.pop();
        state.insert(m.to_owned(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for m in g.keys() {
        if !state.contains_key(m.as_str()) {
            let mut stack = Vec::new();
            if let Some(c) = visit(m, g, &mut state, &mut stack) {
                return Some(c);
            }
        }
    }
    None
}

#[test]
fn no_file_imports_itself_through_others() {
    let g = graph();
    assert!(g.contains_key("tree::spt_file") && g["render::renderer"].contains("tree::scene"));
    // A parent module re-exporting its children is not a cycle of meaning: edges from a
    // module to its own descendants are left out.
    let g: BTreeMap<String, BTreeSet<String>> = g
        .into_iter()
        .map(|(m, deps)| {
            let deps = deps
                .into_iter()
                .filter(|d| !(m.is_empty() || d.starts_with(&format!("{m}::"))))
                .collect();
            (m, deps)
        })
        .collect();
    if let Some(cycle) = find_cycle(&g) {
        panic!("import cycle: {}", cycle.join(" → "));
    }
}

/// Functions of `src/` and their lengths in lines: from the `fn` line to the closing
/// brace at the same indentation (the layout `cargo fmt` gives).
fn function_lengths() -> Vec<(usize, String)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut out = Vec::new();
    for file in sources(&src) {
        let text = std::fs::read_to_string(&file).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let indent = &line[..line.len() - line.trim_start().len()];
            let rest = line.trim_start();
            let rest = rest
                .strip_prefix("pub ")
                .or_else(|| rest.strip_prefix("pub(super) "))
                .or_else(|| rest.strip_prefix("pub(crate) "))
                .unwrap_or(rest);
            let rest = rest.strip_prefix("const ").unwrap_or(rest);
            let Some(name) = rest.strip_prefix("fn ") else {
                continue;
            };
            let close = format!("{indent}}}");
            if let Some(end) = lines[i + 1..].iter().position(|l| *l == close) {
                let name: String = name
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                out.push((end + 2, format!("{}: {name}", file.display())));
            }
        }
    }
    out
}

#[test]
fn no_function_is_over_100_lines() {
    let lengths = function_lengths();
    assert!(
        lengths.len() > 300,
        "found only {} functions",
        lengths.len()
    );
    let long: Vec<_> = lengths.into_iter().filter(|(n, _)| *n > 100).collect();
    assert!(long.is_empty(), "functions over 100 lines: {long:?}");
}
