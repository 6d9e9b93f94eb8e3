//! Every command the README and the chapters of `docs/` show in a code block runs, and exits 0:
//! `tensegrity ...` and `cargo run --release -- ...` lines (the latter through the built
//! binary), in one scratch directory that sees the repository's `scenarios/` and `tests/` (so
//! outputs such as `out/report.json` never land in the repository). README.md comes first, then
//! `docs/*.md` in name order, each file's commands in its order; a command shown again (the
//! README's tutorial steps are the chapters' first lines) runs once, where it is first shown. A
//! line with `${SLURM_ARRAY_TASK_ID}` runs once for every task of its `--shard K/N`.
//!
//! Each command also does what its text says (`unmet_claims`): no panic on its standard error,
//! a `run`'s every scenario line says PASS or "as the scenario expects", and every file its
//! `--out`, `--json`, `--figure`, `--table` or `--record` names exists and is not empty (a
//! directory for `figure --out`, with files in it), a `.json` one parsing as JSON.

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

fn run(dir: &Path, command: &str, task: usize) -> (bool, String, String) {
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
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.success(), text(&out.stdout), text(&out.stderr))
}

/// The flags whose value is a file (or, for `figure`, a directory) the command writes.
const OUTPUT_FLAGS: [&str; 5] = ["--out", "--json", "--figure", "--table", "--record"];

/// What `command` (run as `task`, with this stdout and stderr) claims and its outputs do not show.
fn unmet_claims(dir: &Path, command: &str, task: usize, stdout: &str, stderr: &str) -> Vec<String> {
    let mut unmet = Vec::new();
    if stderr.contains("panicked") {
        unmet.push("a panic on stderr".to_string());
    }
    let words: Vec<&str> = command.split_whitespace().collect();
    if words.get(1) == Some(&"run") {
        let verdicts: Vec<&str> = stdout.lines().chain(stderr.lines()).filter(|l| l.starts_with("== ")).collect();
        if verdicts.is_empty() {
            unmet.push("no scenario's verdict line".to_string());
        }
        for v in verdicts.iter().filter(|v| !v.ends_with(": PASS") && !v.ends_with(", as the scenario expects")) {
            unmet.push(format!("not PASS nor as expected: {v}"));
        }
    }
    for pair in words.windows(2).filter(|w| OUTPUT_FLAGS.contains(&w[0])) {
        let name = pair[1].replace("${SLURM_ARRAY_TASK_ID}", &task.to_string());
        if name == "-" || name.contains('{') || name.contains('|') {
            continue;
        }
        if let Some(problem) = output_problem(&dir.join(&name)) {
            unmet.push(format!("{} {name}: {problem}", pair[0]));
        }
    }
    unmet
}

/// Why the output at `path` does not show it was written (None when it does). A run of several
/// scenarios writes STEM-NAME.EXT per scenario instead: each of those then.
fn output_problem(path: &Path) -> Option<String> {
    if !path.exists() {
        let stem = path.file_stem().map(|s| format!("{}-", s.to_string_lossy())).unwrap_or_default();
        let ext = path.extension().map(|e| e.to_string_lossy().into_owned());
        let per_scenario: Vec<PathBuf> = std::fs::read_dir(path.parent()?)
            .ok()?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.file_name().is_some_and(|n| n.to_string_lossy().starts_with(&stem)))
            .filter(|p| p.extension().map(|e| e.to_string_lossy().into_owned()) == ext)
            .collect();
        if per_scenario.is_empty() {
            return Some("not written".into());
        }
        return per_scenario.iter().find_map(|p| output_problem(p).map(|e| format!("{}: {e}", p.display())));
    }
    let Ok(meta) = std::fs::metadata(path) else { return Some("not readable".into()) };
    if meta.is_dir() {
        let files = std::fs::read_dir(path).map(|d| d.count()).unwrap_or(0);
        return (files == 0).then(|| "an empty directory".into());
    }
    let text = std::fs::read(path).unwrap_or_default();
    if text.is_empty() {
        return Some("empty".into());
    }
    let json = path.extension().is_some_and(|e| e == "json");
    json.then(|| serde_json::from_slice::<serde_json::Value>(&text).err().map(|e| format!("not JSON: {e}"))).flatten()
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
fn every_command_the_readme_and_docs_show_runs_exits_0_and_writes_what_it_says() {
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
            let (ok, stdout, stderr) = run(&dir, command, task);
            let mut unmet = unmet_claims(&dir, command, task, &stdout, &stderr);
            if !ok {
                let said = format!("{stdout}{stderr}");
                unmet.insert(0, format!("exit non-zero\n{}", said.lines().take(5).collect::<Vec<_>>().join("\n")));
            }
            if !unmet.is_empty() {
                failed.push(format!("{file}:{line}: {command} (task {task}): {}", unmet.join("; ")));
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    assert!(failed.is_empty(), "{} command(s) failed:\n{}", failed.len(), failed.join("\n"));
}
