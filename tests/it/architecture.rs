//! The layering of `src/`, read from the source: which top-level modules each module names
//! through `crate::`. Data flows one way (scenario -> model -> simulation -> observers ->
//! report), so no module may reach back to one that reaches it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Top-level module -> the top-level modules its files name through `crate::`.
fn imports() -> BTreeMap<String, BTreeSet<String>> {
    let files = super::common::rust_files(Path::new("src"));
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

/// The Architecture chapter (`docs/architecture.md`, moved there from the README), up to its
/// "How to add" list, as bullets of text.
fn architecture_chapter_bullets() -> Vec<String> {
    let chapter = std::fs::read_to_string("docs/architecture.md").unwrap();
    let start = chapter.find("# Architecture\n").expect("docs/architecture.md has an Architecture section");
    let section = &chapter[start..];
    let end = section.find("How to add").expect("the Architecture section has a How to add list");
    section[..end].split("\n- ").skip(1).map(str::to_string).collect()
}

/// Whether `bullet` names `file`: a file at the root as `src/NAME.rs`; a file in a folder by
/// the folder (`src/DIR/`) and its own name (`NAME.rs`, or for a sub-folder's `mod.rs` the
/// sub-folder `SUB/`).
fn names_file(bullet: &str, file: &Path) -> bool {
    let parts: Vec<String> = file.components().skip(1).map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    match parts.as_slice() {
        [single] => bullet.contains(&format!("src/{single}")),
        [dir, .., last] => {
            let own =
                if last == "mod.rs" && parts.len() > 2 { format!("{}/", parts[parts.len() - 2]) } else { last.clone() };
            bullet.contains(&format!("src/{dir}/")) && (last == "mod.rs" || bullet.contains(&own))
        }
        [] => false,
    }
}

#[test]
fn the_readme_architecture_names_every_source_file() {
    let bullets = architecture_chapter_bullets();
    assert!(bullets.len() >= 10, "read only {} bullets", bullets.len());
    let files = super::common::rust_files(Path::new("src"));
    assert!(files.len() >= 50, "read only {} files", files.len());
    let missing: Vec<String> =
        files.iter().filter(|f| !bullets.iter().any(|b| names_file(b, f))).map(|f| f.display().to_string()).collect();
    assert!(missing.is_empty(), "files of src/ docs/architecture.md does not name: {missing:?}");
}
