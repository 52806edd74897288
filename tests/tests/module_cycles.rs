//! No import cycles between the modules of a crate (the project's design rule), at every level
//! of nesting: between the top-level modules, and between the child modules of any one module
//! (`acquire::refine` and `acquire::solve`, `timing::cycles` and `timing::flash`).
//!
//! Reads every crate's `src/` (not through the compiler). Every file outside `lib.rs`,
//! `main.rs` and `bin/` is a module (`a.rs` and `a/mod.rs` are `a`, `a/b.rs` is `a::b`). Every
//! path it names that starts with `crate::`, `super::`, `self::` or the name of one of its
//! child modules, with every entry of a `{…}` group, is resolved to the deepest module it
//! reaches. A file of module `M` naming module `T` is then an edge at the level of their
//! deepest common ancestor `L`: from the child of `L` that holds `M` to the child of `L` that
//! holds `T` (at the crate root: the top-level modules). Each level's graph must be acyclic.
//! A module and its own descendants may name each other (a child sees its parent's items
//! through `super::`, a parent declares and re-exports its children), as the crate root and
//! the top-level modules do. Comments, string and character literals and `#[cfg(test)]` items
//! (with the files of `#[cfg(test)] mod NAME;`) do not count: tests may reach anywhere. Any
//! cycle fails the test, with its modules in order.
//!
//! `host-sim/src` is also split into layers (see its `lib.rs`): each top-level module may name
//! only the layers below it ([`HOST_SIM_LAYERS`]).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The crates whose `src/` is checked.
const CRATES: [&str; 3] = ["core", "host-sim", "hil-stubs"];

type Graph = BTreeMap<String, BTreeSet<String>>;

/// A module's path from the crate root (`["acquire", "refine"]`; empty for the root).
type ModPath = Vec<String>;

