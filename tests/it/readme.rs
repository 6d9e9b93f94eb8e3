//! Every command the README and the chapters of `docs/` show in a code block runs, and exits 0:
//! `tensegrity ...` and `cargo run --release -- ...` lines (the latter through the built
//! binary), in one scratch directory that sees the repository's `scenarios/` and `tests/` (so
//! outputs such as `out/report.json` never land in the repository). README.md comes first, then
//! `docs/*.md` in name order, each file's commands in its order; a command shown again (the
//! README's tutorial steps are the chapters' first lines) runs once, where it is first shown. A
//! line with `${SLURM_ARRAY_TASK_ID}` runs once for every task of its `--shard K/N`.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The command lines of a Markdown file's code blocks, with their line numbers.
fn commands(readme: &str) -> Vec<(usize, String)> {
    let mut inside = false;
    let mut out = Vec::new();
    for (k, line) in readme.lines().enumerate() {
        if line.starts_with("```") {
            inside = !inside;
            continue;
        }
        let line = line.trim_start_matches("$ ");
        if !inside {
            continue;
        }
        if let Some(rest) = line.strip_prefix("cargo run --release -- ") {
            out.push((k + 1, format!("tensegrity {rest}")));
        } else if line.starts_with("tensegrity ") {
            out.push((k + 1, line.to_string()));
        }
    }
    out
}

/// The number of shards a Slurm line asks for (`--shard ${SLURM_ARRAY_TASK_ID}/N`).
fn shards(command: &str) -> usize {
    command
        .split("${SLURM_ARRAY_TASK_ID}/")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or(1)
}

fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tt-readme-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("out")).expect("scratch directory");
    let repo = std::env::current_dir().expect("the package root");
    for d in ["scenarios", "tests"] {
        let link = dir.join(d);
        if !link.exists() {
            std::os::unix::fs::symlink(repo.join(d), &link).expect("link");
        }
    }
    dir
}

fn run(dir: &Path, command: &str, task: usize) -> (bool, String) {
    let bin = Path::new(env!("CARGO_BIN_EXE_tensegrity")).parent().expect("bin dir").to_path_buf();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let out = Command::new("sh")
        .arg("-c")
        .arg(command)
        .current_dir(dir)
        .env("PATH", path)
        .env("SLURM_ARRAY_TASK_ID", task.to_string())
        .output()
        .expect("sh runs");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    (out.status.success(), text)
}

/// README.md, then every `docs/*.md` in name order.
fn documents() -> Vec<PathBuf> {
    let mut docs: Vec<PathBuf> = std::fs::read_dir("docs")
        .expect("docs/")
        .map(|e| e.expect("docs/ entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    docs.sort();
    assert!(docs.len() >= 10, "docs/ has {} Markdown files", docs.len());
    std::iter::once(PathBuf::from("README.md")).chain(docs).collect()
}

#[test]
fn every_command_the_readme_and_docs_show_runs_and_exits_0() {
    let mut list: Vec<(String, usize, String)> = Vec::new();
    for file in documents() {
        let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        list.extend(commands(&text).into_iter().map(|(line, c)| (file.display().to_string(), line, c)));
    }
    assert!(list.len() >= 20, "the README and docs/ show {} commands", list.len());
    assert!(list.iter().filter(|(f, ..)| f == "README.md").count() >= 5, "the README's own commands");
    let dir = scratch();
    let mut failed = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for (file, line, command) in &list {
        if !seen.insert(command.clone()) {
            continue;
        }
        for task in 1..=shards(command) {
            let (ok, text) = run(&dir, command, task);
            if !ok {
                failed.push(format!(
                    "{file}:{line}: {command} (task {task})\n{}",
                    text.lines().take(5).collect::<Vec<_>>().join("\n")
                ));
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    assert!(failed.is_empty(), "{} command(s) failed:\n{}", failed.len(), failed.join("\n"));
}
