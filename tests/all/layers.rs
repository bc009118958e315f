//! The layers of `docs/design.md`, read from every path in `src/`: the `use` items
//! (groups, renames and globs expanded) and every inline path (`crate::io::x(…)`, in
//! code, types, patterns and macro arguments), resolved against the module it sits in
//! (`super::` and `self::` included, inline `mod` blocks followed).
//!
//! ```text
//! apps ─► eval ─► render ─► tree ─► surfel ─► io
//! ```
//!
//! Each layer imports only those below it, `render` of `io` only the data model
//! (`io::geometry`) and the up axis (`io::up`); no `pub use` re-exports another layer's items; and no module
//! reaches itself through the imports of others.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use syn::visit::Visit;

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

/// One path a file names: where it leads (crate-absolute segments) and whether it is a
/// public re-export.
struct Reference {
    target: Vec<String>,
    reexport: bool,
}

/// Collects the crate-absolute paths of one file. `scope` is the module the visitor is
/// in (the file's module, then any inline `mod` inside it).
struct Paths {
    scope: Vec<String>,
    found: Vec<Reference>,
}

impl Paths {
    /// `segments` resolved from the current scope, if it starts at `crate`, `super` or
    /// `self`; other paths name items of the scope itself, or of other crates.
    fn resolve(&self, segments: &[String]) -> Option<Vec<String>> {
        let first = segments.first()?;
        let mut base = match first.as_str() {
            "crate" => Vec::new(),
            "super" | "self" => self.scope.clone(),
            _ => return None,
        };
        let mut rest = &segments[1..];
        if first == "super" {
            base.pop();
        }
        while rest.first().is_some_and(|s| s == "super") {
            base.pop();
            rest = &rest[1..];
        }
        base.extend(rest.iter().cloned());
        Some(base)
    }

    fn add(&mut self, segments: &[String], reexport: bool) {
        if let Some(target) = self.resolve(segments) {
            self.found.push(Reference { target, reexport });
        }
    }

    /// Every leaf path of a `use` tree, after `prefix`.
    fn use_tree(&mut self, tree: &syn::UseTree, prefix: &mut Vec<String>, reexport: bool) {
        match tree {
            syn::UseTree::Path(p) => {
                prefix.push(p.ident.to_string());
                self.use_tree(&p.tree, prefix, reexport);
                prefix.pop();
            }
            syn::UseTree::Name(n) => self.leaf(prefix, &n.ident, reexport),
            syn::UseTree::Rename(r) => self.leaf(prefix, &r.ident, reexport),
            syn::UseTree::Glob(_) => self.add(prefix, reexport),
            syn::UseTree::Group(g) => {
                for t in &g.items {
                    self.use_tree(t, prefix, reexport);
                }
            }
        }
    }

    fn leaf(&mut self, prefix: &[String], ident: &syn::Ident, reexport: bool) {
        let mut path = prefix.to_vec();
        if ident != "self" {
            path.push(ident.to_string());
        }
        self.add(&path, reexport);
    }

    /// Paths spelled out in a macro's arguments (`format!("{}", crate::x::y())`): every
    /// run of identifiers joined by `::` that starts at `crate`, `super` or `self`.
    fn tokens(&mut self, tokens: proc_macro2::TokenStream) {
        let trees: Vec<proc_macro2::TokenTree> = tokens.into_iter().collect();
        let mut i = 0;
        while i < trees.len() {
            if let proc_macro2::TokenTree::Group(g) = &trees[i] {
                self.tokens(g.stream());
            }
            let mut path = Vec::new();
            let mut j = i;
            while let Some(proc_macro2::TokenTree::Ident(id)) = trees.get(j) {
                path.push(id.to_string());
                let colons = |k: usize| matches!(trees.get(k), Some(proc_macro2::TokenTree::Punct(p)) if p.as_char() == ':');
                if colons(j + 1) && colons(j + 2) {
                    j += 3;
                } else {
                    break;
                }
            }
            if path.len() > 1 {
                self.add(&path, false);
            }
            i = j.max(i) + 1;
        }
    }
}

impl<'ast> Visit<'ast> for Paths {
    fn visit_item_use(&mut self, u: &'ast syn::ItemUse) {
        let reexport = !matches!(u.vis, syn::Visibility::Inherited);
        self.use_tree(&u.tree, &mut Vec::new(), reexport);
    }

