//! The documentation renders and speaks of the code: every relative link of the README
//! and of `docs/` leads to a file that exists (and an `#anchor` to a heading of it), and
//! no tracked text narrates the order in which the work was done.

use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The README and every Markdown page of `docs/`.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![root().join("README.md")];
    let mut dirs = vec![root().join("docs")];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                pages.push(path);
            }
        }
    }
    pages
}

/// The targets of the Markdown links and images of `text`: `[label](target)`, outside
/// code blocks.
fn link_targets(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut in_code = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if in_code {
            continue;
        }
        let mut rest = line;
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let Some(end) = after.find(')') else { break };
            out.push(after[..end].to_owned());
            rest = &after[end..];
        }
    }
    out
}

/// The anchor GitHub gives a heading: lower case, spaces to `-`, punctuation dropped.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The links of `page` that lead nowhere.
fn broken_links(page: &Path, text: &str) -> Vec<String> {
    let mut broken = Vec::new();
    for target in link_targets(text) {
        if target.contains("://") || target.starts_with("mailto:") {
            continue;
        }
        let (file, fragment) = target.split_once('#').unwrap_or((&target, ""));
        let path = match file {
            "" => page.to_owned(),
            f => page.parent().unwrap().join(f),
        };
        if !path.exists() {
            broken.push(format!("{}: {target} (no such file)", page.display()));
            continue;
        }
        if !fragment.is_empty() && path.extension().is_some_and(|e| e == "md") {
            let headings = std::fs::read_to_string(&path).unwrap();
            let found = headings
                .lines()
                .filter_map(|l| l.strip_prefix('#'))
                .any(|h| anchor(h.trim_start_matches('#')) == fragment);
            if !found {
                broken.push(format!("{}: {target} (no such heading)", page.display()));
            }
        }
    }
    broken
}

#[test]
fn every_link_of_the_docs_resolves() {
    let pages = pages();
    assert!(pages.len() >= 10, "found {} pages", pages.len());
    let mut links = 0;
    let mut broken = Vec::new();
    for page in &pages {
        let text = std::fs::read_to_string(page).unwrap();
        links += link_targets(&text).len();
        broken.extend(broken_links(page, &text));
    }
    assert!(links > 30, "found only {links} links");
    assert!(broken.is_empty(), "broken links: {broken:#?}");
}

#[test]
fn a_broken_link_is_caught() {
    let page = root().join("docs/design.md");
    let text = "[ok](image-quality.md) and [gone](no-such-page.md), ![x](../data/none.png)\n\
                [anchor](design.md#data-flow-and-layers) [bad](design.md#no-such-heading)";
    let broken = broken_links(&page, text);
    assert_eq!(broken.len(), 3, "{broken:#?}");
}

#[test]
fn the_readme_is_a_front_door() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let lines = readme.lines().count();
    assert!(lines < 300, "README.md has {lines} lines");
    let first_block = readme.split("```sh").nth(1).expect("a shell block");
    assert!(
        first_block.contains("cargo run --release") && first_block.contains("cargo test --release")
    );
}

/// Words that narrate the order of the work: ordinals of sessions, session and issue
/// numbers.
fn narrative(text: &str) -> Vec<String> {
    const ORDINALS: &[&str] = &[
        "first",
        "second",
        "third",
        "fourth",
        "fifth",
        "sixth",
        "seventh",
        "eighth",
        "ninth",
        "tenth",
        "eleventh",
        "twelfth",
        "thirteenth",
        "fourteenth",
        "fifteenth",
        "sixteenth",
        "seventeenth",
        "eighteenth",
        "nineteenth",
        "twentieth",
        "thirtieth",
    ];
    let lower = text.to_lowercase();
    let words: Vec<&str> = lower
        .split(|c: char| !(c.is_alphanumeric() || c == '-' || c == '#'))
        .filter(|w| !w.is_empty())
        .collect();
    let mut found = Vec::new();
    for pair in words.windows(2) {
        let ordinal = |w: &str| {
            let last = w.rsplit('-').next().unwrap_or(w);
            ORDINALS.contains(&last)
                && (w == last || w.starts_with("twenty") || w.starts_with("thirty"))
        };
        if ordinal(pair[0]) && pair[1].starts_with("session") {
            found.push(format!("{} {}", pair[0], pair[1]));
        }
        if pair[0] == "issue" && pair[1].trim_start_matches('#').parse::<u32>().is_ok() {
            found.push(format!("{} {}", pair[0], pair[1]));
        }
        if pair[1].starts_with("session") && ["this", "that", "last", "next"].contains(&pair[0]) {
            found.push(format!("{} {}", pair[0], pair[1]));
        }
    }
    found
}

#[test]
fn no_tracked_text_narrates_the_work() {
    let out = std::process::Command::new("git")
        .args(["ls-files", "-z"])
        .current_dir(root())
        .output();
    let Some(out) = out.ok().filter(|o| o.status.success()) else {
        eprintln!("skipped: not a git checkout");
        return;
    };
    let mut found = Vec::new();
    for file in out.stdout.split(|b| *b == 0).filter(|f| !f.is_empty()) {
        let path = root().join(String::from_utf8_lossy(file).as_ref());
        let Ok(text) = std::fs::read_to_string(&path) else {
            continue; // binary
        };
        for n in narrative(&text) {
            found.push(format!("{}: {n}", path.display()));
        }
    }
    assert!(found.is_empty(), "narrative of the work: {found:#?}");
    // Made at run time, so that this file does not hold the words it looks for.
    let [s, i] = [["ses", "sion"].concat(), ["iss", "ue"].concat()];
    let sample = format!("the twenty-fifth {s}, {i} #12, this {s}");
    let expect = [
        format!("twenty-fifth {s}"),
        format!("{i} #12"),
        format!("this {s}"),
    ];
    assert_eq!(narrative(&sample), expect);
}