/// `text` without comments and with string and character literals blanked (their quotes kept).
fn strip_comments_and_literals(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    while i < c.len() {
        let next = c.get(i + 1).copied();
        if c[i] == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if c[i] == '/' && next == Some('*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if c[i] == 'r' && (i == 0 || !ident(c[i - 1])) && matches!(next, Some('"' | '#')) {
            // Raw string r"…" or r#"…"# (a `b` before it was copied as an identifier char).
            let mut j = i + 1;
            while c.get(j) == Some(&'#') {
                j += 1;
            }
            if c.get(j) != Some(&'"') {
                out.push(c[i]);
                i += 1;
                continue;
            }
            let hashes = j - i - 1;
            j += 1;
            while j < c.len() && !(c[j] == '"' && (1..=hashes).all(|k| c.get(j + k) == Some(&'#'))) {
                j += 1;
            }
            out.push_str("\"\"");
            i = j + 1 + hashes;
        } else if c[i] == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            out.push_str("\"\"");
            i += 1;
        } else if c[i] == '\'' && next == Some('\\') {
            i += 2;
            while i < c.len() && c[i] != '\'' {
                i += 1;
            }
            out.push_str("' '");
            i += 1;
        } else if c[i] == '\'' && c.get(i + 2) == Some(&'\'') {
            out.push_str("' '");
            i += 3;
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// `code` (already stripped) without its `#[cfg(test)]` items, and the names of the
/// `#[cfg(test)] mod NAME;` declarations among them.
fn strip_test_items(code: &str) -> (String, Vec<String>) {
    const MARK: &str = "#[cfg(test)]";
    let mut out = String::with_capacity(code.len());
    let mut test_mods = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find(MARK) {
        out.push_str(&rest[..at]);
        let item = &rest[at + MARK.len()..];
        // The item ends at its first `;` outside braces or at the brace closing its body.
        let mut depth = 0usize;
        let mut end = item.len();
        for (k, ch) in item.char_indices() {
            match ch {
                '{' => depth += 1,
                '}' => {
                    depth = depth.saturating_sub(1);
                    if depth == 0 {
                        end = k + 1;
                        break;
                    }
                }
                ';' if depth == 0 => {
                    end = k + 1;
                    break;
                }
                _ => {}
            }
        }
        let words: Vec<&str> = item[..end].split(|ch: char| !(ch.is_alphanumeric() || ch == '_')).collect();
        let words: Vec<&str> = words.into_iter().filter(|w| !w.is_empty()).collect();
        if item[..end].ends_with(';')
            && let Some(p) = words.iter().position(|w| *w == "mod")
            && let Some(name) = words.get(p + 1)
        {
            test_mods.push((*name).to_owned());
        }
        rest = &item[end..];
    }
    out.push_str(rest);
    (out, test_mods)
}

/// An identifier at the start of `s` (empty if there is none).
fn ident(s: &str) -> &str {
    let end = s.find(|ch: char| !(ch.is_alphanumeric() || ch == '_')).unwrap_or(s.len());
    &s[..end]
}

/// The paths of the use tree or path expression `tail` (after its first `::`), each with
/// `prefix` before it: `a::b`, `a::{b, c::d}`, `{self, e}`. A path ends where no `::` follows
/// its last name (at `(`, `;`, `<`, `as`, `*`, …); `self` in a group is the group's prefix.
fn tree_paths(tail: &str, prefix: &[String], out: &mut Vec<ModPath>) {
    let mut path = prefix.to_vec();
    let mut rest = tail.trim_start();
    loop {
        if let Some(group) = rest.strip_prefix('{') {
            // Entries at depth 0, up to the closing brace.
            let (mut depth, mut from) = (0usize, 0);
            for (k, ch) in group.char_indices() {
                match ch {
                    '{' => depth += 1,
                    '}' | ',' if depth == 0 => {
                        tree_paths(&group[from..k], &path, out);
                        if ch == '}' {
                            return;
                        }
                        from = k + 1;
                    }
                    '}' => depth -= 1,
                    _ => {}
                }
            }
            return;
        }
        let name = ident(rest);
        if name.is_empty() {
            break;
        }
        if name != "self" {
            path.push(name.to_owned());
        }
        match rest[name.len()..].trim_start().strip_prefix("::") {
            Some(next) => rest = next.trim_start(),
            None => break,
        }
    }
    out.push(path);
}

/// The module paths named in `code`, the code of module `here` whose child modules are
/// `children`, as written from the crate root (not yet cut to a known module).
fn named_paths(code: &str, here: &[String], children: &BTreeSet<String>) -> Vec<ModPath> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(k) = code[from..].find("::").map(|k| k + from) {
        from = k + 2;
        // The name before this `::`, which must start the path (nothing path-like before it).
        let start = code[..k].rfind(|ch: char| !(ch.is_alphanumeric() || ch == '_')).map_or(0, |p| p + 1);
        let first = &code[start..k];
        let before = code[..start].trim_end();
        // Not the middle of a path, nor a macro's `$name::` (its `$crate::` is `crate::`).
        if first.is_empty() || before.ends_with("::") || (before.ends_with('$') && first != "crate") {
            continue;
        }
        let mut base: ModPath = match first {
            "crate" => Vec::new(),
            "self" => here.to_vec(),
            "super" => here[..here.len().saturating_sub(1)].to_vec(),
            child if children.contains(child) => [here, &[child.to_owned()]].concat(),
            _ => continue,
        };
        let mut tail = code[k + 2..].trim_start();
        while let Some(next) = tail.strip_prefix("super").and_then(|t| t.trim_start().strip_prefix("::")) {
            base.pop();
            tail = next.trim_start();
        }
        tree_paths(tail, &base, &mut out);
    }
    out
}

/// `path` cut to the deepest module of `modules` it lies in (empty: the crate root).
fn module_of(path: &[String], modules: &BTreeSet<ModPath>) -> ModPath {
    (0..=path.len()).rev().map(|n| path[..n].to_vec()).find(|p| modules.contains(p)).unwrap_or_default()
}

/// The module of `file` in `src` (`None` for the crate roots `lib.rs`, `main.rs` and `bin/`).
fn module_path(src: &Path, file: &Path) -> Option<ModPath> {
    let rel = file.strip_prefix(src).ok()?.with_extension("");
    let mut path: ModPath = rel.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    if path.last().is_some_and(|m| m == "mod") {
        path.pop();
    }
    let top = path.first()?;
    (top != "lib" && top != "main" && top != "bin").then_some(path)
}

/// The `.rs` files under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries = std::fs::read_dir(&d).unwrap_or_else(|e| panic!("cannot read {}: {e}", d.display()));
        for e in entries {
            let p = e.unwrap_or_else(|e| panic!("{e}")).path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                files.push(p);
            }
        }
    }
    files.sort();
    files
}

