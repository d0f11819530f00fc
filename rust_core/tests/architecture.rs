//! The layering of `rust_core/src`, checked on the sources themselves.
//!
//! Every file's references to other modules of the crate are collected: paths that start with
//! `crate::` or `super::` (in `use` trees too, `use crate::{a::X, b::{Y, Z}}`; `super` resolved
//! against the file's module and the inline modules around it); a name re-exported by a module
//! (`pub use`, as `crate::Status` or `crate::ode::integrate`) is followed to the module that
//! defines it. Comments, strings and character literals are skipped. From these:
//!
//! - the graph of the top-level modules (`model`, `ode`, `steady`, ...) must be acyclic;
//! - inside every folder module (`ode/`, `ensemble/`, ...), the graph of its child modules must be
//!   acyclic (references to items of the folder's own `mod.rs`, its shared vocabulary, are not
//!   edges: a parent declares its children, so parent and child always see each other);
//! - `ode/`, the generic integrators, references no other module of the crate (it knows nothing of
//!   the slider, the steady state or the status codes), except the leaves in [`LEAVES`];
//! - a leaf (`cancel`, the caller's stop request) references no other module of the crate, so
//!   that `ode` using it still knows nothing above itself.
//!
//! Test code counts as well: a test that reaches into a higher layer makes a cycle as real as
//! production code does. The checks run on a synthetic source set too, to show that they fail on
//! a real cycle and on a real layering violation.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Module path of a source file relative to `src/`: `lib.rs` -> `[]`, `ode/mod.rs` -> `[ode]`,
/// `ode/driver.rs` -> `[ode, driver]`, `ode/driver/tests.rs` -> `[ode, driver, tests]`.
fn module_of(rel: &str) -> Vec<String> {
    let mut parts: Vec<String> = rel.trim_end_matches(".rs").split('/').map(str::to_string).collect();
    if matches!(parts.last().map(String::as_str), Some("mod") | Some("lib")) {
        parts.pop();
    }
    parts
}

