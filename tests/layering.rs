//! The crate's files import each other without circles, and the physics core imports nothing
//! outside itself. "Imports" are the `use` declarations and the inline paths that start with
//! `crate::`, `super::` or `self::` (a parent reaching its declared child modules is the module
//! tree, not an import). Each path resolves to the deepest file it names.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// A file's module path: `src/core/forces/mod.rs` is `core::forces`, `src/lib.rs` the root.
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().to_string()).collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib" | "main")) {
        parts.pop();
    }
    parts
}

/// The text that imports: line comments and the `#[cfg(test)]` module at a file's end removed.
fn code(text: &str) -> String {
    let text = text.find("#[cfg(test)]\nmod ").map_or(text, |k| &text[..k]);
    text.lines().map(|l| l.find("//").map_or(l, |k| &l[..k])).collect::<Vec<_>>().join("\n")
}

/// Expands a use tree `a::{b::c, d}` into its paths `a::b::c`, `a::d`.
fn expand(tree: &str) -> Vec<String> {
    let tree = tree.trim();
    let (Some(open), Some(close)) = (tree.find('{'), tree.rfind('}')) else { return vec![tree.to_string()] };
    let (prefix, inner) = (&tree[..open], &tree[open + 1..close.max(open + 1)]);
    let (mut parts, mut depth, mut current) = (vec![], 0, String::new());
    for c in inner.chars() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            _ => {}
        }
        if c == ',' && depth == 0 {
            parts.push(std::mem::take(&mut current));
        } else {
            current.push(c);
        }
    }
    parts.push(current);
    parts.iter().filter(|p| !p.trim().is_empty()).flat_map(|p| expand(p)).map(|p| format!("{prefix}{p}")).collect()
}

/// Module paths that `text` (the file at `module`) imports.
fn imports(module: &[String], text: &str) -> Vec<Vec<String>> {
    let mut paths = vec![];
    // `use` declarations, which may span lines and group items in braces.
    let mut rest = text;
    while let Some(k) = rest.find("use ") {
        let boundary = k == 0 || !rest.as_bytes()[k - 1].is_ascii_alphanumeric() && rest.as_bytes()[k - 1] != b'_';
        let end = rest[k..].find(';').map_or(rest.len(), |e| k + e);
        let tree: String = rest[k + 4..end].split_whitespace().collect::<Vec<_>>().join(" ");
        if boundary && ["crate::", "super::", "self::"].iter().any(|h| tree.starts_with(h)) {
            paths.extend(expand(&tree));
        }
        rest = &rest[if boundary { end } else { k + 4 }..];
    }
    // Inline paths.
    let bytes = text.as_bytes();
    for head in ["crate::", "super::", "self::"] {
        for (k, _) in text.match_indices(head) {
            if k > 0 && (bytes[k - 1].is_ascii_alphanumeric() || bytes[k - 1] == b'_' || bytes[k - 1] == b':') {
                continue;
            }
            let end = text[k..]
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
                .map_or(text.len(), |e| k + e);
            paths.push(text[k..end].to_string());
        }
    }
    paths
        .iter()
        .filter_map(|path| {
            let parts: Vec<&str> =
                path.split("::").map(|p| p.split(" as ").next().unwrap().trim()).filter(|p| !p.is_empty()).collect();
            let mut base: Vec<String> = match *parts.first()? {
                "crate" => vec![],
                "self" | "super" => module.to_vec(),
                _ => return None,
            };
            let mut rest = &parts[1..];
            if parts[0] == "super" {
                base.pop();
            }
            while rest.first() == Some(&"super") {
                base.pop();
                rest = &rest[1..];
            }
            base.extend(rest.iter().map(|p| p.to_string()));
            Some(base)
        })
        .collect()
}

/// The file that module path `path` (or its deepest prefix naming a file) lives in.
fn resolve(files: &BTreeMap<Vec<String>, PathBuf>, path: &[String]) -> Option<PathBuf> {
    (0..=path.len()).rev().find_map(|k| files.get(&path[..k]).cloned())
}