/// The module graphs of one crate's `src/`, one per level: the modules whose children are the
/// nodes (`""` for the crate root) → child → the children it names. Every module with children
/// has its graph (maybe without edges).
fn module_graphs(src: &Path) -> BTreeMap<String, Graph> {
    let mut parsed = Vec::new();
    let mut test_only: Vec<PathBuf> = Vec::new();
    for file in rust_files(src) {
        let Some(module) = module_path(src, &file) else { continue };
        let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("cannot read {}: {e}", file.display()));
        let (code, test_mods) = strip_test_items(&strip_comments_and_literals(&text));
        // `#[cfg(test)] mod NAME;` in `a/b.rs` or `a/b/mod.rs` is `a/b/NAME.rs` or `a/b/NAME/`.
        let dir = if file.file_stem().is_some_and(|s| s == "mod") {
            file.parent().map_or_else(PathBuf::new, Path::to_path_buf)
        } else {
            file.with_extension("")
        };
        for m in test_mods {
            test_only.push(dir.join(format!("{m}.rs")));
            test_only.push(dir.join(&m));
        }
        parsed.push((file, module, code));
    }
    parsed.retain(|(file, _, _)| !test_only.iter().any(|t| file.starts_with(t)));
    let modules: BTreeSet<ModPath> = parsed.iter().map(|(_, m, _)| m.clone()).collect();
    let mut graphs: BTreeMap<String, Graph> = BTreeMap::new();
    for m in &modules {
        let (parent, child) = m.split_at(m.len() - 1);
        graphs.entry(parent.join("::")).or_default().entry(child[0].clone()).or_default();
    }
    for (_, here, code) in &parsed {
        let children: BTreeSet<String> = modules
            .iter()
            .filter(|m| m.len() == here.len() + 1 && m.starts_with(here))
            .map(|m| m[here.len()].clone())
            .collect();
        for path in named_paths(code, here, &children) {
            let target = module_of(&path, &modules);
            let common = here.iter().zip(target.iter()).take_while(|(a, b)| a == b).count();
            // A module naming itself, an ancestor or a descendant: not an edge between siblings.
            if common == here.len() || common == target.len() {
                continue;
            }
            let level = graphs.entry(here[..common].join("::")).or_default();
            level.entry(here[common].clone()).or_default().insert(target[common].clone());
        }
    }
    graphs
}

/// One cycle of `graph` (its modules in order, the first repeated at the end), if any.
fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    // Depth-first search; `path` is the current chain of modules being visited.
    fn visit(n: &str, graph: &Graph, done: &mut BTreeSet<String>, path: &mut Vec<String>) -> Option<Vec<String>> {
        if let Some(p) = path.iter().position(|m| m == n) {
            let mut cycle = path[p..].to_vec();
            cycle.push(n.to_owned());
            return Some(cycle);
        }
        if done.contains(n) {
            return None;
        }
        path.push(n.to_owned());
        for m in graph.get(n).into_iter().flatten() {
            if let Some(c) = visit(m, graph, done, path) {
                return Some(c);
            }
        }
        path.pop();
        done.insert(n.to_owned());
        None
    }
    let mut done = BTreeSet::new();
    graph.keys().find_map(|n| visit(n, graph, &mut done, &mut Vec::new()))
}

/// The cycles of every level of the crate at `src`, each as `level: a -> b -> a` with the
/// modules' paths from the crate root.
fn cycles_of(src: &Path) -> Vec<String> {
    let mut cycles = Vec::new();
    for (level, graph) in module_graphs(src) {
        if let Some(c) = find_cycle(&graph) {
            let full: Vec<String> =
                c.iter().map(|m| if level.is_empty() { m.clone() } else { format!("{level}::{m}") }).collect();
            cycles.push(full.join(" -> "));
        }
    }
    cycles
}

#[test]
fn no_import_cycles_between_modules_at_any_level() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut cycles = Vec::new();
    for krate in CRATES {
        let src = root.join(krate).join("src");
        let graphs = module_graphs(&src);
        let top = graphs.get("").map_or(0, BTreeMap::len);
        assert!(top > 3, "{krate}/src: found only {top} top-level modules");
        // Every crate has at least two modules with child modules of their own.
        assert!(graphs.len() > 2, "{krate}/src: found only {} modules with child modules", graphs.len() - 1);
        cycles.extend(cycles_of(&src).into_iter().map(|c| format!("{krate}/src: {c}")));
    }
    assert!(cycles.is_empty(), "import cycles between modules:\n{}", cycles.join("\n"));
}

/// The layers of `host-sim/src` (its `lib.rs` and each layer's `mod.rs` say the same), lowest
/// first: each top-level module and the layers it may name. `cli` is the binary's command line,
/// which reaches the layers as `evorec_sim::…`, not through `crate::`.
const HOST_SIM_LAYERS: [(&str, &[&str]); 7] = [
    ("sim", &[]),
    ("recording", &[]),
    ("output", &["sim", "recording"]),
    ("experiments", &["sim", "output"]),
    ("rig", &["sim", "recording", "output", "experiments"]),
    ("firmware", &["sim", "output", "experiments"]),
    ("cli", &[]),
];

#[test]
fn host_sim_layers_name_only_the_layers_below_them() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../host-sim/src");
    let graphs = module_graphs(&src);
    let top = graphs.get("").expect("host-sim/src has top-level modules");
    let mut wrong = Vec::new();
    for (layer, named) in top {
        let Some((_, may)) = HOST_SIM_LAYERS.iter().find(|(l, _)| l == layer) else {
            wrong.push(format!("{layer}: not a layer of HOST_SIM_LAYERS"));
            continue;
        };
        wrong.extend(named.iter().filter(|n| !may.contains(&n.as_str())).map(|n| format!("{layer} -> {n}")));
    }
    assert!(wrong.is_empty(), "host-sim/src: a layer names a layer it may not use:\n{}", wrong.join("\n"));
}