    fn visit_path(&mut self, p: &'ast syn::Path) {
        let segments: Vec<String> = p.segments.iter().map(|s| s.ident.to_string()).collect();
        self.add(&segments, false);
        syn::visit::visit_path(self, p);
    }

    fn visit_macro(&mut self, m: &'ast syn::Macro) {
        self.tokens(m.tokens.clone());
        syn::visit::visit_macro(self, m);
    }

    fn visit_item_mod(&mut self, m: &'ast syn::ItemMod) {
        self.scope.push(m.ident.to_string());
        syn::visit::visit_item_mod(self, m);
        self.scope.pop();
    }
}

/// The references of the file `text` of module `module`.
fn references(module: &str, text: &str) -> Vec<Reference> {
    let file = syn::parse_file(text).unwrap_or_else(|e| panic!("{module}: {e}"));
    let scope = module
        .split("::")
        .filter(|s| !s.is_empty())
        .map(str::to_owned)
        .collect();
    let mut paths = Paths {
        scope,
        found: Vec::new(),
    };
    paths.visit_file(&file);
    paths.found
}

/// The longest prefix of `target` that is a module of the crate.
fn module_named(target: &[String], modules: &BTreeSet<String>) -> Option<String> {
    (1..=target.len())
        .rev()
        .map(|k| target[..k].join("::"))
        .find(|m| modules.contains(m))
}

/// File-level graph of a crate's sources: module → (modules it names, modules whose
/// items it re-exports).
type Graph = BTreeMap<String, (BTreeSet<String>, BTreeSet<String>)>;

fn graph_of(files: &[(String, String)]) -> Graph {
    let modules: BTreeSet<String> = files.iter().map(|(m, _)| m.clone()).collect();
    let mut graph = Graph::new();
    for (m, text) in files {
        let (uses, reexports) = graph.entry(m.clone()).or_default();
        for r in references(m, text) {
            let Some(d) = module_named(&r.target, &modules) else {
                continue;
            };
            if d != *m {
                if r.reexport {
                    reexports.insert(d.clone());
                }
                uses.insert(d);
            }
        }
    }
    graph
}

/// The graph of `src/`, the binary's `main.rs` left out.
fn graph() -> Graph {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let files: Vec<(String, String)> = sources(&src)
        .into_iter()
        .filter(|f| !f.ends_with("main.rs"))
        .map(|f| (module_of(&src, &f), std::fs::read_to_string(&f).unwrap()))
        .collect();
    graph_of(&files)
}

fn layer(module: &str) -> &str {
    module.split("::").next().unwrap_or("")
}

/// What each layer may name: module prefixes (a layer, or one module of a layer).
const ALLOWED: &[(&str, &[&str])] = &[
    ("io", &["io"]),
    ("surfel", &["surfel", "io"]),
    ("tree", &["tree", "surfel", "io"]),
    (
        "render",
        &["render", "tree", "surfel", "io::geometry", "io::up"],
    ),
    ("eval", &["eval", "render", "tree", "surfel", "io"]),
];

fn allowed(from: &str, to: &str) -> bool {
    let Some((_, ok)) = ALLOWED.iter().find(|(l, _)| *l == layer(from)) else {
        return true;
    };
    ok.iter()
        .any(|p| to == *p || to.starts_with(&format!("{p}::")))
}

/// The arrows against the layers, and the re-exports of another layer's items.
fn violations(g: &Graph) -> Vec<String> {
    let mut wrong = Vec::new();
    for (m, (uses, reexports)) in g {
        for d in uses.iter().filter(|d| !allowed(m, d)) {
            wrong.push(format!("{m} → {d}"));
        }
        for d in reexports
            .iter()
            .filter(|d| layer(d) != layer(m) && !m.is_empty())
        {
            wrong.push(format!("{m} re-exports items of {d}"));
        }
    }
    wrong
}

#[test]
fn layers_point_one_way() {
    let g = graph();
    assert!(g.len() > 100, "read only {} modules", g.len());
    let wrong = violations(&g);
    assert!(wrong.is_empty(), "against the layers: {wrong:#?}");
}

