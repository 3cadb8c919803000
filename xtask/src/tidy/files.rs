//! The per-file rules: `//!` headers, no environment or /proc in library code, and no
//! library file over the line limit unless its doc says why it is one idea.

use std::path::Path;

use super::paths::strip_comments;
use super::{Package, rel, rs_files};

/// Every `.rs` file of `crates/`, `xtask/` and `tests/` starts with a `//!` doc line.
pub fn file_headers(root: &Path) -> Vec<String> {
    let mut problems = Vec::new();
    for dir in ["crates", "xtask", "tests"] {
        for path in rs_files(&root.join(dir)) {
            let text = std::fs::read_to_string(&path).unwrap_or_default();
            if !text.trim_start().starts_with("//!") {
                problems.push(format!(
                    "{}: does not start with a `//!` doc line",
                    rel(root, &path)
                ));
            }
        }
    }
    problems
}

/// The library crates' `src/` files, relative to `root`, with their text.
fn library_files(root: &Path, pkgs: &[Package]) -> Vec<(String, String)> {
    pkgs.iter()
        .filter(|p| p.is_lib)
        .flat_map(|p| rs_files(&p.dir.join("src")))
        .map(|f| {
            let text = std::fs::read_to_string(&f).unwrap_or_default();
            (rel(root, &f), text)
        })
        .collect()
}

/// What in code reads the environment or /proc (comments ignored; `env!` and
/// `option_env!` are compile-time and allowed).
const ENV_PATTERNS: &[&str] = &[
    "env::var(",
    "env::var_os(",
    "env::vars(",
    "env::vars_os(",
    "\"/proc",
];

/// The lines of `text` whose code reads the environment or /proc.
fn env_reads(text: &str) -> Vec<usize> {
    // Strings are blanked by `strip_comments`, so "/proc" is looked for in the raw line of
    // every code line that is not a comment.
    let code = strip_comments(text);
    text.lines()
        .zip(code.lines())
        .enumerate()
        .filter(|(_, (raw, code))| {
            ENV_PATTERNS.iter().any(|p| {
                if p.starts_with('"') {
                    !code.trim().is_empty() && raw.contains(p)
                } else {
                    code.contains(p)
                }
            })
        })
        .map(|(i, _)| i + 1)
        .collect()
}

/// Library code does not read environment variables or /proc, except the files in
/// `exceptions` (each of which must still do so).
pub fn no_environment(root: &Path, pkgs: &[Package], exceptions: &[(&str, &str)]) -> Vec<String> {
    let mut problems = Vec::new();
    let mut seen = Vec::new();
    for (file, text) in library_files(root, pkgs) {
        let lines = env_reads(&text);
        if lines.is_empty() {
            continue;
        }
        if exceptions.iter().any(|(f, _)| *f == file) {
            seen.push(file);
            continue;
        }
        problems.push(format!(
            "{file}:{}: library code reads the environment or /proc (give the caller an \
             option instead)",
            lines[0]
        ));
    }
    for (f, _) in exceptions {
        if !seen.iter().any(|s| s == f) {
            problems.push(format!(
                "ENV_EXCEPTIONS lists {f}, which no longer reads the environment or /proc: \
                 remove it from xtask/src/tidy/mod.rs"
            ));
        }
    }
    problems
}

/// True when the leading `//!` block of `text` says why the file is one idea.
fn says_one_idea(text: &str) -> bool {
    text.lines()
        .take_while(|l| l.trim_start().starts_with("//!"))
        .any(|l| l.to_lowercase().contains("one idea"))
}

/// No library `.rs` file is over `max` lines unless its `//!` doc says why it is one idea,
/// except the files in `exceptions` (each of which must still be over).
pub fn long_files(
    root: &Path,
    pkgs: &[Package],
    max: usize,
    exceptions: &[(&str, &str)],
) -> Vec<String> {
    let mut problems = Vec::new();
    let mut seen = Vec::new();
    for (file, text) in library_files(root, pkgs) {
        let n = text.lines().count();
        if n <= max || says_one_idea(&text) {
            continue;
        }
        if exceptions.iter().any(|(f, _)| *f == file) {
            seen.push(file);
            continue;
        }
        problems.push(format!(
            "{file}: {n} lines (more than {max}): split it by idea, or say in its `//!` doc \
             why it is one idea"
        ));
    }
    for (f, _) in exceptions {
        if !seen.iter().any(|s| s == f) {
            problems.push(format!(
                "LONG_FILE_EXCEPTIONS lists {f}, which is no longer over {max} lines without \
                 a reason: remove it from xtask/src/tidy/mod.rs"
            ));
        }
    }
    problems
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn environment_reads_are_found_in_code_only() {
        let src = "//! Reads nothing.\n\
                   // std::env::var(\"X\") in a comment\n\
                   fn a() { let _ = std::env::var_os(\"TRACE\"); }\n\
                   fn b() { let dir = env!(\"CARGO_MANIFEST_DIR\"); }\n\
                   fn c() { std::fs::read_to_string(\"/proc/self/status\"); }\n\
                   /// see /proc/self/status\n\
                   fn d() {}\n";
        assert_eq!(env_reads(src), vec![3, 5]);
    }

    #[test]
    fn a_long_file_needs_a_reason_in_its_doc() {
        let plain = "//! A module.\nfn f() {}\n";
        let reasoned = "//! The SU2 format.\n//! One idea: reader and writer share the sections.\n";
        assert!(!says_one_idea(plain));
        assert!(says_one_idea(reasoned));
        // only the leading doc block counts
        assert!(!says_one_idea("//! A module.\nfn f() {}\n//! one idea\n"));
    }
}
