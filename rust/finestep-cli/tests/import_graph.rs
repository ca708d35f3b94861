//! The house's import structure: no crate or module import cycle, and the product path
//! (G-code -> planner -> host driver) never depends on the verification side (the
//! reference model, the Verilated RTL, the co-simulation, the plant, the test kit).
//!
//! Crates are read from their manifests (`[dependencies]`, `[build-dependencies]`; a
//! dev-dependency is a test's and may point anywhere), modules from the sources: an
//! edge A -> B for every `crate::B` path in A, and for every `crate::Name` that the
//! crate root re-exports from B (`pub use crate::B::Name`).

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// Crates a product build is made of: none of them may depend on a verification crate.
const PRODUCT: &[&str] =
    &["finestep-interface", "finestep-gcode", "finestep-planner", "finestep-host", "finestep-hal", "finestep-linuxcnc"];
/// The test oracle and its harness.
const VERIFICATION: &[&str] =
    &["finestep-model", "finestep-rtl-sys", "finestep-cosim", "finestep-plant", "finestep-testkit"];

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").canonicalize().expect("rust/ exists")
}

fn crates() -> BTreeMap<String, PathBuf> {
    let mut found = BTreeMap::new();
    for entry in fs::read_dir(workspace()).expect("rust/ is readable") {
        let dir = entry.expect("a directory entry").path();
        if dir.join("Cargo.toml").is_file() {
            let name = dir.file_name().expect("a name").to_string_lossy().into_owned();
            found.insert(name, dir);
        }
    }
    found
}

/// The workspace crates that `manifest` depends on outside dev-dependencies.
fn crate_dependencies(manifest: &str, members: &BTreeSet<String>) -> BTreeSet<String> {
    let mut section = String::new();
    let mut deps = BTreeSet::new();
    for line in manifest.lines() {
        let line = line.trim();
        if line.starts_with('[') {
            section = line.trim_matches(|c| c == '[' || c == ']').to_string();
            continue;
        }
        if section != "dependencies" && section != "build-dependencies" {
            continue;
        }
        if let Some((name, _)) = line.split_once('=') {
            let name = name.trim();
            if members.contains(name) {
                deps.insert(name.to_string());
            }
        }
    }
    deps
}

/// Strongly connected components of more than one node (Tarjan), each sorted.
fn cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct State<'a> {
        graph: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        found: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, node: &'a str) {
        let i = s.index.len();
        s.index.insert(node, i);
        s.low.insert(node, i);
        s.stack.push(node);
        s.on_stack.insert(node);
        let graph = s.graph;
        for next in graph.get(node).into_iter().flatten() {
            let next = next.as_str();
            if !s.index.contains_key(next) {
                visit(s, next);
                let low = s.low[node].min(s.low[next]);
                s.low.insert(node, low);
            } else if s.on_stack.contains(next) {
                let low = s.low[node].min(s.index[next]);
                s.low.insert(node, low);
            }
        }
        if s.low[node] == s.index[node] {
            let mut component = Vec::new();
            while let Some(top) = s.stack.pop() {
                s.on_stack.remove(top);
                component.push(top.to_string());
                if top == node {
                    break;
                }
            }
            if component.len() > 1 {
                component.sort();
                s.found.push(component);
            }
        }
    }
    let mut state = State {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        found: Vec::new(),
    };
    for node in graph.keys() {
        if !state.index.contains_key(node.as_str()) {
            visit(&mut state, node);
        }
    }
    state.found
}