fn strings(paths: &[&[&str]]) -> Vec<ModPath> {
    paths.iter().map(|p| p.iter().map(|s| (*s).to_owned()).collect()).collect()
}

#[test]
fn the_scanner_sees_groups_and_skips_comments_literals_and_tests() {
    let code = strip_comments_and_literals(
        "use crate::{a::X, b, c::{d, e}};\n// crate::f\n/* crate::g */ let s = \"crate::h\"; let c = '{';\n\
         #[cfg(test)]\nmod tests { use crate::i; }\n#[cfg(test)]\nmod more;\nfn f<'a>() { crate::j::k(); }\n\
         std::mem::swap(x, y); Vec::<u8>::new(); $crate::l::m!(); $x::n();\n",
    );
    let (code, test_mods) = strip_test_items(&code);
    assert_eq!(
        named_paths(&code, &[], &BTreeSet::new()),
        strings(&[&["a", "X"], &["b"], &["c", "d"], &["c", "e"], &["j", "k"], &["l", "m"]])
    );
    assert_eq!(test_mods, ["more"]);
    let graph: Graph = [("a", "b"), ("b", "c"), ("c", "a"), ("d", "a")]
        .iter()
        .map(|(k, v)| ((*k).to_owned(), BTreeSet::from([(*v).to_owned()])))
        .collect();
    assert_eq!(find_cycle(&graph), Some(["a", "b", "c", "a"].map(str::to_owned).to_vec()));
    let acyclic: Graph =
        [("a", "b"), ("b", "c")].iter().map(|(k, v)| ((*k).to_owned(), BTreeSet::from([(*v).to_owned()]))).collect();
    assert_eq!(find_cycle(&acyclic), None);
}

#[test]
fn the_scanner_resolves_super_self_and_child_paths() {
    let here = ["p".to_owned(), "q".to_owned()];
    let code = "use super::s::T; use self::r::U; use r::{V, w::X}; super::super::t::f(); use crate::p::{self, q::Y};\n\
                use super::{self as up, z};";
    assert_eq!(
        named_paths(code, &here, &BTreeSet::from(["r".to_owned()])),
        strings(&[
            &["p", "s", "T"],
            &["p", "q", "r", "U"],
            &["p", "q", "r", "V"],
            &["p", "q", "r", "w", "X"],
            &["t", "f"],
            &["p"],
            &["p", "q", "Y"],
            &["p"],
            &["p", "z"],
        ])
    );
}

/// Writes the crate `files` (path under `src/`, text) into a fresh directory; returns its `src`.
fn fake_crate(name: &str, files: &[(&str, &str)]) -> PathBuf {
    let src = Path::new(env!("CARGO_TARGET_TMPDIR")).join("module_cycles").join(name).join("src");
    let _ = std::fs::remove_dir_all(&src);
    for (path, text) in files {
        let file = src.join(path);
        std::fs::create_dir_all(file.parent().unwrap()).unwrap();
        std::fs::write(file, text).unwrap();
    }
    src
}

#[test]
fn cycles_between_nested_modules_are_found() {
    // A parent and its children naming each other, and a grandchild naming its aunt: no cycle.
    let base: [(&str, &str); 6] = [
        ("lib.rs", "mod a; mod d;"),
        ("a/mod.rs", "mod b; mod c; pub use b::X; pub struct Z;"),
        ("a/b.rs", "use super::Z; pub struct X;"),
        ("a/c/mod.rs", "mod g; use super::b::X; pub use g::G;"),
        ("a/c/g.rs", "use crate::a::{self, b}; use super::super::Z; pub struct G;"),
        ("d.rs", "use crate::a::c::G;"),
    ];
    assert_eq!(cycles_of(&fake_crate("acyclic", &base)), Vec::<String>::new());
    // Two children of one parent naming each other (the second through a grandchild).
    let mut siblings = base;
    siblings[2].1 = "use super::{Z, c::g::G}; pub struct X;";
    assert_eq!(cycles_of(&fake_crate("siblings", &siblings)), ["a::b -> a::c -> a::b"]);
    // A child naming another top-level module that names it back.
    let mut across = base;
    across[2].1 = "use super::Z; use crate::d; pub struct X;";
    across[5].1 = "use crate::a::b::X;";
    assert_eq!(cycles_of(&fake_crate("across", &across)), ["a -> d -> a"]);
    // A test-only file may name anything.
    let mut files = base.to_vec();
    files[1].1 = "mod b; mod c; pub use b::X; pub struct Z;\n#[cfg(test)]\nmod t;";
    files.push(("a/t.rs", "use super::b::X; use crate::d;"));
    assert_eq!(cycles_of(&fake_crate("tests", &files)), Vec::<String>::new());
}
