//! The house's shape, measured from the code itself, so that it stays easy to read:
//! - no file under `src/` holds more than 600 lines before its first `#[cfg(test)]`, or
//!   1,000 in all;
//! - no circle between files: no file reaches back to itself through what it imports
//!   (a `use`, or a path such as `crate::storage::Storage` or `super::Thing` in its
//!   code). A folder's front door (its `mod.rs`) declares, re-exports and composes its
//!   children, and they use what their folder holds: those arrows, between a module and
//!   its own ancestors or descendants, are the inside of one room and are not counted;
//! - the rooms (the crate's top-level modules) sit on floors, and no import runs up a
//!   floor: a room uses only rooms on lower floors.
//!
//! Test code (`#[cfg(test)]` items) may use anything and is not measured.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use syn::visit::Visit;

use crate::support::root;

/// The floors, lowest first: each room may use the rooms of the floors below it.
const FLOORS: &[&[&str]] = &[
    &["engine", "botfiles", "client"],
    &["protocol", "ranking"],
    &["runner"],
    &["competition", "manifest"],
    &["storage"],
    &["metrics", "registry"],
    &["work", "web"],
    &["api"],
    &["cli"],
];

type Module = Vec<String>;

/// Every module of the library with its file (`lib.rs` is the empty path).
fn modules() -> BTreeMap<Module, std::path::PathBuf> {
    fn walk(dir: &Path, at: &Module, out: &mut BTreeMap<Module, std::path::PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_stem().unwrap().to_string_lossy().to_string();
            if path.is_dir() {
                let mut inner = at.clone();
                inner.push(name);
                walk(&path, &inner, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let mut module = at.clone();
                match name.as_str() {
                    "mod" | "lib" => {}
                    "main" if at.is_empty() => continue,
                    _ => module.push(name),
                }
                out.insert(module, path);
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(&root().join("src"), &Vec::new(), &mut out);
    out
}

fn is_test_only(attrs: &[syn::Attribute]) -> bool {
    attrs.iter().any(|a| {
        a.path().is_ident("cfg")
            && a.meta
                .require_list()
                .is_ok_and(|l| l.tokens.to_string().trim() == "test")
    })
}

/// The paths one file names: its `use` trees expanded, the paths in its code, and
/// `crate::`/`super::` paths written inside macro calls.
#[derive(Default)]
struct Named {
    paths: Vec<Vec<String>>,
}

impl Named {
    fn use_tree(&mut self, prefix: &mut Vec<String>, tree: &syn::UseTree) {
        match tree {
            syn::UseTree::Path(p) => {
                prefix.push(p.ident.to_string());
                self.use_tree(prefix, &p.tree);
                prefix.pop();
            }
            syn::UseTree::Name(n) => {
                let mut path = prefix.clone();
                if n.ident != "self" {
                    path.push(n.ident.to_string());
                }
                self.paths.push(path);
            }
            syn::UseTree::Rename(r) => {
                let mut path = prefix.clone();
                path.push(r.ident.to_string());
                self.paths.push(path);
            }
            syn::UseTree::Glob(_) => self.paths.push(prefix.clone()),
            syn::UseTree::Group(g) => g.items.iter().for_each(|t| self.use_tree(prefix, t)),
        }
    }
}

impl<'ast> Visit<'ast> for Named {
    fn visit_item(&mut self, item: &'ast syn::Item) {
        let attrs = match item {
            syn::Item::Mod(m) => &m.attrs,
            syn::Item::Fn(f) => &f.attrs,
            syn::Item::Use(u) => &u.attrs,
            syn::Item::Impl(i) => &i.attrs,
            syn::Item::Const(c) => &c.attrs,
            syn::Item::Struct(s) => &s.attrs,
            _ => return syn::visit::visit_item(self, item),
        };
        if !is_test_only(attrs) {
            syn::visit::visit_item(self, item);
        }
    }

    fn visit_item_use(&mut self, item: &'ast syn::ItemUse) {
        self.use_tree(&mut Vec::new(), &item.tree);
    }

    fn visit_path(&mut self, path: &'ast syn::Path) {
        self.paths
            .push(path.segments.iter().map(|s| s.ident.to_string()).collect());
        syn::visit::visit_path(self, path);
    }

    fn visit_macro(&mut self, mac: &'ast syn::Macro) {
        self.visit_path(&mac.path);
        // `crate :: a :: b` and `super :: c` inside the macro's tokens.
        let text = mac.tokens.to_string();
        let words: Vec<&str> = text.split_whitespace().collect();
        for (i, w) in words.iter().enumerate() {
            if (*w == "crate" || *w == "super") && words.get(i + 1) == Some(&"::") {
                let mut path = vec![w.to_string()];
                let mut j = i + 2;
                while let Some(seg) = words.get(j) {
                    path.push(seg.to_string());
                    if words.get(j + 1) != Some(&"::") {
                        break;
                    }
                    j += 2;
                }
                self.paths.push(path);
            }
        }
    }
}

/// The module a path names, from inside `at`: the longest prefix that is a module of
/// the crate (`crate::`, `super::`, `self::`, or a child of `at` by its name).
fn resolve(
    at: &Module,
    path: &[String],
    modules: &BTreeMap<Module, std::path::PathBuf>,
) -> Option<Module> {
    let (mut base, mut rest) = (at.clone(), path);
    match rest.first().map(String::as_str) {
        Some("crate") => {
            base.clear();
            rest = &rest[1..];
        }
        Some("self") => rest = &rest[1..],
        Some("super") => {
            while rest.first().is_some_and(|s| s == "super") {
                base.pop()?;
                rest = &rest[1..];
            }
        }
        Some(first) => {
            let mut child = at.clone();
            child.push(first.to_string());
            if !modules.contains_key(&child) {
                return None;
            }
        }
        None => return None,
    }
    let full: Module = base.into_iter().chain(rest.iter().cloned()).collect();
    (0..=full.len())
        .rev()
        .map(|n| full[..n].to_vec())
        .find(|m| modules.contains_key(m))
}

/// Every arrow between two files (module -> module it uses), without the arrows
/// between a module and its own ancestors or descendants.
fn arrows() -> BTreeMap<Module, BTreeSet<Module>> {
    let modules = modules();
    let mut arrows: BTreeMap<Module, BTreeSet<Module>> = BTreeMap::new();
    for (module, file) in &modules {
        let text = std::fs::read_to_string(file).unwrap();
        let parsed = syn::parse_file(&text).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let mut named = Named::default();
        named.visit_file(&parsed);
        let out = arrows.entry(module.clone()).or_default();
        for path in named.paths {
            if let Some(to) = resolve(module, &path, &modules)
                && !to.starts_with(module)
                && !module.starts_with(&to)
            {
                out.insert(to);
            }
        }
    }
    arrows
}

fn name(m: &Module) -> String {
    if m.is_empty() {
        "lib".into()
    } else {
        m.join("/")
    }
}

/// A circle through `from`, if there is one: the files on it.
fn circle_through(
    from: &Module,
    arrows: &BTreeMap<Module, BTreeSet<Module>>,
) -> Option<Vec<Module>> {
    let mut stack = vec![(from.clone(), vec![from.clone()])];
    let mut seen = BTreeSet::new();
    while let Some((at, trail)) = stack.pop() {
        for next in arrows.get(&at).into_iter().flatten() {
            if next == from {
                return Some(trail);
            }
            if seen.insert(next.clone()) {
                let mut longer = trail.clone();
                longer.push(next.clone());
                stack.push((next.clone(), longer));
            }
        }
    }
    None
}

#[test]
fn no_file_is_over_600_lines_of_code_or_1000_in_all() {
    let mut over = Vec::new();
    for file in modules().values() {
        let text = std::fs::read_to_string(file).unwrap();
        let all = text.lines().count();
        let code = text
            .lines()
            .take_while(|l| !l.starts_with("#[cfg(test)]"))
            .count();
        if code > 600 || all > 1000 {
            over.push(format!(
                "{}: {code} lines before its tests, {all} in all",
                file.display()
            ));
        }
    }
    assert!(
        over.is_empty(),
        "split these by the job they do:\n{}",
        over.join("\n")
    );
}

#[test]
fn no_file_reaches_back_to_itself_through_its_imports() {
    let arrows = arrows();
    assert!(
        arrows.len() > 150,
        "the crate's files were read: {}",
        arrows.len()
    );
    assert!(
        arrows[&vec!["api".to_string(), "matches".to_string()]]
            .contains(&vec!["storage".to_string()]),
        "the arrows are read from the code"
    );
    let circles: Vec<String> = arrows
        .keys()
        .filter_map(|m| circle_through(m, &arrows))
        .map(|c| c.iter().map(name).collect::<Vec<_>>().join(" -> "))
        .collect();
    assert!(
        circles.is_empty(),
        "circles (give the shared type one home below both):\n{}",
        circles.join("\n")
    );
}

#[test]
fn no_import_runs_up_a_floor() {
    let floor_of: BTreeMap<&str, usize> = FLOORS
        .iter()
        .enumerate()
        .flat_map(|(i, rooms)| rooms.iter().map(move |r| (*r, i)))
        .collect();
    let mut up = Vec::new();
    for (from, to) in arrows()
        .iter()
        .flat_map(|(f, ts)| ts.iter().map(move |t| (f, t)))
    {
        let (Some(a), Some(b)) = (from.first(), to.first()) else {
            continue; // lib.rs declares the rooms
        };
        if a == b {
            continue;
        }
        let floor = |room: &str| {
            *floor_of
                .get(room)
                .unwrap_or_else(|| panic!("the room {room} is on no floor: add it to FLOORS"))
        };
        if floor(b) >= floor(a) {
            up.push(format!(
                "{} -> {} ({a} is on floor {}, {b} on {})",
                name(from),
                name(to),
                floor(a),
                floor(b)
            ));
        }
    }
    assert!(
        up.is_empty(),
        "imports that run up or across a floor:\n{}",
        up.join("\n")
    );
}

/// Every source file the docs, the benchmarks and the scripts name (`src/….rs`) exists:
/// a room that moves takes its readers with it.
#[test]
fn every_source_file_the_docs_and_scripts_name_exists() {
    let mut files = vec![root().join("README.md"), root().join("fuzz/README.md")];
    for dir in ["docs", "benches", ".ci", "deploy"] {
        // The walker the client packs bots with (`.ci` is a hidden folder).
        let walk = ignore::WalkBuilder::new(root().join(dir))
            .hidden(false)
            .build();
        files.extend(
            walk.map(|e| e.unwrap())
                .filter(|e| e.file_type().is_some_and(|t| t.is_file()))
                .map(|e| e.into_path()),
        );
    }
    let mut named = 0;
    let mut missing = Vec::new();
    for file in files {
        let Ok(text) = std::fs::read_to_string(&file) else {
            continue; // not text
        };
        for (i, _) in text.match_indices("src/") {
            if i > 0 && text[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == '/') {
                continue; // part of a longer path (e.g. bots/rust/src/)
            }
            let path: String = text[i..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || matches!(c, '_' | '/' | '.' | '-'))
                .collect();
            let path = path.trim_end_matches('.');
            if path.ends_with(".rs") {
                named += 1;
                if !root().join(path).exists() {
                    missing.push(format!("{}: {path}", file.display()));
                }
            }
        }
    }
    assert!(named > 10, "{named} source files named");
    assert!(
        missing.is_empty(),
        "named but missing:\n{}",
        missing.join("\n")
    );
}