/// Source text without comments and string literals, so that a path named in a doc
/// comment or a message is not an import.
fn code_only(source: &str) -> String {
    let bytes = source.as_bytes();
    let mut out = String::with_capacity(source.len());
    let mut i = 0;
    while i < bytes.len() {
        let rest = &source[i..];
        if rest.starts_with("//") {
            i += rest.find('\n').unwrap_or(rest.len());
        } else if rest.starts_with("/*") {
            i += rest.find("*/").map_or(rest.len(), |end| end + 2);
        } else if rest.starts_with('"') {
            let mut j = 1;
            while j < rest.len() && rest.as_bytes()[j] != b'"' {
                j += if rest.as_bytes()[j] == b'\\' { 2 } else { 1 };
            }
            out.push_str("\"\"");
            i += (j + 1).min(rest.len());
        } else {
            let c = rest.chars().next().expect("not empty");
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

/// The first segments of every path after `crate::` (a use-tree `crate::{a::X, b}` gives
/// `a` and `b`).
fn crate_paths(code: &str) -> Vec<(String, Option<String>)> {
    // (first segment, second segment if the first is followed by `::`)
    fn tree(s: &[u8], mut i: usize, out: &mut Vec<(String, Option<String>)>) -> usize {
        let ident = |s: &[u8], mut i: usize| {
            let start = i;
            while i < s.len() && (s[i].is_ascii_alphanumeric() || s[i] == b'_') {
                i += 1;
            }
            (String::from_utf8_lossy(&s[start..i]).into_owned(), i)
        };
        let skip_ws = |s: &[u8], mut i: usize| {
            while i < s.len() && s[i].is_ascii_whitespace() {
                i += 1;
            }
            i
        };
        i = skip_ws(s, i);
        if i < s.len() && s[i] == b'{' {
            i += 1;
            loop {
                i = skip_ws(s, i);
                if i >= s.len() {
                    return i;
                }
                if s[i] == b'}' {
                    return i + 1;
                }
                if s[i] == b',' {
                    i += 1;
                    continue;
                }
                let before = i;
                i = tree(s, i, out);
                if i == before {
                    i += 1;
                }
            }
        }
        let (first, next) = ident(s, i);
        if first.is_empty() {
            return i;
        }
        i = skip_ws(s, next);
        let mut second = None;
        if s[i..].starts_with(b"::") {
            let j = skip_ws(s, i + 2);
            let (name, after) = ident(s, j);
            if !name.is_empty() {
                second = Some(name);
            }
            // Skip the rest of this path, including a nested use-tree.
            i = j;
            let mut depth = 0usize;
            while i < s.len() {
                match s[i] {
                    b'{' => depth += 1,
                    b'}' if depth == 0 => break,
                    b'}' => depth -= 1,
                    b',' | b';' if depth == 0 => break,
                    _ => {}
                }
                i += 1;
            }
            let _ = after;
        }
        out.push((first, second));
        i
    }
    let bytes = code.as_bytes();
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(at) = code[from..].find("crate::") {
        let start = from + at;
        let boundary = start == 0 || !(bytes[start - 1].is_ascii_alphanumeric() || bytes[start - 1] == b'_');
        from = start + "crate::".len();
        if boundary {
            tree(bytes, from, &mut out);
        }
    }
    out
}

/// The module graph of one crate: its top-level modules and which uses which.
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let root_file = ["lib.rs", "main.rs"].iter().map(|f| src.join(f)).find(|p| p.is_file());
    let Some(root_file) = root_file else { return BTreeMap::new() };
    let mut modules = BTreeSet::new();
    for entry in fs::read_dir(src).expect("src/ is readable") {
        let path = entry.expect("a directory entry").path();
        let name = path.file_stem().expect("a name").to_string_lossy().into_owned();
        let module_file = path.extension().is_some_and(|e| e == "rs") && path != root_file;
        if module_file || path.is_dir() {
            modules.insert(name);
        }
    }
    // Names the root re-exports from a module.
    let root = code_only(&fs::read_to_string(&root_file).expect("the crate root is readable"));
    let mut reexport: BTreeMap<String, String> = BTreeMap::new();
    for statement in root.split(';') {
        let statement = statement.trim();
        let Some(path) = statement.strip_prefix("pub use crate::") else { continue };
        let Some((module, names)) = path.split_once("::") else { continue };
        for name in names.split(|c: char| !(c.is_alphanumeric() || c == '_')) {
            if !name.is_empty() && modules.contains(module) {
                reexport.insert(name.to_string(), module.to_string());
            }
        }
    }
    let mut graph = BTreeMap::new();
    for module in &modules {
        let file = src.join(format!("{module}.rs"));
        let text = if file.is_file() {
            fs::read_to_string(&file).expect("a module is readable")
        } else {
            let mut all = String::new();
            for entry in walk(&src.join(module)) {
                all.push_str(&fs::read_to_string(entry).expect("a module is readable"));
            }
            all
        };
        let mut uses = BTreeSet::new();
        for (first, _) in crate_paths(&code_only(&text)) {
            let target = if modules.contains(&first) { Some(first) } else { reexport.get(&first).cloned() };
            if let Some(target) = target {
                if &target != module {
                    uses.insert(target);
                }
            }
        }
        graph.insert(module.clone(), uses);
    }
    graph
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for entry in fs::read_dir(dir).into_iter().flatten().flatten() {
        let path = entry.path();
        if path.is_dir() {
            files.extend(walk(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
    files
}

fn describe(graph: &BTreeMap<String, BTreeSet<String>>, cycle: &[String]) -> String {
    let mut lines = Vec::new();
    for from in cycle {
        for to in &graph[from] {
            if cycle.contains(to) {
                lines.push(format!("    {from} -> {to}"));
            }
        }
    }
    lines.join("\n")
}

#[test]
fn crates_form_no_cycle_and_the_product_path_needs_no_test_oracle() {
    let crates = crates();
    let members: BTreeSet<String> = crates.keys().cloned().collect();
    let graph: BTreeMap<String, BTreeSet<String>> = crates
        .iter()
        .map(|(name, dir)| {
            let manifest = fs::read_to_string(dir.join("Cargo.toml")).expect("a manifest is readable");
            (name.clone(), crate_dependencies(&manifest, &members))
        })
        .collect();
    let found = cycles(&graph);
    let report: Vec<String> = found.iter().map(|c| describe(&graph, c)).collect();
    assert!(found.is_empty(), "crate dependency cycles:\n{}", report.join("\n\n"));

    // Everything a product crate pulls in, transitively.
    let mut wrong = Vec::new();
    for product in PRODUCT.iter().filter(|p| members.contains(**p)) {
        let mut seen = BTreeSet::new();
        let mut todo = vec![product.to_string()];
        while let Some(name) = todo.pop() {
            for dep in graph.get(&name).into_iter().flatten() {
                if seen.insert(dep.clone()) {
                    todo.push(dep.clone());
                }
            }
        }
        for dep in seen.iter().filter(|d| VERIFICATION.contains(&d.as_str())) {
            wrong.push(format!("{product} depends on {dep}"));
        }
    }
    assert!(wrong.is_empty(), "the product path depends on the verification side:\n  {}", wrong.join("\n  "));
}

#[test]
fn modules_form_no_cycle_in_any_crate() {
    let mut problems = Vec::new();
    for (name, dir) in crates() {
        let graph = module_graph(&dir.join("src"));
        for cycle in cycles(&graph) {
            problems.push(format!("{name}: {}\n{}", cycle.join(", "), describe(&graph, &cycle)));
        }
    }
    assert!(problems.is_empty(), "module import cycles:\n{}", problems.join("\n\n"));
}

#[test]
fn the_cycle_finder_finds_a_cycle_and_passes_a_dag() {
    let graph = |edges: &[(&str, &str)]| {
        let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (a, b) in edges {
            g.entry(a.to_string()).or_default().insert(b.to_string());
            g.entry(b.to_string()).or_default();
        }
        g
    };
    assert!(cycles(&graph(&[("a", "b"), ("b", "c"), ("a", "c")])).is_empty());
    assert_eq!(cycles(&graph(&[("a", "b"), ("b", "c"), ("c", "a"), ("c", "d")])), vec![vec!["a", "b", "c"]]);
    let paths = crate_paths(&code_only(
        "use crate::{config::{A, B}, record::X, Increment};\n// crate::fake\nlet s = \"crate::str\"; crate::top::f();",
    ));
    let firsts: Vec<&str> = paths.iter().map(|(f, _)| f.as_str()).collect();
    assert_eq!(firsts, ["config", "record", "Increment", "top"]);
}
