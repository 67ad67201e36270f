//! The reference docs stay reference: every relative link in README.md and
//! docs/ reaches an existing file (and heading, for `#anchor` links), every
//! page is reachable from the README in at most two clicks, and no line
//! narrates history (see `dated`: that belongs in CHANGELOG.md and
//! bench/results/).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

fn pages() -> Vec<PathBuf> {
    let mut out = vec![Path::new(ROOT).join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(Path::new(ROOT).join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    out.extend(docs);
    out
}

/// GitHub's heading anchors: lower case, punctuation other than `-` and `_`
/// dropped, spaces to `-`.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

fn anchors(text: &str) -> BTreeSet<String> {
    let mut fence = false;
    let mut out = BTreeSet::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fence = !fence;
        } else if !fence && line.starts_with('#') {
            out.insert(slug(line.trim_start_matches('#')));
        }
    }
    out
}

/// The targets of `](target)` links outside code fences and code spans.
fn links(text: &str) -> Vec<String> {
    let mut fence = false;
    let mut out = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fence = !fence;
            continue;
        }
        if fence {
            continue;
        }
        // Drop code spans, where `](` is code, not a link.
        let plain: String = line.split('`').step_by(2).collect::<Vec<_>>().join(" ");
        let mut rest = plain.as_str();
        while let Some(i) = rest.find("](") {
            let tail = &rest[i + 2..];
            let end = tail.find(')').unwrap_or(tail.len());
            out.push(tail[..end].to_string());
            rest = &tail[end..];
        }
    }
    out
}

fn is_external(target: &str) -> bool {
    target.starts_with("http://") || target.starts_with("https://") || target.starts_with("mailto:")
}

#[test]
fn every_relative_link_in_the_docs_reaches_a_file_and_heading() {
    let mut broken = Vec::new();
    let mut anchored = 0;
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for target in links(&text) {
            if is_external(&target) {
                continue;
            }
            let (file, anchor) = target.split_once('#').map_or((target.as_str(), None), |(f, a)| (f, Some(a)));
            let path = if file.is_empty() { page.clone() } else { page.parent().unwrap().join(file) };
            if !path.exists() {
                broken.push(format!("{}: {target} (no such file)", page.display()));
                continue;
            }
            if let Some(anchor) = anchor {
                anchored += 1;
                let target_text = std::fs::read_to_string(&path).unwrap_or_default();
                if !anchors(&target_text).contains(anchor) {
                    broken.push(format!("{}: {target} (no such heading)", page.display()));
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
    // Not vacuous: the pages link to headings of each other (counted 30 and
    // more when this test was written).
    assert!(anchored >= 10, "only {anchored} links to headings found: is the link parser broken?");
}

#[test]
fn every_docs_page_is_at_most_two_clicks_from_the_readme() {
    let pages = pages();
    let mut edges: BTreeMap<PathBuf, Vec<PathBuf>> = BTreeMap::new();
    for page in &pages {
        let text = std::fs::read_to_string(page).unwrap();
        let targets = links(&text)
            .into_iter()
            .filter(|t| !is_external(t))
            .filter_map(|t| {
                let file = t.split('#').next().unwrap().to_string();
                (!file.is_empty()).then(|| page.parent().unwrap().join(file))
            })
            .filter_map(|p| p.canonicalize().ok())
            .collect();
        edges.insert(page.canonicalize().unwrap(), targets);
    }
    let readme = pages[0].canonicalize().unwrap();
    let one: BTreeSet<PathBuf> = edges[&readme].iter().cloned().collect();
    let two: BTreeSet<PathBuf> = one.iter().flat_map(|p| edges.get(p).cloned().unwrap_or_default()).collect();
    let far: Vec<String> = pages[1..]
        .iter()
        .map(|p| p.canonicalize().unwrap())
        .filter(|p| !one.contains(p) && !two.contains(p))
        .map(|p| p.display().to_string())
        .collect();
    assert!(far.is_empty(), "pages more than two clicks from README.md: {far:?}");
}

/// Whether a line narrates history: an ISO date (`YYYY-MM-DD`), a work
/// period's name, or a tracker number ("issue" then a digit).
fn dated(line: &str) -> bool {
    let bytes = line.as_bytes();
    let iso_date = bytes
        .windows(10)
        .any(|w| w.iter().enumerate().all(|(i, c)| if i == 4 || i == 7 { *c == b'-' } else { c.is_ascii_digit() }));
    let lower = line.to_lowercase();
    let issue_number = lower
        .match_indices("issue ")
        .any(|(i, m)| lower[i + m.len()..].chars().next().is_some_and(|c| c.is_ascii_digit()));
    // Spelled in two parts so that this file does not match its own rule.
    iso_date || lower.contains(concat!("ses", "sion")) || issue_number
}

/// The checker itself catches what it should, and not the mathematical
/// words around it. (The examples are assembled at run time so that this
/// file passes its own rule.)
#[test]
fn the_date_checker_catches_what_it_should() {
    assert!(dated(&format!("Measured {}-11-27 on two cores", 2026)));
    assert!(dated(&format!("(fifth {}sion)", "ses")));
    assert!(dated(&format!("see {} 15", "issue")));
    assert!(!dated("an issue with the grid at ny = 2026"));
    assert!(!dated("T = ln(eps/delta)/Sigma^2 with 10-2-3 splits"));
}

#[test]
fn no_line_of_the_reference_docs_narrates_history() {
    let mut found = Vec::new();
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for (i, line) in text.lines().enumerate() {
            if dated(line) {
                found.push(format!("{}:{}: {line}", page.display(), i + 1));
            }
        }
    }
    assert!(found.is_empty(), "history belongs in CHANGELOG.md:\n{}", found.join("\n"));
}
