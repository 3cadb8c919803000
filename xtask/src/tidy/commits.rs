//! The commit-subject rule: every commit since a fixed base has a subject of at most
//! [`MAX_SUBJECT`](super::MAX_SUBJECT) characters (figures and reasons go in the body).

use std::path::Path;
use std::process::Command;

/// The subjects longer than `max` characters of the commits reachable from HEAD and not
/// from `base`, other than the commits (full hashes) in `exceptions`; a problem too when git
/// cannot list them (no repository, `base` unknown). In a shallow clone, where the history
/// since `base` is absent, the rule is skipped with a note on standard error.
pub fn subjects(root: &Path, base: &str, max: usize, exceptions: &[&str]) -> Vec<String> {
    let shallow = Command::new("git")
        .args(["rev-parse", "--is-shallow-repository"])
        .current_dir(root)
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "true");
    if shallow {
        eprintln!("tidy: shallow clone, commit subjects since {base} not checked");
        return Vec::new();
    }
    let out = Command::new("git")
        .args(["log", "--format=%H%x09%s", &format!("{base}..HEAD")])
        .current_dir(root)
        .output();
    let text = match out {
        Ok(o) if o.status.success() => String::from_utf8_lossy(&o.stdout).into_owned(),
        Ok(o) => {
            return vec![format!(
                "cannot list the commits since {base} (a full clone is needed): {}",
                String::from_utf8_lossy(&o.stderr).trim()
            )];
        }
        Err(e) => return vec![format!("cannot run git to list the commits: {e}")],
    };
    too_long(&text, max, exceptions)
}

/// The lines `hash<TAB>subject` of `log` whose subject is over `max` characters, other
/// than those of the commits in `exceptions`.
fn too_long(log: &str, max: usize, exceptions: &[&str]) -> Vec<String> {
    log.lines()
        .filter_map(|l| l.split_once('\t'))
        .filter(|(h, s)| s.chars().count() > max && !exceptions.contains(h))
        .map(|(h, s)| {
            format!(
                "commit {}: subject of {} characters (at most {max}): {s}",
                &h[..h.len().min(10)],
                s.chars().count()
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_subjects_are_reported_by_characters() {
        let ok = "é".repeat(72);
        let long = "x".repeat(73);
        let log = format!("abc1234\t{ok}\ndef5678\t{long}\nfed9876\t{long}\n");
        let p = too_long(&log, 72, &["fed9876"]);
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(p[0].starts_with("commit def5678: subject of 73 characters"));
    }
}
