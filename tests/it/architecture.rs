//! The layering of `src/`, read from the source: which top-level modules each module names
//! through `crate::`. Data flows one way (scenario -> model -> simulation -> observers ->
//! report), so no module may reach back to one that reaches it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Top-level module -> the top-level modules its files name through `crate::`.
fn imports() -> BTreeMap<String, BTreeSet<String>> {
    fn walk(dir: &Path, files: &mut Vec<std::path::PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, files);
            } else if p.extension().is_some_and(|x| x == "rs") {
                files.push(p);
            }
        }
    }
    let mut files = Vec::new();
    walk(Path::new("src"), &mut files);
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let rel = f.strip_prefix("src").unwrap();
        let first = rel.components().next().unwrap().as_os_str().to_string_lossy().into_owned();
        let module = first.trim_end_matches(".rs").to_string();
        if module == "lib" || module == "main" {
            continue;
        }
        let text = std::fs::read_to_string(&f).unwrap();
        for (i, _) in text.match_indices("crate::") {
            let name: String = text[i + 7..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
            if !name.is_empty() && name != module {
                graph.entry(module.clone()).or_default().insert(name);
            }
        }
    }
    graph
}

fn reaches(graph: &BTreeMap<String, BTreeSet<String>>, from: &str, to: &str) -> bool {
    let mut seen = BTreeSet::new();
    let mut stack = vec![from.to_string()];
    while let Some(m) = stack.pop() {
        if m == to {
            return true;
        }
        if seen.insert(m.clone()) {
            stack.extend(graph.get(&m).into_iter().flatten().cloned());
        }
    }
    false
}

#[test]
fn no_module_imports_one_that_imports_it_back() {
    let graph = imports();
    assert!(graph.len() >= 10, "read only {} modules", graph.len());
    let cycles: Vec<String> = graph
        .iter()
        .flat_map(|(a, deps)| deps.iter().filter(|b| reaches(&graph, b, a)).map(move |b| format!("{a} <-> {b}")))
        .collect();
    assert!(cycles.is_empty(), "import cycles: {cycles:?}");
}

#[test]
fn parsing_observing_and_the_models_stay_apart() {
    let graph = imports();
    let uses = |a: &str, b: &str| graph.get(a).is_some_and(|d| d.contains(b));
    for (a, b) in [
        ("scenario", "observers"),
        ("observers", "scenario"),
        ("scenario", "sim"),
        ("scenario", "run"),
        ("observers", "sim"),
        ("mechanisms", "sim"),
        ("mechanisms", "observers"),
        ("sim", "mechanisms"),
    ] {
        assert!(!uses(a, b), "{a} imports {b}: {:?}", graph[a]);
    }
}