/// Every file of `src/` and the files it imports.
fn graph() -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut list = vec![];
    sources(&src, &mut list);
    let files: BTreeMap<Vec<String>, PathBuf> =
        list.iter().filter(|f| !f.ends_with("main.rs")).map(|f| (module_of(&src, f), f.clone())).collect();
    let mut edges = BTreeMap::new();
    for (module, file) in &files {
        let text = code(&std::fs::read_to_string(file).unwrap());
        let targets: BTreeSet<PathBuf> = imports(module, &text)
            .iter()
            .filter_map(|p| resolve(&files, p))
            .filter(|t| t != file)
            .map(|t| t.strip_prefix(&src).unwrap().to_path_buf())
            .collect();
        edges.insert(file.strip_prefix(&src).unwrap().to_path_buf(), targets);
    }
    edges
}

/// The strongly connected components of more than one file (Tarjan).
fn circles(edges: &BTreeMap<PathBuf, BTreeSet<PathBuf>>) -> Vec<Vec<PathBuf>> {
    struct Walk<'a> {
        edges: &'a BTreeMap<PathBuf, BTreeSet<PathBuf>>,
        index: BTreeMap<&'a PathBuf, usize>,
        low: BTreeMap<&'a PathBuf, usize>,
        stack: Vec<&'a PathBuf>,
        found: Vec<Vec<PathBuf>>,
    }
    fn visit<'a>(w: &mut Walk<'a>, v: &'a PathBuf) {
        let k = w.index.len();
        w.index.insert(v, k);
        w.low.insert(v, k);
        w.stack.push(v);
        for t in w.edges.get(v).into_iter().flatten() {
            let Some((t, _)) = w.edges.get_key_value(t) else { continue };
            if !w.index.contains_key(t) {
                visit(w, t);
                let low = w.low[v].min(w.low[t]);
                w.low.insert(v, low);
            } else if w.stack.contains(&t) {
                let low = w.low[v].min(w.index[t]);
                w.low.insert(v, low);
            }
        }
        if w.low[v] == w.index[v] {
            let at = w.stack.iter().rposition(|x| *x == v).unwrap();
            let component: Vec<PathBuf> = w.stack.drain(at..).cloned().collect();
            if component.len() > 1 {
                w.found.push(component);
            }
        }
    }
    let mut walk = Walk { edges, index: BTreeMap::new(), low: BTreeMap::new(), stack: vec![], found: vec![] };
    for v in edges.keys() {
        if !walk.index.contains_key(v) {
            visit(&mut walk, v);
        }
    }
    walk.found
}

#[test]
fn no_file_imports_itself_through_others() {
    let edges = graph();
    assert!(edges.len() > 50, "read {} files", edges.len());
    let found = circles(&edges);
    assert!(found.is_empty(), "import circles: {found:#?}");
}

/// The checker finds a circle where there is one: two files that use each other.
#[test]
fn the_checker_sees_a_circle() {
    let a = PathBuf::from("a.rs");
    let b = PathBuf::from("b.rs");
    let mut edges = BTreeMap::new();
    edges.insert(a.clone(), BTreeSet::from([b.clone()]));
    edges.insert(b.clone(), BTreeSet::from([a.clone()]));
    assert_eq!(circles(&edges).len(), 1);
    let module = vec!["report".to_string(), "digest".to_string()];
    let found = imports(&module, "use super::runs::{Run, load};\nlet x = crate::core::state::State::new();");
    assert!(found.contains(&vec!["report".into(), "runs".into(), "Run".into()]), "{found:?}");
    assert!(found.iter().any(|p| p.starts_with(&["core".into(), "state".into()])), "{found:?}");
}

#[test]
fn the_physics_core_imports_nothing_outside_itself() {
    for (file, targets) in graph() {
        if file.starts_with("core") {
            let outside: Vec<_> = targets.iter().filter(|t| !t.starts_with("core")).collect();
            assert!(outside.is_empty(), "{} imports {outside:?}", file.display());
        }
    }
}
