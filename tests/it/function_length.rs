//! Functions fit on a screen: no `fn` item under `src/` or `python/src/` spans more than
//! [`MAX_LINES`] lines, counted from the line of its `fn` to the line of its closing brace.
//! The source is read with its comments, strings and character literals blanked out, so that
//! a brace inside one of them counts for nothing.

use std::path::{Path, PathBuf};

/// The most lines a function may span.
const MAX_LINES: usize = 80;

use super::common::rust_files;

/// The index after the literal that opens at `i` (a string, a raw string or a character
/// literal), or None when none opens there (a lifetime's quote is none).
fn literal_end(c: &[char], i: usize) -> Option<usize> {
    let ident_before = i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_');
    match c[i] {
        '"' => {
            let mut j = i + 1;
            while j < c.len() && c[j] != '"' {
                j += if c[j] == '\\' { 2 } else { 1 };
            }
            Some(j + 1)
        }
        // r"..", r#".."#, br#".."#: no escapes inside, closed by the quote and as many #.
        'r' if !ident_before || (i == 1 || !c[i - 2].is_alphanumeric()) && c[i - 1] == 'b' => {
            let hashes = c[i + 1..].iter().take_while(|&&x| x == '#').count();
            if c.get(i + 1 + hashes) != Some(&'"') {
                return None;
            }
            let close: Vec<char> = std::iter::once('"').chain(std::iter::repeat_n('#', hashes)).collect();
            let from = i + 2 + hashes;
            (from..c.len()).find(|&j| c[j..].starts_with(&close)).map(|j| j + close.len())
        }
        '\'' if c.get(i + 1) == Some(&'\\') => {
            let mut j = i + 2;
            while j < c.len() && c[j] != '\'' {
                j += 1;
            }
            Some(j + 1)
        }
        '\'' if c.get(i + 2) == Some(&'\'') => Some(i + 3),
        _ => None,
    }
}

/// The source with every comment, string and character literal blanked (line breaks kept).
fn blanked(text: &str) -> Vec<char> {
    let c: Vec<char> = text.chars().collect();
    let mut out = c.clone();
    let blank = |out: &mut Vec<char>, from: usize, to: usize| {
        for x in &mut out[from..to.min(c.len())] {
            if *x != '\n' {
                *x = ' ';
            }
        }
    };
    let mut i = 0;
    while i < c.len() {
        if c[i..].starts_with(&['/', '/']) {
            let end = (i..c.len()).find(|&j| c[j] == '\n').unwrap_or(c.len());
            blank(&mut out, i, end);
            i = end;
        } else if c[i..].starts_with(&['/', '*']) {
            // Block comments nest.
            let (mut depth, mut j) = (0usize, i);
            while j < c.len() {
                if c[j..].starts_with(&['/', '*']) {
                    depth += 1;
                    j += 2;
                } else if c[j..].starts_with(&['*', '/']) {
                    depth -= 1;
                    j += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    j += 1;
                }
            }
            blank(&mut out, i, j);
            i = j;
        } else if let Some(end) = literal_end(&c, i) {
            blank(&mut out, i, end);
            i = end;
        } else {
            i += 1;
        }
    }
    out
}

/// Every function of the source: its name, the line of its `fn` and the lines it spans (a
/// declaration without a body spans none).
fn functions(text: &str) -> Vec<(String, usize, usize)> {
    let c = blanked(text);
    let line_at = |i: usize| c[..i].iter().filter(|&&x| x == '\n').count() + 1;
    let is_ident = |x: char| x.is_alphanumeric() || x == '_';
    let mut out = Vec::new();
    for i in 0..c.len().saturating_sub(3) {
        let keyword = c[i] == 'f' && c[i + 1] == 'n' && c[i + 2].is_whitespace();
        if !keyword || (i > 0 && is_ident(c[i - 1])) {
            continue;
        }
        let name_at = (i + 2..c.len()).find(|&j| !c[j].is_whitespace()).unwrap_or(c.len());
        let name: String = c[name_at..].iter().take_while(|&&x| is_ident(x)).collect();
        if name.is_empty() {
            continue; // a function pointer type: `fn(u32) -> u32`
        }
        // The body opens at the first `{` outside brackets; a `;` there first: no body.
        let mut nesting = 0i32;
        let mut open = None;
        for (j, &x) in c.iter().enumerate().skip(name_at) {
            match x {
                '(' | '[' => nesting += 1,
                ')' | ']' => nesting -= 1,
                ';' if nesting == 0 => break,
                '{' if nesting == 0 => {
                    open = Some(j);
                    break;
                }
                _ => {}
            }
        }
        let Some(open) = open else { continue };
        let mut depth = 0i32;
        let close = (open..c.len()).find(|&j| {
            depth += match c[j] {
                '{' => 1,
                '}' => -1,
                _ => 0,
            };
            depth == 0
        });
        let close = close.unwrap_or(c.len() - 1);
        let first = line_at(i);
        out.push((name, first, line_at(close) - first + 1));
    }
    out
}

#[test]
fn the_scanner_skips_braces_in_comments_strings_and_characters() {
    let text = "fn a() {\n    let s = \"}}}\";\n    let r = r#\"{ \"}\" \"#;\n    // }\n    /* } /* } */ } */\n    \
                let c = '}';\n    let l: &'static str = \"\";\n}\n\nfn b(x: [u8; 3]) -> fn(u8) {\n    todo!()\n}\n\
                trait T {\n    fn c(&self);\n}\n";
    let found = functions(text);
    assert_eq!(found, vec![("a".into(), 1, 8), ("b".into(), 10, 3)], "{found:?}");
}

#[test]
fn no_function_spans_more_than_80_lines() {
    let files: Vec<PathBuf> = [Path::new("src"), Path::new("python/src")].iter().flat_map(|d| rust_files(d)).collect();
    assert!(files.len() >= 100, "read only {} files", files.len());
    let mut long = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for (name, line, lines) in functions(&text) {
            if lines > MAX_LINES {
                long.push(format!("{}:{line}: fn {name} spans {lines} lines", f.display()));
            }
        }
    }
    assert!(long.is_empty(), "functions longer than {MAX_LINES} lines:\n{}", long.join("\n"));
}
