//! The layering of the code: within every crate of the workspace, no module imports one that
//! imports it back, directly or through others. Imports are read as text (`crate::a::b` and
//! `super::b` paths outside comments and test modules; a module also reaches its submodules),
//! which is enough for this code base: it writes every import as a full path.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Module path of a source file below its crate's `src/` (`solve/mod.rs` → `solve`).
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The modules each module of the crate at `src` imports (their longest known path).
fn imports(src: &Path) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let modules: BTreeMap<Vec<String>, PathBuf> = files
        .iter()
        .map(|f| (module_of(src, f), f.clone()))
        .collect();
    let mut graph = BTreeMap::new();
    for (module, file) in &modules {
        let text = std::fs::read_to_string(file).unwrap();
        let code = text.split("#[cfg(test)]").next().unwrap_or_default();
        let mut targets = BTreeSet::new();
        for line in code
            .lines()
            .map(|l| l.split("//").next().unwrap_or_default())
        {
            for (prefix, base) in [
                ("crate::", &[][..]),
                ("super::", &module[..module.len().saturating_sub(1)]),
            ] {
                for path in line.split(prefix).skip(1) {
                    let mut parts = base.to_vec();
                    let name_chars = |c: char| {
                        c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_' || c == ':'
                    };
                    let tail: String = path.chars().take_while(|&c| name_chars(c)).collect();
                    parts.extend(tail.split("::").filter(|p| !p.is_empty()).map(String::from));
                    let known = (1..=parts.len())
                        .rev()
                        .map(|k| parts[..k].to_vec())
                        .find(|p| modules.contains_key(p));
                    if let Some(target) = known.filter(|t| !module.starts_with(t)) {
                        targets.insert(target);
                    }
                }
            }
        }
        graph.insert(module.clone(), targets);
    }
    // a module holds its submodules: what they import, it imports
    let children: Vec<Vec<String>> = graph.keys().filter(|m| !m.is_empty()).cloned().collect();
    for child in children {
        let parent = child[..child.len() - 1].to_vec();
        if let Some(targets) = graph.get_mut(&parent) {
            targets.insert(child);
        }
    }
    graph
}

/// A cycle through `start`, if the graph has one.
fn cycle_from(
    graph: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
    start: &Vec<String>,
) -> Option<Vec<String>> {
    let mut stack = vec![(start.clone(), vec![start.join("::")])];
    let mut seen = BTreeSet::new();
    while let Some((node, path)) = stack.pop() {
        for next in graph.get(&node).into_iter().flatten() {
            if next == start {
                return Some([path.clone(), vec![start.join("::")]].concat());
            }
            if seen.insert(next.clone()) {
                stack.push((next.clone(), [path.clone(), vec![next.join("::")]].concat()));
            }
        }
    }
    None
}

#[test]
fn no_module_imports_one_that_imports_it_back() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut crates = vec![root.join("src")];
    for entry in std::fs::read_dir(root.join("crates")).unwrap() {
        crates.push(entry.unwrap().path().join("src"));
    }
    crates.push(root.join("python/src"));
    let mut cycles = Vec::new();
    for src in crates.iter().filter(|s| s.is_dir()) {
        let graph = imports(src);
        assert!(
            graph.len() > 1 || src.ends_with("python/src"),
            "{}: no modules read",
            src.display()
        );
        cycles.extend(
            graph
                .keys()
                .filter_map(|m| cycle_from(&graph, m))
                .map(|c| format!("{}: {}", src.display(), c.join(" -> "))),
        );
    }
    assert!(cycles.is_empty(), "import cycles:\n{}", cycles.join("\n"));
}
