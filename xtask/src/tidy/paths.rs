//! The paths a Rust source names under a crate (`geom_db::…`, `intersect::…`), read from
//! its text without a parser dependency: comments are dropped, `use` trees are expanded
//! (`use a::{b, c::{d, e}}` names `b`, `c::d`, `c::e`), qualified paths are read to their
//! last segment (`a::b::C::new(…)` names `b::C::new`).

/// The text with comments (`//`, doc comments, `/* … */`) and the contents of string and
/// char literals (plain and raw) replaced by spaces, so that only code is read.
pub fn strip_comments(text: &str) -> String {
    let b: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let blank = |out: &mut String, c: char| out.push(if c == '\n' { '\n' } else { ' ' });
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let prev_ident = i > 0 && is_ident(b[i - 1]);
        if c == '/' && b.get(i + 1) == Some(&'/') {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && b.get(i + 1) == Some(&'*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == '/' && b.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if b[i] == '*' && b.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, b[i]);
                    i += 1;
                }
            }
        } else if c == 'r' && !prev_ident && matches!(b.get(i + 1), Some('"') | Some('#')) {
            // raw string r"…", r#"…"#
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            j += 1;
            while j < b.len() {
                if b[j] == '"' && (0..hashes).all(|k| b.get(j + 1 + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                blank(&mut out, b[j]);
                j += 1;
            }
            out.push('"');
            i = j;
        } else if c == '"' {
            i += 1;
            while i < b.len() && b[i] != '"' {
                if b[i] == '\\' {
                    i += 1;
                }
                if i < b.len() {
                    blank(&mut out, b[i]);
                }
                i += 1;
            }
            out.push_str("\"\"");
            i += 1;
        } else if c == '\'' && b.get(i + 2) == Some(&'\'') {
            out.push_str("' '");
            i += 3;
        } else if c == '\'' && b.get(i + 1) == Some(&'\\') {
            // escaped char literal: '\n', '\'', '\u{…}'
            let mut j = i + 3;
            while j < b.len() && b[j] != '\'' {
                j += 1;
            }
            out.push_str("' '");
            i = j + 1;
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

fn skip_ws(s: &[char], i: &mut usize) {
    while *i < s.len() && s[*i].is_whitespace() {
        *i += 1;
    }
}

fn ident(s: &[char], i: &mut usize) -> Option<String> {
    skip_ws(s, i);
    if *i < s.len() && s[*i] == '*' {
        *i += 1;
        return Some("*".into());
    }
    let start = *i;
    while *i < s.len() && is_ident(s[*i]) {
        *i += 1;
    }
    (*i > start).then(|| s[start..*i].iter().collect())
}

fn join(prefix: &str, seg: &str) -> String {
    if prefix.is_empty() {
        seg.to_string()
    } else {
        format!("{prefix}::{seg}")
    }
}

/// Reads a path or a `{…}` group at `i`, pushing the full paths (under `prefix`) to `out`.
fn tree(s: &[char], i: &mut usize, prefix: &str, out: &mut Vec<String>) {
    skip_ws(s, i);
    if *i < s.len() && s[*i] == '{' {
        *i += 1;
        loop {
            skip_ws(s, i);
            if *i >= s.len() {
                return;
            }
            if s[*i] == '}' {
                *i += 1;
                return;
            }
            let before = *i;
            tree(s, i, prefix, out);
            skip_ws(s, i);
            if *i < s.len() && s[*i] == ',' {
                *i += 1;
            } else if *i == before {
                *i += 1; // not a path: step over it
            }
        }
    }
    let mut path = prefix.to_string();
    let mut named_self = false;
    while let Some(seg) = ident(s, i) {
        if seg == "self" {
            named_self = true;
        } else {
            path = join(&path, &seg);
        }
        let mut j = *i;
        skip_ws(s, &mut j);
        if j + 1 < s.len() && s[j] == ':' && s[j + 1] == ':' {
            *i = j + 2;
            skip_ws(s, i);
            if *i < s.len() && s[*i] == '{' {
                tree(s, i, &path, out);
                return;
            }
        } else {
            break;
        }
    }
    // `as Alias` renames; the path is what is named.
    let mut j = *i;
    if ident(s, &mut j).as_deref() == Some("as") {
        ident(s, &mut j);
        *i = j;
    }
    if !path.is_empty() && (path != prefix || named_self) {
        out.push(path);
    }
}

/// The paths named under `krate::` in `text` (comments ignored), without the crate name,
/// sorted and deduplicated. `krate` is the crate's name as written in code (`geom_db`).
pub fn named_paths(text: &str, krate: &str) -> Vec<String> {
    let text = strip_comments(text);
    let s: Vec<char> = text.chars().collect();
    let pat: Vec<char> = format!("{krate}::").chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i + pat.len() <= s.len() {
        let starts =
            s[i..i + pat.len()] == pat[..] && (i == 0 || !(is_ident(s[i - 1]) || s[i - 1] == ':'));
        if starts {
            let mut j = i + pat.len();
            tree(&s, &mut j, "", &mut out);
            i = j.max(i + 1);
        } else {
            i += 1;
        }
    }
    out.sort();
    out.dedup();
    out
}

/// True when `path` is allowed by `allowed`: an entry `X` allows `X` and everything under
/// it (`X::…`); `*` allows every path.
pub fn allowed(path: &str, allowed: &[&str]) -> bool {
    allowed.iter().any(|a| {
        *a == "*" || path == *a || (path.starts_with(a) && path[a.len()..].starts_with("::"))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn use_trees_and_qualified_paths_are_expanded() {
        let src = r##"
            use geom_db::{GeomDb, eval::{ParamCurve, ParamSurface as S}, prelude::*};
            use geom_db::SurfaceId;
            // geom_db::import::import is mentioned in a comment only
            /* and geom_db::check in a block comment */
            fn f(db: &geom_db::GeomDb) -> Vec<geom_db::prelude::Point3> {
                let s = "geom_db::in_a_string"; // strings are left out
                let q = '"'; // a quote in a char literal does not open a string
                let r = r#"geom_db::raw"#;
                let _ = my_geom_db::X;
                geom_db::bspline::KnotVector::new(3)
            }
        "##;
        assert_eq!(
            named_paths(src, "geom_db"),
            vec![
                "GeomDb",
                "SurfaceId",
                "bspline::KnotVector::new",
                "eval::ParamCurve",
                "eval::ParamSurface",
                "prelude::*",
                "prelude::Point3",
            ]
        );
        let src = "use intersect::{self, project::{self, SurfaceProjector}};";
        assert_eq!(
            named_paths(src, "intersect"),
            vec!["project", "project::SurfaceProjector"]
        );
    }

    #[test]
    fn allowed_paths_match_on_segment_boundaries() {
        let list = ["GeomDb", "eval", "update"];
        assert!(allowed("GeomDb", &list));
        assert!(allowed("GeomDb::from_ron_str", &list));
        assert!(allowed("eval::ParamSurface", &list));
        assert!(!allowed("GeomDbx", &list));
        assert!(!allowed("project::SurfaceProjector", &list));
        assert!(!allowed("updates::X", &list));
        assert!(allowed("anything::at_all", &["*"]));
    }
}