#[test]
fn an_inline_call_against_the_layers_is_caught() {
    let render = "pub fn save(p: &std::path::Path) {\n\
                  let _ = crate::io::atomic::write_atomically(p, |_| Ok(()));\n}\n";
    let grouped = "use crate::{io::{atomic, geometry::Geometry}, tree::scene};\n";
    let in_test = "mod tests {\n use super::super::super::io::ply::read_ply;\n}\n";
    let in_macro = "fn f() { println!(\"{}\", crate::io::ply::read_ply); }\n";
    let reexport = "pub use crate::surfel::shape::SplatShape;\n";
    for (text, expect) in [
        (render, "render::metrics → io::atomic"),
        (grouped, "render::metrics → io::atomic"),
        (in_test, "render::metrics → io::ply"),
        (in_macro, "render::metrics → io::ply"),
    ] {
        let files = fixture("render::metrics", text);
        let wrong = violations(&graph_of(&files));
        assert_eq!(wrong, [expect], "{text}");
    }
    let wrong = violations(&graph_of(&fixture("tree::record", reexport)));
    assert_eq!(wrong, ["tree::record re-exports items of surfel::shape"]);
}

/// The modules a fixture file can name, and the file as `module`.
fn fixture(module: &str, text: &str) -> Vec<(String, String)> {
    let mut files: Vec<(String, String)> = [
        "io",
        "io::atomic",
        "io::geometry",
        "io::ply",
        "render",
        "surfel",
        "surfel::shape",
        "tree",
        "tree::record",
        "tree::scene",
        "render::metrics",
    ]
    .into_iter()
    .filter(|m| *m != module)
    .map(|m| (m.to_owned(), String::new()))
    .collect();
    files.push((module.to_owned(), text.to_owned()));
    files
}

/// A module that reaches itself through the modules it names, if any: the cycle's path.
/// A module's own descendants are left out of its arrows (a parent naming its children
/// is not a cycle of meaning), and so are arrows to the crate root.
fn find_cycle(g: &Graph) -> Option<Vec<String>> {
    let arrows: BTreeMap<&str, Vec<&str>> = g
        .iter()
        .map(|(m, (uses, _))| {
            let own = format!("{m}::");
            let to = uses
                .iter()
                .filter(|d| !(m.is_empty() || d.is_empty() || d.starts_with(&own)))
                .map(String::as_str)
                .collect();
            (m.as_str(), to)
        })
        .collect();
    let mut state: BTreeMap<&str, u8> = BTreeMap::new();
    for start in arrows.keys() {
        let mut stack = Vec::new();
        if let Some(c) = visit(start, &arrows, &mut state, &mut stack) {
            return Some(c);
        }
    }
    None
}

fn visit<'a>(
    m: &'a str,
    arrows: &BTreeMap<&'a str, Vec<&'a str>>,
    state: &mut BTreeMap<&'a str, u8>,
    stack: &mut Vec<&'a str>,
) -> Option<Vec<String>> {
    match state.get(m) {
        Some(1) => {
            let at = stack.iter().position(|s| *s == m).unwrap();
            let mut cycle: Vec<String> = stack[at..].iter().map(|s| s.to_string()).collect();
            cycle.push(m.to_owned());
            return Some(cycle);
        }
        Some(_) => return None,
        None => {}
    }
    state.insert(m, 1);
    stack.push(m);
    for d in arrows.get(m).into_iter().flatten() {
        if let Some(c) = visit(d, arrows, state, stack) {
            return Some(c);
        }
    }
    stack.pop();
    state.insert(m, 2);
    None
}

#[test]
fn no_module_imports_itself_through_others() {
    let g = graph();
    assert!(g["render::renderer"].0.contains("tree::scene"));
    if let Some(cycle) = find_cycle(&g) {
        panic!("import cycle: {}", cycle.join(" → "));
    }
    let circle = [
        ("surfel::a", "fn f() { super::b::g(); }"),
        (
            "surfel::b",
            "pub fn g() {}\nfn h() { crate::surfel::a::f(); }",
        ),
        ("surfel", ""),
    ]
    .map(|(m, t)| (m.to_owned(), t.to_owned()));
    assert!(find_cycle(&graph_of(&circle)).is_some());
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