/// The source without comments, string literals and character literals (each replaced by a space).
fn code_only(src: &str) -> String {
    let c: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    while i < c.len() {
        if c[i] == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if c[i] == '/' && c.get(i + 1) == Some(&'*') {
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
        } else if c[i] == 'r'
            && (c.get(i + 1) == Some(&'"') || c.get(i + 1) == Some(&'#'))
            && !ident_char(c.get(i.wrapping_sub(1)))
        {
            // Raw string r"..." or r#"..."#.
            let mut j = i + 1;
            let mut hashes = 0;
            while c.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if c.get(j) != Some(&'"') {
                out.push(c[i]);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= c.len() {
                    break;
                }
                if c[j] == '"' && (0..hashes).all(|k| c.get(j + 1 + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            i = j;
            out.push(' ');
        } else if c[i] == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push(' ');
        } else if c[i] == '\'' {
            // A character literal ('a', '\n', '\u{..}'), else a lifetime or label ('a).
            if c.get(i + 1) == Some(&'\\') {
                let mut j = i + 2;
                while j < c.len() && c[j] != '\'' {
                    j += 1;
                }
                i = j + 1;
                out.push(' ');
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
                out.push(' ');
            } else {
                out.push('\'');
                i += 1;
            }
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

fn ident_char(c: Option<&char>) -> bool {
    c.is_some_and(|c| c.is_alphanumeric() || *c == '_')
}

/// Tokens: identifiers, `::`, and single punctuation characters.
fn tokens(code: &str) -> Vec<String> {
    let c: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        if c[i].is_alphanumeric() || c[i] == '_' {
            let s = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push(c[s..i].iter().collect());
        } else if c[i] == ':' && c.get(i + 1) == Some(&':') {
            out.push("::".to_string());
            i += 2;
        } else if c[i].is_whitespace() {
            i += 1;
        } else {
            out.push(c[i].to_string());
            i += 1;
        }
    }
    out
}

/// Every full path of the path or `use` tree that starts at token `i` (just after a `::`),
/// prefixed by `prefix`, with the name it is known by here (`as` aliases included; `*` for a
/// glob); returns the index after the tree.
fn use_tree(t: &[String], mut i: usize, prefix: Vec<String>, out: &mut Vec<(Vec<String>, String)>) -> usize {
    let mut path = prefix;
    loop {
        match t.get(i).map(String::as_str) {
            Some("{") => {
                i += 1;
                loop {
                    match t.get(i).map(String::as_str) {
                        Some("}") => return i + 1,
                        Some(",") => i += 1,
                        None => return i,
                        _ => i = use_tree(t, i, path.clone(), out),
                    }
                }
            }
            Some("*") => {
                out.push((path, "*".to_string()));
                return i + 1;
            }
            Some("self") => {
                let name = path.last().cloned().unwrap_or_default();
                out.push((path, name));
                return i + 1;
            }
            Some(id) if id.chars().all(|c| c.is_alphanumeric() || c == '_') => {
                path.push(id.to_string());
                if t.get(i + 1).map(String::as_str) == Some("::") {
                    i += 2;
                } else if t.get(i + 1).map(String::as_str) == Some("as") && t.get(i + 2).is_some() {
                    out.push((path, t[i + 2].clone()));
                    return i + 3;
                } else {
                    out.push((path, id.to_string()));
                    return i + 1;
                }
            }
            _ => {
                let name = path.last().cloned().unwrap_or_default();
                out.push((path, name));
                return i;
            }
        }
    }
}

/// The module paths a file refers to (each full path as written, `super` resolved), given the
/// file's module.
fn references(src: &str, module: &[String]) -> Vec<Vec<String>> {
    let t = tokens(&code_only(src));
    let mut out = Vec::new();
    // Inline modules `mod name { ... }` around the current token: (name, brace depth inside).
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth = 0usize;
    let mut i = 0;
    while i < t.len() {
        match t[i].as_str() {
            "{" => depth += 1,
            "}" => {
                depth = depth.saturating_sub(1);
                if inline.last().is_some_and(|m| m.1 > depth) {
                    inline.pop();
                }
            }
            "mod" if t.get(i + 2).map(String::as_str) == Some("{") => {
                inline.push((t[i + 1].clone(), depth + 1));
                depth += 1;
                i += 3;
                continue;
            }
            "crate" | "super" if t.get(i + 1).map(String::as_str) == Some("::") => {
                let preceded_by_path = i > 0 && t[i - 1] == "::";
                if !preceded_by_path {
                    let mut base: Vec<String> = module.to_vec();
                    base.extend(inline.iter().map(|m| m.0.clone()));
                    let mut j = i;
                    if t[j] == "crate" {
                        base.clear();
                        j += 2;
                    } else {
                        while t.get(j).map(String::as_str) == Some("super")
                            && t.get(j + 1).map(String::as_str) == Some("::")
                        {
                            base.pop();
                            j += 2;
                        }
                    }
                    let mut paths = Vec::new();
                    i = use_tree(&t, j, base, &mut paths);
                    out.extend(paths.into_iter().map(|(p, _)| p));
                    continue;
                }
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// A module's re-exports (`pub use` and `pub(crate) use`): `pub use model::{Params, Slider}` in
/// `lib.rs` gives `Params -> model::Params`; `pub use driver::integrate` in `ode/mod.rs` gives
/// `integrate -> ode::driver::integrate`. Paths relative to the module (its children) or through
/// `crate`, `super`, `self`.
fn reexports(src: &str, module: &[String]) -> Vec<(String, Vec<String>)> {
    let t = tokens(&code_only(src));
    let mut out = Vec::new();
    for i in 0..t.len() {
        if t[i] != "pub" {
            continue;
        }
        let mut j = i + 1;
        if t.get(j).map(String::as_str) == Some("(") {
            while j < t.len() && t[j] != ")" {
                j += 1;
            }
            j += 1;
        }
        if t.get(j).map(String::as_str) != Some("use") {
            continue;
        }
        j += 1;
        let mut base = module.to_vec();
        match t.get(j).map(String::as_str) {
            Some("crate") => {
                base.clear();
                j += 2;
            }
            Some("self") => j += 2,
            _ => {
                while t.get(j).map(String::as_str) == Some("super") {
                    base.pop();
                    j += 2;
                }
            }
        }
        let mut paths = Vec::new();
        use_tree(&t, j, base, &mut paths);
        out.extend(paths.into_iter().filter(|(_, name)| name != "*").map(|(p, name)| (name, p)));
    }
    out
}

/// `p` with re-exported names replaced by what they name, until it names no re-export.
fn resolve(
    mut p: Vec<String>,
    modules: &BTreeSet<Vec<String>>,
    aliases: &BTreeMap<(Vec<String>, String), Vec<String>>,
) -> Vec<String> {
    for _ in 0..16 {
        // The longest prefix of `p` that is a module (the crate root `[]` always is).
        let k = (0..p.len()).rev().find(|&k| modules.contains(&p[..k])).unwrap_or(0);
        match aliases.get(&(p[..k].to_vec(), p[k].clone())) {
            Some(target) if *target != p[..=k] => p = [target.clone(), p[k + 1..].to_vec()].concat(),
            _ => break,
        }
    }
    p
}

/// Leaf modules: they reference no other module of the crate, and `ode/` may use them.
const LEAVES: [&str; 1] = ["cancel"];

/// What the checks found.
#[derive(Debug, Default)]
struct Report {
    /// A cycle among the top-level modules, if any.
    top_cycle: Option<Vec<String>>,
    /// Cycles among the children of a folder module: (folder, cycle).
    folder_cycles: Vec<(String, Vec<String>)>,
    /// References from `ode/` to other modules of the crate (leaves excepted): (file, path).
    ode_violations: Vec<(String, String)>,
    /// References from a leaf module to other modules of the crate: (file, path).
    leaf_violations: Vec<(String, String)>,
    /// The top-level graph, for the test output.
    top_edges: BTreeSet<(String, String)>,
}

/// Analyse a source set: relative path under `src/` -> text.
fn analyse(files: &BTreeMap<String, String>) -> Report {
    let modules: BTreeSet<Vec<String>> = files.keys().map(|k| module_of(k)).collect();
    let mut aliases = BTreeMap::new();
    for (rel, src) in files {
        let me = module_of(rel);
        for (name, target) in reexports(src, &me) {
            aliases.insert((me.clone(), name), target);
        }
    }
    let top: BTreeSet<String> = modules.iter().filter_map(|m| m.first().cloned()).collect();
    // Folder modules: those with a child module.
    let folders: BTreeSet<Vec<String>> =
        modules.iter().filter(|m| m.len() >= 2).map(|m| m[..m.len() - 1].to_vec()).filter(|f| !f.is_empty()).collect();
    let mut report = Report::default();
    let mut folder_edges: BTreeMap<Vec<String>, BTreeSet<(String, String)>> = BTreeMap::new();
    for (rel, src) in files {
        let me = module_of(rel);
        for p in references(src, &me) {
            if p.is_empty() {
                continue;
            }
            let p = resolve(p, &modules, &aliases);
            let (Some(from), Some(to)) = (me.first(), p.first()) else { continue };
            if from != to && top.contains(to) {
                report.top_edges.insert((from.clone(), to.clone()));
                if from == "ode" && !LEAVES.contains(&to.as_str()) {
                    report.ode_violations.push((rel.clone(), p.join("::")));
                }
                if LEAVES.contains(&from.as_str()) {
                    report.leaf_violations.push((rel.clone(), p.join("::")));
                }
            }
            for f in &folders {
                let n = f.len();
                if me.len() > n && p.len() > n && me[..n] == f[..] && p[..n] == f[..] {
                    let (a, b) = (&me[n], &p[n]);
                    let child = modules.contains(&[f.clone(), vec![b.clone()]].concat());
                    if a != b && child {
                        folder_edges.entry(f.clone()).or_default().insert((a.clone(), b.clone()));
                    }
                }
            }
        }
    }
    report.top_cycle = find_cycle(&report.top_edges);
    for (f, edges) in &folder_edges {
        if let Some(c) = find_cycle(edges) {
            report.folder_cycles.push((f.join("::"), c));
        }
    }
    report
}

/// A cycle of the directed graph, as the nodes along it (first repeated at the end), if any.
fn find_cycle(edges: &BTreeSet<(String, String)>) -> Option<Vec<String>> {
    let mut next: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for (a, b) in edges {
        next.entry(a).or_default().push(b);
    }
    // 0: unseen, 1: on the stack, 2: done.
    fn visit<'a>(
        n: &'a str,
        next: &BTreeMap<&'a str, Vec<&'a str>>,
        state: &mut BTreeMap<&'a str, u8>,
        stack: &mut Vec<&'a str>,
    ) -> Option<Vec<String>> {
        state.insert(n, 1);
        stack.push(n);
        for &m in next.get(n).map(Vec::as_slice).unwrap_or(&[]) {
            match state.get(m).copied().unwrap_or(0) {
                1 => {
                    let at = stack.iter().position(|&x| x == m).expect("on the stack");
                    let mut c: Vec<String> = stack[at..].iter().map(|s| s.to_string()).collect();
                    c.push(m.to_string());
                    return Some(c);
                }
                0 => {
                    if let Some(c) = visit(m, next, state, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state.insert(n, 2);
        None
    }
    let mut state = BTreeMap::new();
    let nodes: Vec<&str> = next.keys().copied().collect();
    for n in nodes {
        if state.get(n).copied().unwrap_or(0) == 0 {
            if let Some(c) = visit(n, &next, &mut state, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

/// Every `.rs` file under `dir`, keyed by its path relative to `root`.
fn read_tree(root: &Path, dir: &Path, out: &mut BTreeMap<String, String>) {
    for entry in std::fs::read_dir(dir).expect("reading the source tree") {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            read_tree(root, &path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let rel = path.strip_prefix(root).expect("under src").to_string_lossy().replace('\\', "/");
            out.insert(rel, std::fs::read_to_string(&path).expect("reading a source file"));
        }
    }
}

#[test]
fn the_module_graph_of_the_core_is_acyclic_and_ode_is_generic() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = BTreeMap::new();
    read_tree(&src, &src, &mut files);
    assert!(files.contains_key("lib.rs") && files.contains_key("ode/mod.rs"), "not the core's source tree");
    let r = analyse(&files);
    for (a, b) in &r.top_edges {
        println!("{a} -> {b}");
    }
    // A graph that found nothing would pass every check: the real one has these layers.
    for edge in [("model", "ode"), ("steady", "model"), ("ensemble", "steady"), ("shooting", "steady")] {
        assert!(r.top_edges.contains(&(edge.0.to_string(), edge.1.to_string())), "missing edge {edge:?}");
    }
    assert_eq!(r.top_cycle, None, "a cycle among the top-level modules");
    assert!(r.folder_cycles.is_empty(), "cycles inside folder modules: {:?}", r.folder_cycles);
    assert!(r.ode_violations.is_empty(), "ode/ depends on the layers above it: {:?}", r.ode_violations);
    assert!(r.leaf_violations.is_empty(), "a leaf module depends on others: {:?}", r.leaf_violations);
    assert!(files.contains_key("cancel.rs") && r.top_edges.contains(&("ode".to_string(), "cancel".to_string())));
}

#[test]
fn ode_may_use_a_leaf_but_a_leaf_uses_nothing() {
    let ok = synthetic(&[
        ("lib.rs", "pub mod ode;\npub mod cancel;\npub mod model;"),
        ("cancel.rs", "pub fn requested() -> bool { false }"),
        ("model.rs", "use crate::ode::OdeSystem;"),
        ("ode/mod.rs", "pub mod driver;\npub trait OdeSystem {}"),
        ("ode/driver.rs", "use crate::cancel;\nfn f() -> bool { cancel::requested() }"),
    ]);
    let r = analyse(&ok);
    assert!(r.ode_violations.is_empty() && r.leaf_violations.is_empty(), "{r:?}");
    let mut bad = ok.clone();
    bad.insert("cancel.rs".into(), "use crate::model::Slider;".into());
    let r = analyse(&bad);
    assert_eq!(r.leaf_violations, vec![("cancel.rs".to_string(), "model::Slider".to_string())]);
}

fn synthetic(files: &[(&str, &str)]) -> BTreeMap<String, String> {
    files.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
}

#[test]
fn a_cycle_between_top_level_modules_is_found() {
    let ok = synthetic(&[
        ("lib.rs", "pub mod a;\npub mod b;\npub use b::Thing;"),
        (
            "a.rs",
            "use crate::b::{self, Thing};\n// crate::a is named in a comment only\nfn f() { let s = \"crate::a::g\"; }",
        ),
        ("b.rs", "pub struct Thing;\nfn g() -> char { '\"' }\nfn h<'a>(x: &'a str) -> &'a str { x }"),
    ]);
    let r = analyse(&ok);
    assert_eq!(r.top_cycle, None, "{:?}", r.top_edges);
    assert!(r.top_edges.contains(&("a".to_string(), "b".to_string())));

    // b refers back to a: through a path in code, through a grouped use, through a root re-export.
    for back in ["fn g() { crate::a::f(); }", "use crate::{x::Y, a::{f, g}};", "use crate::Alpha;"] {
        let mut bad = ok.clone();
        bad.insert("lib.rs".into(), "pub mod a;\npub mod b;\npub use a::Alpha;".into());
        bad.insert("b.rs".into(), back.into());
        let r = analyse(&bad);
        let c = r.top_cycle.unwrap_or_else(|| panic!("no cycle found with b.rs = {back:?}: {:?}", r.top_edges));
        assert!(c.contains(&"a".to_string()) && c.contains(&"b".to_string()), "{c:?}");
    }
}

#[test]
fn a_cycle_inside_a_folder_and_a_layering_violation_are_found() {
    // The cycle the old driver had: the steppers import the Stepper trait from the driver, which
    // names the steppers.
    let old = synthetic(&[
        ("lib.rs", "pub mod ode;\npub mod model;"),
        ("model.rs", "use crate::ode::OdeSystem;"),
        ("ode/mod.rs", "pub mod driver;\npub mod dopri5;\npub trait OdeSystem {}"),
        ("ode/driver.rs", "use super::dopri5::Dopri5;\npub(crate) trait Stepper {}\n#[cfg(test)]\nmod tests {\n    use super::*;\n    use super::super::OdeSystem;\n}"),
        ("ode/dopri5.rs", "use super::driver::Stepper;\nuse super::OdeSystem;\npub struct Dopri5;"),
    ]);
    let r = analyse(&old);
    assert_eq!(r.top_cycle, None);
    assert_eq!(r.folder_cycles.len(), 1, "{:?}", r.folder_cycles);
    assert_eq!(r.folder_cycles[0].0, "ode");
    assert!(r.ode_violations.is_empty());

    // The trait in a file of its own: no cycle. `super` inside an inline module is the file's module.
    let mut new = old.clone();
    new.insert(
        "ode/mod.rs".into(),
        "pub mod driver;\npub mod dopri5;\npub mod stepper;\npub trait OdeSystem {}".into(),
    );
    new.insert("ode/stepper.rs".into(), "use super::OdeSystem;\npub(crate) trait Stepper {}".into());
    new.insert("ode/driver.rs".into(), "use super::dopri5::Dopri5;\nuse super::stepper::Stepper;\nmod tests {\n    use super::super::stepper::Stepper;\n}".into());
    new.insert(
        "ode/dopri5.rs".into(),
        "use super::stepper::Stepper;\npub struct Dopri5;\nmod tests {\n    use super::Dopri5;\n}".into(),
    );
    let r = analyse(&new);
    assert!(r.folder_cycles.is_empty(), "{:?}", r.folder_cycles);

    // ode reaching up into the model: a violation (and here a cycle too).
    let mut up = new.clone();
    up.insert("ode/stepper.rs".into(), "use crate::model::Slider;".into());
    let r = analyse(&up);
    assert_eq!(r.ode_violations, vec![("ode/stepper.rs".to_string(), "model::Slider".to_string())]);
    assert!(r.top_cycle.is_some());
}
