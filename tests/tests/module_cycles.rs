//! No import cycles between the top-level modules of a crate (the project's design rule).
//!
//! Reads every crate's `src/` (not through the compiler): in each file outside `lib.rs` and
//! `main.rs`, every `crate::NAME` path and every name of a `crate::{A, B::c}` group is an edge
//! from the file's top-level module to `NAME`. Comments, string and character literals and
//! `#[cfg(test)]` items (with the files of `#[cfg(test)] mod NAME;`) do not count: tests may
//! reach anywhere. Any cycle fails the test, with its modules in order.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The crates whose `src/` is checked.
const CRATES: [&str; 3] = ["core", "host-sim", "hil-stubs"];

type Graph = BTreeMap<String, BTreeSet<String>>;

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

/// The top-level modules named by `crate::` paths in `code`.
fn crate_refs(code: &str) -> BTreeSet<String> {
    let mut refs = BTreeSet::new();
    let ident = |s: &str| s.chars().take_while(|ch| ch.is_alphanumeric() || *ch == '_').collect::<String>();
    for (at, _) in code.match_indices("crate::") {
        if code[..at].chars().next_back().is_some_and(|ch| ch.is_alphanumeric() || ch == '_') {
            continue; // e.g. `evorec_crate::`
        }
        let after = code[at + "crate::".len()..].trim_start();
        if let Some(group) = after.strip_prefix('{') {
            // The first name of every entry at depth 0 of the group.
            let mut depth = 0usize;
            let mut expect = true;
            for (k, ch) in group.char_indices() {
                match ch {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => expect = true,
                    ch if expect && depth == 0 && (ch.is_alphabetic() || ch == '_') => {
                        refs.insert(ident(&group[k..]));
                        expect = false;
                    }
                    _ => {}
                }
            }
        } else {
            let name = ident(after);
            if !name.is_empty() {
                refs.insert(name);
            }
        }
    }
    refs.remove("self");
    refs
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

/// The top-level module of `file` in `src` (`None` for the crate roots `lib.rs`, `main.rs`).
fn top_module(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).ok()?;
    let top = rel.components().next()?.as_os_str().to_string_lossy().trim_end_matches(".rs").to_owned();
    (top != "lib" && top != "main" && top != "bin").then_some(top)
}

/// The module graph of one crate's `src/`: top-level module → the modules it names.
fn module_graph(src: &Path) -> Graph {
    let mut parsed = Vec::new();
    let mut test_only: Vec<PathBuf> = Vec::new();
    for file in rust_files(src) {
        let Some(top) = top_module(src, &file) else { continue };
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
        parsed.push((file, top, crate_refs(&code)));
    }
    let mut graph = Graph::new();
    for (file, top, refs) in parsed {
        let edges = graph.entry(top.clone()).or_default();
        if !test_only.iter().any(|t| file.starts_with(t)) {
            edges.extend(refs.into_iter().filter(|r| *r != top));
        }
    }
    let modules: BTreeSet<String> = graph.keys().cloned().collect();
    for edges in graph.values_mut() {
        edges.retain(|m| modules.contains(m));
    }
    graph
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

#[test]
fn no_import_cycles_between_top_level_modules() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut cycles = Vec::new();
    for krate in CRATES {
        let graph = module_graph(&root.join(krate).join("src"));
        assert!(graph.len() > 3, "{krate}/src: found only {} modules", graph.len());
        if let Some(c) = find_cycle(&graph) {
            cycles.push(format!("{krate}/src: {}", c.join(" -> ")));
        }
    }
    assert!(cycles.is_empty(), "import cycles between modules:\n{}", cycles.join("\n"));
}

#[test]
fn the_scanner_sees_groups_and_skips_comments_literals_and_tests() {
    let code = strip_comments_and_literals(
        "use crate::{a::X, b, c::{d, e}};\n// crate::f\n/* crate::g */ let s = \"crate::h\"; let c = '{';\n\
         #[cfg(test)]\nmod tests { use crate::i; }\n#[cfg(test)]\nmod more;\nfn f<'a>() { crate::j::k(); }\n",
    );
    let (code, test_mods) = strip_test_items(&code);
    let refs: Vec<String> = crate_refs(&code).into_iter().collect();
    assert_eq!(refs, ["a", "b", "c", "j"]);
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
